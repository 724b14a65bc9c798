//! The one contact search: which tet pairs of different bodies might
//! touch, found on this rank, and which rank finds each (seed 000 sec 3.1
//! pairs a boundary face with the tets of another body). Every consumer
//! reads its list: the penalty contact (pairs of two boundary tets within
//! a margin), the thermal contact (a boundary tet against any tet of
//! another body) and the partition links (touching bodies). Pure: no MPI
//! or PETSc; the caller says which tets it owns.
//!
//! Two levels: the bodies' boxes in one tree, then, for each pair of
//! bodies whose boxes come within the margin, the owned boundary tets of
//! the searching body against trees of the other body's tets. A body
//! falling alone costs one box test; the trees of bodies that never move
//! are built once.

use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

use super::BoundaryTets;
use crate::geometry::tet_bounds;
use crate::mesh::TetMesh;

/// The one ownership rule for a pair of two boundary tets of different
/// bodies `a` and `b` (body ids): whether body `a` finds it. The free body
/// finds its pairs with a held one (a container's pairs fall to the
/// particles, which the partition balances); of two free or two held
/// bodies, the lower id. A pair of a boundary tet and an interior tet is
/// found from the boundary tet's body. Bodies' elements are numbered in
/// body order, so "the lower body" is also "the lower element id". The
/// rank that owns the searching tet finds the pair: over a partition of
/// the tets, every pair is found exactly once.
#[inline]
pub fn finds_pair(a: u32, held_a: bool, b: u32, held_b: bool) -> bool {
    if held_a != held_b {
        !held_a
    } else {
        a < b
    }
}

/// The tets the search runs over, per body. Lists hold element ids.
#[derive(Debug, Clone, Default)]
pub struct BodyTets {
    /// Per body, its boundary tets (a face on its surface), ascending.
    pub boundary: Vec<Vec<u32>>,
    /// Per body, its other tets, ascending (contactors of the thermal
    /// contact only: a face that penetrates deeply lies in them).
    pub interior: Vec<Vec<u32>>,
    /// Per body, the positions in `boundary` of the tets this rank owns:
    /// the ones it searches from.
    pub owned: Vec<Vec<u32>>,
}

impl BodyTets {
    /// The lists of `mesh` with `bodies` bodies; this rank owns the tets
    /// for which `owns` holds.
    pub fn new(
        mesh: &TetMesh,
        bt: &BoundaryTets,
        bodies: usize,
        owns: impl Fn(u32) -> bool,
    ) -> BodyTets {
        let mut l = BodyTets {
            boundary: vec![Vec::new(); bodies],
            interior: vec![Vec::new(); bodies],
            owned: vec![Vec::new(); bodies],
        };
        let mut is_boundary = vec![false; mesh.tets.len()];
        for &e in &bt.elems {
            is_boundary[e as usize] = true;
        }
        for (e, &b) in mesh.body.iter().enumerate() {
            let (b, e32) = (b as usize, e as u32);
            if is_boundary[e] {
                if owns(e32) {
                    l.owned[b].push(l.boundary[b].len() as u32);
                }
                l.boundary[b].push(e32);
            } else {
                l.interior[b].push(e32);
            }
        }
        l
    }
}

/// What to look for.
#[derive(Debug, Clone, Copy)]
pub struct SearchOptions {
    /// Distance (m) within which two tets' boxes make a candidate.
    pub margin: f64,
    /// Each tet's box is first loosened by this fraction of its size, so
    /// boxes that only touch are candidates too (0: exact boxes).
    pub pad: f64,
    /// Also pairs of a boundary tet with another body's interior tets.
    pub interior: bool,
    /// Also pairs of two held bodies (held bodies exert no penalty force
    /// on each other, but they conduct heat).
    pub held_pairs: bool,
}

/// A candidate pair: tet `a` (a boundary tet of the body that searches,
/// see [`finds_pair`]) and tet `b` of another body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Candidate {
    /// The searching tet (element id).
    pub a: u32,
    /// The other tet (element id).
    pub b: u32,
    /// Whether `b` is a boundary tet (else an interior one).
    pub b_boundary: bool,
    /// Whether the two tets' boxes overlap without the margin.
    pub hot: bool,
}

/// A box (low, high corner) loosened by `pad` of its size, then grown by
/// `margin` on every side.
fn grown((lo, hi): ([f64; 3], [f64; 3]), pad: f64, margin: f64) -> ([f64; 3], [f64; 3]) {
    let g = pad * ((hi[0] - lo[0]) + (hi[1] - lo[1]) + (hi[2] - lo[2])) + margin;
    (
        [lo[0] - g, lo[1] - g, lo[2] - g],
        [hi[0] + g, hi[1] + g, hi[2] + g],
    )
}

fn aabb((lo, hi): &([f64; 3], [f64; 3]), g: f64) -> Aabb {
    Aabb::new(
        Point::new(lo[0] - g, lo[1] - g, lo[2] - g),
        Point::new(hi[0] + g, hi[1] + g, hi[2] + g),
    )
}

fn overlap(a: &([f64; 3], [f64; 3]), b: &([f64; 3], [f64; 3]), g: f64) -> bool {
    (0..3).all(|d| a.0[d] - g <= b.1[d] && b.0[d] <= a.1[d] + g)
}

/// A body's tree: its tets' (padded) boxes and the tree over them.
struct Tree {
    boxes: Vec<([f64; 3], [f64; 3])>,
    bvh: Bvh,
}

impl Tree {
    fn new(boxes: Vec<([f64; 3], [f64; 3])>) -> Tree {
        let leaves: Vec<Aabb> = boxes.iter().map(|b| aabb(b, 0.0)).collect();
        Tree {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves),
            boxes,
        }
    }
}

/// The contact search, with the trees of the bodies that never move kept
/// between searches.
#[derive(Default)]
pub struct ContactSearch {
    boundary_trees: Vec<Option<Tree>>,
    interior_trees: Vec<Option<Tree>>,
}

impl ContactSearch {
    /// A search over `bodies` bodies.
    pub fn new(bodies: usize) -> ContactSearch {
        ContactSearch {
            boundary_trees: (0..bodies).map(|_| None).collect(),
            interior_trees: (0..bodies).map(|_| None).collect(),
        }
    }

    /// The candidate pairs this rank finds: each owned boundary tet of a
    /// body against the tets of every other body it searches (see
    /// [`finds_pair`]) whose boxes come within the margin. `corners(e)`
    /// are the current corners of tet `e`; `held[b]` whether body b is
    /// held (fixed or moved kinematically), `fixed[b]` whether it never
    /// moves (its trees are kept). Candidates come grouped by searching
    /// body, then by the other body, both ascending.
    pub fn find(
        &mut self,
        tets: &BodyTets,
        corners: impl Fn(u32) -> [[f64; 3]; 4],
        held: &[bool],
        fixed: &[bool],
        opts: SearchOptions,
    ) -> Vec<Candidate> {
        let nb = tets.boundary.len();
        if self.boundary_trees.len() != nb {
            *self = ContactSearch::new(nb);
        }
        let (pad, margin) = (opts.pad, opts.margin);
        let bounds = |e: u32| grown(tet_bounds(&corners(e)), pad, 0.0);
        // Boxes of every boundary tet, and each body's box from them.
        let boxes: Vec<Vec<([f64; 3], [f64; 3])>> = tets
            .boundary
            .iter()
            .map(|l| l.iter().map(|&e| bounds(e)).collect())
            .collect();
        let body_box: Vec<([f64; 3], [f64; 3])> = boxes
            .iter()
            .map(|l| {
                l.iter().fold(
                    ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                    |(mut lo, mut hi), (a, b)| {
                        for d in 0..3 {
                            lo[d] = lo[d].min(a[d]);
                            hi[d] = hi[d].max(b[d]);
                        }
                        (lo, hi)
                    },
                )
            })
            .collect();
        let with_tets: Vec<u32> = (0..nb as u32)
            .filter(|&b| !tets.boundary[b as usize].is_empty())
            .collect();
        let leaves: Vec<Aabb> = with_tets
            .iter()
            .map(|&b| aabb(&body_box[b as usize], 0.0))
            .collect();
        let body_tree = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        let mut moving: Vec<Option<Tree>> = (0..nb).map(|_| None).collect();
        let mut moving_interior: Vec<Option<Tree>> = (0..nb).map(|_| None).collect();
        let mut found = Vec::new();
        for ba in 0..nb {
            if tets.owned[ba].is_empty() {
                continue;
            }
            let pairs_with = |bb: usize| {
                let allowed = opts.held_pairs || !(held[ba] && held[bb]);
                let boundary = allowed && finds_pair(ba as u32, held[ba], bb as u32, held[bb]);
                let interior = allowed && opts.interior && !tets.interior[bb].is_empty();
                (boundary, interior)
            };
            let mut near: Vec<usize> = body_tree
                .intersect_aabb(&aabb(&body_box[ba], margin))
                .map(|i| with_tets[i as usize] as usize)
                .filter(|&bb| bb != ba && pairs_with(bb) != (false, false))
                .collect();
            near.sort_unstable();
            for bb in near {
                let (with_boundary, with_interior) = pairs_with(bb);
                if with_boundary && fixed[bb] && self.boundary_trees[bb].is_none() {
                    self.boundary_trees[bb] = Some(Tree::new(boxes[bb].clone()));
                }
                if with_interior && fixed[bb] && self.interior_trees[bb].is_none() {
                    let b: Vec<_> = tets.interior[bb].iter().map(|&e| bounds(e)).collect();
                    self.interior_trees[bb] = Some(Tree::new(b));
                }
                let tree_b = with_boundary.then(|| match &self.boundary_trees[bb] {
                    Some(t) => t,
                    None => moving[bb].get_or_insert_with(|| Tree::new(boxes[bb].clone())),
                });
                let tree_i = with_interior.then(|| match &self.interior_trees[bb] {
                    Some(t) => t,
                    None => moving_interior[bb].get_or_insert_with(|| {
                        Tree::new(tets.interior[bb].iter().map(|&e| bounds(e)).collect())
                    }),
                });
                for &ia in &tets.owned[ba] {
                    let own = &boxes[ba][ia as usize];
                    if !overlap(own, &body_box[bb], margin) {
                        continue;
                    }
                    let a = tets.boundary[ba][ia as usize];
                    let query = aabb(own, margin);
                    for (tree, list, b_boundary) in [
                        (tree_b, &tets.boundary[bb], true),
                        (tree_i, &tets.interior[bb], false),
                    ] {
                        let Some(tree) = tree else { continue };
                        for leaf in tree.bvh.intersect_aabb(&query) {
                            found.push(Candidate {
                                a,
                                b: list[leaf as usize],
                                b_boundary,
                                hot: overlap(own, &tree.boxes[leaf as usize], 0.0),
                            });
                        }
                    }
                }
            }
        }
        found
    }
}

/// The pairs of boundary tets of different bodies whose boxes touch
/// (padded by `pad` of their size), as (lower, higher) element id,
/// sorted: the links that keep touching bodies on one rank when the mesh
/// is partitioned. Every tet is searched from (one process).
pub fn touching_pairs(mesh: &TetMesh, bodies: usize, pad: f64) -> Vec<(u32, u32)> {
    let bt = BoundaryTets::new(mesh);
    let tets = BodyTets::new(mesh, &bt, bodies, |_| true);
    let all = vec![false; bodies];
    let opts = SearchOptions {
        margin: 0.0,
        pad,
        interior: false,
        held_pairs: true,
    };
    let mut pairs: Vec<(u32, u32)> = ContactSearch::new(bodies)
        .find(&tets, |e| mesh.element_coords(e as usize), &all, &all, opts)
        .into_iter()
        .map(|c| (c.a.min(c.b), c.a.max(c.b)))
        .collect();
    pairs.sort_unstable();
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    /// Unit cubes (h = 0.5) along x, each overlapping the next by `overlap`.
    fn row(n: usize, overlap: f64) -> TetMesh {
        let mut m = box_mesh([0.0; 3], [1.0; 3], 0.5).unwrap();
        for i in 1..n {
            let x = i as f64 * (1.0 - overlap);
            m.append(box_mesh([x, 0.0, 0.0], [1.0; 3], 0.5).unwrap(), i as u32);
        }
        m
    }

    /// Every pair of tets of different bodies whose boxes come within
    /// `margin`, with at least one boundary tet: the brute-force answer.
    fn brute(m: &TetMesh, bt: &BoundaryTets, margin: f64, interior: bool) -> Vec<(u32, u32)> {
        let boundary: Vec<bool> = {
            let mut b = vec![false; m.tets.len()];
            bt.elems.iter().for_each(|&e| b[e as usize] = true);
            b
        };
        let mut out = Vec::new();
        for x in 0..m.tets.len() {
            for y in x + 1..m.tets.len() {
                if m.body[x] == m.body[y] {
                    continue;
                }
                let both = boundary[x] && boundary[y];
                let one = boundary[x] || boundary[y];
                if !(both || (interior && one)) {
                    continue;
                }
                let (a, b) = (
                    tet_bounds(&m.element_coords(x)),
                    tet_bounds(&m.element_coords(y)),
                );
                if overlap(&a, &b, margin) {
                    out.push((x as u32, y as u32));
                }
            }
        }
        out
    }

    #[test]
    fn finds_every_pair_once_over_any_split() {
        let m = row(3, 0.1);
        let bt = BoundaryTets::new(&m);
        let (held, fixed) = (vec![true, false, false], vec![true, false, false]);
        for interior in [false, true] {
            let opts = SearchOptions {
                margin: 0.05,
                pad: 0.0,
                interior,
                held_pairs: true,
            };
            let corners = |e: u32| m.element_coords(e as usize);
            let all = ContactSearch::new(3).find(
                &BodyTets::new(&m, &bt, 3, |_| true),
                corners,
                &held,
                &fixed,
                opts,
            );
            let mut got: Vec<(u32, u32)> =
                all.iter().map(|c| (c.a.min(c.b), c.a.max(c.b))).collect();
            got.sort_unstable();
            let n = got.len();
            got.dedup();
            assert_eq!(n, got.len(), "a pair found twice");
            assert_eq!(got, brute(&m, &bt, 0.05, interior));
            // The searching tet is a boundary tet, of the body the rule names.
            for c in &all {
                let (ba, bb) = (m.body[c.a as usize], m.body[c.b as usize]);
                assert!(bt.elems.binary_search(&c.a).is_ok());
                if c.b_boundary {
                    assert!(finds_pair(ba, held[ba as usize], bb, held[bb as usize]));
                }
            }
            // Split over three "ranks": the same pairs, each once.
            let mut split: Vec<Candidate> = (0..3)
                .flat_map(|r| {
                    let tets = BodyTets::new(&m, &bt, 3, |e| e % 3 == r);
                    ContactSearch::new(3).find(&tets, corners, &held, &fixed, opts)
                })
                .collect();
            let mut whole = all.clone();
            let key = |c: &Candidate| (c.a, c.b);
            split.sort_by_key(key);
            whole.sort_by_key(key);
            assert_eq!(split, whole);
        }
    }

    #[test]
    fn held_pairs_and_kept_trees() {
        let m = row(2, 0.1);
        let bt = BoundaryTets::new(&m);
        let tets = BodyTets::new(&m, &bt, 2, |_| true);
        let corners = |e: u32| m.element_coords(e as usize);
        let both_held = [true, true];
        let mut opts = SearchOptions {
            margin: 0.0,
            pad: 1e-9,
            interior: false,
            held_pairs: false,
        };
        let mut s = ContactSearch::new(2);
        assert!(s
            .find(&tets, corners, &both_held, &both_held, opts)
            .is_empty());
        opts.held_pairs = true;
        let first = s.find(&tets, corners, &both_held, &both_held, opts);
        assert!(!first.is_empty());
        // The fixed bodies' trees are kept and give the same answer.
        assert!(s.boundary_trees.iter().any(Option::is_some));
        assert_eq!(s.find(&tets, corners, &both_held, &both_held, opts), first);
        // Pairs with a hot flag overlap without the margin.
        assert!(first.iter().all(|c| c.hot));
    }

    #[test]
    fn touching_pairs_link_only_touching_bodies() {
        let near = touching_pairs(&row(2, 0.001), 2, 1e-9);
        assert!(!near.is_empty());
        let m = row(2, 0.001);
        assert!(near
            .iter()
            .all(|&(a, b)| a < b && m.body[a as usize] != m.body[b as usize]));
        assert!(touching_pairs(&row(2, -0.01), 2, 1e-9).is_empty());
    }
}
