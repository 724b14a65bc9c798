//! Points binned on a uniform grid of cubes, for neighbour searches within
//! one cell size: a point's neighbours closer than the cell size lie in
//! its own cell or one of the 26 around it.

use std::collections::HashMap;

/// Point numbers binned by the cube of side `h` that holds each point.
pub struct PointGrid {
    h: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl PointGrid {
    /// An empty grid of cubes of side `h` (> 0).
    pub fn new(h: f64) -> PointGrid {
        PointGrid {
            h,
            cells: HashMap::new(),
        }
    }

    /// The grid of `points`, numbered in order.
    pub fn of(h: f64, points: impl IntoIterator<Item = [f64; 3]>) -> PointGrid {
        let mut g = PointGrid::new(h);
        for (i, p) in points.into_iter().enumerate() {
            g.insert(p, i as u32);
        }
        g
    }

    /// Bin point number `i` at `p`.
    pub fn insert(&mut self, p: [f64; 3], i: u32) {
        let c = self.cell(p);
        self.cells.entry(c).or_default().push(i);
    }

    /// The points in the 27 cubes around the one holding `p`, in no set
    /// order, until `f` returns `false`.
    pub fn near(&self, p: [f64; 3], mut f: impl FnMut(u32) -> bool) {
        let c = self.cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &j in list {
                        if !f(j) {
                            return;
                        }
                    }
                }
            }
        }
    }

    fn cell(&self, p: [f64; 3]) -> [i64; 3] {
        p.map(|v| (v / self.h).floor() as i64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair closer than the cell size is found, against all pairs,
    /// for points on either side of the origin (negative cells).
    #[test]
    fn finds_every_pair_within_the_cell_size() {
        let mut rng = crate::geometry::overlap::tests::Rng(12345);
        let mut next = || 2.0 * rng.next() - 1.0;
        let pts: Vec<[f64; 3]> = (0..400).map(|_| [next(), next(), next()]).collect();
        let h = 0.2;
        let grid = PointGrid::of(h, pts.iter().copied());
        let d2 = |a: [f64; 3], b: [f64; 3]| (0..3).map(|d| (a[d] - b[d]).powi(2)).sum::<f64>();
        let mut found = Vec::new();
        for (i, &p) in pts.iter().enumerate() {
            grid.near(p, |j| {
                if j as usize > i && d2(p, pts[j as usize]) < h * h {
                    found.push((i, j as usize));
                }
                true
            });
        }
        found.sort_unstable();
        let mut all = Vec::new();
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                if d2(pts[i], pts[j]) < h * h {
                    all.push((i, j));
                }
            }
        }
        assert!(
            all.len() > 100,
            "{} pairs: the test needs neighbours",
            all.len()
        );
        assert_eq!(found, all);
        // Stopping early: the walk ends at the first `false`.
        let mut seen = 0;
        grid.near(pts[0], |_| {
            seen += 1;
            false
        });
        assert_eq!(seen, 1);
    }
}
