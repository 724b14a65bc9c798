//! Structured Tet4 mesh of an open-top cylindrical container (a cup):
//! [`container_mesh`].

use super::generate::check_center_and_sizes;
use super::{tet_signed_volume, MeshError, TetMesh};

/// Planar section of the container: a disc of radius `inner_radius` (centre
/// node and rings) followed by the wall rings out to the outer radius.
struct Section {
    /// Points relative to the axis.
    points: Vec<[f64; 2]>,
    /// Counter-clockwise triangles.
    tris: Vec<[u32; 3]>,
    /// Index of the first point of the ring at `r = inner_radius`; points
    /// from here on are in the wall (`r >= inner_radius`).
    inner_start: usize,
}

/// Nodes on core ring `i` (`1 <= i <= n_r`) of a disc with `m` boundary
/// nodes: `max(3, round(m i / n_r))`, exactly `m` on the boundary ring.
fn core_ring_size(m: usize, n_r: usize, i: usize) -> usize {
    if i == n_r {
        m
    } else {
        (m as f64 * i as f64 / n_r as f64).round().max(3.0) as usize
    }
}

/// Angle offset of core ring `i`: half a spacing on every other ring counted
/// from the boundary ring (which starts at angle 0).
fn core_ring_offset(n_r: usize, i: usize, size: usize) -> f64 {
    if (n_r - i) % 2 == 1 {
        0.5 * std::f64::consts::TAU / size as f64
    } else {
        0.0
    }
}

/// A closed ring of `m` points numbered from `start`, point `j` at angle
/// `offset + 2 pi j / m`.
#[derive(Clone, Copy)]
struct Ring {
    start: usize,
    m: usize,
    offset: f64,
}

impl Ring {
    fn node(&self, j: usize) -> u32 {
        (self.start + j % self.m) as u32
    }

    fn angle(&self, j: usize) -> f64 {
        self.offset + std::f64::consts::TAU * j as f64 / self.m as f64
    }

    /// Appends the ring's points on the circle of radius `rho`.
    fn push(points: &mut Vec<[f64; 2]>, rho: f64, m: usize, offset: f64) -> Ring {
        let ring = Ring {
            start: points.len(),
            m,
            offset,
        };
        for j in 0..m {
            let (s, c) = ring.angle(j).sin_cos();
            points.push([rho * c, rho * s]);
        }
        ring
    }
}

/// Triangulates the strip between two concentric rings (`inner` at the
/// smaller radius) by a merge walk over the angles: advance the ring whose
/// next point has the smaller angle, the inner one on ties;
/// `inner.m + outer.m` counter-clockwise triangles.
fn merge_strip(tris: &mut Vec<[u32; 3]>, inner: Ring, outer: Ring) {
    let (mut ia, mut ib) = (0, 0);
    while ia < inner.m || ib < outer.m {
        let advance_inner =
            ib == outer.m || (ia < inner.m && inner.angle(ia + 1) <= outer.angle(ib + 1));
        if advance_inner {
            tris.push([inner.node(ia), outer.node(ib), inner.node(ia + 1)]);
            ia += 1;
        } else {
            tris.push([inner.node(ia), outer.node(ib), outer.node(ib + 1)]);
            ib += 1;
        }
    }
}

/// Builds the section: a centre node and `n_core` rings out to `r_in`
/// (ring `i` at radius `r_in i / n_core`, [`core_ring_size`] points,
/// alternately staggered), joined by a fan and merge strips; then `n_wall`
/// strips of aligned rings with `m` points each from `r_in` to `r_out`.
fn section(r_in: f64, r_out: f64, m: usize, n_core: usize, n_wall: usize) -> Section {
    let mut points = vec![[0.0, 0.0]];
    let mut tris = Vec::new();
    let mut prev: Option<Ring> = None;
    for i in 1..=n_core {
        let size = core_ring_size(m, n_core, i);
        let rho = if i == n_core {
            r_in
        } else {
            r_in * (i as f64 / n_core as f64)
        };
        let ring = Ring::push(&mut points, rho, size, core_ring_offset(n_core, i, size));
        match prev {
            None => {
                for j in 0..size {
                    tris.push([0, ring.node(j), ring.node(j + 1)]);
                }
            }
            Some(p) => merge_strip(&mut tris, p, ring),
        }
        prev = Some(ring);
    }
    let inner_start = points.len() - m;
    let mut prev = prev.expect("n_core >= 1");
    for i in 1..=n_wall {
        // r_i = r_in + (r_out - r_in) i / n_wall, exactly r_out at the end.
        let rho = if i == n_wall {
            r_out
        } else {
            r_in + (r_out - r_in) * (i as f64 / n_wall as f64)
        };
        let ring = Ring::push(&mut points, rho, m, 0.0);
        merge_strip(&mut tris, prev, ring);
        prev = ring;
    }
    Section {
        points,
        tris,
        inner_start,
    }
}

/// Tetrahedral mesh of an open-top cylindrical container (a cup) with its
/// axis along z through `(center[0], center[1])`: a floor disc of radius
/// `inner_radius + wall` from `z = center[2] - bottom` to `z = center[2]`
/// (the floor's top, where particles rest, is exactly at `center[2]`), and
/// a wall `inner_radius <= r <= inner_radius + wall` from `z = center[2]` to
/// `center[2] + height` (`height` is the inner height). One conforming mesh:
/// floor and wall share the nodes of the annulus at `z = center[2]`.
///
/// * Section: `m = 8 max(2, round(2 pi inner_radius / (8 h)))` nodes (a
///   multiple of 8, spacing about `h` on the inner circle) on every wall
///   ring, all at angles `2 pi j / m` exactly on their circles;
///   `n_w = max(1, round(wall / h))` wall strips (aligned rings, each cell a
///   convex trapezoid split in 2 triangles). Inside `r = inner_radius`,
///   `n_c = max(1, round(inner_radius / h))` concentric rings (ring `i` at
///   radius `inner_radius i / n_c` with `max(3, round(m i / n_c))` nodes,
///   alternately staggered by half a spacing) around a centre node, joined
///   by a fan at the centre and a merge walk over angles (as
///   [`cylinder_mesh`](super::generate::cylinder_mesh)); no degenerate
///   elements at the centre. The meshed section is the inscribed regular
///   `m`-gon of each circle.
/// * Layers: `n_f = max(1, round(bottom / h))` floor layers (whole section)
///   and `n_h = max(1, round(height / h))` wall layers (wall strips only),
///   uniform, with the end layers exactly at `center[2] - bottom`,
///   `center[2]` and `center[2] + height`. Each prism is split into 3
///   tetrahedra by the sorted-vertex rule on the section indices (every
///   vertical quad cut along the diagonal from the bottom node of its
///   lower-index section point), conforming; all elements positive.
/// * Numbering: floor layers `0..=n_f` (whole section each, section order:
///   centre, rings inside out), then wall layers `1..=n_h` (wall points of
///   the section only, from the inner circle out). Elements: floor layers
///   then wall layers, by section triangle, 3 per prism.
/// * Volume (`P(m, r) = (m / 2) r^2 sin(2 pi / m)`, the inscribed `m`-gon):
///   `bottom P(m, r_o) + height (P(m, r_o) - P(m, r_i))`, with
///   `r_i = inner_radius`, `r_o = inner_radius + wall`. With the deficit
///   `D(r) = pi r^2 - P(m, r) = r^2 (pi - (m/2) sin(2 pi / m))`, increasing
///   in `r` and at most `(pi / 6) r^2 (2 pi / m)^2`, the mesh is below the
///   exact cup by `bottom D(r_o) + height (D(r_o) - D(r_i))`, which is
///   positive and at most `(pi / 6)(2 pi / m)^2 r_o^2 (bottom + height)`.
/// * Body id 0, element set `all`. Face sets (outward) and node sets (the
///   nodes of the face set): `floor` (top of the floor inside the wall,
///   `z = center[2]`, `r <= inner_radius`), `wall_inner` (inner wall face,
///   `r = inner_radius`), `inner` (`floor` + `wall_inner`: every face a
///   particle inside can touch), `rim` (top annulus of the wall),
///   `outer` (outer wall face over the full height + the underside).
///   The boundary is exactly `inner` + `rim` + `outer`.
///
/// Errors: non-finite centre, non-positive or non-finite sizes
/// ([`MeshError::InvalidParameter`]); more than `u32::MAX` nodes or
/// [`MAX_ELEMENTS`](super::MAX_ELEMENTS) elements ([`MeshError::TooLarge`]); degenerate elements for extreme
/// aspect ratios (from [`TetMesh::validate`]).
pub fn container_mesh(
    center: [f64; 3],
    inner_radius: f64,
    wall: f64,
    bottom: f64,
    height: f64,
    h: f64,
) -> Result<TetMesh, MeshError> {
    check_center_and_sizes(
        "container",
        center,
        &[
            ("inner_radius", inner_radius),
            ("wall", wall),
            ("bottom", bottom),
            ("height", height),
            ("element size h", h),
        ],
    )?;
    let r_out = inner_radius + wall;
    let m_f = 8.0
        * (std::f64::consts::TAU * inner_radius / (8.0 * h))
            .round()
            .max(2.0);
    let n_c_f = (inner_radius / h).round().max(1.0);
    let n_w_f = (wall / h).round().max(1.0);
    let n_f_f = (bottom / h).round().max(1.0);
    let n_h_f = (height / h).round().max(1.0);
    // Lower bounds on the node count: m (n_w + 1) per wall layer, and at
    // least 3 n_c + 1 per floor layer.
    let layers = n_f_f + n_h_f + 1.0;
    if m_f * (n_w_f + 1.0) * layers > u32::MAX as f64
        || (3.0 * n_c_f + 1.0) * (n_f_f + 1.0) > u32::MAX as f64
    {
        return Err(MeshError::TooLarge(format!(
            "container mesh with {m_f} nodes around, {n_c_f} floor rings, {n_w_f} wall cells, \
             {n_f_f} + {n_h_f} layers (h {h}) exceeds {} nodes; increase h",
            u32::MAX
        )));
    }
    let (m, n_c, n_w, n_f, n_h) = (
        m_f as usize,
        n_c_f as usize,
        n_w_f as usize,
        n_f_f as usize,
        n_h_f as usize,
    );
    // Exact counts before allocating.
    let core_pts: u128 = 1
        + (1..=n_c)
            .map(|i| core_ring_size(m, n_c, i) as u128)
            .sum::<u128>();
    let n2d = core_pts + (m * n_w) as u128;
    let n_wall_pts = (m * (n_w + 1)) as u128;
    let n_wall_tris = (2 * m * n_w) as u128;
    let n_tris = core_ring_size(m, n_c, 1) as u128
        + (1..n_c)
            .map(|i| (core_ring_size(m, n_c, i) + core_ring_size(m, n_c, i + 1)) as u128)
            .sum::<u128>()
        + n_wall_tris;
    let num_nodes = n2d * (n_f as u128 + 1) + n_wall_pts * n_h as u128;
    let num_elems = 3 * (n_tris * n_f as u128 + n_wall_tris * n_h as u128);
    if num_nodes > u32::MAX as u128 || num_elems > u32::MAX as u128 {
        return Err(MeshError::TooLarge(format!(
            "container mesh has {num_nodes} nodes and {num_elems} elements (limit {} each); \
             increase h",
            u32::MAX
        )));
    }
    super::check_element_count(
        &format!("container mesh with {m} nodes around and {n_f} + {n_h} layers"),
        num_elems,
    )?;

    let sec = section(inner_radius, r_out, m, n_c, n_w);
    let n2d = sec.points.len();
    let s0 = sec.inner_start;
    let n_wall_pts = n2d - s0;
    debug_assert_eq!(n_wall_pts, m * (n_w + 1));

    // Levels: 0..=n_f floor (z from center.z - bottom to center.z), then
    // n_f + j for wall layer j = 1..=n_h (up to center.z + height).
    let zc = center[2];
    let level_z = |lv: usize| {
        if lv <= n_f {
            match lv {
                _ if lv == n_f => zc,
                0 => zc - bottom,
                _ => zc - bottom + bottom * (lv as f64 / n_f as f64),
            }
        } else {
            let j = lv - n_f;
            if j == n_h {
                zc + height
            } else {
                zc + height * (j as f64 / n_h as f64)
            }
        }
    };
    // Global id of section point p on level lv (wall levels hold p >= s0).
    let first_wall = (n_f + 1) * n2d;
    let gid = |lv: usize, p: usize| -> u32 {
        if lv <= n_f {
            (lv * n2d + p) as u32
        } else {
            (first_wall + (lv - n_f - 1) * n_wall_pts + (p - s0)) as u32
        }
    };
    let total_nodes = first_wall + n_h * n_wall_pts;
    let mut nodes = Vec::with_capacity(total_nodes);
    let mut node_level = Vec::with_capacity(total_nodes);
    let mut node_point = Vec::with_capacity(total_nodes);
    for lv in 0..=n_f + n_h {
        let z = level_z(lv);
        let range = if lv <= n_f { 0..n2d } else { s0..n2d };
        for p in range {
            debug_assert_eq!(gid(lv, p) as usize, nodes.len());
            let q = sec.points[p];
            nodes.push([center[0] + q[0], center[1] + q[1], z]);
            node_level.push(lv);
            node_point.push(p);
        }
    }

    let wall_tris: Vec<[u32; 3]> = sec
        .tris
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&p| p as usize >= s0))
        .collect();
    debug_assert_eq!(wall_tris.len(), 2 * m * n_w);
    let mut tets = Vec::with_capacity(num_elems as usize);
    for lv in 0..n_f + n_h {
        let tris = if lv < n_f { &sec.tris } else { &wall_tris };
        for t in tris {
            // Sorted-vertex rule: a < b < c by section index, primes on top.
            let mut s = t.map(|p| p as usize);
            s.sort_unstable();
            let [a, b, c] = s.map(|p| gid(lv, p));
            let [a1, b1, c1] = s.map(|p| gid(lv + 1, p));
            for mut tet in [[a, b, c, c1], [a, b, b1, c1], [a, a1, b1, c1]] {
                if tet_signed_volume(&tet.map(|v| nodes[v as usize])) < 0.0 {
                    tet.swap(2, 3);
                }
                tets.push(tet);
            }
        }
    }
    let mut mesh = TetMesh::one_body(nodes, tets);
    // No element may be degenerate (only possible for extreme aspect ratios).
    mesh.validate()?;

    let top = n_f + n_h;
    let on_inner = |p: usize| (s0..s0 + m).contains(&p);
    let on_outer = |p: usize| p >= n2d - m;
    let (mut floor, mut wall_inner, mut rim, mut outer) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for bf in mesh.boundary_faces() {
        let f = bf.nodes;
        let lv = f.map(|v| node_level[v as usize]);
        let p = f.map(|v| node_point[v as usize]);
        if lv.iter().all(|&l| l == top) {
            rim.push(f);
        } else if lv.iter().all(|&l| l == 0) {
            outer.push(f);
        } else if lv.iter().all(|&l| l == n_f) {
            // Top of the floor; the wall annulus at this level is interior.
            floor.push(f);
        } else if p.iter().all(|&q| on_outer(q)) {
            outer.push(f);
        } else {
            debug_assert!(p.iter().all(|&q| on_inner(q)) && lv.iter().all(|&l| l >= n_f));
            wall_inner.push(f);
        }
    }
    let inner: Vec<[u32; 3]> = floor.iter().chain(&wall_inner).copied().collect();
    for (name, faces) in [
        ("floor", floor),
        ("wall_inner", wall_inner),
        ("inner", inner),
        ("rim", rim),
        ("outer", outer),
    ] {
        mesh.face_sets.insert(name.to_string(), faces);
        let ns = mesh.nodes_of_face_set(name).unwrap_or_default();
        mesh.node_sets.insert(name.to_string(), ns);
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::assert_conforming;
    use std::f64::consts::PI;

    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// Area of the regular m-gon inscribed in a circle of radius r.
    fn polygon_area(m: usize, r: f64) -> f64 {
        0.5 * m as f64 * r * r * (2.0 * PI / m as f64).sin()
    }

    fn radius(c: [f64; 3], p: [f64; 3]) -> f64 {
        (p[0] - c[0]).hypot(p[1] - c[1])
    }

    /// Thorough checks; returns (nodes, tets, min quality, m).
    fn check_container(
        c: [f64; 3],
        ri: f64,
        wall: f64,
        bottom: f64,
        height: f64,
        h: f64,
    ) -> (usize, usize, f64, usize) {
        let mesh = container_mesh(c, ri, wall, bottom, height, h).unwrap();
        mesh.validate().unwrap();
        mesh.check_closed_volume().unwrap();
        let ro = ri + wall;
        assert!(mesh.body.iter().all(|&b| b == 0));
        assert_eq!(
            mesh.elem_sets["all"],
            (0..mesh.num_elems() as u32).collect::<Vec<_>>()
        );

        // Nodes on the inner circle at the floor top: m.
        let m = mesh
            .nodes
            .iter()
            .filter(|p| p[2] == c[2] && (radius(c, **p) - ri).abs() < 1e-12 * ri)
            .count();
        assert_eq!(m % 8, 0);
        assert_eq!(m, 8 * ((2.0 * PI * ri / (8.0 * h)).round() as usize).max(2));

        // Volume of the polygonal cup, and within the polygon bound of the
        // exact one: pi r^2 - P(m, r) <= (pi / 6) r^2 (2 pi / m)^2.
        let v = mesh.total_volume();
        let expect =
            bottom * polygon_area(m, ro) + height * (polygon_area(m, ro) - polygon_area(m, ri));
        assert!(rel(v, expect) < 1e-12, "volume {v} vs {expect}");
        let exact = PI * ro * ro * bottom + PI * (ro * ro - ri * ri) * height;
        let t = 2.0 * PI / m as f64;
        let bound = PI / 6.0 * t * t * ro * ro * (bottom + height);
        assert!(
            v < exact && exact - v <= bound,
            "{v} vs {exact} (bound {bound})"
        );

        // Conforming.
        assert_conforming(&mesh);

        // inner + rim + outer partition the boundary; inner = floor + wall_inner.
        let bf = mesh.boundary_faces();
        let mut all: Vec<[u32; 3]> = bf.iter().map(|f| f.nodes).collect();
        let mut named: Vec<[u32; 3]> = ["inner", "rim", "outer"]
            .iter()
            .flat_map(|n| mesh.face_sets[*n].iter().copied())
            .collect();
        all.sort_unstable();
        named.sort_unstable();
        assert_eq!(named, all);
        let mut a: Vec<[u32; 3]> = mesh.face_sets["inner"].clone();
        let mut b: Vec<[u32; 3]> = ["floor", "wall_inner"]
            .iter()
            .flat_map(|n| mesh.face_sets[*n].iter().copied())
            .collect();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
        for name in ["inner", "outer", "rim", "floor", "wall_inner"] {
            assert!(!mesh.face_sets[name].is_empty(), "{name}");
            assert_eq!(
                mesh.node_sets[name],
                mesh.nodes_of_face_set(name).unwrap(),
                "{name}"
            );
        }

        let centroid = |f: &[u32; 3]| {
            let mut x = [0.0; 3];
            for &v in f {
                for (xd, pd) in x.iter_mut().zip(mesh.nodes[v as usize]) {
                    *xd += pd / 3.0;
                }
            }
            x
        };
        let radial = |f: &[u32; 3], n: [f64; 3]| {
            let x = centroid(f);
            (n[0] * (x[0] - c[0]) + n[1] * (x[1] - c[1])) / radius(c, x)
        };
        // Floor: z = center.z exactly, up, inside the inner circle, area P(m, ri).
        let mut area = 0.0;
        for f in &mesh.face_sets["floor"] {
            let (fa, n) = mesh.face_area_normal(*f);
            area += fa;
            assert!((n[2] - 1.0).abs() < 1e-12, "floor normal {n:?}");
        }
        assert!(rel(area, polygon_area(m, ri)) < 1e-12);
        for &v in &mesh.node_sets["floor"] {
            let p = mesh.nodes[v as usize];
            assert_eq!(p[2], c[2], "floor node {v}");
            assert!(radius(c, p) <= ri * (1.0 + 1e-12));
        }
        // Inner wall: r = ri, normals towards the axis, from z = c.z to c.z + height.
        for &v in &mesh.node_sets["wall_inner"] {
            let p = mesh.nodes[v as usize];
            assert!((radius(c, p) - ri).abs() < 1e-12 * ri, "wall node {v}");
            assert!(p[2] >= c[2] && p[2] <= c[2] + height);
        }
        let n_h = ((height / h).round() as usize).max(1);
        assert_eq!(mesh.node_sets["wall_inner"].len(), m * (n_h + 1));
        assert_eq!(mesh.face_sets["wall_inner"].len(), 2 * m * n_h);
        for f in &mesh.face_sets["wall_inner"] {
            let (_, n) = mesh.face_area_normal(*f);
            assert!(n[2].abs() < 1e-12 && radial(f, n) < -0.9, "{n:?}");
        }
        // Rim: up, at the top, area P(m, ro) - P(m, ri).
        let mut area = 0.0;
        for f in &mesh.face_sets["rim"] {
            let (fa, n) = mesh.face_area_normal(*f);
            area += fa;
            assert!((n[2] - 1.0).abs() < 1e-12);
            assert!(f
                .iter()
                .all(|&v| mesh.nodes[v as usize][2] == c[2] + height));
        }
        assert!(rel(area, polygon_area(m, ro) - polygon_area(m, ri)) < 1e-12);
        // Outer: down at z = c.z - bottom, or outward on r = ro.
        let (mut under, mut side) = (0.0, 0usize);
        for f in &mesh.face_sets["outer"] {
            let (fa, n) = mesh.face_area_normal(*f);
            if f.iter()
                .all(|&v| mesh.nodes[v as usize][2] == c[2] - bottom)
            {
                assert!((n[2] + 1.0).abs() < 1e-12, "{n:?}");
                under += fa;
            } else {
                assert!(n[2].abs() < 1e-12 && radial(f, n) > 0.9, "{n:?}");
                for &v in f {
                    let r = radius(c, mesh.nodes[v as usize]);
                    assert!((r - ro).abs() < 1e-12 * ro);
                }
                side += 1;
            }
        }
        assert!(rel(under, polygon_area(m, ro)) < 1e-12);
        let n_f = ((bottom / h).round() as usize).max(1);
        assert_eq!(side, 2 * m * (n_f + n_h));
        let (lo, hi) = mesh.bounding_box().unwrap();
        assert_eq!((lo[2], hi[2]), (c[2] - bottom, c[2] + height));
        assert_eq!(
            mesh,
            container_mesh(c, ri, wall, bottom, height, h).unwrap(),
            "not deterministic"
        );
        let q = mesh.min_quality().unwrap().0;
        (mesh.num_nodes(), mesh.num_elems(), q, m)
    }

    #[test]
    fn container_seed_size() {
        let (nn, ne, q, m) = check_container([0.0; 3], 0.225, 0.02, 0.02, 0.5, 0.02);
        println!("container ri=0.225 wall=0.02 bottom=0.02 height=0.5 h=0.02: {nn} nodes, {ne} tets, m = {m}, min quality {q:.3}");
        assert_eq!(m, 72);
        assert!(ne <= 40_000, "{ne} tets");
        assert!(q > 0.2, "min quality {q}");
    }

    #[test]
    fn container_various_sizes_and_offsets() {
        for (c, ri, wall, bottom, height, h) in [
            ([1.0, -2.0, 0.3], 0.225, 0.02, 0.02, 0.5, 0.05),
            ([0.0; 3], 0.1, 0.05, 0.03, 0.2, 0.01),
            ([0.0; 3], 1.0, 0.1, 0.2, 1.0, 1.0),
            ([0.0; 3], 0.01, 0.001, 0.001, 0.02, 0.05),
            ([0.3, 0.0, -5.0], 0.5, 0.3, 0.1, 0.4, 0.07),
        ] {
            let (nn, ne, q, m) = check_container(c, ri, wall, bottom, height, h);
            println!(
                "container ri={ri} wall={wall} bottom={bottom} height={height} h={h}: \
                 {nn} nodes, {ne} tets, m = {m}, min quality {q:.3}"
            );
            assert!(q > 0.0);
        }
    }

    /// The floor section is valid over a sweep of radius / h (positive
    /// triangles are enforced by validate() inside container_mesh).
    #[test]
    fn container_floor_sweep() {
        let mut worst = f64::INFINITY;
        for k in 1..=120 {
            let ri = 0.05 * k as f64;
            let mesh = container_mesh([0.0; 3], ri, 0.1, 0.1, 0.1, 0.1).unwrap();
            mesh.check_closed_volume().unwrap();
            worst = worst.min(mesh.min_quality().unwrap().0);
        }
        println!("container floor sweep: worst quality {worst:.3}");
        assert!(worst > 0.1, "worst quality {worst}");
    }

    #[test]
    fn container_rejects_bad_parameters() {
        for (c, ri, wall, bottom, height, h) in [
            ([0.0; 3], 0.0, 0.02, 0.02, 0.5, 0.02),
            ([0.0; 3], 0.2, -0.02, 0.02, 0.5, 0.02),
            ([0.0; 3], 0.2, 0.02, 0.0, 0.5, 0.02),
            ([0.0; 3], 0.2, 0.02, 0.02, f64::NAN, 0.02),
            ([0.0; 3], 0.2, 0.02, 0.02, 0.5, 0.0),
            ([0.0; 3], 0.2, 0.02, 0.02, 0.5, f64::INFINITY),
            ([0.0, 0.0, f64::NAN], 0.2, 0.02, 0.02, 0.5, 0.02),
        ] {
            let e = container_mesh(c, ri, wall, bottom, height, h).unwrap_err();
            assert!(matches!(e, MeshError::InvalidParameter(_)), "{e}");
        }
        let e = container_mesh([0.0; 3], 1.0, 0.1, 0.1, 1.0, 1e-6).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge(_)), "{e}");
    }
}
