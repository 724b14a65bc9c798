//! The contact surface between a target and a contactor tet (seed 000
//! sec 3.1, eq 25) and the face-node weights that carry its heat.

use crate::geometry::{cross, dot, face_tet_clip, polygon_area, sub, tet4_geometry};

/// Surfaces and nodal weights of one tet pair.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactSurface {
    /// Area of the target's boundary faces inside the contactor (S_tar).
    pub s_target: f64,
    /// Area of the contactor's boundary faces inside the target (S_con).
    pub s_contactor: f64,
    /// Weight of each target node (sums to 1): each boundary face gives a
    /// third of its clipped area share to each of its nodes (eq 24's 1/3).
    pub w_target: [f64; 4],
    /// Same for the contactor's nodes.
    pub w_contactor: [f64; 4],
    /// The target's temperature where the contactor's clipped faces lie:
    /// its shape functions at their centroid, on its surface nodes (sums
    /// to 1; equal to `w_target` when S_con = 0).
    pub v_target: [f64; 4],
    /// The contactor's temperature where the target's clipped faces lie.
    pub v_contactor: [f64; 4],
    /// Bit f set: the target's local face f (opposite node f) has clipped
    /// area (the face's contact status is closed).
    pub faces_target: u8,
    /// Same for the contactor's faces.
    pub faces_contactor: u8,
}

impl ContactSurface {
    /// Seed 000 eq 25: S = (S_tar + S_con)/2.
    pub fn area(&self) -> f64 {
        0.5 * (self.s_target + self.s_contactor)
    }

    /// The surface of two faces that cover each other exactly (the two
    /// faces of a closed crack): local face `face_target` of the target
    /// (opposite that node) on `face_contactor` of the contactor, of area
    /// `area`; each face's corners weigh a third, as seed 000 eq 24 gives
    /// a face wholly inside the other tet.
    pub fn coincident_faces(
        area: f64,
        face_target: usize,
        face_contactor: usize,
    ) -> ContactSurface {
        let third = |f: usize| {
            let mut w = [1.0 / 3.0; 4];
            w[f] = 0.0;
            w
        };
        ContactSurface {
            s_target: area,
            s_contactor: area,
            w_target: third(face_target),
            w_contactor: third(face_contactor),
            v_target: third(face_target),
            v_contactor: third(face_contactor),
            faces_target: 1 << face_target,
            faces_contactor: 1 << face_contactor,
        }
    }
}

/// Local node indices of face `f` (opposite node f).
const FACE_NODES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Bit i set for each local face i in `faces`.
fn face_mask(faces: &[u8]) -> u8 {
    faces.iter().fold(0, |m, &f| m | (1 << f))
}

/// Clip each listed boundary face of `a` by the volume of `b` (whose
/// boundary faces are `faces_b`): the total area, the node weights
/// (area-weighted thirds, normalised; zero when no area) and the
/// area-weighted centroid of the clipped polygons.
fn side(
    a: &[[f64; 3]; 4],
    faces_a: &[u8],
    b: &[[f64; 3]; 4],
    faces_b: &[u8],
) -> (f64, [f64; 4], [f64; 3], u8) {
    let mask_b = face_mask(faces_b);
    let mut touched = 0u8;
    let mut s = 0.0;
    let mut w = [0.0; 4];
    let mut centroid = [0.0; 3];
    for &f in faces_a {
        let fl = FACE_NODES[f as usize];
        let tri = [a[fl[0]], a[fl[1]], a[fl[2]]];
        // Outward: away from the node opposite the face.
        let mut n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
        if dot(n, sub(a[f as usize], tri[0])) > 0.0 {
            n = [-n[0], -n[1], -n[2]];
        }
        let poly = face_tet_clip(&tri, n, b, mask_b);
        let area = polygon_area(&poly);
        if area > 0.0 {
            touched |= 1 << f;
            s += area;
            for &k in &fl {
                w[k] += area / 3.0;
            }
            let c = polygon_centroid(&poly);
            for d in 0..3 {
                centroid[d] += area * c[d];
            }
        }
    }
    if s > 0.0 {
        for x in w.iter_mut() {
            *x /= s;
        }
        for c in centroid.iter_mut() {
            *c /= s;
        }
    }
    (s, w, centroid, touched)
}

/// Area centroid of a planar convex polygon (fan of triangles).
fn polygon_centroid(p: &[[f64; 3]]) -> [f64; 3] {
    let mut c = [0.0; 3];
    let mut total = 0.0;
    for i in 1..p.len() - 1 {
        let t = cross(sub(p[i], p[0]), sub(p[i + 1], p[0]));
        let a = 0.5 * dot(t, t).sqrt();
        for d in 0..3 {
            c[d] += a * (p[0][d] + p[i][d] + p[i + 1][d]) / 3.0;
        }
        total += a;
    }
    if total > 0.0 {
        c.map(|x| x / total)
    } else {
        p[0]
    }
}

/// Barycentric coordinates (the Tet4 shape functions N_i) of `p` in `t`,
/// clamped to [0, 1] and renormalised against round-off.
fn barycentric(t: &[[f64; 3]; 4], p: [f64; 3]) -> [f64; 4] {
    let g = tet4_geometry(t);
    let mut n = [0.0; 4];
    for (i, ni) in n.iter_mut().enumerate() {
        // N_i is linear with gradient g.grad[i] and N_i(x_i) = 1.
        *ni = (1.0 + dot(g.grad[i], sub(p, t[i]))).clamp(0.0, 1.0);
    }
    let s: f64 = n.iter().sum();
    n.map(|x| x / s)
}

/// One side of a pair: the tet's corners, its boundary faces (local face i
/// opposite node i), and the bits of its nodes on its body's boundary.
pub type TetSide<'a> = (&'a [[f64; 3]; 4], &'a [u8], u8);

/// Seed 000 sec 3.1: the surface between target tet `t` and contactor `c`.
///
/// A side whose own faces have no area inside the other tet (a tet that
/// reaches the other body's face only with an edge, a corner or its
/// interior) takes its temperature where the other side's clipped faces
/// lie: the weights are its shape functions at their centroid, restricted
/// to its nodes on the body's boundary (renormalised) when it has any, so
/// that contact heat enters a body through its surface nodes, not through
/// a node a whole element deep (with the link-per-node-pair operator of
/// [`super::local_conductance_block`] such a node would conduct straight
/// across the contact).
pub fn tet_tet_contact_surface(t: TetSide, c: TetSide) -> ContactSurface {
    let (s_target, w_target, cen_t, faces_target) = side(t.0, t.1, c.0, c.1);
    let (s_contactor, w_contactor, cen_c, faces_contactor) = side(c.0, c.1, t.0, t.1);
    // Each side's temperature at the other side's clipped faces; exact for
    // the integral of a linear temperature over them (centroid rule).
    let v_target = if s_contactor > 0.0 {
        surface_weights(t, cen_c)
    } else {
        w_target
    };
    let v_contactor = if s_target > 0.0 {
        surface_weights(c, cen_t)
    } else {
        w_contactor
    };
    ContactSurface {
        s_target,
        s_contactor,
        // A side without clipped faces of its own carries its heat where
        // the other side's lie.
        w_target: if s_target > 0.0 { w_target } else { v_target },
        w_contactor: if s_contactor > 0.0 {
            w_contactor
        } else {
            v_contactor
        },
        v_target,
        v_contactor,
        faces_target,
        faces_contactor,
    }
}

/// The temperature of tet side `t` at point `p` as weights on its nodes,
/// carried by its surface: with boundary faces, the linear interpolation
/// on the face nearest to `p` at `p`'s projection onto it (no weight on a
/// node inside the body); otherwise its shape functions at `p`, restricted
/// to its nodes on the body's boundary (renormalised) when it has any.
fn surface_weights(t: TetSide, p: [f64; 3]) -> [f64; 4] {
    let (x, faces, boundary) = t;
    let mut best: Option<(f64, [f64; 4])> = None;
    for &f in faces {
        let fl = FACE_NODES[f as usize];
        let (w, dist) = triangle_weights([x[fl[0]], x[fl[1]], x[fl[2]]], p);
        if best.is_none_or(|(d, _)| dist < d) {
            let mut out = [0.0; 4];
            for (k, &node) in fl.iter().enumerate() {
                out[node] = w[k];
            }
            best = Some((dist, out));
        }
    }
    if let Some((_, w)) = best {
        return w;
    }
    let n = barycentric(x, p);
    let mut w = n;
    for (i, v) in w.iter_mut().enumerate() {
        if boundary & (1 << i) == 0 {
            *v = 0.0;
        }
    }
    let s: f64 = w.iter().sum();
    if s > 0.0 {
        w.map(|v| v / s)
    } else {
        n
    }
}

/// Barycentric weights (clamped to the triangle, summing to 1) of the
/// projection of `p` onto triangle `tri`, and the distance from `p` to the
/// clamped point.
fn triangle_weights(tri: [[f64; 3]; 3], p: [f64; 3]) -> ([f64; 3], f64) {
    let (e1, e2, d) = (sub(tri[1], tri[0]), sub(tri[2], tri[0]), sub(p, tri[0]));
    let (a, b, c) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
    let (r1, r2) = (dot(d, e1), dot(d, e2));
    let det = a * c - b * b;
    let mut u = (c * r1 - b * r2) / det;
    let mut v = (a * r2 - b * r1) / det;
    let mut w0 = 1.0 - u - v;
    // Clamp into the triangle and renormalise (a point beyond an edge
    // takes the nearest part of the face).
    u = u.max(0.0);
    v = v.max(0.0);
    w0 = w0.max(0.0);
    let s = u + v + w0;
    let w = [w0 / s, u / s, v / s];
    let q = [0, 1, 2].map(|k| tri[0][k] + w[1] * e1[k] + w[2] * e2[k]);
    let off = sub(p, q);
    (w, dot(off, off).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corner(s: f64, d: [f64; 3]) -> [[f64; 3]; 4] {
        [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
            .map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
    }

    #[test]
    fn symmetric_under_swap() {
        let a = corner(1.0, [0.0; 3]);
        let b = corner(1.0, [0.2, 0.1, -0.6]);
        let all = [0u8, 1, 2, 3];
        let ab = tet_tet_contact_surface((&a, &all, 0b1111), (&b, &all, 0b1111));
        let ba = tet_tet_contact_surface((&b, &all, 0b1111), (&a, &all, 0b1111));
        assert_eq!(ab.s_target, ba.s_contactor);
        assert_eq!(ab.w_target, ba.w_contactor);
        assert!((ab.area() - ba.area()).abs() < 1e-15);
        assert!(ab.area() > 0.0);
        assert!((ab.w_target.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn face_to_face_overlap_area() {
        // Target: corner tet; its face z = 0 (face 3, opposite node 3) is its
        // only boundary face. Contactor: a big tet whose volume covers the
        // region just below and above z = 0 around that face, penetrating it.
        let t = corner(1.0, [0.0; 3]);
        let c = [
            [-10.0, -10.0, 0.01],
            [10.0, -10.0, 0.01],
            [0.0, 12.0, 0.01],
            [0.0, 0.0, -5.0],
        ];
        let s = tet_tet_contact_surface((&t, &[3], 0b0111), (&c, &[], 0));
        // The whole face z = 0 (area 1/2) is inside the contactor.
        assert!((s.s_target - 0.5).abs() < 1e-12, "{}", s.s_target);
        assert_eq!(s.s_contactor, 0.0);
        // Weights: a third on each node of face 3 (nodes 0, 1, 2).
        for i in 0..3 {
            assert!((s.w_target[i] - 1.0 / 3.0).abs() < 1e-14);
        }
        assert_eq!(s.w_target[3], 0.0);
        assert!((s.area() - 0.25).abs() < 1e-12);
        // The contactor has no face in the target: its weights are its shape
        // functions at the centroid (1/3, 1/3, 0) of the target's face.
        let want = barycentric(&c, [1.0 / 3.0, 1.0 / 3.0, 0.0]);
        assert_eq!(s.w_contactor, want);
        assert!((s.w_contactor.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(s.w_contactor.iter().all(|&x| x >= 0.0));
    }

    #[test]
    fn barycentric_reproduces_vertices_and_centroid() {
        let t = corner(2.0, [1.0, 0.0, 0.0]);
        for i in 0..4 {
            let n = barycentric(&t, t[i]);
            for (j, nj) in n.iter().enumerate() {
                assert!((nj - f64::from(u8::from(i == j))).abs() < 1e-14);
            }
        }
        let c = [1.5, 0.5, 0.5];
        assert!(barycentric(&t, c).iter().all(|x| (x - 0.25).abs() < 1e-14));
    }
}
