//! Contact detection: a BVH (parry) over the bounding boxes of the tets,
//! queried with each owned boundary tet; candidate pairs of different
//! bodies are kept when their volumes overlap (separating axes) and their
//! contact surface is positive. O(n log n).

use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

use super::{tet_tet_contact_surface, ContactPair};
use crate::geometry::tet_tet_overlap;
use crate::mesh::TetMesh;

/// Up to four local face indices, held inline (no allocation in the
/// detection loop).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaceList {
    faces: [u8; 4],
    len: u8,
}

impl FaceList {
    /// The faces whose bits are set in `mask` (bit i: face opposite node i).
    pub fn from_mask(mask: u8) -> FaceList {
        let mut l = FaceList::default();
        for f in 0..4u8 {
            if mask & (1 << f) != 0 {
                l.faces[l.len as usize] = f;
                l.len += 1;
            }
        }
        l
    }

    /// The faces as a slice.
    pub fn as_slice(&self) -> &[u8] {
        &self.faces[..self.len as usize]
    }
}

/// The tets with at least one boundary face, with those faces.
#[derive(Debug, Clone, Default)]
pub struct BoundaryTets {
    /// Element ids, ascending.
    pub elems: Vec<u32>,
    /// Bit i set when local face i (opposite node i) is on the boundary.
    pub face_mask: Vec<u8>,
    /// Per mesh node: whether it lies on its body's boundary.
    pub boundary_node: Vec<bool>,
}

impl BoundaryTets {
    /// Collect from the mesh's boundary faces.
    pub fn new(mesh: &TetMesh) -> BoundaryTets {
        let mut mask = vec![0u8; mesh.tets.len()];
        let mut bt = BoundaryTets {
            boundary_node: vec![false; mesh.nodes.len()],
            ..Default::default()
        };
        for f in mesh.boundary_faces() {
            mask[f.elem as usize] |= 1 << f.local_face;
            for n in f.nodes {
                bt.boundary_node[n as usize] = true;
            }
        }
        for (e, &m) in mask.iter().enumerate() {
            if m != 0 {
                bt.elems.push(e as u32);
                bt.face_mask.push(m);
            }
        }
        bt
    }

    /// Bit i set when local node i of element `e` lies on its body's boundary.
    pub fn node_bits(&self, mesh: &TetMesh, e: u32) -> u8 {
        mesh.tets[e as usize]
            .iter()
            .enumerate()
            .fold(0, |m, (i, &n)| {
                m | (u8::from(self.boundary_node[n as usize]) << i)
            })
    }

    /// Local boundary faces of boundary tet `i`.
    pub fn faces(&self, i: usize) -> FaceList {
        FaceList::from_mask(self.face_mask[i])
    }

    /// Number of boundary tets.
    pub fn len(&self) -> usize {
        self.elems.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.elems.is_empty()
    }
}

fn aabb(x: &[[f64; 3]; 4]) -> Aabb {
    let (lo, hi) = crate::geometry::tet_bounds(x);
    // Loosen by a hair so touching boxes are candidates too.
    let pad = 1e-9 * ((hi[0] - lo[0]) + (hi[1] - lo[1]) + (hi[2] - lo[2]));
    Aabb::new(
        Point::new(lo[0] - pad, lo[1] - pad, lo[2] - pad),
        Point::new(hi[0] + pad, hi[1] + pad, hi[2] + pad),
    )
}

/// Pairs `(x, y)`, `x < y`, of boundary tets of different bodies whose
/// boxes overlap: the broad phase alone, no narrow phase. Used to tell the
/// partitioner which bodies touch, so that touching particles land on the
/// same rank.
pub fn proximity_pairs(mesh: &TetMesh, bt: &BoundaryTets) -> Vec<(u32, u32)> {
    if bt.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = bt
        .elems
        .iter()
        .map(|&e| aabb(&mesh.element_coords(e as usize)))
        .collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut pairs = Vec::new();
    for (i, &x) in bt.elems.iter().enumerate() {
        for j in bvh.intersect_aabb(&boxes[i]) {
            let y = bt.elems[j as usize];
            if x < y && mesh.body[x as usize] != mesh.body[y as usize] {
                pairs.push((x, y));
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// Find the contact pairs this caller is responsible for: those found
/// from a boundary tet `x` with `owns(x)`. The contactor volume may be any
/// tet of another body (a face that penetrates a few per cent of an element
/// can lie in an interior tet); a pair of two boundary tets is kept only
/// from its lower id, so over a partition of `owns` every pair is found
/// exactly once. Pairs are labelled target = lower id and come sorted by
/// (target, contactor).
pub fn detect_contacts(
    mesh: &TetMesh,
    bt: &BoundaryTets,
    owns: impl Fn(u32) -> bool,
) -> Vec<ContactPair> {
    let ne = mesh.tets.len();
    let mut mask = vec![0u8; ne];
    for (i, &e) in bt.elems.iter().enumerate() {
        mask[e as usize] = bt.face_mask[i];
    }
    let faces = |e: u32| FaceList::from_mask(mask[e as usize]);
    let boxes: Vec<Aabb> = (0..ne).map(|e| aabb(&mesh.element_coords(e))).collect();
    let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    let mut pairs = Vec::new();
    for &x in &bt.elems {
        if !owns(x) {
            continue;
        }
        let cx = mesh.element_coords(x as usize);
        let fx = faces(x);
        for y in bvh.intersect_aabb(&boxes[x as usize]) {
            if mesh.body[y as usize] == mesh.body[x as usize] {
                continue;
            }
            // Two boundary tets: the lower id finds the pair.
            if mask[y as usize] != 0 && y < x {
                continue;
            }
            let cy = mesh.element_coords(y as usize);
            if !tet_tet_overlap(&cx, &cy) {
                continue;
            }
            let fy = faces(y);
            let pair = if x < y {
                ContactPair {
                    target: x,
                    contactor: y,
                    surface: tet_tet_contact_surface(
                        (&cx, fx.as_slice(), bt.node_bits(mesh, x)),
                        (&cy, fy.as_slice(), bt.node_bits(mesh, y)),
                    ),
                }
            } else {
                ContactPair {
                    target: y,
                    contactor: x,
                    surface: tet_tet_contact_surface(
                        (&cy, fy.as_slice(), bt.node_bits(mesh, y)),
                        (&cx, fx.as_slice(), bt.node_bits(mesh, x)),
                    ),
                }
            };
            if pair.area() > 0.0 {
                pairs.push(pair);
            }
        }
    }
    pairs.sort_by_key(|p| (p.target, p.contactor));
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    fn two_bars(overlap: f64, h: f64) -> TetMesh {
        let mut m = box_mesh([0.0; 3], [0.5, 0.1, 0.1], h).unwrap();
        let b = box_mesh([0.5 - overlap, 0.0, 0.0], [0.5, 0.1, 0.1], h).unwrap();
        m.append(b, 1);
        m
    }

    #[test]
    fn overlapping_bars_have_the_cross_section_as_surface() {
        for h in [0.1, 0.05] {
            let m = two_bars(0.001, h);
            let bt = BoundaryTets::new(&m);
            let pairs = detect_contacts(&m, &bt, |_| true);
            let s: f64 = pairs.iter().map(|p| p.area()).sum();
            // The two end faces overlap fully: 0.1 × 0.1 on each side.
            assert!((s - 0.01).abs() < 1e-12, "h = {h}: S = {s}");
            assert!(pairs
                .iter()
                .all(|p| m.body[p.target as usize] != m.body[p.contactor as usize]));
        }
    }

    #[test]
    fn proximity_pairs_link_only_touching_bodies() {
        let m = two_bars(0.001, 0.1);
        let bt = BoundaryTets::new(&m);
        let near = proximity_pairs(&m, &bt);
        assert!(!near.is_empty());
        // Every contact pair of two boundary tets is among them.
        for p in detect_contacts(&m, &bt, |_| true) {
            let key = (p.target.min(p.contactor), p.target.max(p.contactor));
            assert!(near.binary_search(&key).is_ok(), "{key:?} missing");
        }
        assert!(near
            .iter()
            .all(|&(a, b)| a < b && m.body[a as usize] != m.body[b as usize]));
        assert!(proximity_pairs(&two_bars(-0.01, 0.1), &bt).is_empty());
    }

    #[test]
    fn separated_bars_have_no_contact_and_split_detection_is_exact() {
        let m = two_bars(-0.01, 0.1);
        let bt = BoundaryTets::new(&m);
        assert!(detect_contacts(&m, &bt, |_| true).is_empty());
        // Owned-target filters that split the elements find each pair once.
        let m = two_bars(0.003, 0.05);
        let bt = BoundaryTets::new(&m);
        let all = detect_contacts(&m, &bt, |_| true);
        let mut split = detect_contacts(&m, &bt, |e| e % 3 == 0);
        split.extend(detect_contacts(&m, &bt, |e| e % 3 != 0));
        split.sort_by_key(|p| (p.target, p.contactor));
        assert_eq!(all, split);
    }
}
