//! Exact intersection of two tetrahedra: the volume and centroid of a ∩ b
//! and, for every face of either tet, the area and area-centroid of the part
//! of that face on the boundary of a ∩ b. This is what the volume-based
//! penalty contact (`contact::penalty`) needs for its potential and its
//! exact gradient.
//!
//! Method: the boundary of the convex polyhedron a ∩ b is (∂a ∩ b) ∪ (∂b ∩ a),
//! so each of the 8 faces is clipped (Sutherland–Hodgman, as in
//! [`super::face_tet_clip`]) by the other tet's 4 half-spaces, and the volume
//! and centroid follow from the divergence theorem / a pyramid fan over those
//! polygons from one reference point. Everything is on the stack: no
//! allocation per pair. Disjoint pairs usually leave early through the
//! bounding boxes or the 8 face-normal separating axes (from a 4 × 4 table
//! of vertex–plane distances that the clipping reuses); the 36 edge–edge
//! axes are only consulted when the clipped volume vanishes, to tell
//! touching from a genuine sliver.
//!
//! Coplanar faces: a face of a lying in a face plane of b with the *same*
//! outward normal (the two bodies' surfaces flush) bounds a ∩ b once, so each
//! of the two copies is counted with weight ½ (symmetric in a ↔ b, and the
//! gradient is the mean of the two one-sided derivatives). "Flush" means all
//! six vertices within 1e-8 × the longer tet edge of the other face's plane;
//! two faces merged that way close the surface only to ~ gap × perimeter, so
//! Σ area × normal (and the penalty's net force) is then zero to ~1e-8
//! relative instead of round-off. Faces with *opposite* normals (touching)
//! need no rule (unlike [`super::face_tet_clip`], which counts them as
//! contact area): a ∩ b is then flat and the terms cancel; touching tets are
//! in any case rejected by the separating-axis test, giving V = 0 exactly.

use super::{cross, dot, sub};

/// Local node indices of face `f` (the face opposite node `f`).
pub const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Most vertices a clipped polygon can hold: a triangle clipped by four
/// planes has at most 3 + 4 = 7; the rest is slack for round-off.
const MAXV: usize = 10;

/// Face planes of a tet with everything needed for clipping and for its
/// linear shape functions (barycentric coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetPlanes {
    /// Outward unit normal of face i (opposite node i).
    pub normal: [[f64; 3]; 4],
    /// Plane offset: n_i · x = offset_i on face i; inside is n_i · x ≤ offset_i.
    pub offset: [f64; 4],
    /// Distance from node i to face i (positive for a non-degenerate tet).
    pub height: [f64; 4],
    /// Volume (unsigned).
    pub volume: f64,
    /// Longest edge.
    pub size: f64,
}

impl TetPlanes {
    /// Planes of tet `t` (either vertex ordering).
    pub fn new(t: &[[f64; 3]; 4]) -> Self {
        let mut normal = [[0.0; 3]; 4];
        let mut offset = [0.0; 4];
        let mut height = [0.0; 4];
        for i in 0..4 {
            let [j, k, l] = TET_FACES[i];
            let mut n = cross(sub(t[k], t[j]), sub(t[l], t[j]));
            let len = dot(n, n).sqrt();
            // Unit length, oriented away from the opposite node.
            let s = if dot(n, sub(t[i], t[j])) > 0.0 {
                -1.0
            } else {
                1.0
            };
            if len > 0.0 {
                let inv = s / len;
                n = [n[0] * inv, n[1] * inv, n[2] * inv];
            }
            normal[i] = n;
            offset[i] = dot(n, t[j]);
            height[i] = offset[i] - dot(n, t[i]);
        }
        // Standard: V = |(x1 − x0) · ((x2 − x0) × (x3 − x0))| / 6.
        let volume = dot(sub(t[1], t[0]), cross(sub(t[2], t[0]), sub(t[3], t[0]))).abs() / 6.0;
        let mut m: f64 = 0.0;
        for i in 0..4 {
            for j in i + 1..4 {
                let d = sub(t[i], t[j]);
                m = m.max(dot(d, d));
            }
        }
        TetPlanes {
            normal,
            offset,
            height,
            volume,
            size: m.sqrt(),
        }
    }

    /// Whether the tet has a usable volume (not flat, finite).
    pub fn is_proper(&self) -> bool {
        self.volume.is_finite() && self.volume > 1e-14 * self.size * self.size * self.size
    }

    /// Barycentric coordinates (the Tet4 shape functions) N_i(p), summing
    /// to 1. Needs [`Self::is_proper`].
    #[inline]
    pub fn barycentric(&self, p: [f64; 3]) -> [f64; 4] {
        self.barycentric_moment(1.0, p)
    }

    /// ∫ N_i dA over a planar patch of the given area and first moment
    /// (area × centroid): A · N_i(c), affine in (A, A c), so it needs no
    /// division by a possibly vanishing area.
    #[inline]
    pub fn barycentric_moment(&self, area: f64, moment: [f64; 3]) -> [f64; 4] {
        // Standard (linear FE): N_i(p) = (offset_i − n_i · p) / h_i, the
        // distance of p from face i over that of node i; N_0 = 1 − Σ others.
        let n = |i: usize| (area * self.offset[i] - dot(self.normal[i], moment)) / self.height[i];
        let (w1, w2, w3) = (n(1), n(2), n(3));
        [area - w1 - w2 - w3, w1, w2, w3]
    }

    /// Whether p is inside the closed tet (with tolerance `tol` in length).
    pub fn contains(&self, p: [f64; 3], tol: f64) -> bool {
        (0..4).all(|i| dot(self.normal[i], p) - self.offset[i] <= tol)
    }
}

/// The part of one tet face on the boundary of a ∩ b.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FacePatch {
    /// Area of the part of the face inside the other tet (weighted ½ when
    /// the face is flush with a same-facing face of the other tet).
    pub area: f64,
    /// First moment: area × centroid (well defined for vanishing slivers).
    pub moment: [f64; 3],
}

impl FacePatch {
    /// Area centroid (`moment / area`; the origin when the area is 0).
    pub fn centroid(&self) -> [f64; 3] {
        if self.area > 0.0 {
            self.moment.map(|m| m / self.area)
        } else {
            [0.0; 3]
        }
    }
}

/// Intersection of two tets a and b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intersection {
    /// Volume of a ∩ b (≥ 0).
    pub volume: f64,
    /// Centroid of a ∩ b (meaningful when `volume > 0`).
    pub centroid: [f64; 3],
    /// Face i of a (opposite node i, outward normal `planes_a.normal[i]`)
    /// inside b.
    pub faces_a: [FacePatch; 4],
    /// Face j of b inside a.
    pub faces_b: [FacePatch; 4],
    /// Planes and shape functions of a.
    pub planes_a: TetPlanes,
    /// Planes and shape functions of b.
    pub planes_b: TetPlanes,
}

/// Intersection of two tets whose planes the caller holds: an
/// [`Intersection`] without its copies of the planes (what the penalty's
/// inner loop needs, without moving them around).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Overlap {
    /// Volume of a ∩ b (≥ 0).
    pub volume: f64,
    /// Centroid of a ∩ b (meaningful when `volume > 0`).
    pub centroid: [f64; 3],
    /// Face i of a inside b.
    pub faces_a: [FacePatch; 4],
    /// Face j of b inside a.
    pub faces_b: [FacePatch; 4],
}

impl Intersection {
    /// Σ over the patches of both tets of area × outward normal: zero up to
    /// round-off, since they close the surface of a ∩ b (up to gap ×
    /// perimeter for faces merged as flush, see the module notes).
    pub fn closure_defect(&self) -> [f64; 3] {
        let mut s = [0.0; 3];
        for (faces, planes) in [
            (&self.faces_a, &self.planes_a),
            (&self.faces_b, &self.planes_b),
        ] {
            for (f, n) in faces.iter().zip(&planes.normal) {
                for d in 0..3 {
                    s[d] += f.area * n[d];
                }
            }
        }
        s
    }
}

/// Stack polygon for clipping.
#[derive(Clone, Copy)]
struct Poly {
    n: usize,
    p: [[f64; 3]; MAXV],
}

impl Poly {
    #[inline]
    fn push(&mut self, q: [f64; 3]) {
        // Saturate rather than panic: only round-off in a degenerate
        // configuration can exceed 7 vertices, and then the area is ~0.
        if self.n < MAXV {
            self.p[self.n] = q;
            self.n += 1;
        }
    }
}

/// Signed distances n_k · x_v − offset_k of each vertex v of `t` to each
/// face plane k of `other` (positive outside).
fn distances(t: &[[f64; 3]; 4], other: &TetPlanes) -> [[f64; 4]; 4] {
    t.map(|x| std::array::from_fn(|k| dot(other.normal[k], x) - other.offset[k]))
}

/// (area, first moment) of a planar polygon with unit normal `n`, by a
/// triangle fan; the sign of the area follows the winding.
fn polygon_moments(p: &[[f64; 3]], n: [f64; 3]) -> (f64, [f64; 3]) {
    let (mut area, mut m) = (0.0, [0.0; 3]);
    let p0 = p[0];
    for w in p[1..].windows(2) {
        // Standard: fan triangle (p0, p_i, p_i+1) has signed area
        // ½ ((p_i − p0) × (p_i+1 − p0)) · n and centroid (p0 + p_i + p_i+1)/3.
        let a = 0.5 * dot(cross(sub(w[0], p0), sub(w[1], p0)), n);
        for d in 0..3 {
            m[d] += a * (p0[d] + w[0][d] + w[1][d]) / 3.0;
        }
        area += a;
    }
    (area, m)
}

/// Clip triangle `tri` (a face of its tet, outward unit normal `n_face`;
/// `dt[i][k]` the distance of vertex i to plane k of `other`) by the
/// half-spaces of `other`, skipping plane `skip` (a flush coplanar face);
/// returns the polygon's (area, first moment).
fn clip_face(
    tri: [[f64; 3]; 3],
    dt: [[f64; 4]; 3],
    n_face: [f64; 3],
    other: &TetPlanes,
    skip: usize,
    bufs: &mut (Poly, Poly),
) -> (f64, [f64; 3]) {
    // Classify the triangle against each plane from the table: wholly
    // outside one plane → empty; planes it is wholly inside of are skipped
    // (so are they for every sub-polygon, convex combinations of it).
    let mut cutting = [false; 4];
    for k in 0..4 {
        if k == skip {
            continue;
        }
        let any_out = dt.iter().any(|d| d[k] > 0.0);
        let any_in = dt.iter().any(|d| d[k] < 0.0);
        if any_out && !any_in {
            return (0.0, [0.0; 3]);
        }
        cutting[k] = any_out;
    }
    let (mut src, mut dst) = (&mut bufs.0, &mut bufs.1);
    src.n = 3;
    src.p[..3].copy_from_slice(&tri);
    let mut first = true;
    let mut d = [0.0; MAXV];
    for k in (0..4).filter(|&k| cutting[k]) {
        let (n, c) = (other.normal[k], other.offset[k]);
        let (mut any_out, mut any_in) = (false, false);
        for i in 0..src.n {
            // Sutherland–Hodgman (1974): signed distance to the plane.
            d[i] = if first {
                dt[i][k]
            } else {
                dot(n, src.p[i]) - c
            };
            any_out |= d[i] > 0.0;
            any_in |= d[i] < 0.0;
        }
        first = false;
        if !any_out {
            continue; // wholly inside this (closed) half-space: unchanged
        }
        if !any_in {
            return (0.0, [0.0; 3]); // wholly outside, or on the plane
        }
        dst.n = 0;
        for i in 0..src.n {
            let j = if i + 1 == src.n { 0 } else { i + 1 };
            let (pi, pj, di, dj) = (src.p[i], src.p[j], d[i], d[j]);
            if di <= 0.0 {
                dst.push(pi);
            }
            if (di < 0.0 && dj > 0.0) || (di > 0.0 && dj < 0.0) {
                // Sutherland–Hodgman: the edge crosses the plane at s.
                let s = di / (di - dj);
                dst.push([
                    pi[0] + s * (pj[0] - pi[0]),
                    pi[1] + s * (pj[1] - pi[1]),
                    pi[2] + s * (pj[2] - pi[2]),
                ]);
            }
        }
        std::mem::swap(&mut src, &mut dst);
        if src.n < 3 {
            return (0.0, [0.0; 3]);
        }
    }
    let poly = &*src;
    let (area, m) = polygon_moments(&poly.p[..poly.n], n_face);
    // Clipping keeps the winding, so all fan areas share the triangle's sign.
    if area < 0.0 {
        (-area, [-m[0], -m[1], -m[2]])
    } else {
        (area, m)
    }
}

/// Whether the axis-aligned boxes of a and b overlap by at most `eps`.
fn boxes_separated(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], eps: f64) -> bool {
    (0..3).any(|d| {
        let lo = |t: &[[f64; 3]; 4]| t.iter().fold(f64::MAX, |m, p| m.min(p[d]));
        let hi = |t: &[[f64; 3]; 4]| t.iter().fold(f64::MIN, |m, p| m.max(p[d]));
        hi(a) <= lo(b) + eps || hi(b) <= lo(a) + eps
    })
}

/// Separating-axis test on the 36 edge–edge cross products (the face
/// normals are tested from the distance tables); overlap ≤ `eps` counts as
/// separated (touching).
fn edges_separated(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], eps: f64) -> bool {
    let ea = TET_EDGES.map(|(i, j)| sub(a[j], a[i]));
    let eb = TET_EDGES.map(|(i, j)| sub(b[j], b[i]));
    for u in &ea {
        for v in &eb {
            let axis = cross(*u, *v);
            let len2 = dot(axis, axis);
            if len2 < 1e-24 * dot(*u, *u) * dot(*v, *v) {
                continue; // parallel edges: covered by the face normals
            }
            let ([amin, amax], [bmin, bmax]) = (interval(axis, a), interval(axis, b));
            let e = eps * len2.sqrt();
            if amax <= bmin + e || bmax <= amin + e {
                return true;
            }
        }
    }
    false
}

/// Volume, centroid and boundary patches of a ∩ b (see the module notes).
/// Disjoint or merely touching tets (by a separating-axis test with
/// tolerance 1e-12 × the larger tet's longest edge) and degenerate (flat)
/// tets give volume 0 and empty patches.
pub fn tet_tet_intersection(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4]) -> Intersection {
    tet_tet_intersection_with(a, &TetPlanes::new(a), b, &TetPlanes::new(b))
}

/// [`tet_tet_intersection`] with the planes of a and b given (`pa` must be
/// `TetPlanes::new(a)`, likewise `pb`), for callers that reuse them over
/// many pairs.
pub fn tet_tet_intersection_with(
    a: &[[f64; 3]; 4],
    pa: &TetPlanes,
    b: &[[f64; 3]; 4],
    pb: &TetPlanes,
) -> Intersection {
    let o = intersect_tets(a, pa, b, pb);
    Intersection {
        volume: o.volume,
        centroid: o.centroid,
        faces_a: o.faces_a,
        faces_b: o.faces_b,
        planes_a: *pa,
        planes_b: *pb,
    }
}

/// [`tet_tet_intersection_with`] without copies of the planes in the
/// result.
pub fn intersect_tets(
    a: &[[f64; 3]; 4],
    pa: &TetPlanes,
    b: &[[f64; 3]; 4],
    pb: &TetPlanes,
) -> Overlap {
    let mut out = Overlap::default();
    let size = pa.size.max(pb.size);
    let eps = 1e-12 * size;
    if !pa.is_proper() || !pb.is_proper() || boxes_separated(a, b, eps) {
        return out;
    }
    // da[v][k]: vertex v of a against plane k of b; db likewise.
    let da = distances(a, pb);
    let db = distances(b, pa);
    // Separating axes along the 8 face normals: b wholly beyond a face
    // plane of a (or the reverse), up to eps.
    for k in 0..4 {
        if db.iter().all(|d| d[k] >= -eps) || da.iter().all(|d| d[k] >= -eps) {
            return out;
        }
    }
    // Flush faces: a's face i and b's face j in one plane (all six vertices
    // within 1e-8 × size of the other's plane: ~√ε, as tighter would leave
    // near-coplanar faces whose crossing lines are ill-conditioned, error
    // ~ ε/angle) with the same outward normal.
    let tol = 1e-8 * size;
    let (mut flush_a, mut flush_b) = ([4; 4], [4; 4]);
    for i in 0..4 {
        for j in 0..4 {
            if TET_FACES[i].iter().all(|&v| da[v][j].abs() <= tol)
                && TET_FACES[j].iter().all(|&v| db[v][i].abs() <= tol)
                && dot(pa.normal[i], pb.normal[j]) > 0.0
            {
                flush_a[i] = j;
                flush_b[j] = i;
            }
        }
    }
    let mut total_area = 0.0;
    let mut total_m = [0.0; 3];
    let empty = Poly {
        n: 0,
        p: [[0.0; 3]; MAXV],
    };
    let mut bufs = (empty, empty);
    for (t, dist, p, q, flush, faces) in [
        (a, &da, pa, pb, &flush_a, &mut out.faces_a),
        (b, &db, pb, pa, &flush_b, &mut out.faces_b),
    ] {
        for f in 0..4 {
            let [i, j, k] = TET_FACES[f];
            let (mut area, mut m) = clip_face(
                [t[i], t[j], t[k]],
                [dist[i], dist[j], dist[k]],
                p.normal[f],
                q,
                flush[f],
                &mut bufs,
            );
            if flush[f] < 4 {
                // Not in the seeds: a flush face pair bounds a ∩ b once, so
                // each copy counts ½ (keeps ∂(a∩b) closed and a ↔ b symmetric).
                area *= 0.5;
                m = [0.5 * m[0], 0.5 * m[1], 0.5 * m[2]];
            }
            total_area += area;
            for d in 0..3 {
                total_m[d] += m[d];
            }
            faces[f] = FacePatch { area, moment: m };
        }
    }
    if total_area <= 0.0 {
        return Overlap::default();
    }
    // Reference point: the area centroid of ∂(a∩b), close to the polygons
    // so that the pyramid heights below lose little to cancellation.
    let r = [
        total_m[0] / total_area,
        total_m[1] / total_area,
        total_m[2] / total_area,
    ];
    let mut vol = 0.0;
    let mut first = [0.0; 3];
    for (faces, p) in [(&out.faces_a, pa), (&out.faces_b, pb)] {
        for (f, patch) in faces.iter().enumerate() {
            if patch.area == 0.0 {
                continue;
            }
            // Not in the seeds: divergence theorem, V = Σ_P A_P h_P / 3 with
            // h_P = n_P · (c_P − r) the height of the pyramid from r on P.
            let h = p.offset[f] - dot(p.normal[f], r);
            vol += patch.area * h / 3.0;
            // Not in the seeds: a pyramid's centroid is r + ¾ (c_P − r), so
            // ∫ (x − r) dV = Σ_P (A_P h_P / 3) ¾ (c_P − r) = Σ_P h_P (M_P − A_P r) / 4.
            for d in 0..3 {
                first[d] += h * (patch.moment[d] - patch.area * r[d]);
            }
        }
    }
    // A vanishing result may be tets touching edge to edge: settle it with
    // the remaining separating axes (skipped for real overlaps: they cost
    // as much as the clipping).
    if vol <= 1e-10 * pa.volume.min(pb.volume) && (vol <= 0.0 || edges_separated(a, b, eps)) {
        return Overlap::default();
    }
    out.volume = vol;
    out.centroid = [
        r[0] + 0.25 * first[0] / vol,
        r[1] + 0.25 * first[1] / vol,
        r[2] + 0.25 * first[2] / vol,
    ];
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Corner tet of the unit cube scaled by s: (0, s e1, s e2, s e3).
    pub(crate) fn corner_tet(s: f64) -> [[f64; 3]; 4] {
        [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
    }

    pub(crate) fn shift(t: &[[f64; 3]; 4], d: [f64; 3]) -> [[f64; 3]; 4] {
        t.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
    }

    /// Small deterministic generator (xorshift64*), uniform in [0, 1).
    pub(crate) struct Rng(pub u64);

    impl Rng {
        pub(crate) fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }

        /// A tet with corners in [0, 1)^3 + c, of volume ≥ 0.02.
        pub(crate) fn tet(&mut self, c: [f64; 3]) -> [[f64; 3]; 4] {
            loop {
                let t: [[f64; 3]; 4] = std::array::from_fn(|_| {
                    [c[0] + self.next(), c[1] + self.next(), c[2] + self.next()]
                });
                if TetPlanes::new(&t).volume > 0.02 {
                    return t;
                }
            }
        }
    }

    /// Random overlapping pair (volume of a ∩ b > 1e-3).
    pub(crate) fn overlapping_pair(rng: &mut Rng) -> ([[f64; 3]; 4], [[f64; 3]; 4]) {
        loop {
            let a = rng.tet([0.0; 3]);
            let d = [
                0.6 * (rng.next() - 0.5),
                0.6 * (rng.next() - 0.5),
                0.6 * (rng.next() - 0.5),
            ];
            let b = rng.tet(d);
            if tet_tet_intersection(&a, &b).volume > 1e-3 {
                return (a, b);
            }
        }
    }

    fn vol(t: &[[f64; 3]; 4]) -> f64 {
        TetPlanes::new(t).volume
    }

    fn close(x: f64, y: f64, tol: f64) -> bool {
        (x - y).abs() <= tol
    }

    fn close3(x: [f64; 3], y: [f64; 3], tol: f64) -> bool {
        (0..3).all(|d| (x[d] - y[d]).abs() <= tol)
    }

    fn mean(t: &[[f64; 3]; 4]) -> [f64; 3] {
        let mut c = [0.0; 3];
        for p in t {
            for d in 0..3 {
                c[d] += 0.25 * p[d];
            }
        }
        c
    }

    #[test]
    fn identical_tets_give_the_tet() {
        let mut rng = Rng(7);
        for t in [
            corner_tet(1.0),
            rng.tet([0.0; 3]),
            rng.tet([5.0, -3.0, 2.0]),
        ] {
            let i = tet_tet_intersection(&t, &t);
            assert!(
                close(i.volume, vol(&t), 1e-13 * vol(&t)),
                "{} {}",
                i.volume,
                vol(&t)
            );
            assert!(close3(i.centroid, mean(&t), 1e-12));
            // Every face is flush with its twin: half its area each.
            for f in 0..4 {
                assert!(close(i.faces_a[f].area, i.faces_b[f].area, 1e-14));
            }
            let s = i.closure_defect();
            assert!(close3(s, [0.0; 3], 1e-13), "{s:?}");
        }
    }

    #[test]
    fn tet_inside_another() {
        // Strictly inside: the small tet whole.
        let big = corner_tet(3.0);
        let small = shift(&corner_tet(1.0), [0.2, 0.3, 0.4]);
        for (a, b) in [(big, small), (small, big)] {
            let i = tet_tet_intersection(&a, &b);
            assert!(close(i.volume, 1.0 / 6.0, 1e-14), "{}", i.volume);
            assert!(close3(i.centroid, mean(&small), 1e-14));
        }
        // Inside with three faces flush with the big tet's faces.
        let i = tet_tet_intersection(&corner_tet(2.0), &corner_tet(1.0));
        assert!(close(i.volume, 1.0 / 6.0, 1e-14), "{}", i.volume);
        assert!(close3(i.centroid, [0.25; 3], 1e-14));
        // The small tet's three flush faces count half, its slanted face whole.
        assert!(close(i.faces_b[0].area, 3f64.sqrt() / 2.0, 1e-14));
        for f in 1..4 {
            assert!(close(i.faces_b[f].area, 0.25, 1e-14));
            assert!(close(i.faces_a[f].area, 0.25, 1e-14));
        }
        assert_eq!(i.faces_a[0].area, 0.0);
    }

    #[test]
    fn translated_corner_tets_by_hand() {
        let t = corner_tet(1.0);
        for s in [0.1, 0.25, 0.5, 0.9] {
            // a ∩ (a + s e1) = {x ≥ s, y, z ≥ 0, x + y + z ≤ 1}: legs 1 − s.
            let b = shift(&t, [s, 0.0, 0.0]);
            let l = 1.0 - s;
            let i = tet_tet_intersection(&t, &b);
            assert!(
                close(i.volume, l * l * l / 6.0, 1e-15),
                "s {s}: {}",
                i.volume
            );
            let want = mean(&[[s, 0.0, 0.0], [1.0, 0.0, 0.0], [s, l, 0.0], [s, 0.0, l]]);
            assert!(close3(i.centroid, want, 1e-14), "{:?}", i.centroid);
            // Patches: a's slanted face beyond x = s; b's face x = s whole;
            // the y = 0 and z = 0 faces flush (½ each); a's x = 0 face none.
            let pa = &i.faces_a;
            assert!(close(pa[0].area, 3f64.sqrt() / 2.0 * l * l, 1e-14));
            assert!(close(pa[1].area, 0.0, 1e-15));
            assert!(close(pa[2].area, 0.25 * l * l, 1e-14));
            assert!(close(i.faces_b[1].area, 0.5 * l * l, 1e-14));
            assert!(close(i.faces_b[0].area, 0.0, 1e-14));
            let s3 = i.closure_defect();
            assert!(close3(s3, [0.0; 3], 1e-14), "{s3:?}");
            // Along the diagonal: {x, y, z ≥ s, x + y + z ≤ 1}, legs 1 − 3s.
            let b = shift(&t, [s, s, s]);
            let l = (1.0 - 3.0 * s).max(0.0);
            let v = tet_tet_intersection(&t, &b).volume;
            assert!(close(v, l * l * l / 6.0, 1e-15), "diag s {s}: {v}");
        }
        // A genuine sliver (V / vol = 1e-12) is kept, and accurate.
        let i = tet_tet_intersection(&t, &shift(&t, [1.0 - 1e-4, 0.0, 0.0]));
        let want = 1e-12 / 6.0;
        assert!(close(i.volume, want, 1e-9 * want), "{}", i.volume);
    }

    /// Flush faces under a rotation (coplanar only up to round-off), and
    /// nearly flush ones on either side of the 1e-8 flush tolerance.
    #[test]
    fn flush_and_nearly_flush_faces_under_rotation() {
        let (c1, s1) = (0.7f64.cos(), 0.7f64.sin());
        let (c2, s2) = (1.9f64.cos(), 1.9f64.sin());
        let rot = |p: [f64; 3]| {
            let q = [c1 * p[0] - s1 * p[1], s1 * p[0] + c1 * p[1], p[2]];
            [q[0], c2 * q[1] - s2 * q[2], s2 * q[1] + c2 * q[2]]
        };
        let t = corner_tet(1.0);
        let s = 0.3;
        for dz in [0.0, 1e-11, 1e-9, 1e-7, 1e-5, -1e-9, -1e-5] {
            // b = t + (s, 0, dz): {x ≥ s, y ≥ 0, z ≥ max(dz, 0), …}; faces
            // y = 0 (and z = 0 when dz = 0) flush.
            let b = shift(&t, [s, 0.0, dz]);
            let l = 1.0 - s - dz.max(0.0);
            let want = l * l * l / 6.0;
            let i = tet_tet_intersection(&t.map(rot), &b.map(rot));
            let j = tet_tet_intersection(&b.map(rot), &t.map(rot));
            assert!(
                close(i.volume, want, 1e-8 * want),
                "dz {dz}: {} vs {want}",
                i.volume
            );
            assert!(close(i.volume, j.volume, 1e-15), "dz {dz}");
            // Faces < 1e-8 apart are merged as flush: the surface closes to
            // about (perimeter × gap).
            let gap = if dz.abs() < 1e-8 { dz.abs() } else { 0.0 };
            let tol = 1e-14 + 4.0 * gap;
            assert!(close3(i.closure_defect(), [0.0; 3], tol), "dz {dz}");
        }
    }

    #[test]
    fn disjoint_and_touching_give_zero() {
        let t = corner_tet(1.0);
        let mirror = |d: usize| {
            t.map(|p| {
                let mut q = p;
                q[d] = -q[d];
                q
            })
        };
        let cases = [
            shift(&t, [2.0, 0.0, 0.0]),           // far apart
            shift(&t, [1.0, 0.0, 0.0]),           // vertex on vertex
            shift(&t, [0.5, 0.5, 0.0]),           // edge on the slanted face
            shift(&t, [0.4, 0.4, 0.4]),           // AABBs overlap, slanted face separates
            mirror(0),                            // face to face (x = 0), touching
            mirror(2),                            // face to face (z = 0), touching
            shift(&mirror(0), [-1e-3, 0.0, 0.0]), // a gap
            // Edge across edge at (0.5, 0, 0): only the axis e1 × (0, 1, −1) separates.
            [
                [0.5, 1.0, -1.0],
                [0.5, -1.0, 1.0],
                [0.0, -1.0, -1.0],
                [1.0, -1.0, -1.0],
            ],
        ];
        for (k, b) in cases.iter().enumerate() {
            for (x, y) in [(&t, b), (b, &t)] {
                let i = tet_tet_intersection(x, y);
                assert_eq!(i.volume, 0.0, "case {k}");
                assert!(i.faces_a.iter().chain(&i.faces_b).all(|f| f.area == 0.0));
            }
        }
        // Degenerate (flat) tet.
        let flat = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, 0.0]];
        assert_eq!(tet_tet_intersection(&t, &flat).volume, 0.0);
    }

    #[test]
    fn random_pairs_are_symmetric_bounded_and_closed() {
        let mut rng = Rng(0x1234_5678);
        let mut n_pos = 0;
        for _ in 0..2000 {
            let a = rng.tet([0.0; 3]);
            let d = [rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5];
            let b = rng.tet(d);
            let i = tet_tet_intersection(&a, &b);
            let j = tet_tet_intersection(&b, &a);
            let v = i.volume;
            assert!(close(v, j.volume, 1e-14), "{v} {}", j.volume);
            assert!(v <= vol(&a).min(vol(&b)) * (1.0 + 1e-12));
            for f in 0..4 {
                assert!(close(i.faces_a[f].area, j.faces_b[f].area, 1e-14));
            }
            assert!(close3(i.closure_defect(), [0.0; 3], 1e-14));
            if v > 0.0 {
                n_pos += 1;
                assert!(close3(i.centroid, j.centroid, 1e-10));
                // The centroid of a convex set lies inside both tets.
                assert!(i.planes_a.contains(i.centroid, 1e-12));
                assert!(i.planes_b.contains(i.centroid, 1e-12));
            }
        }
        assert!(n_pos > 500, "{n_pos}");
    }

    /// Additivity: splitting a into 4 tets at an interior point.
    #[test]
    fn volume_is_additive_over_a_split() {
        let mut rng = Rng(99);
        for _ in 0..300 {
            let (a, b) = overlapping_pair(&mut rng);
            let w = [
                rng.next() + 0.1,
                rng.next() + 0.1,
                rng.next() + 0.1,
                rng.next() + 0.1,
            ];
            let ws: f64 = w.iter().sum();
            let mut c = [0.0; 3];
            for k in 0..4 {
                for d in 0..3 {
                    c[d] += w[k] / ws * a[k][d];
                }
            }
            let (mut sum, mut first) = (0.0, [0.0; 3]);
            for f in 0..4 {
                let mut sub_tet = a;
                sub_tet[f] = c;
                let i = tet_tet_intersection(&sub_tet, &b);
                sum += i.volume;
                for (m, c) in first.iter_mut().zip(i.centroid) {
                    *m += i.volume * c;
                }
            }
            let i = tet_tet_intersection(&a, &b);
            assert!(close(i.volume, sum, 1e-13), "{} vs {sum}", i.volume);
            let cs = first.map(|x| x / sum);
            assert!(close3(i.centroid, cs, 1e-11), "{:?} {cs:?}", i.centroid);
        }
    }

    /// Jittered-grid Monte Carlo estimate of the volume and centroid.
    #[test]
    fn volume_matches_monte_carlo() {
        let mut rng = Rng(2024);
        for _ in 0..4 {
            let (a, b) = overlapping_pair(&mut rng);
            let i = tet_tet_intersection(&a, &b);
            let (pa, pb) = (&i.planes_a, &i.planes_b);
            // Sample the intersection of the two bounding boxes.
            let mut lo = [f64::MIN; 3];
            let mut hi = [f64::MAX; 3];
            for t in [&a, &b] {
                for d in 0..3 {
                    lo[d] = lo[d].max(t.iter().fold(f64::MAX, |m, p| m.min(p[d])));
                    hi[d] = hi[d].min(t.iter().fold(f64::MIN, |m, p| m.max(p[d])));
                }
            }
            let n = 120;
            let h = [0, 1, 2].map(|d| (hi[d] - lo[d]) / n as f64);
            let (mut count, mut first) = (0usize, [0.0; 3]);
            for ix in 0..n {
                for iy in 0..n {
                    for iz in 0..n {
                        let p = [
                            lo[0] + (ix as f64 + rng.next()) * h[0],
                            lo[1] + (iy as f64 + rng.next()) * h[1],
                            lo[2] + (iz as f64 + rng.next()) * h[2],
                        ];
                        if pa.contains(p, 0.0) && pb.contains(p, 0.0) {
                            count += 1;
                            for d in 0..3 {
                                first[d] += p[d];
                            }
                        }
                    }
                }
            }
            let v_mc = count as f64 * h[0] * h[1] * h[2];
            let rel = (v_mc - i.volume).abs() / i.volume;
            assert!(rel < 5e-3, "MC {v_mc} vs {} ({rel})", i.volume);
            let c_mc = first.map(|x| x / count as f64);
            assert!(close3(c_mc, i.centroid, 2e-3), "{c_mc:?} {:?}", i.centroid);
        }
    }

    #[test]
    fn shape_functions() {
        let mut rng = Rng(5);
        let t = rng.tet([0.0; 3]);
        let p = TetPlanes::new(&t);
        for (k, x) in t.iter().enumerate() {
            let n = p.barycentric(*x);
            for (j, nj) in n.iter().enumerate() {
                assert!(close(*nj, (j == k) as u8 as f64, 1e-13), "{n:?}");
            }
        }
        let c = mean(&t);
        let n = p.barycentric(c);
        assert!(n.iter().all(|x| close(*x, 0.25, 1e-13)));
        let m = p.barycentric_moment(2.0, c.map(|x| 2.0 * x));
        assert!(m.iter().all(|x| close(*x, 0.5, 1e-13)));
    }
}

/// Whether two tets may come within `gap` of each other: false when the
/// projections on one of the eight face normals are more than `gap` apart
/// (then the distance between the tets exceeds `gap`). Conservative: the
/// edge–edge axes are not tried, so a few farther pairs pass. Used to prune
/// contact candidates found by bounding boxes.
pub fn tets_within(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], gap: f64) -> bool {
    planes_within((a, &face_planes(a)), (b, &face_planes(b)), gap)
}

/// Outward unit face normals and offsets of a tet, `[nx, ny, nz, d]` for
/// face f (opposite node f): a point x is beyond the face's plane by
/// n · x − d. For [`planes_within`], built once per tet per search.
pub fn face_planes(t: &[[f64; 3]; 4]) -> [[f64; 4]; 4] {
    std::array::from_fn(|f| {
        let [i, j, k] = TET_FACES[f];
        let mut n = cross(sub(t[j], t[i]), sub(t[k], t[i]));
        // Orient away from the opposite node.
        if dot(n, sub(t[f], t[i])) > 0.0 {
            n = [-n[0], -n[1], -n[2]];
        }
        let len = dot(n, n).sqrt();
        if len == 0.0 {
            // A flat tet: a plane that separates nothing.
            return [0.0, 0.0, 0.0, f64::INFINITY];
        }
        let n = [n[0] / len, n[1] / len, n[2] / len];
        [n[0], n[1], n[2], dot(n, t[i])]
    })
}

/// [`tets_within`] with the face planes of both tets given
/// ([`face_planes`]): false when b lies more than `gap` beyond a face plane
/// of a, or a beyond one of b.
#[inline]
pub fn planes_within(
    (a, pa): (&[[f64; 3]; 4], &[[f64; 4]; 4]),
    (b, pb): (&[[f64; 3]; 4], &[[f64; 4]; 4]),
    gap: f64,
) -> bool {
    for (q, planes) in [(b, pa), (a, pb)] {
        for pl in planes {
            let nearest = q
                .iter()
                .map(|x| pl[0] * x[0] + pl[1] * x[1] + pl[2] * x[2])
                .fold(f64::INFINITY, f64::min);
            if nearest - pl[3] > gap {
                return false;
            }
        }
    }
    true
}

/// The edges of a tet as (node, node).
const TET_EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// [min, max] of the projections x · `dir` of a tet's corners.
#[inline]
fn interval(dir: [f64; 3], t: &[[f64; 3]; 4]) -> [f64; 2] {
    t.iter().fold([f64::MAX, f64::MIN], |[lo, hi], p| {
        let x = dot(dir, *p);
        [lo.min(x), hi.max(x)]
    })
}

/// Clearance, relative to the larger tet's longest edge, by which
/// [`separating_axis`] and [`separated_along`] want two tets apart: far
/// above round-off, so tets they call apart have an empty exact
/// intersection ([`tet_tet_intersection`] gives volume 0), and far below
/// any contact scale.
const WITNESS_GAP: f64 = 1e-9;

/// The squared diagonal of the box around tets a and b (boxes given as
/// low and high corners): the size [`separated_along`] scales its
/// clearance with.
#[inline]
pub fn pair_size2(a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> f64 {
    (0..3)
        .map(|d| {
            let w = a.1[d].max(b.1[d]) - a.0[d].min(b.0[d]);
            w * w
        })
        .sum()
}

/// Whether the projections of a and b on `dir` are apart by more than
/// [`WITNESS_GAP`] of the pair's size.
#[inline]
fn apart_on(dir: [f64; 3], a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], size2: f64) -> bool {
    let ([amin, amax], [bmin, bmax]) = (interval(dir, a), interval(dir, b));
    let gap = WITNESS_GAP * (size2 * dot(dir, dir)).sqrt();
    amax + gap < bmin || bmax + gap < amin
}

/// Whether tets a and b are apart by more than [`WITNESS_GAP`] along the
/// axis coded `axis` (see [`separating_axis`]; 0 is no axis: false);
/// `size2` from [`pair_size2`]. Needs no planes: a face normal or an edge
/// cross product from the corners, then 8 projections.
#[inline]
pub fn separated_along(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], axis: u8, size2: f64) -> bool {
    let axis = axis as usize;
    let dir = match axis {
        1..=8 => {
            let (p, f) = if axis <= 4 {
                (a, axis - 1)
            } else {
                (b, axis - 5)
            };
            let [i, j, k] = TET_FACES[f];
            cross(sub(p[j], p[i]), sub(p[k], p[i]))
        }
        9..=44 => {
            let (ea, eb) = (TET_EDGES[(axis - 9) / 6], TET_EDGES[(axis - 9) % 6]);
            cross(sub(a[ea.1], a[ea.0]), sub(b[eb.1], b[eb.0]))
        }
        _ => return false,
    };
    apart_on(dir, a, b, size2)
}

/// A separating axis of tets a and b with clearance (see
/// [`separated_along`]), coded 1–4 for the normal of face 0–3 of a, 5–8
/// for those of b, 9 + 6 i + j for edge i of a crossed with edge j of b;
/// `None` when they overlap or touch. Kept per contact candidate, it
/// rules the pair out in a few operations while it still separates
/// (temporal coherence), instead of a clipping each substep. The axes are
/// those [`separated_along`] builds, each edge computed once.
pub fn separating_axis(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4]) -> Option<u8> {
    let size2 = pair_size2(super::tet_bounds(a), super::tet_bounds(b));
    for (base, p) in [(1u8, a), (5, b)] {
        for (f, [i, j, k]) in TET_FACES.iter().enumerate() {
            if apart_on(cross(sub(p[*j], p[*i]), sub(p[*k], p[*i])), a, b, size2) {
                return Some(base + f as u8);
            }
        }
    }
    let edges = |p: &[[f64; 3]; 4]| TET_EDGES.map(|(i, j)| sub(p[j], p[i]));
    let (ea, eb) = (edges(a), edges(b));
    for (i, u) in ea.iter().enumerate() {
        for (j, w) in eb.iter().enumerate() {
            if apart_on(cross(*u, *w), a, b, size2) {
                return Some(9 + (6 * i + j) as u8);
            }
        }
    }
    None
}

#[cfg(test)]
mod within_tests {
    use super::*;

    /// The witness axes agree with the exact intersection: an axis is found
    /// for every disjoint pair of the sample, never for an overlapping one,
    /// and the axis found separates the pair when checked alone.
    #[test]
    fn separating_axes_witness_disjoint_pairs() {
        let mut rng = tests::Rng(5);
        let (mut found, mut disjoint, mut edge_axes) = (0, 0, 0);
        for _ in 0..4000 {
            let a = rng.tet([0.0; 3]);
            let d = [rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5].map(|x| 1.6 * x);
            let b = rng.tet(d);
            let v = tet_tet_intersection(&a, &b).volume;
            match separating_axis(&a, &b) {
                Some(axis) => {
                    assert_eq!(v, 0.0, "axis {axis} for an overlap of {v}");
                    let size2 = pair_size2(
                        crate::geometry::tet_bounds(&a),
                        crate::geometry::tet_bounds(&b),
                    );
                    assert!(separated_along(&a, &b, axis, size2));
                    found += 1;
                    if axis >= 9 {
                        edge_axes += 1;
                    }
                }
                None => assert!(v > 0.0 || tets_within(&a, &b, 1e-6), "no axis, volume {v}"),
            }
            if v == 0.0 {
                disjoint += 1;
            }
        }
        assert!(
            found > 0 && found == disjoint,
            "{found} axes for {disjoint} disjoint pairs"
        );
        assert!(
            edge_axes > 0,
            "some pairs are separated only by an edge-edge axis"
        );
        // Touching (no clearance) is not separated; a clear gap is.
        let a = tests::corner_tet(1.0);
        let touching = tests::shift(&a, [0.0, 0.0, -1.0]);
        assert_eq!(separating_axis(&a, &touching), None);
        let apart = tests::shift(&a, [0.0, 0.0, -1.0 - 1e-6]);
        assert!(separating_axis(&a, &apart).is_some());
        assert!(!separated_along(&a, &apart, 0, 1.0));
    }

    #[test]
    fn separated_beyond_the_gap_are_pruned() {
        let a = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        // b is a copy of a shifted along -z by 1 + s: a gap of s below a's base.
        let shifted = |s: f64| a.map(|p| [p[0], p[1], p[2] - 1.0 - s]);
        assert!(!tets_within(&a, &shifted(0.2), 0.1));
        assert!(tets_within(&a, &shifted(0.05), 0.1));
        assert!(tets_within(&a, &a, 0.0));
        // Overlapping tets are always within any gap.
        let b = a.map(|p| [p[0] + 0.1, p[1] + 0.1, p[2] + 0.1]);
        assert!(tets_within(&a, &b, 0.0));
    }
}
