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
//! the searching body against trees of the other body's tets, or, for a
//! small moving body (a particle), against the list of its tets near the
//! searching body. A body falling alone costs one box test; the trees of
//! bodies that never move are built once.

use std::collections::HashMap;

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

/// The tets the search runs over, grouped by the bodies present. Tets are
/// named by handles (element ids, or local indices over own and ghost
/// tets: the caller's choice), bodies by their global ids.
#[derive(Debug, Clone, Default)]
pub struct BodyTets {
    /// Global id of each body present, ascending.
    pub body: Vec<u32>,
    /// Per body: held (fixed or moved kinematically).
    pub held: Vec<bool>,
    /// Per body: never moves (its trees are kept between searches).
    pub fixed: Vec<bool>,
    /// Per body, its boundary tets (a face on its surface).
    pub boundary: Vec<Vec<u32>>,
    /// Per body, its other tets (contactors of the thermal contact only: a
    /// face that penetrates deeply lies in them).
    pub interior: Vec<Vec<u32>>,
    /// Per body, the positions in `boundary` of the tets this rank owns:
    /// the ones it searches from.
    pub owned: Vec<Vec<u32>>,
}

/// What the search needs to know of one tet.
#[derive(Debug, Clone, Copy)]
pub struct TetRole {
    /// Global body id.
    pub body: u32,
    /// Whether it has a face on its body's boundary.
    pub boundary: bool,
    /// Whether this rank searches from it (owns it).
    pub owned: bool,
}

impl BodyTets {
    /// The lists of tets `0..n` with roles `role(handle)`; `held(body)` and
    /// `fixed(body)` by global body id.
    pub fn new(
        n: u32,
        role: impl Fn(u32) -> TetRole,
        held: impl Fn(u32) -> bool,
        fixed: impl Fn(u32) -> bool,
    ) -> BodyTets {
        let roles: Vec<TetRole> = (0..n).map(&role).collect();
        let mut body: Vec<u32> = roles.iter().map(|r| r.body).collect();
        body.sort_unstable();
        body.dedup();
        let nb = body.len();
        let mut l = BodyTets {
            held: body.iter().map(|&b| held(b)).collect(),
            fixed: body.iter().map(|&b| fixed(b)).collect(),
            boundary: vec![Vec::new(); nb],
            interior: vec![Vec::new(); nb],
            owned: vec![Vec::new(); nb],
            body,
        };
        for (h, r) in roles.iter().enumerate() {
            let b = l.body.binary_search(&r.body).expect("listed");
            if r.boundary {
                if r.owned {
                    l.owned[b].push(l.boundary[b].len() as u32);
                }
                l.boundary[b].push(h as u32);
            } else {
                l.interior[b].push(h as u32);
            }
        }
        l
    }

    /// The lists of a whole mesh's element ids, this rank owning the tets
    /// for which `owns` holds (bodies free unless `held` says otherwise).
    pub fn of_mesh(
        mesh: &TetMesh,
        bt: &BoundaryTets,
        owns: impl Fn(u32) -> bool,
        held: impl Fn(u32) -> bool,
        fixed: impl Fn(u32) -> bool,
    ) -> BodyTets {
        BodyTets::new(
            mesh.tets.len() as u32,
            |e| TetRole {
                body: mesh.body[e as usize],
                boundary: bt.mask[e as usize] != 0,
                owned: owns(e),
            },
            held,
            fixed,
        )
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

/// Boundary tets up to which a moving body is searched without a tree
/// (a nut has about 140).
const SMALL_BODY_TETS: usize = 512;

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

/// A fingerprint of a tet list (by the tets' ids), so a kept tree is
/// reused only for the same tets.
fn fingerprint(list: &[u32], id: &impl Fn(u32) -> u32) -> u64 {
    list.iter()
        .fold(0xcbf2_9ce4_8422_2325u64 ^ list.len() as u64, |h, &t| {
            (h ^ u64::from(id(t))).wrapping_mul(0x0000_0100_0000_01b3)
        })
}

/// The contact search, with the trees of the bodies that never move kept
/// between searches.
#[derive(Default)]
pub struct ContactSearch {
    /// Per global body id: (fingerprint of the tets, tree) of its boundary
    /// and of its interior tets.
    boundary_trees: HashMap<u32, (u64, Tree)>,
    interior_trees: HashMap<u32, (u64, Tree)>,
    /// Trees for small moving bodies too (tests compare both ways).
    trees_only: bool,
}

impl ContactSearch {
    /// A new search (no trees kept yet).
    pub fn new() -> ContactSearch {
        ContactSearch::default()
    }

    /// Bytes the kept trees hold (boxes; the tree nodes estimated as two
    /// boxes per leaf).
    pub fn held_bytes(&self) -> usize {
        self.boundary_trees
            .values()
            .chain(self.interior_trees.values())
            .map(|(_, t)| t.boxes.capacity() * 48 * 3)
            .sum()
    }

    /// The candidate pairs this rank finds: each owned boundary tet of a
    /// body against the tets of every other body it searches (see
    /// [`finds_pair`]) whose boxes come within the margin. `corners(h)`
    /// are the current corners of tet `h`, `id(h)` a stable id (kept trees
    /// are matched by it). Candidates come grouped by searching body, then
    /// by the other body, both ascending.
    pub fn find(
        &mut self,
        tets: &BodyTets,
        corners: impl Fn(u32) -> [[f64; 3]; 4],
        id: impl Fn(u32) -> u32,
        opts: SearchOptions,
    ) -> Vec<Candidate> {
        let nb = tets.body.len();
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
        // Kept trees of fixed bodies, dropped when their tets changed.
        for (i, &b) in tets.body.iter().enumerate() {
            if !tets.fixed[i] {
                continue;
            }
            for (kept, list) in [
                (&mut self.boundary_trees, &tets.boundary[i]),
                (&mut self.interior_trees, &tets.interior[i]),
            ] {
                if let Some((key, _)) = kept.get(&b) {
                    if *key != fingerprint(list, &id) {
                        kept.remove(&b);
                    }
                }
            }
        }
        let mut moving: Vec<Option<Tree>> = (0..nb).map(|_| None).collect();
        let mut moving_interior: Vec<Option<Tree>> = (0..nb).map(|_| None).collect();
        let mut found = Vec::new();
        for ba in 0..nb {
            if tets.owned[ba].is_empty() {
                continue;
            }
            let (gb_a, held_a) = (tets.body[ba], tets.held[ba]);
            let pairs_with = |bb: usize| {
                let held_b = tets.held[bb];
                let allowed = opts.held_pairs || !(held_a && held_b);
                let boundary = allowed && finds_pair(gb_a, held_a, tets.body[bb], held_b);
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
                let gb = tets.body[bb];
                if with_boundary && tets.fixed[bb] && !self.boundary_trees.contains_key(&gb) {
                    let key = fingerprint(&tets.boundary[bb], &id);
                    let tree = Tree::new(boxes[bb].clone());
                    self.boundary_trees.insert(gb, (key, tree));
                }
                if with_interior && tets.fixed[bb] && !self.interior_trees.contains_key(&gb) {
                    let key = fingerprint(&tets.interior[bb], &id);
                    let b: Vec<_> = tets.interior[bb].iter().map(|&e| bounds(e)).collect();
                    self.interior_trees.insert(gb, (key, Tree::new(b)));
                }
                // A small moving body: its tets near the searching body's
                // box, tested against each searching tet in turn, cost
                // less than a tree built for this search.
                let small = with_boundary
                    && !self.trees_only
                    && !tets.fixed[bb]
                    && tets.boundary[bb].len() <= SMALL_BODY_TETS;
                let b_near: Vec<u32> = if small {
                    (0..boxes[bb].len() as u32)
                        .filter(|&l| overlap(&boxes[bb][l as usize], &body_box[ba], margin))
                        .collect()
                } else {
                    Vec::new()
                };
                let tree_b =
                    (with_boundary && !small).then(|| match self.boundary_trees.get(&gb) {
                        Some((_, t)) => t,
                        None => moving[bb].get_or_insert_with(|| Tree::new(boxes[bb].clone())),
                    });
                let tree_i = with_interior.then(|| match self.interior_trees.get(&gb) {
                    Some((_, t)) => t,
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
                    for &l in &b_near {
                        let other = &boxes[bb][l as usize];
                        if overlap(own, other, margin) {
                            found.push(Candidate {
                                a,
                                b: tets.boundary[bb][l as usize],
                                b_boundary: true,
                                hot: overlap(own, other, 0.0),
                            });
                        }
                    }
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
pub fn touching_pairs(mesh: &TetMesh, pad: f64) -> Vec<(u32, u32)> {
    let bt = BoundaryTets::new(mesh);
    let tets = BodyTets::of_mesh(mesh, &bt, |_| true, |_| false, |_| false);
    let opts = SearchOptions {
        margin: 0.0,
        pad,
        interior: false,
        held_pairs: true,
    };
    let mut pairs: Vec<(u32, u32)> = ContactSearch::new()
        .find(&tets, |e| mesh.element_coords(e as usize), |e| e, opts)
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
        let boundary = |e: usize| bt.mask[e] != 0;
        let mut out = Vec::new();
        for x in 0..m.tets.len() {
            for y in x + 1..m.tets.len() {
                if m.body[x] == m.body[y] {
                    continue;
                }
                let both = boundary(x) && boundary(y);
                let one = boundary(x) || boundary(y);
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
        let held = |b: u32| b == 0;
        let corners = |e: u32| m.element_coords(e as usize);
        for interior in [false, true] {
            let opts = SearchOptions {
                margin: 0.05,
                pad: 0.0,
                interior,
                held_pairs: true,
            };
            let tets = BodyTets::of_mesh(&m, &bt, |_| true, held, held);
            let all = ContactSearch::new().find(&tets, corners, |e| e, opts);
            // Small moving bodies searched by list find what trees find.
            let mut by_trees = ContactSearch {
                trees_only: true,
                ..ContactSearch::new()
            }
            .find(&tets, corners, |e| e, opts);
            let mut by_lists = all.clone();
            by_trees.sort_by_key(|c| (c.a, c.b));
            by_lists.sort_by_key(|c| (c.a, c.b));
            assert_eq!(by_lists, by_trees);
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
                assert!(bt.mask[c.a as usize] != 0);
                if c.b_boundary {
                    assert!(finds_pair(ba, held(ba), bb, held(bb)));
                }
            }
            // Split over three "ranks": the same pairs, each once.
            let mut split: Vec<Candidate> = (0..3)
                .flat_map(|r| {
                    let tets = BodyTets::of_mesh(&m, &bt, |e| e % 3 == r, held, held);
                    ContactSearch::new().find(&tets, corners, |e| e, opts)
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
        let tets = BodyTets::of_mesh(&m, &bt, |_| true, |_| true, |_| true);
        let corners = |e: u32| m.element_coords(e as usize);
        let mut opts = SearchOptions {
            margin: 0.0,
            pad: 1e-9,
            interior: false,
            held_pairs: false,
        };
        let mut s = ContactSearch::new();
        assert!(s.find(&tets, corners, |e| e, opts).is_empty());
        opts.held_pairs = true;
        let first = s.find(&tets, corners, |e| e, opts);
        assert!(!first.is_empty());
        // The fixed bodies' trees are kept and give the same answer; a
        // different tet list (other ids) is not served a kept tree.
        assert!(!s.boundary_trees.is_empty());
        assert_eq!(s.find(&tets, corners, |e| e, opts), first);
        let key = s.boundary_trees.values().next().unwrap().0;
        s.find(&tets, corners, |e| e + 1, opts);
        assert_ne!(s.boundary_trees.values().next().unwrap().0, key);
        // Pairs with a hot flag overlap without the margin.
        assert!(first.iter().all(|c| c.hot));
    }

    #[test]
    fn touching_pairs_link_only_touching_bodies() {
        let near = touching_pairs(&row(2, 0.001), 1e-9);
        assert!(!near.is_empty());
        let m = row(2, 0.001);
        assert!(near
            .iter()
            .all(|&(a, b)| a < b && m.body[a as usize] != m.body[b as usize]));
        assert!(touching_pairs(&row(2, -0.01), 1e-9).is_empty());
    }
}
