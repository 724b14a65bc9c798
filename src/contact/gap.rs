//! Near-field gaps (issue 20, seed 001 sec 7.1.1): a boundary face of one
//! body facing a boundary face of another across a gap smaller than the
//! pinball distance. Each searching face is linked once per other body, to
//! the face its centroid's normal ray meets first; the heat across it is
//! that of the gap at the ray's length. Pure: no MPI or PETSc.

use crate::geometry::{cross, dot, sub};
use crate::mesh::LOCAL_FACES;

/// A face's link across a gap: its nodes' and the facing face's nodes'
/// PETSc rows, where the ray meets the facing face (barycentric), the
/// searching face's area and the gap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GapLink {
    /// Rows of the searching face's corners (each weighs a third).
    pub rows_a: [u32; 3],
    /// Rows of the facing face's corners.
    pub rows_b: [u32; 3],
    /// Barycentric weights of the ray's point on the facing face.
    pub beta: [f64; 3],
    /// Area of the searching face (m²).
    pub area: f64,
    /// The gap along the searching face's normal (m).
    pub gap: f64,
    /// Materials of the two faces.
    pub materials: [u32; 2],
    /// Global element ids of the searching and the facing tet.
    pub tets: [u32; 2],
    /// Their local faces (opposite that node).
    pub faces: [u8; 2],
}

/// Corners and outward unit normal of face `f` (opposite node f) of a tet.
pub fn outward_face(c: &[[f64; 3]; 4], f: usize) -> ([[f64; 3]; 3], [f64; 3], f64) {
    let x = LOCAL_FACES[f].map(|i| c[i]);
    let n = cross(sub(x[1], x[0]), sub(x[2], x[0]));
    let len = dot(n, n).sqrt();
    let mut n = if len > 0.0 { n.map(|v| v / len) } else { n };
    // Away from the opposite node.
    if dot(n, sub(c[f], x[0])) > 0.0 {
        n = n.map(|v| -v);
    }
    (x, n, 0.5 * len)
}

/// Seed 001 sec 7.1.1, near field: the gap from face `a` (corners, outward
/// normal) along its normal from its centroid to face `b` (corners,
/// outward normal), when the faces face each other (normals more than 60°
/// apart from parallel) and the ray meets `b` at a distance in (0,
/// pinball]; with the barycentric weights of the point met.
pub fn face_gap(
    a: &[[f64; 3]; 3],
    na: [f64; 3],
    b: &[[f64; 3]; 3],
    nb: [f64; 3],
    pinball: f64,
) -> Option<(f64, [f64; 3])> {
    let facing = dot(na, nb);
    if facing > -0.5 {
        return None;
    }
    let c = [0, 1, 2].map(|d| (a[0][d] + a[1][d] + a[2][d]) / 3.0);
    let s = dot(sub(b[0], c), nb) / facing;
    if !(s > 0.0 && s <= pinball) {
        return None;
    }
    let p = [0, 1, 2].map(|d| c[d] + s * na[d]);
    // Barycentric weights of p in b (areas of the sub-triangles).
    let full = cross(sub(b[1], b[0]), sub(b[2], b[0]));
    let den = dot(full, full);
    if den == 0.0 {
        return None;
    }
    let w1 = dot(cross(sub(b[1], p), sub(b[2], p)), full) / den;
    let w2 = dot(cross(sub(b[2], p), sub(b[0], p)), full) / den;
    let w3 = 1.0 - w1 - w2;
    let tol = -1e-9;
    (w1 >= tol && w2 >= tol && w3 >= tol).then(|| {
        let w = [w1, w2, w3].map(|v| v.max(0.0));
        let sum = w[0] + w[1] + w[2];
        (s, w.map(|v| v / sum))
    })
}

/// The pinball distance and the smallest gap of the links: faces closer
/// than `min_gap` exchange heat as if `min_gap` apart (k/g stays bounded
/// as a gap closes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GapRange {
    /// Faces farther apart are not linked (m).
    pub pinball: f64,
    /// Gaps below it count as it (m).
    pub min_gap: f64,
}

impl GapRange {
    /// The range of scenario key `contact.gap` with its pinball resolved:
    /// `min_gap` defaults to 1 % of the pinball distance.
    pub fn new(pinball: f64, min_gap: Option<f64>) -> GapRange {
        GapRange {
            pinball,
            min_gap: min_gap.unwrap_or(0.01 * pinball),
        }
    }
}

/// The links from the boundary faces of tet a (corners `ca`, boundary
/// faces `mask_a`) to those of tet b: per face of a, each face of b its
/// centroid's normal ray meets within the pinball ([`face_gap`]), as (face
/// of a, face of b, gap (at least the range's smallest), weights, area of
/// a's face).
pub fn tet_links(
    ca: &[[f64; 3]; 4],
    mask_a: u8,
    cb: &[[f64; 3]; 4],
    mask_b: u8,
    range: GapRange,
) -> Vec<(u8, u8, f64, [f64; 3], f64)> {
    let pinball = range.pinball;
    let mut out = Vec::new();
    for fa in (0..4).filter(|f| mask_a & (1 << f) != 0) {
        let (xa, na, area) = outward_face(ca, fa);
        for fb in (0..4).filter(|f| mask_b & (1 << f) != 0) {
            let (xb, nb, _) = outward_face(cb, fb);
            if let Some((gap, beta)) = face_gap(&xa, na, &xb, nb, pinball) {
                out.push((fa as u8, fb as u8, gap.max(range.min_gap), beta, area));
            }
        }
    }
    out
}

/// Whether `l` replaces `best` as a face's link to a body: the smaller
/// gap, ties to the lower (tet, face) met, so the choice does not depend
/// on the order links are found in.
pub fn better(l: &GapLink, best: &GapLink) -> bool {
    (l.gap, l.tets[1], l.faces[1]) < (best.gap, best.tets[1], best.faces[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_faces_a_millimetre_apart_have_a_millimetre_gap() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let b = [[0.0, 0.0, 1e-3], [0.0, 1.0, 1e-3], [1.0, 0.0, 1e-3]];
        let (g, w) = face_gap(&a, [0.0, 0.0, 1.0], &b, [0.0, 0.0, -1.0], 0.01).unwrap();
        assert!((g - 1e-3).abs() < 1e-15);
        // The centroid (1/3, 1/3) is b's centroid too.
        assert!(w.iter().all(|v| (v - 1.0 / 3.0).abs() < 1e-12));
        // Beyond the pinball, behind, or not facing: no gap.
        assert!(face_gap(&a, [0.0, 0.0, 1.0], &b, [0.0, 0.0, -1.0], 5e-4).is_none());
        assert!(face_gap(&a, [0.0, 0.0, -1.0], &b, [0.0, 0.0, 1.0], 0.01).is_none());
        assert!(face_gap(&a, [0.0, 0.0, 1.0], &b, [0.0, 0.0, 1.0], 0.01).is_none());
    }

    #[test]
    fn outward_normals_point_away_from_the_tet() {
        let c = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let (_, n3, area) = outward_face(&c, 3);
        assert_eq!(n3, [0.0, 0.0, -1.0]);
        assert!((area - 0.5).abs() < 1e-15);
        let (_, n0, _) = outward_face(&c, 0);
        assert!(n0.iter().all(|&v| v > 0.0));
    }
}
