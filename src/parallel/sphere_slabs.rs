//! Which rank owns a free sphere (issue 21, beyond the papers): the
//! spheres' region is cut into one slab per rank along its longest axis
//! (heights along gravity shrunk as for the bodies' cuts),
//! at fixed cuts chosen at set-up as quantiles of the sphere count, and a
//! sphere belongs to the slab its centre is in. A sphere within reach of
//! another slab (its radius plus the largest radius) is a ghost there.

/// The fixed cuts of the spheres' region.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereSlabs {
    /// The axis cut (0, 1, 2).
    pub axis: usize,
    /// Ascending cut coordinates, one fewer than the ranks: slab k is
    /// [cuts[k − 1], cuts[k]), the first and last open to infinity.
    pub cuts: Vec<f64>,
}

impl SphereSlabs {
    /// Cuts for `ranks` slabs of the `centres` along the longest axis of
    /// the box [`lo`, `hi`], its extents along gravity `g` shrunk as the
    /// bodies' bisection shrinks heights ([`super::rcb::level`]), so that a
    /// settling bed is cut across its floor: each cut halfway between the
    /// two centres either side of a count quantile, so the slabs hold the
    /// spheres in equal shares (ties on a cut go above it).
    pub fn new(
        centres: &[[f64; 3]],
        lo: [f64; 3],
        hi: [f64; 3],
        ranks: usize,
        g: [f64; 3],
    ) -> SphereSlabs {
        let len = g.iter().map(|c| c * c).sum::<f64>().sqrt();
        let extent = |a: usize| {
            let along = if len > 0.0 && len.is_finite() {
                (g[a] / len).abs()
            } else {
                0.0
            };
            (hi[a] - lo[a]) * (1.0 - (1.0 - super::rcb::HEIGHT_SHARE) * along)
        };
        let axis = (0..3)
            .max_by(|&a, &b| extent(a).total_cmp(&extent(b)).then(b.cmp(&a)))
            .unwrap_or(0);
        let mut c: Vec<f64> = centres.iter().map(|x| x[axis]).collect();
        c.sort_by(f64::total_cmp);
        let n = c.len();
        let cuts = (1..ranks)
            .map(|k| {
                let i = k * n / ranks;
                match i {
                    0 => c.first().map_or(0.5 * (lo[axis] + hi[axis]), |&v| v - 1.0),
                    i if i >= n => c[n - 1] + 1.0,
                    i => 0.5 * (c[i - 1] + c[i]),
                }
            })
            .collect();
        SphereSlabs { axis, cuts }
    }

    /// The rank owning a sphere centred at `x`.
    pub fn owner(&self, x: &[f64; 3]) -> usize {
        self.cuts.partition_point(|&c| c <= x[self.axis])
    }

    /// The ranks other than `own` whose slab comes within `reach` of `x`
    /// along the axis, ascending.
    pub fn within(&self, x: &[f64; 3], reach: f64, own: usize) -> impl Iterator<Item = usize> + '_ {
        let c = x[self.axis];
        let lo = self.cuts.partition_point(|&k| k <= c - reach);
        let hi = self.cuts.partition_point(|&k| k <= c + reach);
        (lo..=hi).filter(move |&k| k != own)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box three times taller than wide, under gravity along its
    /// height (or against it), is cut across its floor.
    #[test]
    fn under_gravity_the_cut_runs_along_it() {
        let centres: Vec<[f64; 3]> = (0..12).map(|i| [i as f64 / 12.0, 0.5, 1.5]).collect();
        for g in [[0.0, 0.0, -9.81], [0.0, 0.0, 9.81]] {
            let s = SphereSlabs::new(&centres, [0.0; 3], [1.0, 0.8, 3.0], 2, g);
            assert_eq!(s.axis, 0, "gravity {g:?}");
        }
        let s = SphereSlabs::new(&centres, [0.0; 3], [1.0, 0.8, 3.0], 2, [0.0; 3]);
        assert_eq!(s.axis, 2);
    }

    #[test]
    fn quantile_cuts_own_and_reach() {
        let centres: Vec<[f64; 3]> = (0..10).map(|i| [0.0, i as f64, 0.5]).collect();
        let s = SphereSlabs::new(&centres, [0.0; 3], [1.0, 9.0, 1.0], 2, [0.0; 3]);
        assert_eq!((s.axis, s.cuts.clone()), (1, vec![4.5]));
        assert_eq!(s.owner(&[0.0, 4.0, 0.0]), 0);
        assert_eq!(s.owner(&[0.0, 4.5, 0.0]), 1);
        assert_eq!(s.within(&[0.0, 4.0, 0.0], 0.6, 0).collect::<Vec<_>>(), [1]);
        assert_eq!(s.within(&[0.0, 3.0, 0.0], 0.6, 0).count(), 0);
        // One rank: one slab, no cut, no ghosts.
        let one = SphereSlabs::new(&centres, [0.0; 3], [1.0, 9.0, 1.0], 1, [0.0; 3]);
        assert!(one.cuts.is_empty() && one.within(&[0.0, 4.0, 0.0], 9.0, 0).count() == 0);
        // More ranks than spheres: empty slabs, every sphere owned once.
        let many = SphereSlabs::new(&centres[..2], [0.0; 3], [1.0, 9.0, 1.0], 4, [0.0; 3]);
        let owners: Vec<usize> = centres[..2].iter().map(|x| many.owner(x)).collect();
        assert!(owners[0] != owners[1]);
    }
}
