//! Thermal contact detection: the boundary tets, and the narrow phase on
//! the contact search's candidates ([`super::search`]): a pair is kept
//! when the two tets' volumes overlap (separating axes) and their contact
//! surface (seed 000 sec 3.1, eq 25) is positive.

use super::search::{BodyTets, Candidate, ContactSearch, SearchOptions};
use super::{tet_tet_contact_surface, ContactPair};
use crate::geometry::{shapes_overlap, TetShape};
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
    /// Per element: its boundary faces' bits (0 for an interior tet).
    pub mask: Vec<u8>,
    /// Per element: its position in `elems` (`u32::MAX` for an interior tet).
    pub index: Vec<u32>,
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
        bt.index = vec![u32::MAX; mesh.tets.len()];
        for (e, &m) in mask.iter().enumerate() {
            if m != 0 {
                bt.index[e] = bt.elems.len() as u32;
                bt.elems.push(e as u32);
                bt.face_mask.push(m);
            }
        }
        bt.mask = mask;
        bt
    }

    /// From per-element face masks (bit i: the face opposite node i lies
    /// on its body's boundary) and per-node boundary flags, as a part of a
    /// distributed mesh carries them.
    pub fn from_masks(mask: &[u8], boundary_node: Vec<bool>) -> BoundaryTets {
        let mut bt = BoundaryTets {
            boundary_node,
            index: vec![u32::MAX; mask.len()],
            ..Default::default()
        };
        for (e, &m) in mask.iter().enumerate() {
            if m != 0 {
                bt.index[e] = bt.elems.len() as u32;
                bt.elems.push(e as u32);
                bt.face_mask.push(m);
            }
        }
        bt.mask = mask.to_vec();
        bt
    }

    /// The boundary faces of element `e` (none for an interior tet).
    pub fn faces_of(&self, e: u32) -> FaceList {
        FaceList::from_mask(self.mask[e as usize])
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

/// What the narrow phase needs to know of a tet besides its corners.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TetFaces {
    /// Global element id (pairs are labelled by it: target = the lower).
    pub id: u32,
    /// Bit i: its face opposite node i lies on its body's boundary.
    pub mask: u8,
    /// Bit i: its node i lies on its body's boundary.
    pub bits: u8,
}

/// Seed 000 sec 3.1 for one candidate pair: tets `a` and `b` of
/// different bodies (at least one a boundary tet) at corners `ca` and
/// `cb`. None unless their volumes overlap (separating axes) and the
/// contact surface is positive. Labelled target = the lower id.
pub fn tet_pair_contact(
    (a, ca): (TetFaces, &[[f64; 3]; 4]),
    (b, cb): (TetFaces, &[[f64; 3]; 4]),
) -> Option<ContactPair> {
    tet_shapes_contact((a, &TetShape::new(*ca)), (b, &TetShape::new(*cb)))
}

/// [`tet_pair_contact`] of two tets' shapes (a tet met in several
/// candidate pairs makes its shape once).
pub fn tet_shapes_contact(
    (a, sa): (TetFaces, &TetShape),
    (b, sb): (TetFaces, &TetShape),
) -> Option<ContactPair> {
    if !shapes_overlap(sa, sb) {
        return None;
    }
    let (ca, cb) = (&sa.corners, &sb.corners);
    let ((t, ct), (c, cc)) = if a.id < b.id {
        ((a, ca), (b, cb))
    } else {
        ((b, cb), (a, ca))
    };
    let (ft, fc) = (FaceList::from_mask(t.mask), FaceList::from_mask(c.mask));
    let pair = ContactPair {
        target: t.id,
        contactor: c.id,
        surface: tet_tet_contact_surface((ct, ft.as_slice(), t.bits), (cc, fc.as_slice(), c.bits)),
    };
    (pair.area() > 0.0).then_some(pair)
}

/// The thermal contact pairs among `candidates` (the contact search's,
/// [`super::search`], over tet handles) with `faces(h)` and corners
/// `corners(h)` of each tet: those whose volumes overlap with a positive
/// surface, sorted by (target, contactor).
pub fn contact_pairs(
    candidates: &[Candidate],
    faces: impl Fn(u32) -> TetFaces,
    corners: impl Fn(u32) -> [[f64; 3]; 4],
) -> Vec<ContactPair> {
    let mut pairs: Vec<ContactPair> = candidates
        .iter()
        .filter_map(|c| tet_pair_contact((faces(c.a), &corners(c.a)), (faces(c.b), &corners(c.b))))
        .collect();
    pairs.sort_by_key(|p| (p.target, p.contactor));
    pairs
}

/// The search options of a thermal contact detection at the current
/// positions: no margin; boxes loosened by a hair so touching boxes are
/// candidates too; a boundary face against every tet of another body (a
/// face that penetrates a few per cent of an element can lie in an
/// interior tet), held bodies included.
pub const THERMAL_SEARCH: SearchOptions = SearchOptions {
    margin: 0.0,
    pad: 1e-9,
    interior: true,
    held_pairs: true,
};

/// Find the contact pairs this caller is responsible for: those of the
/// contact search ([`ContactSearch`] with [`THERMAL_SEARCH`]) from the
/// boundary tets that `tets` lists as owned, at the corners `corners(e)`
/// (`tets` over element ids of `mesh`). Over a partition of the tets every
/// pair is found exactly once; pairs come sorted by (target, contactor).
pub fn detect_contacts(
    mesh: &TetMesh,
    bt: &BoundaryTets,
    search: &mut ContactSearch,
    tets: &BodyTets,
    corners: impl Fn(u32) -> [[f64; 3]; 4] + Copy,
) -> Vec<ContactPair> {
    let candidates = search.find(tets, corners, |e| e, THERMAL_SEARCH);
    let faces = |e: u32| TetFaces {
        id: e,
        mask: bt.mask[e as usize],
        bits: bt.node_bits(mesh, e),
    };
    contact_pairs(&candidates, faces, corners)
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

    /// The pairs found from the tets `owns` picks, every body free.
    fn detect(m: &TetMesh, owns: impl Fn(u32) -> bool) -> Vec<ContactPair> {
        let bt = BoundaryTets::new(m);
        let tets = BodyTets::of_mesh(m, &bt, owns, |_| false, |_| false);
        let corners = |e: u32| m.element_coords(e as usize);
        detect_contacts(m, &bt, &mut ContactSearch::new(), &tets, corners)
    }

    #[test]
    fn overlapping_bars_have_the_cross_section_as_surface() {
        for h in [0.1, 0.05] {
            let m = two_bars(0.001, h);
            let pairs = detect(&m, |_| true);
            let s: f64 = pairs.iter().map(|p| p.area()).sum();
            // The two end faces overlap fully: 0.1 × 0.1 on each side.
            assert!((s - 0.01).abs() < 1e-12, "h = {h}: S = {s}");
            assert!(pairs
                .iter()
                .all(|p| m.body[p.target as usize] != m.body[p.contactor as usize]));
        }
    }

    #[test]
    fn touching_pairs_hold_every_boundary_contact() {
        let m = two_bars(0.001, 0.1);
        let near = super::super::search::touching_pairs(&m, 1e-9);
        assert!(!near.is_empty());
        let bt = BoundaryTets::new(&m);
        // Every contact pair of two boundary tets is among them.
        for p in detect(&m, |_| true) {
            if bt.mask[p.target as usize] == 0 || bt.mask[p.contactor as usize] == 0 {
                continue;
            }
            let key = (p.target, p.contactor);
            assert!(near.binary_search(&key).is_ok(), "{key:?} missing");
        }
    }

    #[test]
    fn separated_bars_have_no_contact_and_split_detection_is_exact() {
        let m = two_bars(-0.01, 0.1);
        assert!(detect(&m, |_| true).is_empty());
        // Owned-tet filters that split the elements find each pair once.
        let m = two_bars(0.003, 0.05);
        let all = detect(&m, |_| true);
        let mut split = detect(&m, |e| e % 3 == 0);
        split.extend(detect(&m, |e| e % 3 != 0));
        split.sort_by_key(|p| (p.target, p.contactor));
        assert_eq!(all, split);
    }
}
