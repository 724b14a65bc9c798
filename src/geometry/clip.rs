//! Triangle ∩ tetrahedron by Sutherland–Hodgman clipping against the tet's
//! four half-spaces, and tet–tet overlap by separating axes.
//!
//! Seed 000 sec 3.1: the contact surface on a target boundary face is the
//! part of the face inside the contactor tet's volume. Half-spaces are
//! closed with a tolerance scaled to the tet's size, so faces lying in a
//! tet's face plane (touching, coplanar) count as inside rather than
//! flickering with round-off.

use super::{cross, dot, sub};

/// A planar convex polygon in 3D (at most 3 + 4 vertices after clipping a
/// triangle by four planes).
pub type Polygon = Vec<[f64; 3]>;

/// Area of a planar polygon (magnitude of its vector area).
pub fn polygon_area(p: &[[f64; 3]]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let mut s = [0.0; 3];
    for i in 1..p.len() - 1 {
        let c = cross(sub(p[i], p[0]), sub(p[i + 1], p[0]));
        s[0] += c[0];
        s[1] += c[1];
        s[2] += c[2];
    }
    0.5 * dot(s, s).sqrt()
}

/// Outward unit normals and offsets of a tet's face planes: point p is
/// inside when n_i · p − c_i ≤ 0 for every face i (face i opposite node i).
fn tet_planes(t: &[[f64; 3]; 4]) -> [([f64; 3], f64); 4] {
    let mut planes = [([0.0; 3], 0.0); 4];
    for (i, plane) in planes.iter_mut().enumerate() {
        let (a, b, c) = match i {
            0 => (t[1], t[2], t[3]),
            1 => (t[0], t[2], t[3]),
            2 => (t[0], t[1], t[3]),
            _ => (t[0], t[1], t[2]),
        };
        let mut n = cross(sub(b, a), sub(c, a));
        let len = dot(n, n).sqrt();
        if len > 0.0 {
            n = [n[0] / len, n[1] / len, n[2] / len];
        }
        // Orient away from the opposite node.
        if dot(n, sub(t[i], a)) > 0.0 {
            n = [-n[0], -n[1], -n[2]];
        }
        *plane = (n, dot(n, a));
    }
    planes
}

fn tet_size(t: &[[f64; 3]; 4]) -> f64 {
    let mut m: f64 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(t[i], t[j]);
            m = m.max(dot(d, d));
        }
    }
    m.sqrt()
}

/// The part of triangle `tri` inside tet `tet` (seed 000 sec 3.1, Fig 3).
///
/// `outward` is the normal pointing out of the triangle's own body, and bit
/// i of `tet_boundary` is set when the tet's face i (opposite node i) lies
/// on the boundary of the tet's body. A triangle lying in one of the tet's
/// face planes is a tie that the rule below breaks so that every part of a
/// boundary face counts exactly once over the other body's tets:
/// - on a boundary face of the other body, it counts when the two face each
///   other (opposite normals: touching contact) and not when they point the
///   same way (two surfaces side by side, as the flanks of two overlapping
///   aligned bars), so only facing surfaces make contact area;
/// - on an interior face of the other body (shared by two of its tets, one
///   on each side), it counts in the tet on the triangle's own side (behind
///   `outward`), the one whose volume overlaps the triangle's tet, and not
///   in the tet in front of it, which only touches it.
pub fn face_tet_clip(
    tri: &[[f64; 3]; 3],
    outward: [f64; 3],
    tet: &[[f64; 3]; 4],
    tet_boundary: u8,
) -> Polygon {
    let eps = 1e-12 * tet_size(tet);
    let mut poly: Polygon = tri.to_vec();
    let mut next: Polygon = Vec::with_capacity(8);
    for (face, (n, c)) in tet_planes(tet).into_iter().enumerate() {
        if poly.is_empty() {
            break;
        }
        next.clear();
        let d: Vec<f64> = poly.iter().map(|p| dot(n, *p) - c).collect();
        if d.iter().all(|x| x.abs() <= eps) {
            // In the plane of face i: the tet lies in front of the triangle
            // (its outward normal opposes `outward`) or behind it.
            let in_front = dot(n, outward) < 0.0;
            let on_boundary = tet_boundary & (1 << face) != 0;
            if in_front != on_boundary {
                return Vec::new();
            }
            // Kept whole by this plane.
            continue;
        }
        for i in 0..poly.len() {
            let j = (i + 1) % poly.len();
            let (pi, pj, di, dj) = (poly[i], poly[j], d[i], d[j]);
            if di <= eps {
                next.push(pi);
            }
            // The edge crosses the plane strictly: add the crossing point.
            if (di < -eps && dj > eps) || (di > eps && dj < -eps) {
                let s = di / (di - dj);
                next.push([
                    pi[0] + s * (pj[0] - pi[0]),
                    pi[1] + s * (pj[1] - pi[1]),
                    pi[2] + s * (pj[2] - pi[2]),
                ]);
            }
        }
        std::mem::swap(&mut poly, &mut next);
    }
    poly
}

/// Area of the part of `tri` inside `tet`, a tet whose four faces all lie
/// on its body's boundary; the triangle's outward normal follows its vertex
/// order (right-hand rule).
pub fn triangle_in_tet_area(tri: &[[f64; 3]; 3], tet: &[[f64; 3]; 4]) -> f64 {
    let n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
    polygon_area(&face_tet_clip(tri, n, tet, 0b1111))
}

/// Whether two tets' closed volumes overlap by more than touching, by the
/// separating axis theorem (4 + 4 face normals, 6 × 6 edge cross products).
/// "Touching" is within 1e-12 of the smaller tet's size, no more than the
/// coplanarity tolerance of [`face_tet_clip`] for either tet: a face that
/// the clipping finds inside a tet is never in a pair ruled out here.
///
/// A corner of one tet deep inside the other (farther than a few times the
/// tolerance, and the round-off of the coordinates, from each of its face
/// planes) answers at once: every axis then sees the two intervals overlap
/// by at least that depth, so the separating axes would find no gap. Only
/// the other pairs run the 44 axes.
pub fn tet_tet_overlap(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4]) -> bool {
    shapes_overlap(&TetShape::new(*a), &TetShape::new(*b))
}

/// A tet's corners with what [`tet_tet_overlap`] derives from them (face
/// planes, size), made once for a tet met in several candidate pairs.
#[derive(Debug, Clone, Copy)]
pub struct TetShape {
    /// The corners.
    pub corners: [[f64; 3]; 4],
    planes: [([f64; 3], f64); 4],
    size: f64,
}

impl TetShape {
    /// The shape of the tet at `corners`.
    pub fn new(corners: [[f64; 3]; 4]) -> TetShape {
        TetShape {
            planes: tet_planes(&corners),
            size: tet_size(&corners),
            corners,
        }
    }
}

/// [`tet_tet_overlap`] of two tets' shapes.
pub fn shapes_overlap(sa: &TetShape, sb: &TetShape) -> bool {
    let (a, b) = (&sa.corners, &sb.corners);
    let eps = 1e-12 * sa.size.min(sb.size);
    let (pa, pb) = (sa.planes, sb.planes);
    let scale = a
        .iter()
        .chain(b)
        .flatten()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let depth = 4.0 * eps + 1e-13 * scale;
    let deep = |planes: &[([f64; 3], f64); 4], p: &[f64; 3]| {
        planes.iter().all(|(n, c)| dot(*n, *p) - c < -depth)
    };
    if b.iter().any(|p| deep(&pa, p)) || a.iter().any(|p| deep(&pb, p)) {
        return true;
    }
    separating_axes(a, b, &pa, &pb, eps)
}

/// The separating-axis test of [`tet_tet_overlap`] with the tets' face
/// planes given: false when an axis separates the closed volumes by more
/// than `eps`.
fn separating_axes(
    a: &[[f64; 3]; 4],
    b: &[[f64; 3]; 4],
    pa: &[([f64; 3], f64); 4],
    pb: &[([f64; 3], f64); 4],
    eps: f64,
) -> bool {
    // Projections relative to a's first corner, compared with the
    // tolerance scaled by the axis length (no normalisation per point).
    let o = a[0];
    let (ra, rb) = (a.map(|p| sub(p, o)), b.map(|p| sub(p, o)));
    let range = |axis: [f64; 3], t: &[[f64; 3]; 4]| {
        let x = t.map(|p| dot(axis, p));
        (
            x[0].min(x[1]).min(x[2].min(x[3])),
            x[0].max(x[1]).max(x[2].max(x[3])),
        )
    };
    let separated = |axis: [f64; 3]| {
        let len = dot(axis, axis).sqrt();
        if len < 1e-300 {
            return false;
        }
        let ((amin, amax), (bmin, bmax)) = (range(axis, &ra), range(axis, &rb));
        let tol = eps * len;
        amax <= bmin + tol || bmax <= amin + tol
    };
    if pa.iter().chain(pb.iter()).any(|(n, _)| separated(*n)) {
        return false;
    }
    const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
    let (ea, eb) = (
        EDGES.map(|(i, j)| sub(ra[j], ra[i])),
        EDGES.map(|(k, l)| sub(rb[l], rb[k])),
    );
    !ea.iter()
        .any(|u| eb.iter().any(|v| separated(cross(*u, *v))))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The separating-axis test as first written (each projection divided
    /// by the axis length), the reference of the faster one.
    fn reference_overlap(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4]) -> bool {
        let eps = 1e-12 * tet_size(a).min(tet_size(b));
        let separated = |axis: [f64; 3]| {
            let len = dot(axis, axis).sqrt();
            if len < 1e-300 {
                return false;
            }
            let (mut amin, mut amax, mut bmin, mut bmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for p in a {
                let x = dot(axis, *p) / len;
                amin = amin.min(x);
                amax = amax.max(x);
            }
            for p in b {
                let x = dot(axis, *p) / len;
                bmin = bmin.min(x);
                bmax = bmax.max(x);
            }
            amax <= bmin + eps || bmax <= amin + eps
        };
        const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
        let faces = tet_planes(a).into_iter().chain(tet_planes(b));
        !faces.map(|(n, _)| n).any(separated)
            && !EDGES.iter().any(|&(i, j)| {
                EDGES
                    .iter()
                    .any(|&(k, l)| separated(cross(sub(a[j], a[i]), sub(b[l], b[k]))))
            })
    }

    /// The separating axes, and the early answer of a deep corner, agree
    /// with the reference, on random pairs from far apart to nested, and on pairs that
    /// share a face, an edge or a corner (touching: not overlapping).
    #[test]
    fn deep_corners_agree_with_the_separating_axes() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(22);
        let mut tet = |c: [f64; 3], s: f64| -> [[f64; 3]; 4] {
            std::array::from_fn(|_| std::array::from_fn(|d| c[d] + s * rng.gen_range(-1.0..1.0)))
        };
        let (mut yes, mut no) = (0, 0);
        for k in 0..200_000 {
            let a = tet([0.0; 3], 1.0);
            let mut b = tet([0.5 * (k % 5) as f64; 3], 0.1 + (k % 7) as f64 * 0.3);
            if k % 3 == 0 {
                // Share a face, an edge or a corner of a, reflected through it.
                let shared = 1 + k % 4;
                b[..shared].copy_from_slice(&a[..shared]);
            }
            let eps = 1e-12 * tet_size(&a).min(tet_size(&b));
            let want = reference_overlap(&a, &b);
            let axes = separating_axes(&a, &b, &tet_planes(&a), &tet_planes(&b), eps);
            assert_eq!(axes, want, "{a:?} {b:?}");
            assert_eq!(tet_tet_overlap(&a, &b), want, "{a:?} {b:?}");
            if want {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(yes > 10_000 && no > 10_000, "{yes} overlapping, {no} apart");
    }

    /// The tet with corners at the origin and the three unit points, scaled.
    fn corner_tet(s: f64) -> [[f64; 3]; 4] {
        [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
    }

    /// A big tet containing the box [-1, 1]^2 × [z0, z1] region used below.
    fn slab_tet() -> [[f64; 3]; 4] {
        // Large enough that its faces are far from the test triangles except
        // for the bottom plane z = 0.
        [
            [-50.0, -50.0, 0.0],
            [50.0, -50.0, 0.0],
            [0.0, 60.0, 0.0],
            [0.0, 0.0, 80.0],
        ]
    }

    fn rot(p: [f64; 3], ang: f64, axis: usize) -> [f64; 3] {
        let (c, s) = (ang.cos(), ang.sin());
        let (i, j) = match axis {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        let mut q = p;
        q[i] = c * p[i] - s * p[j];
        q[j] = s * p[i] + c * p[j];
        q
    }

    #[test]
    fn area_of_simple_polygons() {
        let sq = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert!((polygon_area(&sq) - 2.0).abs() < 1e-15);
        assert_eq!(polygon_area(&sq[..2]), 0.0);
    }

    #[test]
    fn face_inside_is_kept_whole() {
        let tet = corner_tet(10.0);
        let tri = [[1.0, 1.0, 1.0], [2.0, 1.0, 1.0], [1.0, 2.0, 1.0]];
        assert!((triangle_in_tet_area(&tri, &tet) - 0.5).abs() < 1e-14);
    }

    #[test]
    fn face_outside_gives_zero() {
        let tet = corner_tet(1.0);
        let tri = [[2.0, 2.0, 2.0], [3.0, 2.0, 2.0], [2.0, 3.0, 2.0]];
        assert_eq!(triangle_in_tet_area(&tri, &tet), 0.0);
        // Outside but with an overlapping bounding box.
        let tri = [[0.6, 0.6, 0.1], [0.9, 0.5, 0.1], [0.5, 0.9, 0.1]];
        assert_eq!(triangle_in_tet_area(&tri, &tet), 0.0);
    }

    #[test]
    fn half_covered_face() {
        // A vertical triangle crossing the plane z = 0: the part with z ≥ 0
        // is inside the big tet. Triangle (−1,0,−1), (1,0,−1), (0,0,1):
        // area 2; the part above z = 0 is a triangle of base 1, height 1.
        let tri = [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]];
        let a = triangle_in_tet_area(&tri, &slab_tet());
        assert!((a - 0.5).abs() < 1e-13, "{a}");
    }

    #[test]
    fn rotated_cases_match_by_hand() {
        // The same half-covered configuration under rotations of both shapes.
        let tri = [[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]];
        for (k, ang) in [0.3, 1.1, 2.5, -0.7].iter().enumerate() {
            let axis = k % 3;
            let tri_r = tri.map(|p| rot(p, *ang, axis));
            let tet_r = slab_tet().map(|p| rot(p, *ang, axis));
            let a = triangle_in_tet_area(&tri_r, &tet_r);
            assert!((a - 0.5).abs() < 1e-12, "rotation {ang} about {axis}: {a}");
        }
        // A triangle in the plane z = 0.5 cutting the corner tet: the
        // section of the tet at height z is the triangle x, y ≥ 0, x + y ≤ 1 − z.
        let tet = corner_tet(1.0);
        let big = [[-1.0, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]];
        let a = triangle_in_tet_area(&big, &tet);
        assert!((a - 0.125).abs() < 1e-14, "{a}");
    }

    #[test]
    fn coplanar_touching_face_counts_its_overlap() {
        // Triangle lying in the tet's face plane z = 0 (touching contact).
        let tet = corner_tet(1.0);
        let tri = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]];
        let a = triangle_in_tet_area(&tri, &tet);
        assert!((a - 0.125).abs() < 1e-14, "{a}");
        // The same triangle facing the same way as the tet's face (side by
        // side, not touching): no contact area.
        let flipped = [tri[0], tri[2], tri[1]];
        assert_eq!(triangle_in_tet_area(&flipped, &tet), 0.0);
        // Just below the face: nothing.
        let below = tri.map(|p| [p[0], p[1], -1e-9]);
        assert_eq!(triangle_in_tet_area(&below, &tet), 0.0);
    }

    #[test]
    fn face_on_a_shared_interior_face_counts_once() {
        // Two tets of one body share the face z = 0 (face 3 of each); a
        // triangle of another body lies in it, facing up or down.
        let above = corner_tet(1.0);
        let below = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
        ];
        let tri = [[0.1, 0.1, 0.0], [0.5, 0.1, 0.0], [0.1, 0.5, 0.0]];
        let whole = polygon_area(&tri);
        for outward in [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]] {
            let a = polygon_area(&face_tet_clip(&tri, outward, &above, 0));
            let b = polygon_area(&face_tet_clip(&tri, outward, &below, 0));
            assert!((a + b - whole).abs() < 1e-15, "{a} + {b}");
            assert!(a == 0.0 || b == 0.0, "counted twice: {a}, {b}");
            // It counts in the tet behind the triangle (on its body's side).
            let behind = if outward[2] > 0.0 { b } else { a };
            assert!((behind - whole).abs() < 1e-15);
        }
        // The same face on the boundary (only `above` exists): facing counts,
        // side by side does not.
        let down = polygon_area(&face_tet_clip(&tri, [0.0, 0.0, 1.0], &above, 0b1000));
        let up = polygon_area(&face_tet_clip(&tri, [0.0, 0.0, -1.0], &above, 0b1000));
        assert!((down - whole).abs() < 1e-15 && up == 0.0, "{down}, {up}");
    }

    #[test]
    fn edge_on_and_vertex_on_give_zero_area_without_nan() {
        let tet = corner_tet(1.0);
        // Triangle touching the tet along an edge only.
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, -1.0, -1.0]];
        let a = triangle_in_tet_area(&tri, &tet);
        assert!(a.is_finite() && a.abs() < 1e-14, "{a}");
        // Triangle touching at a vertex only.
        let tri = [[1.0, 0.0, 0.0], [2.0, 0.0, -1.0], [2.0, -1.0, 0.0]];
        let a = triangle_in_tet_area(&tri, &tet);
        assert!(a.is_finite() && a.abs() < 1e-14, "{a}");
    }

    #[test]
    fn tet_overlap_by_separating_axes() {
        let a = corner_tet(1.0);
        let shifted = |d: [f64; 3]| a.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]);
        assert!(tet_tet_overlap(&a, &shifted([0.1, 0.1, 0.1])));
        assert!(!tet_tet_overlap(&a, &shifted([2.0, 0.0, 0.0])));
        // Touching across the slanted face only: no overlap.
        assert!(!tet_tet_overlap(&a, &shifted([1.0, 0.0, 0.0])));
        // Overlapping bounding boxes, separated by the slanted face plane.
        let b = [
            [0.6, 0.6, 0.6],
            [1.6, 0.6, 0.6],
            [0.6, 1.6, 0.6],
            [0.6, 0.6, 1.6],
        ];
        assert!(!tet_tet_overlap(&a, &b));
    }
}
