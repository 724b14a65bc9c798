//! Self-contact search: pairs of boundary tets of the same body that might
//! touch, for bodies whose parts can meet themselves (a jointed body whose
//! cracks free fragments). Not in the seeds: seed 000 sec 3.1 pairs faces
//! of different bodies; here a body's owned boundary tets are searched
//! against its own boundary tets, the pair kept once (the lower id
//! searching) and only when the caller says the two tets are apart (they
//! shared no vertex of the continuous mesh: tets that did are held by
//! their joints, or pressed by their crack faces). Pure: no MPI or PETSc.

use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

use super::search::{BodyTets, Candidate};
use crate::geometry::tet_bounds;

fn aabb((lo, hi): &([f64; 3], [f64; 3]), g: f64) -> Aabb {
    Aabb::new(
        Point::new(lo[0] - g, lo[1] - g, lo[2] - g),
        Point::new(hi[0] + g, hi[1] + g, hi[2] + g),
    )
}

fn overlap(a: &([f64; 3], [f64; 3]), b: &([f64; 3], [f64; 3])) -> bool {
    (0..3).all(|d| a.0[d] <= b.1[d] && b.0[d] <= a.1[d])
}

/// The candidate pairs within each body `searches(body)` names: each owned
/// boundary tet `a` against the body's boundary tets `b` with
/// `id(a) < id(b)` whose boxes come within `margin`, kept when
/// `apart(a, b)`. `corners(h)` are tet `h`'s current corners. Candidates
/// come by body, then searching tet, both in list order.
pub fn find_within(
    tets: &BodyTets,
    searches: impl Fn(u32) -> bool,
    corners: impl Fn(u32) -> [[f64; 3]; 4],
    id: impl Fn(u32) -> u32,
    apart: impl Fn(u32, u32) -> bool,
    margin: f64,
) -> Vec<Candidate> {
    let mut found = Vec::new();
    for (i, &body) in tets.body.iter().enumerate() {
        if tets.owned[i].is_empty() || !searches(body) {
            continue;
        }
        let list = &tets.boundary[i];
        let boxes: Vec<([f64; 3], [f64; 3])> =
            list.iter().map(|&h| tet_bounds(&corners(h))).collect();
        let leaves: Vec<Aabb> = boxes.iter().map(|b| aabb(b, 0.0)).collect();
        let tree = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        for &ia in &tets.owned[i] {
            let a = list[ia as usize];
            let own = &boxes[ia as usize];
            let mut near: Vec<u32> = tree
                .intersect_aabb(&aabb(own, margin))
                .filter(|&l| id(list[l as usize]) > id(a))
                .collect();
            near.sort_unstable();
            for l in near {
                let b = list[l as usize];
                if apart(a, b) {
                    found.push(Candidate {
                        a,
                        b,
                        b_boundary: true,
                        hot: overlap(own, &boxes[l as usize]),
                    });
                }
            }
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::search::TetRole;
    use crate::contact::BoundaryTets;
    use crate::mesh::generate::box_mesh;

    /// Every pair of boundary tets of one body whose boxes come within
    /// `margin` and that share no node: the brute-force answer.
    fn brute(m: &crate::mesh::TetMesh, bt: &BoundaryTets, margin: f64) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for x in 0..m.tets.len() {
            for y in x + 1..m.tets.len() {
                let shares = m.tets[x].iter().any(|v| m.tets[y].contains(v));
                if bt.mask[x] == 0 || bt.mask[y] == 0 || shares {
                    continue;
                }
                let (a, b) = (
                    tet_bounds(&m.element_coords(x)),
                    tet_bounds(&m.element_coords(y)),
                );
                if (0..3).all(|d| a.0[d] - margin <= b.1[d] && b.0[d] <= a.1[d] + margin) {
                    out.push((x as u32, y as u32));
                }
            }
        }
        out
    }

    #[test]
    fn finds_each_apart_pair_of_a_body_once_over_any_split() {
        let mut m = box_mesh([0.0; 3], [2.0, 1.0, 1.0], 0.5).unwrap();
        m.append(box_mesh([3.0, 0.0, 0.0], [1.0; 3], 0.5).unwrap(), 1);
        let bt = BoundaryTets::new(&m);
        let corners = |e: u32| m.element_coords(e as usize);
        let apart = |a: u32, b: u32| {
            !m.tets[a as usize]
                .iter()
                .any(|v| m.tets[b as usize].contains(v))
        };
        let role = |owns: &dyn Fn(u32) -> bool| {
            BodyTets::new(
                m.tets.len() as u32,
                |e| TetRole {
                    body: m.body[e as usize],
                    boundary: bt.mask[e as usize] != 0,
                    owned: owns(e),
                },
                |_| false,
                |_| false,
            )
        };
        let all = find_within(&role(&|_| true), |b| b == 0, corners, |e| e, apart, 0.1);
        let mut got: Vec<(u32, u32)> = all.iter().map(|c| (c.a, c.b)).collect();
        got.sort_unstable();
        let want: Vec<(u32, u32)> = brute(&m, &bt, 0.1)
            .into_iter()
            .filter(|&(a, _)| m.body[a as usize] == 0)
            .collect();
        assert!(!want.is_empty());
        assert_eq!(got, want);
        // Body 1 does not search itself; split over two owners, each pair once.
        let mut split: Vec<(u32, u32)> = (0..2)
            .flat_map(|r| {
                let t = role(&|e| e % 2 == r);
                find_within(&t, |b| b == 0, corners, |e| e, apart, 0.1)
            })
            .map(|c| (c.a, c.b))
            .collect();
        split.sort_unstable();
        assert_eq!(split, want);
    }
}
