//! Row-wise sums of the element and contact-pair blocks before they reach
//! PETSc: one `MatSetValues` call per row with its distinct columns,
//! sorted, where a call per block sent every node's entries once per
//! element and pair around it (45 M entries for the 3 M of the N = 2000
//! heat-up's operators, most of the set-up's time).

/// Which blocks touch which global rows: (row, item) sorted by row, an
/// item below `elements` an element, else `elements` + a pair.
pub(super) struct Incidence {
    inc: Vec<(i32, u32)>,
    elements: usize,
}

/// A block that touches a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Item {
    /// An element of the part.
    Element(usize),
    /// A contact pair of the contact set.
    Pair(usize),
}

impl Incidence {
    /// The rows of `elements` (the first n of each (rows, n): 4 for a
    /// Tet4, 8 for a Hex8, 0 for a tet that is part of a Hex8) and of
    /// `pairs` (8 each).
    pub(super) fn new(
        elements: impl ExactSizeIterator<Item = ([i32; 8], usize)>,
        pairs: impl ExactSizeIterator<Item = [i32; 8]>,
    ) -> Incidence {
        let ne = elements.len();
        let mut inc = Vec::with_capacity(4 * ne + 8 * pairs.len());
        for (e, (idx, n)) in elements.enumerate() {
            inc.extend(idx[..n].iter().map(|&r| (r, e as u32)));
        }
        for (p, idx) in pairs.enumerate() {
            inc.extend(idx.iter().map(|&r| (r, (ne + p) as u32)));
        }
        inc.sort_unstable();
        // A node twice in one pair (self-contact) is one visit of that row.
        inc.dedup();
        Incidence { inc, elements: ne }
    }

    /// Each row with the blocks that touch it, rows ascending.
    pub(super) fn rows(&self) -> impl Iterator<Item = (i32, impl Iterator<Item = Item> + '_)> {
        self.inc.chunk_by(|a, b| a.0 == b.0).map(move |c| {
            let items = c.iter().map(move |&(_, i)| {
                let i = i as usize;
                if i < self.elements {
                    Item::Element(i)
                } else {
                    Item::Pair(i - self.elements)
                }
            });
            (c[0].0, items)
        })
    }
}

/// One row's sums of two matrices over its distinct columns.
#[derive(Default)]
pub(super) struct RowSum {
    entries: Vec<(i32, f64, f64)>,
    cols: Vec<i32>,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl RowSum {
    /// Start a new row.
    pub(super) fn clear(&mut self) {
        self.entries.clear();
    }

    /// Add `a` and `b` at column `col` (a row has tens of columns: a
    /// linear search beats a map).
    pub(super) fn add(&mut self, col: i32, a: f64, b: f64) {
        match self.entries.iter_mut().find(|e| e.0 == col) {
            Some(e) => {
                e.1 += a;
                e.2 += b;
            }
            None => self.entries.push((col, a, b)),
        }
    }

    /// The columns ascending with the two sums.
    pub(super) fn sorted(&mut self) -> (&[i32], &[f64], &[f64]) {
        self.entries.sort_unstable_by_key(|e| e.0);
        self.cols.clear();
        self.a.clear();
        self.b.clear();
        for &(c, a, b) in &self.entries {
            self.cols.push(c);
            self.a.push(a);
            self.b.push(b);
        }
        (&self.cols, &self.a, &self.b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_list_their_blocks_once_and_sums_merge_columns() {
        let elements = [[0, 1, 2, 3], [2, 3, 4, 5]].map(|r| {
            let mut rows = [0; 8];
            rows[..4].copy_from_slice(&r);
            (rows, 4)
        });
        let pairs = [[3, 4, 5, 6, 6, 7, 8, 3]];
        let inc = Incidence::new(elements.into_iter(), pairs.into_iter());
        let rows: Vec<(i32, Vec<Item>)> = inc.rows().map(|(r, i)| (r, i.collect())).collect();
        assert_eq!(rows.len(), 9);
        assert_eq!(rows[0], (0, vec![Item::Element(0)]));
        assert_eq!(
            rows[3],
            (3, vec![Item::Element(0), Item::Element(1), Item::Pair(0)])
        );
        assert_eq!(rows[6], (6, vec![Item::Pair(0)]));
        let mut s = RowSum::default();
        s.add(7, 1.0, 2.0);
        s.add(3, 0.5, 0.0);
        s.add(7, 0.25, -2.0);
        let (c, a, b) = s.sorted();
        assert_eq!((c, a, b), (&[3, 7][..], &[0.5, 1.25][..], &[0.0, 0.0][..]));
        s.clear();
        assert_eq!(s.sorted().0.len(), 0);
    }
}
