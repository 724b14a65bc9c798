//! Structured mesh generators (no external mesher needed): [`box_mesh`],
//! [`cylinder_mesh`], [`annulus_mesh`] (hollow cylinder) and
//! [`concentric_cylinder_mesh`] (core bonded inside a ring).

use super::{tet_signed_volume, MeshError, TetMesh};

/// Where the nodes of a generated circular boundary lie.
///
/// A boundary of `n` straight segments cannot be the circle. Nodes on the
/// circle make the inscribed polygon: the section is smaller than the disc by
/// about `pi r^2 theta^2 / 6` (`theta = 2 pi / n`) and the facets lie inside
/// the circle everywhere but at the nodes. Nodes at `r sqrt(theta / sin
/// theta)` make a polygon with the disc's area: the body has its true volume
/// (mass, heat capacity) and the facets' radial deviation from the circle
/// averages zero, so a quantity that depends on where the surface is (the
/// contact surface of two overlapping discs, seed 000 sec 5) is unbiased
/// over the possible node alignments instead of always too small.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CircleNodes {
    /// Boundary nodes on the circle (the inscribed polygon, a mesher's usual choice).
    #[default]
    Inscribed,
    /// Boundary nodes at `r sqrt(theta / sin theta)`: the polygon has the circle's area.
    AreaPreserving,
}

impl CircleNodes {
    /// Radius of the boundary nodes of a circle of radius `radius` drawn
    /// with `n` segments.
    pub fn node_radius(self, radius: f64, n: usize) -> f64 {
        match self {
            CircleNodes::Inscribed => radius,
            CircleNodes::AreaPreserving => {
                // (n/2) R^2 sin(2 pi / n) = pi r^2.
                let theta = std::f64::consts::TAU / n as f64;
                radius * (theta / theta.sin()).sqrt()
            }
        }
    }
}

/// Kuhn (Freudenthal) split of the unit cube into 6 positively oriented
/// tetrahedra sharing the main diagonal from corner 0 to corner 7. Corner
/// `c` has offsets `(c & 1, (c >> 1) & 1, (c >> 2) & 1)`. Each tet walks
/// 0 -> +e_a -> +e_a+e_b -> 7 for a permutation (a, b, c) of the axes (the
/// last two nodes swapped for odd permutations to keep positive orientation).
/// Because every cell uses the same diagonal direction, the split of each
/// cell face matches the neighbouring cell's, so the mesh is conforming.
const KUHN_TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7], // x, y, z
    [0, 1, 7, 5], // x, z, y (odd)
    [0, 2, 7, 3], // y, x, z (odd)
    [0, 2, 6, 7], // y, z, x
    [0, 4, 5, 7], // z, x, y
    [0, 4, 7, 6], // z, y, x (odd)
];

/// Names of the 6 box sides, in the order (axis, min/max).
const SIDES: [&str; 6] = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"];

/// Number of cells along an axis of length `len` with target spacing `h`.
pub(crate) fn cells(len: f64, h: f64) -> Result<usize, MeshError> {
    let n = (len / h).round().max(1.0);
    if n > u32::MAX as f64 {
        return Err(MeshError::TooLarge(format!(
            "{n} cells along one axis (length {len}, h {h})"
        )));
    }
    Ok(n as usize)
}

/// Tetrahedral mesh of the box `[origin, origin + size]` with target element
/// size `h`.
///
/// * `n_d = max(1, round(size[d] / h))` cells along axis `d`, uniform
///   spacing `size[d] / n_d`; nodes on the max sides are exactly at
///   `origin[d] + size[d]`.
/// * Each hexahedral cell is split into 6 tetrahedra sharing the cell
///   diagonal from its min corner to its max corner (Kuhn/Freudenthal
///   split), which is conforming across cells. All elements are positively
///   oriented.
/// * Node `(i, j, k)` (grid indices, `0 <= i <= n_x`, ...) has index
///   `i + (n_x + 1) * (j + (n_y + 1) * k)`: x fastest, then y, then z.
///   Elements are ordered by cell (same x-fastest order), 6 per cell.
/// * Body id 0 for all elements. Face sets and node sets `xmin`, `xmax`,
///   `ymin`, `ymax`, `zmin`, `zmax` (faces oriented outward), and an element
///   set `all`.
///
/// Errors: non-finite origin, non-positive or non-finite size or `h`
/// ([`MeshError::InvalidParameter`]); more than `u32::MAX` nodes or
/// [`MAX_ELEMENTS`](super::MAX_ELEMENTS) elements ([`MeshError::TooLarge`]).
pub fn box_mesh(origin: [f64; 3], size: [f64; 3], h: f64) -> Result<TetMesh, MeshError> {
    if !origin.iter().all(|v| v.is_finite()) {
        return Err(MeshError::InvalidParameter(format!(
            "box origin {origin:?} must be finite"
        )));
    }
    if !size.iter().all(|v| v.is_finite() && *v > 0.0) {
        return Err(MeshError::InvalidParameter(format!(
            "box size {size:?} must be positive and finite"
        )));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(MeshError::InvalidParameter(format!(
            "element size h = {h} must be positive and finite"
        )));
    }
    let n = [cells(size[0], h)?, cells(size[1], h)?, cells(size[2], h)?];
    let num_nodes = (n[0] as u128 + 1) * (n[1] as u128 + 1) * (n[2] as u128 + 1);
    let num_elems = 6 * n[0] as u128 * n[1] as u128 * n[2] as u128;
    if num_nodes > u32::MAX as u128 || num_elems > u32::MAX as u128 {
        return Err(MeshError::TooLarge(format!(
            "box mesh with {}x{}x{} cells has {num_nodes} nodes and {num_elems} elements \
             (limit {} each); increase h",
            n[0],
            n[1],
            n[2],
            u32::MAX
        )));
    }
    super::check_element_count(
        &format!("box mesh with {}x{}x{} cells", n[0], n[1], n[2]),
        num_elems,
    )?;
    let (sx, sy) = (n[0] + 1, n[1] + 1);
    let id = |i: usize, j: usize, k: usize| (i + sx * (j + sy * k)) as u32;
    let coord = |d: usize, i: usize| origin[d] + size[d] * (i as f64 / n[d] as f64);

    let mut nodes = Vec::with_capacity(num_nodes as usize);
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                nodes.push([coord(0, i), coord(1, j), coord(2, k)]);
            }
        }
    }

    let mut tets = Vec::with_capacity(num_elems as usize);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let corner = |c: usize| id(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                for t in KUHN_TETS {
                    tets.push(t.map(corner));
                }
            }
        }
    }
    let mut mesh = TetMesh::one_body(nodes, tets);

    // Grid index of a node along axis d.
    let grid = |v: u32, d: usize| {
        let v = v as usize;
        match d {
            0 => v % sx,
            1 => (v / sx) % sy,
            _ => v / (sx * sy),
        }
    };
    // Side index (0..6) on which all nodes of a boundary face lie.
    let side_of = |f: &[u32; 3]| {
        (0..3).find_map(|d| {
            if f.iter().all(|&v| grid(v, d) == 0) {
                Some(2 * d)
            } else if f.iter().all(|&v| grid(v, d) == n[d]) {
                Some(2 * d + 1)
            } else {
                None
            }
        })
    };
    let mut faces: [Vec<[u32; 3]>; 6] = Default::default();
    for bf in mesh.boundary_faces() {
        if let Some(s) = side_of(&bf.nodes) {
            faces[s].push(bf.nodes);
        }
    }
    for (s, f) in faces.into_iter().enumerate() {
        mesh.face_sets.insert(SIDES[s].to_string(), f);
    }
    let mut node_sets: [Vec<u32>; 6] = Default::default();
    for v in 0..mesh.nodes.len() as u32 {
        for d in 0..3 {
            let g = grid(v, d);
            if g == 0 {
                node_sets[2 * d].push(v);
            }
            if g == n[d] {
                node_sets[2 * d + 1].push(v);
            }
        }
    }
    for (s, ns) in node_sets.into_iter().enumerate() {
        mesh.node_sets.insert(SIDES[s].to_string(), ns);
    }
    Ok(mesh)
}

/// Move every node not on the boundary by a deterministic pseudo-random
/// offset in [−a, a]³ (a = `amplitude`), turning a structured mesh into an
/// irregular one for tests. `seed` selects the sequence. Fails if a tet
/// would invert (keep `amplitude` below about a fifth of the spacing).
pub fn jitter_interior(mesh: &mut TetMesh, amplitude: f64, seed: u64) -> Result<(), MeshError> {
    let mut on_boundary = vec![false; mesh.nodes.len()];
    for f in mesh.boundary_faces() {
        for n in f.nodes {
            on_boundary[n as usize] = true;
        }
    }
    // SplitMix64: small, deterministic, good enough for mesh jitter.
    let mut state = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    };
    for (n, p) in mesh.nodes.iter_mut().enumerate() {
        if !on_boundary[n] {
            for x in p.iter_mut() {
                *x += amplitude * (2.0 * next() - 1.0);
            }
        }
    }
    mesh.validate()
}

/// Triangulation of a disc centred at the origin, built by [`disc_triangulation`].
struct Disc {
    /// Node coordinates relative to the disc centre; node 0 is the centre,
    /// then the rings from the inside out; the last `n_boundary` nodes are
    /// the boundary ring, starting at angle 0.
    points: Vec<[f64; 2]>,
    /// Counter-clockwise triangles.
    tris: Vec<[u32; 3]>,
}

/// Number of nodes on each of the `n_r` rings (inner to outer) of the disc
/// triangulation: `max(3, round(n_b * i / n_r))` on ring `i`, so the spacing
/// along every ring is close to the boundary spacing, and exactly `n_b` on
/// the boundary ring.
fn ring_sizes(n_b: usize, n_r: usize) -> Vec<usize> {
    (1..=n_r)
        .map(|i| {
            if i == n_r {
                n_b
            } else {
                (n_b as f64 * i as f64 / n_r as f64).round().max(3.0) as usize
            }
        })
        .collect()
}

/// Angle of node `j` (`0 <= j <= m`, `j = m` being node 0 again, one turn
/// later) on a ring of `m` nodes. Rings are staggered by half a spacing on
/// every other ring counted from the boundary, which has a node at angle 0.
fn ring_angle(ring: usize, n_r: usize, m: usize, j: usize) -> f64 {
    let step = std::f64::consts::TAU / m as f64;
    let offset = if (n_r - ring) % 2 == 1 {
        0.5 * step
    } else {
        0.0
    };
    offset + step * j as f64
}

/// Disc of radius `radius` triangulated with `n_r` concentric rings (ring
/// `i` at radius `radius * i / n_r`, node counts from [`ring_sizes`]) around
/// a single centre node. The centre is joined to ring 1 by a fan; each
/// annulus between consecutive rings is triangulated by a merge walk over
/// the node angles (advance the ring whose next node has the smaller angle,
/// the inner ring on ties), which closes on the starting edge after
/// `m_inner + m_outer` triangles. Adjacent annuli share their ring's edges,
/// so the triangulation is conforming. The outer ring's nodes lie at
/// `nodes.node_radius(radius, n_b)`.
fn disc_triangulation(radius: f64, n_b: usize, n_r: usize, nodes: CircleNodes) -> Disc {
    let sizes = ring_sizes(n_b, n_r);
    let mut points = Vec::with_capacity(1 + sizes.iter().sum::<usize>());
    points.push([0.0, 0.0]);
    let mut start = Vec::with_capacity(n_r);
    for (i, &m) in sizes.iter().enumerate() {
        let ring = i + 1;
        start.push(points.len());
        let rho = if ring == n_r {
            nodes.node_radius(radius, m)
        } else {
            radius * ring as f64 / n_r as f64
        };
        for j in 0..m {
            let (s, c) = ring_angle(ring, n_r, m, j).sin_cos();
            points.push([rho * c, rho * s]);
        }
    }
    let mut tris = Vec::new();
    let m1 = sizes[0];
    for j in 0..m1 {
        let a = start[0] + j;
        let b = start[0] + (j + 1) % m1;
        tris.push([0, a as u32, b as u32]);
    }
    // Ring `r` (1-based) as a `RingNodes`; its angles are exactly those of
    // `ring_angle` (offset + step * j, the offset being ring_angle at j = 0).
    let ring = |r: usize| {
        let m = sizes[r - 1];
        RingNodes {
            start: start[r - 1],
            m,
            offset: ring_angle(r, n_r, m, 0),
        }
    };
    for i in 1..n_r {
        merge_strip(&mut tris, ring(i), ring(i + 1));
    }
    Disc { points, tris }
}

/// A closed ring of `m` nodes of a planar section, numbered consecutively
/// from `start`, node `j` at angle `offset + (2 pi / m) j` (counter-clockwise).
#[derive(Debug, Clone, Copy)]
struct RingNodes {
    start: usize,
    m: usize,
    offset: f64,
}

impl RingNodes {
    /// Index of node `k` (taken modulo `m`, so `k = m` is node 0 again).
    fn node(&self, k: usize) -> u32 {
        (self.start + k % self.m) as u32
    }

    /// Angle of node `j`, `0 <= j <= m` (`j = m` is node 0 one turn later).
    fn angle(&self, j: usize) -> f64 {
        let step = std::f64::consts::TAU / self.m as f64;
        self.offset + step * j as f64
    }
}

/// Triangulates the strip between two concentric rings (`inner` at the
/// smaller radius) by a merge walk over the node angles: advance the ring
/// whose next node has the smaller angle (the inner ring on ties); closes
/// on the starting edge after `inner.m + outer.m` counter-clockwise
/// triangles. Both rings must start near angle 0.
fn merge_strip(tris: &mut Vec<[u32; 3]>, inner: RingNodes, outer: RingNodes) {
    let (ma, mb) = (inner.m, outer.m);
    let (mut ia, mut ib) = (0, 0);
    while ia < ma || ib < mb {
        let advance_inner = ib == mb || (ia < ma && inner.angle(ia + 1) <= outer.angle(ib + 1));
        if advance_inner {
            tris.push([inner.node(ia), outer.node(ib), inner.node(ia + 1)]);
            ia += 1;
        } else {
            tris.push([inner.node(ia), outer.node(ib), outer.node(ib + 1)]);
            ib += 1;
        }
    }
}

/// z of the `n_z + 1` layers of a slab `[zc - width/2, zc + width/2]`,
/// uniform, with the end layers exactly at the ends.
fn layer_zs(zc: f64, width: f64, n_z: usize) -> Vec<f64> {
    let z_lo = zc - 0.5 * width;
    let z_hi = zc + 0.5 * width;
    (0..=n_z)
        .map(|k| {
            if k == n_z {
                z_hi
            } else {
                z_lo + width * (k as f64 / n_z as f64)
            }
        })
        .collect()
}

/// Extrudes a counter-clockwise planar triangulation (`points` relative to
/// `(center[0], center[1])`) through the layers `zs` (ascending).
///
/// Nodes: layer by layer, each numbered like `points`. Each prism
/// (triangle x layer) is split into 3 tetrahedra by the sorted-vertex rule:
/// with the triangle's nodes ordered by global index `a < b < c` (primes on
/// the top layer), `(a,b,c,c')`, `(a,b,b',c')`, `(a,a',b',c')`, i.e. every
/// quad face is cut along the diagonal from its lowest-index bottom node.
/// The rule depends only on the nodes of the shared quad, so neighbouring
/// prisms match and the mesh is conforming. Elements are reoriented (local
/// nodes 2 and 3 swapped) where needed to be positive; they are ordered by
/// layer, then triangle, 3 per prism.
fn extrude(
    center: [f64; 3],
    zs: &[f64],
    points: &[[f64; 2]],
    tris: &[[u32; 3]],
) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let n2d = points.len();
    let n_z = zs.len() - 1;
    let mut nodes = Vec::with_capacity(n2d * zs.len());
    for &z in zs {
        for p in points {
            nodes.push([center[0] + p[0], center[1] + p[1], z]);
        }
    }
    let mut tets = Vec::with_capacity(3 * tris.len() * n_z);
    for k in 0..n_z {
        let (bot, top) = ((k * n2d) as u32, ((k + 1) * n2d) as u32);
        for t in tris {
            let mut s = *t;
            s.sort_unstable();
            let [a, b, c] = s.map(|v| v + bot);
            let [a1, b1, c1] = s.map(|v| v + top);
            for mut tet in [[a, b, c, c1], [a, b, b1, c1], [a, a1, b1, c1]] {
                let x = tet.map(|v| nodes[v as usize]);
                if tet_signed_volume(&x) < 0.0 {
                    tet.swap(2, 3);
                }
                tets.push(tet);
            }
        }
    }
    (nodes, tets)
}

/// Tetrahedral mesh of a solid circular cylinder (a thick disc) with its
/// axis along z through `(center[0], center[1])`, extending from
/// `z = center[2] - width/2` to `center[2] + width/2`, with target element
/// size `h`.
///
/// * Cross-section: `n_b = max(8, round(2 pi radius / h))` boundary nodes
///   evenly spaced on a circle, one at angle 0 (the +x direction). With
///   [`CircleNodes::Inscribed`] they lie exactly on the circle of radius
///   `radius` (node `center + (radius, 0, z)` on every layer) and the meshed
///   cross-section is the inscribed regular `n_b`-gon; with
///   [`CircleNodes::AreaPreserving`] on the circle of radius
///   `radius sqrt(theta / sin theta)`, `theta = 2 pi / n_b`, so the `n_b`-gon
///   has the area `pi radius^2`.
///   Inside, `n_r = max(1, round(radius / h))` concentric rings (ring `i` at
///   radius `radius * i / n_r` with `max(3, round(n_b i / n_r))` nodes,
///   alternate rings staggered by half a spacing) around a centre node,
///   triangulated by a fan at the centre and a merge walk over angles in
///   each annulus (deterministic, conforming, counter-clockwise).
/// * Extrusion: `n_z = max(1, round(width / h))` uniform layers. Each prism
///   (triangle x layer) is split into 3 tetrahedra by the sorted-vertex
///   rule: with the triangle's nodes ordered by global index `a < b < c`
///   (primes on the top layer), every quad face is cut along the diagonal
///   from its lowest-index bottom node, giving `(a,b,c,c')`, `(a,b,b',c')`,
///   `(a,a',b',c')`. The rule depends only on the nodes of the shared quad,
///   so neighbouring prisms match and the mesh is conforming. Elements are
///   reoriented (local nodes 2 and 3 swapped) where needed to be positive.
/// * Node numbering: layer by layer from the bottom (`z` min), each layer
///   numbered like the cross-section (centre, rings inside out, boundary ring
///   last, counter-clockwise from angle 0). Elements are ordered by layer,
///   then triangle, 3 per prism.
/// * Body id 0 for all elements. Face sets and node sets `side`, `zmin`,
///   `zmax` (faces oriented outward), and an element set `all`.
///
/// Errors: non-finite centre, non-positive or non-finite radius, width or
/// `h` ([`MeshError::InvalidParameter`]); more than `u32::MAX` nodes or
/// [`MAX_ELEMENTS`](super::MAX_ELEMENTS) elements ([`MeshError::TooLarge`]);
/// degenerate elements for extreme aspect ratios (`width` many orders of magnitude below `h`, from
/// [`TetMesh::validate`]).
pub fn cylinder_mesh(
    center: [f64; 3],
    radius: f64,
    width: f64,
    h: f64,
    nodes: CircleNodes,
) -> Result<TetMesh, MeshError> {
    check_center_and_sizes(
        "cylinder",
        center,
        &[("radius", radius), ("width", width), ("element size h", h)],
    )?;
    let n_b_f = (std::f64::consts::TAU * radius / h).round().max(8.0);
    let n_r_f = (radius / h).round().max(1.0);
    let n_z_f = (width / h).round().max(1.0);
    // Beyond these the mesh certainly exceeds u32::MAX nodes (the rings hold
    // at least about n_b n_r / 2 nodes per layer, with n_b >= 8).
    if n_b_f * n_r_f > 1e11 || n_z_f > 1e10 {
        return Err(MeshError::TooLarge(format!(
            "cylinder mesh with {n_b_f} boundary nodes, {n_r_f} rings and {n_z_f} layers \
             (radius {radius}, width {width}, h {h}) exceeds {} nodes; increase h",
            u32::MAX
        )));
    }
    let (n_b, n_r, n_z) = (n_b_f as usize, n_r_f as usize, n_z_f as usize);
    let sizes = ring_sizes(n_b, n_r);
    let n2d = 1 + sizes.iter().map(|&m| m as u128).sum::<u128>();
    let n_tri = sizes[0] as u128
        + sizes
            .windows(2)
            .map(|w| (w[0] + w[1]) as u128)
            .sum::<u128>();
    let num_nodes = n2d * (n_z as u128 + 1);
    let num_elems = 3 * n_tri * n_z as u128;
    if num_nodes > u32::MAX as u128 || num_elems > u32::MAX as u128 {
        return Err(MeshError::TooLarge(format!(
            "cylinder mesh with {n_b} boundary nodes, {n_r} rings and {n_z} layers has \
             {num_nodes} nodes and {num_elems} elements (limit {} each); increase h",
            u32::MAX
        )));
    }
    super::check_element_count(
        &format!("cylinder mesh with {n_b} boundary nodes, {n_r} rings and {n_z} layers"),
        num_elems,
    )?;

    let disc = disc_triangulation(radius, n_b, n_r, nodes);
    let n2d = disc.points.len();
    let zs = layer_zs(center[2], width, n_z);
    let (nodes, tets) = extrude(center, &zs, &disc.points, &disc.tris);
    let mut mesh = TetMesh::one_body(nodes, tets);
    // No element may be degenerate (only possible for extreme aspect ratios).
    mesh.validate()?;

    let layer = |v: u32| v as usize / n2d;
    let (mut side, mut zmin, mut zmax) = (Vec::new(), Vec::new(), Vec::new());
    for bf in mesh.boundary_faces() {
        if bf.nodes.iter().all(|&v| layer(v) == 0) {
            zmin.push(bf.nodes);
        } else if bf.nodes.iter().all(|&v| layer(v) == n_z) {
            zmax.push(bf.nodes);
        } else {
            side.push(bf.nodes);
        }
    }
    mesh.face_sets.insert("side".to_string(), side);
    mesh.face_sets.insert("zmin".to_string(), zmin);
    mesh.face_sets.insert("zmax".to_string(), zmax);
    let side_nodes = (0..=n_z)
        .flat_map(|k| (k * n2d + n2d - n_b)..((k + 1) * n2d))
        .map(|v| v as u32)
        .collect();
    mesh.node_sets.insert("side".to_string(), side_nodes);
    mesh.node_sets
        .insert("zmin".to_string(), (0..n2d as u32).collect());
    mesh.node_sets.insert(
        "zmax".to_string(),
        ((n_z * n2d) as u32..((n_z + 1) * n2d) as u32).collect(),
    );
    Ok(mesh)
}

/// Rings of the section of an annulus `a <= r <= b` (inner ring given): ring
/// `i` (`0 <= i <= n_r`) at radius `a + (b - a) i / n_r` (exactly `a` and
/// `b` at the ends) with `m0` nodes on ring 0 and
/// `max(8, round(2 pi r_i / h))` on ring `i >= 1`, except that a single
/// strip (`n_r = 1`) keeps `m0` nodes on both rings. All rings start at
/// angle 0 (no stagger).
///
/// Why: with equal counts and aligned nodes every strip cell is a convex
/// trapezoid, valid however thin the annulus; with `n_r >= 2` the radial
/// spacing is at least `0.75 h`, enough for the merge walk between rings
/// of different counts to give positive triangles (checked over a wide
/// parameter sweep in the tests).
#[derive(Debug, Clone, Copy)]
struct AnnulusRings {
    a: f64,
    b: f64,
    n_r: usize,
    m0: usize,
    h: f64,
}

impl AnnulusRings {
    fn radius(&self, i: usize) -> f64 {
        if i == 0 {
            self.a
        } else if i == self.n_r {
            self.b
        } else {
            self.a + (self.b - self.a) * (i as f64 / self.n_r as f64)
        }
    }

    fn size(&self, i: usize) -> usize {
        if i == 0 || self.n_r == 1 {
            self.m0
        } else {
            (std::f64::consts::TAU * self.radius(i) / self.h)
                .round()
                .max(8.0) as usize
        }
    }

    /// Nodes on rings `1..=n_r` and triangles of the `n_r` strips, without
    /// allocating; stops counting once the nodes exceed `u32::MAX`.
    fn counts(&self) -> (u128, u128) {
        let (mut nodes, mut tris) = (0u128, 0u128);
        for i in 1..=self.n_r {
            let m = self.size(i) as u128;
            nodes += m;
            tris += self.size(i - 1) as u128 + m;
            if nodes > u32::MAX as u128 {
                break;
            }
        }
        (nodes, tris)
    }

    /// Appends the points of rings `1..=n_r` (counter-clockwise from angle
    /// 0) and the strip triangles, ring 0 being `inner` (already in
    /// `points`, `m0` nodes from angle 0). Returns the outer ring.
    fn build(
        &self,
        points: &mut Vec<[f64; 2]>,
        tris: &mut Vec<[u32; 3]>,
        inner: RingNodes,
    ) -> RingNodes {
        debug_assert_eq!((inner.m, inner.offset), (self.m0, 0.0));
        let mut prev = inner;
        for i in 1..=self.n_r {
            let ring = push_ring(points, self.radius(i), self.size(i));
            merge_strip(tris, prev, ring);
            prev = ring;
        }
        prev
    }
}

/// Appends `m` points on the circle of radius `rho` about the origin,
/// counter-clockwise from angle 0, and returns them as a ring.
fn push_ring(points: &mut Vec<[f64; 2]>, rho: f64, m: usize) -> RingNodes {
    let ring = RingNodes {
        start: points.len(),
        m,
        offset: 0.0,
    };
    for j in 0..m {
        let (s, c) = ring.angle(j).sin_cos();
        points.push([rho * c, rho * s]);
    }
    ring
}

/// Checks a generator's centre (finite) and sizes (positive and finite),
/// naming the generator `what` and the offending parameter.
pub(crate) fn check_center_and_sizes(
    what: &str,
    center: [f64; 3],
    params: &[(&str, f64)],
) -> Result<(), MeshError> {
    if !center.iter().all(|v| v.is_finite()) {
        return Err(MeshError::InvalidParameter(format!(
            "{what} center {center:?} must be finite"
        )));
    }
    for &(name, v) in params {
        if !(v.is_finite() && v > 0.0) {
            return Err(MeshError::InvalidParameter(format!(
                "{what} {name} = {v} must be positive and finite"
            )));
        }
    }
    Ok(())
}

/// Checks a ring generator's centre and positive parameters.
fn check_ring_params(
    what: &str,
    center: [f64; 3],
    params: &[(&str, f64)],
    inner: (&str, f64),
    outer: (&str, f64),
) -> Result<(), MeshError> {
    check_center_and_sizes(what, center, params)?;
    if inner.1 >= outer.1 {
        return Err(MeshError::InvalidParameter(format!(
            "{what} {} = {} must be below {} = {}",
            inner.0, inner.1, outer.0, outer.1
        )));
    }
    Ok(())
}

/// Rejects ring meshes that certainly exceed the `u32` index range before
/// anything is counted or allocated: every layer holds at least
/// `8 (n_r + 1)` and at least `n_b` nodes.
fn check_ring_size_bound(
    what: &str,
    n_b: f64,
    n_r: f64,
    n_z: f64,
    h: f64,
) -> Result<(), MeshError> {
    let layers = n_z + 1.0;
    if n_z > 1e10 || 8.0 * (n_r + 1.0) * layers > u32::MAX as f64 || n_b * layers > u32::MAX as f64
    {
        return Err(MeshError::TooLarge(format!(
            "{what} mesh with {n_b} outer nodes, {n_r} radial cells and {n_z} layers (h {h}) \
             exceeds {} nodes; increase h",
            u32::MAX
        )));
    }
    Ok(())
}

/// Rejects ring meshes whose exact counts exceed the `u32` index range or
/// [`MAX_ELEMENTS`](super::MAX_ELEMENTS).
fn check_ring_counts(what: &str, n2d: u128, n_tri: u128, n_z: usize) -> Result<(), MeshError> {
    let num_nodes = n2d * (n_z as u128 + 1);
    let num_elems = 3 * n_tri * n_z as u128;
    if num_nodes > u32::MAX as u128 || num_elems > u32::MAX as u128 {
        return Err(MeshError::TooLarge(format!(
            "{what} mesh with {n2d} nodes per layer and {n_z} layers has {num_nodes} nodes and \
             {num_elems} elements (limit {} each); increase h",
            u32::MAX
        )));
    }
    super::check_element_count(
        &format!("{what} mesh with {n2d} nodes per layer and {n_z} layers"),
        num_elems,
    )
}

/// Builds the extruded mesh (body 0, element set `all`) and its sets:
/// `zmin`, `zmax` (end layers), and for each `(name, flags)` of `circles`
/// the nodes whose section point is flagged and the boundary faces all of
/// whose nodes are flagged (faces oriented outward).
fn extruded_mesh_with_sets(
    center: [f64; 3],
    height: f64,
    n_z: usize,
    points: &[[f64; 2]],
    tris: &[[u32; 3]],
    circles: &[(&str, &[bool])],
) -> Result<TetMesh, MeshError> {
    let zs = layer_zs(center[2], height, n_z);
    let (nodes, tets) = extrude(center, &zs, points, tris);
    let mut mesh = TetMesh::one_body(nodes, tets);
    // No element may be degenerate (only possible for extreme aspect ratios).
    mesh.validate()?;

    let n2d = points.len();
    let layer = |v: u32| v as usize / n2d;
    let (mut zmin, mut zmax) = (Vec::new(), Vec::new());
    let mut side: Vec<Vec<[u32; 3]>> = vec![Vec::new(); circles.len()];
    for bf in mesh.boundary_faces() {
        if bf.nodes.iter().all(|&v| layer(v) == 0) {
            zmin.push(bf.nodes);
        } else if bf.nodes.iter().all(|&v| layer(v) == n_z) {
            zmax.push(bf.nodes);
        } else {
            let c = circles
                .iter()
                .position(|(_, on)| bf.nodes.iter().all(|&v| on[v as usize % n2d]))
                .expect("every side face of an extruded ring mesh lies on a named circle");
            side[c].push(bf.nodes);
        }
    }
    mesh.face_sets.insert("zmin".to_string(), zmin);
    mesh.face_sets.insert("zmax".to_string(), zmax);
    for ((name, on), faces) in circles.iter().zip(side) {
        mesh.face_sets.insert(name.to_string(), faces);
        let nodes = (0..=n_z)
            .flat_map(|k| {
                (0..n2d)
                    .filter(|&p| on[p])
                    .map(move |p| (k * n2d + p) as u32)
            })
            .collect();
        mesh.node_sets.insert(name.to_string(), nodes);
    }
    mesh.node_sets
        .insert("zmin".to_string(), (0..n2d as u32).collect());
    mesh.node_sets.insert(
        "zmax".to_string(),
        ((n_z * n2d) as u32..((n_z + 1) * n2d) as u32).collect(),
    );
    Ok(mesh)
}

/// Flags of the section points `ring.start .. ring.start + ring.m`.
fn ring_flags(n2d: usize, ring: RingNodes) -> Vec<bool> {
    (0..n2d)
        .map(|p| (ring.start..ring.start + ring.m).contains(&p))
        .collect()
}

/// Tetrahedral mesh of a hollow circular cylinder (a thick annulus
/// `inner_radius <= r <= outer_radius`) with its axis along z through
/// `(center[0], center[1])`, extending from `z = center[2] - height/2` to
/// `center[2] + height/2` (the convention of [`cylinder_mesh`]), with target
/// element size `h`.
///
/// * Cross-section: `n_r = max(1, round((b - a) / h))` radial cells; ring
///   `i` at radius `a + (b - a) i / n_r` (`a`, `b` the radii) carries
///   `max(8, round(2 pi r_i / h))` nodes evenly spaced from angle 0 (the +x
///   direction), so the spacing along every ring is about `h`; a single
///   radial cell (`n_r = 1`) uses the inner ring's count on both rings.
///   Boundary nodes lie exactly on the circles `r = a` and `r = b` (to
///   rounding), so the meshed section lies between the inscribed regular
///   polygons. Consecutive rings are joined by a merge walk over angles
///   (counter-clockwise triangles, conforming).
/// * Extrusion: `n_z = max(1, round(height / h))` uniform layers, each
///   prism split into 3 tetrahedra by the sorted-vertex rule as in
///   [`cylinder_mesh`] (conforming, all elements positively oriented).
/// * Volume: `V = height (P(m_b, b) - P(m_a, a))` with
///   `P(m, r) = (m/2) r^2 sin(2 pi / m)` the inscribed `m`-gon area, so
///   `|V - pi (b^2 - a^2) height| <= (pi / 6) height max(a^2 t_a^2, b^2 t_b^2)`
///   with `t = 2 pi / m` (about `pi h^2 height / 6`).
/// * Node numbering: layer by layer from the bottom, each layer ring by ring
///   from the inside out, counter-clockwise from angle 0. Elements are
///   ordered by layer, then triangle, 3 per prism.
/// * Body id 0 for all elements. Face sets and node sets `inner`, `outer`,
///   `zmin`, `zmax` (faces oriented outward: `inner` faces point towards
///   the axis), and an element set `all`.
///
/// Errors: non-finite centre, non-positive or non-finite radii, height or
/// `h`, `inner_radius >= outer_radius` ([`MeshError::InvalidParameter`]);
/// more than `u32::MAX` nodes or [`MAX_ELEMENTS`](super::MAX_ELEMENTS)
/// elements ([`MeshError::TooLarge`]); degenerate elements for extreme
/// aspect ratios (from [`TetMesh::validate`]).
pub fn annulus_mesh(
    center: [f64; 3],
    inner_radius: f64,
    outer_radius: f64,
    height: f64,
    h: f64,
) -> Result<TetMesh, MeshError> {
    const WHAT: &str = "annulus";
    check_ring_params(
        WHAT,
        center,
        &[
            ("inner_radius", inner_radius),
            ("outer_radius", outer_radius),
            ("height", height),
            ("element size h", h),
        ],
        ("inner_radius", inner_radius),
        ("outer_radius", outer_radius),
    )?;
    let tau = std::f64::consts::TAU;
    let n_r_f = ((outer_radius - inner_radius) / h).round().max(1.0);
    let n_z_f = (height / h).round().max(1.0);
    let n_b_f = (tau * outer_radius / h).round().max(8.0);
    check_ring_size_bound(WHAT, n_b_f, n_r_f, n_z_f, h)?;
    // At most n_b_f, as inner_radius < outer_radius.
    let m0 = (tau * inner_radius / h).round().max(8.0);
    let rings = AnnulusRings {
        a: inner_radius,
        b: outer_radius,
        n_r: n_r_f as usize,
        m0: m0 as usize,
        h,
    };
    let n_z = n_z_f as usize;
    let (n_ring_nodes, n_tri) = rings.counts();
    check_ring_counts(WHAT, rings.m0 as u128 + n_ring_nodes, n_tri, n_z)?;

    let mut points = Vec::with_capacity(rings.m0 + n_ring_nodes as usize);
    let mut tris = Vec::with_capacity(n_tri as usize);
    let inner = push_ring(&mut points, inner_radius, rings.m0);
    let outer = rings.build(&mut points, &mut tris, inner);
    let n2d = points.len();
    extruded_mesh_with_sets(
        center,
        height,
        n_z,
        &points,
        &tris,
        &[
            ("inner", &ring_flags(n2d, inner)),
            ("outer", &ring_flags(n2d, outer)),
        ],
    )
}

/// Tetrahedral mesh of a solid circular cylinder of radius `outer_radius`
/// made of a core (`r <= core_radius`) bonded to a ring
/// (`core_radius <= r <= outer_radius`): one conforming mesh whose core and
/// ring share the nodes on `r = core_radius`. Axis along z through
/// `(center[0], center[1])`, from `z = center[2] - height/2` to
/// `center[2] + height/2` (as [`cylinder_mesh`]); target element size `h`.
///
/// * Core section: exactly the section of
///   `cylinder_mesh(center, core_radius, height, h)` (centre node, staggered
///   rings, `n_c = max(8, round(2 pi core_radius / h))` nodes on the
///   interface circle, one at angle 0).
/// * Ring section: as [`annulus_mesh`] from `core_radius` to `outer_radius`,
///   its inner ring being the core's interface ring (same nodes).
/// * Extrusion, numbering (layer by layer; in each layer the core's points,
///   interface ring last, then the ring's rings inside out), element order
///   and orientation as in [`cylinder_mesh`]. The meshed volume is
///   `height P(m_b, outer_radius)` (inscribed polygon, see
///   [`annulus_mesh`]); the core's is `height P(n_c, core_radius)`.
/// * Body id 0 for all elements; element sets `core`, `ring` (a partition)
///   and `all`. Node sets and face sets `outer`, `zmin`, `zmax` (boundary
///   faces oriented outward) and `interface`: the nodes on
///   `r = core_radius` and the interior triangles there, oriented with the
///   normal pointing out of the core into the ring (each is a face of one
///   core and one ring element, and is not a boundary face).
///
/// Errors: as [`annulus_mesh`] (`core_radius >= outer_radius` is an
/// [`MeshError::InvalidParameter`]).
pub fn concentric_cylinder_mesh(
    center: [f64; 3],
    core_radius: f64,
    outer_radius: f64,
    height: f64,
    h: f64,
) -> Result<TetMesh, MeshError> {
    const WHAT: &str = "concentric cylinder";
    check_ring_params(
        WHAT,
        center,
        &[
            ("core_radius", core_radius),
            ("outer_radius", outer_radius),
            ("height", height),
            ("element size h", h),
        ],
        ("core_radius", core_radius),
        ("outer_radius", outer_radius),
    )?;
    let tau = std::f64::consts::TAU;
    // Core parameters exactly as cylinder_mesh(center, core_radius, ..).
    let n_c_f = (tau * core_radius / h).round().max(8.0);
    let n_rc_f = (core_radius / h).round().max(1.0);
    let n_r_f = ((outer_radius - core_radius) / h).round().max(1.0);
    let n_z_f = (height / h).round().max(1.0);
    let n_b_f = (tau * outer_radius / h).round().max(8.0);
    check_ring_size_bound(WHAT, n_b_f, n_r_f, n_z_f, h)?;
    // As in cylinder_mesh: the core's rings alone then exceed u32::MAX nodes.
    if n_c_f * n_rc_f > 1e11 {
        return Err(MeshError::TooLarge(format!(
            "{WHAT} mesh with {n_c_f} interface nodes and {n_rc_f} core rings (h {h}) \
             exceeds {} nodes; increase h",
            u32::MAX
        )));
    }
    let (n_c, n_rc, n_z) = (n_c_f as usize, n_rc_f as usize, n_z_f as usize);
    let core_sizes = ring_sizes(n_c, n_rc);
    let core_nodes = 1 + core_sizes.iter().map(|&m| m as u128).sum::<u128>();
    let core_tris = core_sizes[0] as u128
        + core_sizes
            .windows(2)
            .map(|w| (w[0] + w[1]) as u128)
            .sum::<u128>();
    let rings = AnnulusRings {
        a: core_radius,
        b: outer_radius,
        n_r: n_r_f as usize,
        m0: n_c,
        h,
    };
    let (ring_nodes, ring_tris) = rings.counts();
    check_ring_counts(WHAT, core_nodes + ring_nodes, core_tris + ring_tris, n_z)?;

    let disc = disc_triangulation(core_radius, n_c, n_rc, CircleNodes::Inscribed);
    let n_core_tris = disc.tris.len();
    let (mut points, mut tris) = (disc.points, disc.tris);
    let interface = RingNodes {
        start: points.len() - n_c,
        m: n_c,
        offset: 0.0,
    };
    // The disc's boundary ring is unstaggered (angle 0 first), as the
    // annulus rings expect.
    debug_assert_eq!(ring_angle(n_rc, n_rc, n_c, 0), 0.0);
    let outer = rings.build(&mut points, &mut tris, interface);
    let n2d = points.len();
    let on_interface = ring_flags(n2d, interface);
    let mut mesh = extruded_mesh_with_sets(
        center,
        height,
        n_z,
        &points,
        &tris,
        &[("outer", &ring_flags(n2d, outer))],
    )?;

    // Elements are ordered by layer, then triangle, 3 per prism.
    let n_tri = tris.len();
    let (core, ring): (Vec<u32>, Vec<u32>) =
        (0..mesh.num_elems() as u32).partition(|&e| (e as usize / 3) % n_tri < n_core_tris);
    // Interface triangles: faces of core elements with all nodes on the
    // interface circle (a section triangle never has all three vertices on
    // one ring, so these are exactly the faces on r = core_radius).
    let mut iface = Vec::new();
    for &e in &core {
        for f in 0..4 {
            let nodes = mesh.local_face_nodes(e as usize, f);
            if nodes.iter().all(|&v| on_interface[v as usize % n2d]) {
                iface.push(nodes);
            }
        }
    }
    mesh.face_sets.insert("interface".to_string(), iface);
    let iface_nodes = (0..=n_z)
        .flat_map(|k| (interface.start..interface.start + n_c).map(move |p| (k * n2d + p) as u32))
        .collect();
    mesh.node_sets.insert("interface".to_string(), iface_nodes);
    mesh.elem_sets.insert("core".to_string(), core);
    mesh.elem_sets.insert("ring".to_string(), ring);
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::super::testutil::assert_conforming;
    use std::collections::HashMap;

    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// A lowered element limit refuses a larger box (naming the limit), only
    /// on its thread and only inside the call; the default takes it.
    #[test]
    fn a_lowered_element_limit_refuses_a_larger_box_and_is_restored() {
        let build = || box_mesh([0.0; 3], [1.0; 3], 0.25);
        let err = crate::mesh::with_element_limit(383, build).unwrap_err();
        assert!(matches!(err, MeshError::TooLarge(_)), "{err}");
        assert!(err.to_string().contains("384 elements") && err.to_string().contains("383"));
        assert_eq!(
            crate::mesh::with_element_limit(384, build)
                .unwrap()
                .tets
                .len(),
            384
        );
        assert_eq!(crate::mesh::element_limit(), crate::mesh::MAX_ELEMENTS);
        let other = std::thread::spawn(move || {
            crate::mesh::with_element_limit(10, || {
                std::thread::spawn(crate::mesh::element_limit)
                    .join()
                    .unwrap()
            })
        });
        assert_eq!(other.join().unwrap(), crate::mesh::MAX_ELEMENTS);
        assert!(build().is_ok());
    }

    #[test]
    fn kuhn_template_is_positive_and_fills_cube() {
        let c = |k: usize| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64];
        let mut total = 0.0;
        for t in KUHN_TETS {
            let v = tet_signed_volume(&t.map(c));
            assert!((v - 1.0 / 6.0).abs() < 1e-15);
            total += v;
        }
        assert!((total - 1.0).abs() < 1e-15);
    }

    fn check_box(origin: [f64; 3], size: [f64; 3], h: f64, n: [usize; 3]) {
        let m = box_mesh(origin, size, h).unwrap();
        m.validate().unwrap();
        assert_eq!(m.num_nodes(), (n[0] + 1) * (n[1] + 1) * (n[2] + 1));
        assert_eq!(m.num_elems(), 6 * n[0] * n[1] * n[2]);
        assert!(m.body.iter().all(|&b| b == 0));
        assert_eq!(m.elem_sets["all"].len(), m.num_elems());
        assert_eq!(
            m.elem_sets["all"][m.num_elems() - 1] as usize,
            m.num_elems() - 1
        );

        let vol = size[0] * size[1] * size[2];
        assert!(rel(m.total_volume(), vol) < 1e-12);

        let bf = m.boundary_faces();
        assert_eq!(
            bf.len(),
            4 * (n[0] * n[1] + n[1] * n[2] + n[0] * n[2]),
            "non-conforming split"
        );
        let area: f64 = bf.iter().map(|f| m.face_area_normal(f.nodes).0).sum();
        let surf = 2.0 * (size[0] * size[1] + size[1] * size[2] + size[0] * size[2]);
        assert!(rel(area, surf) < 1e-12);

        let total_faces: usize = m.face_sets.values().map(|f| f.len()).sum();
        assert_eq!(total_faces, bf.len());
        for (s, name) in SIDES.iter().enumerate() {
            let d = s / 2;
            let is_max = s % 2 == 1;
            let faces = &m.face_sets[*name];
            let side_area = size[(d + 1) % 3] * size[(d + 2) % 3];
            let mut a = 0.0;
            for f in faces {
                let (fa, normal) = m.face_area_normal(*f);
                a += fa;
                let mut expect = [0.0; 3];
                expect[d] = if is_max { 1.0 } else { -1.0 };
                for k in 0..3 {
                    assert!((normal[k] - expect[k]).abs() < 1e-12, "{name}: {normal:?}");
                }
            }
            assert!(rel(a, side_area) < 1e-12, "{name}: {a} vs {side_area}");
            let plane = if is_max {
                origin[d] + size[d]
            } else {
                origin[d]
            };
            let ns = &m.node_sets[*name];
            assert_eq!(ns, &m.nodes_of_face_set(name).unwrap());
            assert_eq!(ns.len(), (n[(d + 1) % 3] + 1) * (n[(d + 2) % 3] + 1));
            for &v in ns {
                assert_eq!(m.nodes[v as usize][d], plane, "{name} node {v}");
            }
        }
        let (lo, hi) = m.bounding_box().unwrap();
        for d in 0..3 {
            assert_eq!(lo[d], origin[d]);
            assert_eq!(hi[d], origin[d] + size[d]);
        }
        let (q, _) = m.min_quality().unwrap();
        assert!(q > 0.1);
    }

    #[test]
    fn unit_cube_single_cell() {
        check_box([0.0; 3], [1.0; 3], 1.0, [1, 1, 1]);
        check_box([0.0; 3], [1.0; 3], 5.0, [1, 1, 1]);
    }

    #[test]
    fn anisotropic_box_with_offset() {
        check_box([-1.5, 2.0, 1e-3], [0.3, 0.2, 0.1], 0.1, [3, 2, 1]);
        check_box([0.1, 0.2, 0.3], [1.0, 0.7, 0.45], 0.1, [10, 7, 5]);
    }

    #[test]
    fn node_numbering_is_x_fastest() {
        let m = box_mesh([0.0; 3], [2.0, 3.0, 4.0], 1.0).unwrap();
        assert_eq!(m.nodes[1], [1.0, 0.0, 0.0]);
        assert_eq!(m.nodes[3], [0.0, 1.0, 0.0]);
        assert_eq!(m.nodes[12], [0.0, 0.0, 1.0]);
        assert_eq!(m.nodes[59], [2.0, 3.0, 4.0]);
    }

    #[test]
    fn rejects_bad_parameters() {
        for (o, s, h) in [
            ([0.0; 3], [1.0, 0.0, 1.0], 0.1),
            ([0.0; 3], [1.0, -1.0, 1.0], 0.1),
            ([0.0; 3], [1.0, f64::INFINITY, 1.0], 0.1),
            ([0.0; 3], [1.0, 1.0, f64::NAN], 0.1),
            ([0.0; 3], [1.0; 3], 0.0),
            ([0.0; 3], [1.0; 3], -1.0),
            ([0.0; 3], [1.0; 3], f64::NAN),
            ([f64::NAN, 0.0, 0.0], [1.0; 3], 0.1),
        ] {
            let e = box_mesh(o, s, h).unwrap_err();
            assert!(matches!(e, MeshError::InvalidParameter(_)), "{e}");
        }
        let e = box_mesh([0.0; 3], [1.0; 3], 1e-6).unwrap_err();
        assert!(matches!(e, MeshError::TooLarge(_)), "{e}");
    }
    /// Signed area of a 2D triangle.
    fn tri_area(p: &[[f64; 2]], t: [u32; 3]) -> f64 {
        let [a, b, c] = t.map(|v| p[v as usize]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }

    /// Area of the regular n-gon inscribed in a circle of radius r.
    fn polygon_area(n: usize, r: f64) -> f64 {
        0.5 * n as f64 * r * r * (std::f64::consts::TAU / n as f64).sin()
    }

    #[test]
    fn disc_triangulation_is_valid_and_conforming() {
        // Every (n_b, n_r) pair cylinder_mesh produces for radius/h up to 40.
        let pairs: std::collections::BTreeSet<(usize, usize)> = (1..=2000)
            .map(|i| {
                let rho = 0.02 * i as f64;
                let n_b = ((std::f64::consts::TAU * rho).round() as usize).max(8);
                (n_b, (rho.round() as usize).max(1))
            })
            .collect();
        let mut min_q = f64::INFINITY;
        for (n_b, n_r) in pairs {
            let d = disc_triangulation(1.3, n_b, n_r, CircleNodes::Inscribed);
            let sizes = ring_sizes(n_b, n_r);
            assert_eq!(d.points.len(), 1 + sizes.iter().sum::<usize>());
            let n_tri = sizes[0] + sizes.windows(2).map(|w| w[0] + w[1]).sum::<usize>();
            assert_eq!(d.tris.len(), n_tri);
            let mut area = 0.0;
            let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
            for &t in &d.tris {
                let a = tri_area(&d.points, t);
                assert!(a > 0.0, "n_b {n_b} n_r {n_r}: triangle {t:?} area {a}");
                area += a;
                let [p, q, r] = t.map(|v| d.points[v as usize]);
                let l2 = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
                let quality = 4.0 * 3f64.sqrt() * a / (l2(p, q) + l2(q, r) + l2(r, p));
                min_q = min_q.min(quality);
                for k in 0..3 {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    *edges.entry((u.min(v), u.max(v))).or_default() += 1;
                }
            }
            assert!(rel(area, polygon_area(n_b, 1.3)) < 1e-12);
            let first_b = (d.points.len() - n_b) as u32;
            let mut n_boundary_edges = 0;
            for ((u, v), count) in edges {
                assert!(count <= 2);
                if count == 1 {
                    assert!(u >= first_b && v >= first_b);
                    n_boundary_edges += 1;
                }
            }
            assert_eq!(n_boundary_edges, n_b);
            assert_eq!(d.points[first_b as usize], [1.3, 0.0]);
        }
        assert!(min_q > 0.4, "worst triangle quality {min_q}");
    }

    /// Checks a cylinder mesh thoroughly; returns (nodes, tets, min quality).
    fn check_cylinder(center: [f64; 3], r: f64, w: f64, h: f64) -> (usize, usize, f64) {
        let m = cylinder_mesh(center, r, w, h, CircleNodes::Inscribed).unwrap();
        m.validate().unwrap();
        let n_b = ((std::f64::consts::TAU * r / h).round() as usize).max(8);
        let n_z = ((w / h).round() as usize).max(1);
        let n_layer = m.num_nodes() / (n_z + 1);
        assert_eq!(n_layer * (n_z + 1), m.num_nodes());
        assert!(m.body.iter().all(|&b| b == 0));
        assert_eq!(
            m.elem_sets["all"],
            (0..m.num_elems() as u32).collect::<Vec<_>>()
        );

        // Volume and surface of the inscribed-polygon prism.
        let area = polygon_area(n_b, r);
        assert!(rel(m.total_volume(), area * w) < 1e-12);
        let perimeter = n_b as f64 * 2.0 * r * (std::f64::consts::PI / n_b as f64).sin();
        let bf = m.boundary_faces();
        let surf: f64 = bf.iter().map(|f| m.face_area_normal(f.nodes).0).sum();
        assert!(rel(surf, perimeter * w + 2.0 * area) < 1e-12);

        // Conforming: no face shared by more than two tets, and the boundary
        // faces are exactly the named sides.
        assert_conforming(&m);
        let n_tri = m.face_sets["zmin"].len();
        assert_eq!(m.face_sets["zmax"].len(), n_tri);
        assert_eq!(m.face_sets["side"].len(), 2 * n_b * n_z);
        assert_eq!(bf.len(), 2 * n_tri + 2 * n_b * n_z);
        assert_eq!(m.num_elems(), 3 * n_tri * n_z);

        // Outward normals and areas of the named sides.
        let (z_lo, z_hi) = (center[2] - 0.5 * w, center[2] + 0.5 * w);
        for (name, nz) in [("zmin", -1.0), ("zmax", 1.0)] {
            let mut a = 0.0;
            for f in &m.face_sets[name] {
                let (fa, n) = m.face_area_normal(*f);
                a += fa;
                assert!((n[2] - nz).abs() < 1e-12, "{name}: {n:?}");
            }
            assert!(rel(a, area) < 1e-12, "{name}");
        }
        let mut a = 0.0;
        for f in &m.face_sets["side"] {
            let (fa, n) = m.face_area_normal(*f);
            a += fa;
            let c: Vec<f64> = (0..2)
                .map(|d| f.iter().map(|&v| m.nodes[v as usize][d]).sum::<f64>() / 3.0 - center[d])
                .collect();
            let radial = (n[0] * c[0] + n[1] * c[1]) / c[0].hypot(c[1]);
            assert!(n[2].abs() < 1e-12 && radial > 0.99, "side normal {n:?}");
        }
        assert!(rel(a, perimeter * w) < 1e-12);

        // Node sets.
        for name in ["side", "zmin", "zmax"] {
            assert_eq!(
                m.node_sets[name],
                m.nodes_of_face_set(name).unwrap(),
                "{name}"
            );
        }
        assert_eq!(m.node_sets["side"].len(), n_b * (n_z + 1));
        for &v in &m.node_sets["side"] {
            let p = m.nodes[v as usize];
            let d = (p[0] - center[0]).hypot(p[1] - center[1]);
            assert!((d - r).abs() < 1e-12 * r, "side node {v} at distance {d}");
        }
        for (name, z) in [("zmin", z_lo), ("zmax", z_hi)] {
            assert_eq!(m.node_sets[name].len(), n_layer);
            assert!(m.node_sets[name]
                .iter()
                .all(|&v| m.nodes[v as usize][2] == z));
        }

        // A node at angle 0 on every layer.
        let mut zs: Vec<f64> = m
            .nodes
            .iter()
            .filter(|p| p[0] == center[0] + r && p[1] == center[1])
            .map(|p| p[2])
            .collect();
        zs.sort_by(f64::total_cmp);
        assert_eq!(zs.len(), n_z + 1);
        for (k, z) in zs.iter().enumerate() {
            let expect = z_lo + w * k as f64 / n_z as f64;
            assert!((z - expect).abs() < 1e-12 * w.max(center[2].abs()));
        }
        assert_eq!((zs[0], zs[n_z]), (z_lo, z_hi));
        let (lo, hi) = m.bounding_box().unwrap();
        assert_eq!((lo[2], hi[2]), (z_lo, z_hi));
        assert_eq!(hi[0], center[0] + r);

        assert_eq!(
            m,
            cylinder_mesh(center, r, w, h, CircleNodes::Inscribed).unwrap(),
            "not deterministic"
        );
        let (q, _) = m.min_quality().unwrap();
        (m.num_nodes(), m.num_elems(), q)
    }

    #[test]
    fn cylinder_seed_000_table3_sizes() {
        for h in [0.08, 0.04] {
            let (nn, ne, q) = check_cylinder([0.0; 3], 1.0, 0.1, h);
            println!("cylinder r=1 w=0.1 h={h}: {nn} nodes, {ne} tets, min quality {q:.3}");
            assert!(q > 0.1, "h = {h}: min quality {q}");
        }
    }

    /// Area-preserving boundary nodes: the section has the circle's area and
    /// the body the cylinder's volume, for coarse and fine boundaries; the
    /// boundary nodes sit on one circle just outside the radius, and nothing
    /// else moves.
    #[test]
    fn area_preserving_cylinder_has_the_true_volume() {
        for (r, w, h) in [
            (1.0, 0.1, 0.08),
            (1.0, 0.1, 0.04),
            (0.3, 0.2, 0.1),
            (2.0, 0.5, 1.0),
        ] {
            let m = cylinder_mesh([0.5, -0.2, 1.0], r, w, h, CircleNodes::AreaPreserving).unwrap();
            m.validate().unwrap();
            assert_conforming(&m);
            let exact = std::f64::consts::PI * r * r * w;
            assert!(
                rel(m.total_volume(), exact) < 1e-12,
                "r {r} h {h}: {}",
                m.total_volume()
            );
            let n_b = ((std::f64::consts::TAU * r / h).round() as usize).max(8);
            let big = CircleNodes::AreaPreserving.node_radius(r, n_b);
            let t = std::f64::consts::TAU / n_b as f64;
            // The outward shift is about r theta^2 / 12 (a little more for coarse n_b).
            assert!(big > r && big - r < r * t * t / 10.0, "{big}");
            let plain = cylinder_mesh([0.5, -0.2, 1.0], r, w, h, CircleNodes::Inscribed).unwrap();
            let side: std::collections::HashSet<u32> =
                m.node_sets["side"].iter().copied().collect();
            for (v, (p, q)) in m.nodes.iter().zip(&plain.nodes).enumerate() {
                let rad = radial_distance([0.5, -0.2, 1.0], *p);
                if side.contains(&(v as u32)) {
                    assert!((rad - big).abs() < 1e-12, "side node {v} at {rad}");
                } else {
                    assert_eq!(p, q, "interior node {v} moved");
                }
            }
        }
    }

    #[test]
    fn cylinder_various_sizes_and_offsets() {
        for (c, r, w, h) in [
            ([0.0; 3], 1.0, 0.1, 1.0),
            ([0.0; 3], 1.0, 0.1, 10.0),
            ([2.0, -1.0, 0.5], 1.0, 0.1, 0.5),
            ([1.99, 0.0, 0.0], 1.0, 0.1, 0.08),
            ([0.0; 3], 0.3, 1.0, 0.05),
            ([-0.1, 0.2, 0.3], 0.05, 0.02, 0.007),
            ([0.0; 3], 2.0, 0.3, 0.1),
        ] {
            let (_, _, q) = check_cylinder(c, r, w, h);
            assert!(q > 0.05, "r {r} w {w} h {h}: min quality {q}");
        }
    }

    #[test]
    fn cylinder_rejects_bad_parameters() {
        for (c, r, w, h) in [
            ([0.0; 3], 0.0, 0.1, 0.1),
            ([0.0; 3], -1.0, 0.1, 0.1),
            ([0.0; 3], f64::NAN, 0.1, 0.1),
            ([0.0; 3], 1.0, 0.0, 0.1),
            ([0.0; 3], 1.0, f64::INFINITY, 0.1),
            ([0.0; 3], 1.0, 0.1, 0.0),
            ([0.0; 3], 1.0, 0.1, -0.1),
            ([0.0, f64::NAN, 0.0], 1.0, 0.1, 0.1),
        ] {
            let e = cylinder_mesh(c, r, w, h, CircleNodes::Inscribed).unwrap_err();
            assert!(matches!(e, MeshError::InvalidParameter(_)), "{e}");
        }
        for (r, w, h) in [(1.0, 0.1, 1e-6), (1.0, 1e12, 1.0), (1.0, 0.1, 2e-4)] {
            let e = cylinder_mesh([0.0; 3], r, w, h, CircleNodes::AreaPreserving).unwrap_err();
            assert!(matches!(e, MeshError::TooLarge(_)), "{e}");
        }
    }

    /// Inscribed-polygon deficit bound: pi r^2 - P(m, r) <= (pi / 6) r^2 (2 pi / m)^2.
    fn polygon_deficit_bound(m: usize, r: f64) -> f64 {
        let t = std::f64::consts::TAU / m as f64;
        std::f64::consts::PI / 6.0 * r * r * t * t
    }

    /// Distance of `p` from the z axis through `center`.
    fn radial_distance(center: [f64; 3], p: [f64; 3]) -> f64 {
        (p[0] - center[0]).hypot(p[1] - center[1])
    }

    /// Checks shared by the ring meshes: conformity, closed outward-oriented
    /// boundary, z sets, node sets equal to the nodes of their face sets and
    /// to the nodes geometrically on their surfaces, normals of the circle
    /// sets `(name, radius, sign)` (`sign` +1: boundary faces pointing away
    /// from the axis, -1: towards it, 0: interior set, node set only).
    /// Returns the minimum element quality.
    fn check_ring_mesh(
        m: &TetMesh,
        center: [f64; 3],
        height: f64,
        circles: &[(&str, f64, f64)],
    ) -> f64 {
        m.validate().unwrap();
        assert!(m.body.iter().all(|&b| b == 0));
        assert_eq!(
            m.elem_sets["all"],
            (0..m.num_elems() as u32).collect::<Vec<_>>()
        );
        let (z_lo, z_hi) = (center[2] - 0.5 * height, center[2] + 0.5 * height);

        // Conforming: no face in more than two tets.
        assert_conforming(m);

        // Closed, consistently oriented boundary: every directed boundary
        // edge appears once and its reverse once, so every boundary edge is
        // shared by exactly two boundary faces.
        let bf = m.boundary_faces();
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for f in &bf {
            for k in 0..3 {
                *directed
                    .entry((f.nodes[k], f.nodes[(k + 1) % 3]))
                    .or_default() += 1;
            }
        }
        for (&(u, v), &c) in &directed {
            assert_eq!(c, 1, "edge {u}-{v} used {c} times in one direction");
            assert_eq!(directed.get(&(v, u)), Some(&1), "open edge {u}-{v}");
        }

        // Boundary faces are exactly the named boundary sets.
        let mut names: Vec<&str> = vec!["zmin", "zmax"];
        names.extend(circles.iter().filter(|c| c.2 != 0.0).map(|c| c.0));
        let total: usize = names.iter().map(|n| m.face_sets[*n].len()).sum();
        assert_eq!(total, bf.len());
        let mut named: Vec<[u32; 3]> = names
            .iter()
            .flat_map(|n| m.face_sets[*n].iter().copied())
            .collect();
        let mut all: Vec<[u32; 3]> = bf.iter().map(|f| f.nodes).collect();
        named.sort_unstable();
        all.sort_unstable();
        assert_eq!(named, all);

        for (name, nz, z) in [("zmin", -1.0, z_lo), ("zmax", 1.0, z_hi)] {
            for f in &m.face_sets[name] {
                let n = m.face_area_normal(*f).1;
                assert!((n[2] - nz).abs() < 1e-12, "{name}: {n:?}");
            }
            let expect: Vec<u32> = (0..m.num_nodes() as u32)
                .filter(|&v| m.nodes[v as usize][2] == z)
                .collect();
            assert_eq!(m.node_sets[name], expect, "{name}");
            assert_eq!(m.node_sets[name], m.nodes_of_face_set(name).unwrap());
        }
        let (lo, hi) = m.bounding_box().unwrap();
        assert_eq!((lo[2], hi[2]), (z_lo, z_hi));

        for &(name, r, sign) in circles {
            let tol = 1e-12 * (r + center[0].abs() + center[1].abs());
            let expect: Vec<u32> = (0..m.num_nodes() as u32)
                .filter(|&v| (radial_distance(center, m.nodes[v as usize]) - r).abs() < tol)
                .collect();
            assert_eq!(m.node_sets[name], expect, "{name}");
            assert!(!expect.is_empty());
            if sign == 0.0 {
                continue;
            }
            assert_eq!(m.node_sets[name], m.nodes_of_face_set(name).unwrap());
            for f in &m.face_sets[name] {
                let (_, n) = m.face_area_normal(*f);
                let c: Vec<f64> = (0..2)
                    .map(|d| {
                        f.iter().map(|&v| m.nodes[v as usize][d]).sum::<f64>() / 3.0 - center[d]
                    })
                    .collect();
                let radial = (n[0] * c[0] + n[1] * c[1]) / c[0].hypot(c[1]);
                assert!(
                    n[2].abs() < 1e-12 && radial * sign > 0.9,
                    "{name} normal {n:?}"
                );
            }
        }
        m.min_quality().unwrap().0
    }

    /// Nodes of the ring of radius r on the bottom layer.
    fn count_on_circle(m: &TetMesh, center: [f64; 3], r: f64, z: f64) -> usize {
        m.nodes
            .iter()
            .filter(|p| p[2] == z && (radial_distance(center, **p) - r).abs() < 1e-12 * r.max(1.0))
            .count()
    }

    /// Checks an annulus mesh; returns (nodes, tets, min quality).
    fn check_annulus(c: [f64; 3], a: f64, b: f64, w: f64, h: f64) -> (usize, usize, f64) {
        let m = annulus_mesh(c, a, b, w, h).unwrap();
        let q = check_ring_mesh(&m, c, w, &[("inner", a, -1.0), ("outer", b, 1.0)]);
        let n_z = ((w / h).round() as usize).max(1);
        let z_lo = c[2] - 0.5 * w;
        let (m_a, m_b) = (
            count_on_circle(&m, c, a, z_lo),
            count_on_circle(&m, c, b, z_lo),
        );
        assert_eq!(m.node_sets["inner"].len(), m_a * (n_z + 1));
        assert_eq!(m.node_sets["outer"].len(), m_b * (n_z + 1));
        assert_eq!(m.face_sets["inner"].len(), 2 * m_a * n_z);
        assert_eq!(m.face_sets["outer"].len(), 2 * m_b * n_z);
        let n_tri = m.face_sets["zmin"].len();
        assert_eq!(m.num_elems(), 3 * n_tri * n_z);

        // Volume: exactly the difference of the inscribed polygons, and
        // within the stated bound of the exact annulus.
        let v = m.total_volume();
        assert!(rel(v, w * (polygon_area(m_b, b) - polygon_area(m_a, a))) < 1e-12);
        let exact = std::f64::consts::PI * (b * b - a * a) * w;
        let bound = w * polygon_deficit_bound(m_a, a).max(polygon_deficit_bound(m_b, b));
        assert!(
            (v - exact).abs() <= bound * (1.0 + 1e-9),
            "{v} vs {exact} (bound {bound})"
        );
        assert_eq!(m, annulus_mesh(c, a, b, w, h).unwrap(), "not deterministic");
        (m.num_nodes(), m.num_elems(), q)
    }

    #[test]
    fn annulus_seed_004_hollow_cylinder() {
        // Seed 004 sec 3.3, Table 2: a = 0.03 m, b = 0.15 m, height 0.01 m.
        for h in [0.01, 0.005] {
            let (nn, ne, q) = check_annulus([0.0; 3], 0.03, 0.15, 0.01, h);
            let m = annulus_mesh([0.0; 3], 0.03, 0.15, 0.01, h).unwrap();
            let v = m.total_volume();
            let exact = std::f64::consts::PI * (0.15f64.powi(2) - 0.03f64.powi(2)) * 0.01;
            println!(
                "annulus a=0.03 b=0.15 height=0.01 h={h}: {nn} nodes, {ne} tets, \
                 min quality {q:.3}, volume rel. error {:.2e}",
                (v - exact) / exact
            );
            assert!(q > 0.2, "h = {h}: min quality {q}");
        }
    }

    #[test]
    fn annulus_various_sizes_and_offsets() {
        for (c, a, b, w, h) in [
            ([0.0; 3], 0.03, 0.15, 0.01, 0.02),
            ([0.0; 3], 1.0, 2.0, 0.1, 0.08),
            ([2.0, -1.0, 0.5], 0.5, 1.0, 0.1, 0.5),
            ([0.0; 3], 0.01, 1.0, 0.3, 0.1),
            // Thin annuli: one radial cell, equal counts on both rings.
            ([0.0; 3], 1.0, 1.001, 0.1, 0.1),
            ([0.1, 0.2, 0.3], 1.0, 1.14, 0.1, 0.1),
            ([0.0; 3], 0.05, 0.06, 0.02, 0.2),
            ([0.0; 3], 1.0, 1.3, 0.05, 0.2),
        ] {
            let (_, _, q) = check_annulus(c, a, b, w, h);
            assert!(q > 0.0, "a {a} b {b} w {w} h {h}: min quality {q}");
        }
    }

    /// The ring sections are valid (positive, conforming, closed) over a
    /// wide sweep of radius ratios and element sizes, including inner
    /// radii far below h and annuli far thinner than h.
    #[test]
    fn ring_sections_valid_over_sweep() {
        let mut worst = f64::INFINITY;
        for ia in 0..16 {
            let a = 0.01 * 1.6f64.powi(ia);
            for ib in 0..20 {
                let b = a * (1.0 + 0.001 * 2f64.powi(ib));
                let h = 0.1;
                for core in [false, true] {
                    let rings = AnnulusRings {
                        a,
                        b,
                        n_r: ((b - a) / h).round().max(1.0) as usize,
                        m0: (std::f64::consts::TAU * a / h).round().max(8.0) as usize,
                        h,
                    };
                    if rings.counts().0 > 20_000 {
                        continue;
                    }
                    let (mut points, mut tris) = if core {
                        let d = disc_triangulation(
                            a,
                            rings.m0,
                            (a / h).round().max(1.0) as usize,
                            CircleNodes::Inscribed,
                        );
                        (d.points, d.tris)
                    } else {
                        (Vec::new(), Vec::new())
                    };
                    let inner = if core {
                        RingNodes {
                            start: points.len() - rings.m0,
                            m: rings.m0,
                            offset: 0.0,
                        }
                    } else {
                        push_ring(&mut points, a, rings.m0)
                    };
                    let (n_points0, n_tri0) = (points.len(), tris.len());
                    let outer = rings.build(&mut points, &mut tris, inner);
                    assert_eq!(outer.start + outer.m, points.len());
                    let (n_nodes, n_tri) = rings.counts();
                    assert_eq!(n_nodes as usize, points.len() - n_points0);
                    assert_eq!(n_tri as usize, tris.len() - n_tri0);
                    let mut area = 0.0;
                    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
                    for &t in &tris {
                        let ar = tri_area(&points, t);
                        let [p, q, r] = t.map(|v| points[v as usize]);
                        let l2 = |a: [f64; 2], b: [f64; 2]| {
                            (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
                        };
                        assert!(ar > 0.0, "a {a} b {b} core {core}: {t:?} area {ar}");
                        worst =
                            worst.min(ar * 4.0 * 3f64.sqrt() / (l2(p, q) + l2(q, r) + l2(r, p)));
                        area += ar;
                        for k in 0..3 {
                            let (u, v) = (t[k], t[(k + 1) % 3]);
                            *edges.entry((u.min(v), u.max(v))).or_default() += 1;
                        }
                    }
                    let expect = polygon_area(outer.m, b)
                        - if core { 0.0 } else { polygon_area(inner.m, a) };
                    assert!(rel(area, expect) < 1e-10, "a {a} b {b} core {core}");
                    assert!(edges.values().all(|&c| c <= 2));
                    let n_open = edges.values().filter(|&&c| c == 1).count();
                    assert_eq!(n_open, outer.m + if core { 0 } else { inner.m });
                }
            }
        }
        println!("worst section triangle quality over the sweep: {worst:.3}");
    }

    #[test]
    fn concentric_seed_004_steel_in_concrete() {
        // Seed 004 sec 4, Table 3: steel core a = 0.03 m in a concrete ring
        // b = 0.15 m, height 0.01 m.
        for (c, a, b, w, h) in [
            ([0.0; 3], 0.03, 0.15, 0.01, 0.01),
            ([0.0; 3], 0.03, 0.15, 0.01, 0.005),
            ([1.0, -2.0, 0.3], 0.5, 1.0, 0.2, 0.1),
            ([0.0; 3], 1.0, 1.001, 0.1, 0.1),
            ([0.0; 3], 0.01, 1.0, 0.1, 0.1),
        ] {
            let m = concentric_cylinder_mesh(c, a, b, w, h).unwrap();
            let q = check_ring_mesh(&m, c, w, &[("outer", b, 1.0), ("interface", a, 0.0)]);
            let n_z = ((w / h).round() as usize).max(1);
            let z_lo = c[2] - 0.5 * w;
            let (n_c, m_b) = (
                count_on_circle(&m, c, a, z_lo),
                count_on_circle(&m, c, b, z_lo),
            );

            // The core is exactly cylinder_mesh's.
            let cyl = cylinder_mesh(c, a, w, h, CircleNodes::Inscribed).unwrap();
            let core = &m.elem_sets["core"];
            let ring = &m.elem_sets["ring"];
            assert_eq!(core.len(), cyl.num_elems());
            assert_eq!(core.len() + ring.len(), m.num_elems());
            let mut both: Vec<u32> = core.iter().chain(ring).copied().collect();
            both.sort_unstable();
            assert_eq!(both, m.elem_sets["all"]);
            let vol = |set: &[u32]| {
                set.iter()
                    .map(|&e| m.element_volume(e as usize))
                    .sum::<f64>()
            };
            assert!(rel(vol(core), cyl.total_volume()) < 1e-12);
            assert!(rel(vol(core), w * polygon_area(n_c, a)) < 1e-12);
            assert!(rel(vol(ring), w * (polygon_area(m_b, b) - polygon_area(n_c, a))) < 1e-12);
            let exact = std::f64::consts::PI * b * b * w;
            let bound = w * polygon_deficit_bound(m_b, b);
            assert!((m.total_volume() - exact).abs() <= bound && m.total_volume() < exact);
            for &e in core {
                let x = m.element_coords(e as usize);
                assert!(x.iter().all(|p| radial_distance(c, *p) < a * (1.0 + 1e-12)));
            }
            for &e in ring {
                let x = m.element_coords(e as usize);
                assert!(x.iter().all(|p| radial_distance(c, *p) > a * (1.0 - 1e-12)));
            }

            // Interface: shared nodes, interior faces of one core and one
            // ring element, normals out of the core, area = polygon side.
            assert_eq!(m.node_sets["interface"].len(), n_c * (n_z + 1));
            assert_eq!(
                m.nodes_of_face_set("interface").unwrap(),
                m.node_sets["interface"]
            );
            let iface = &m.face_sets["interface"];
            assert_eq!(iface.len(), 2 * n_c * n_z);
            let is_core: Vec<bool> = {
                let mut v = vec![false; m.num_elems()];
                core.iter().for_each(|&e| v[e as usize] = true);
                v
            };
            let mut owners: HashMap<[u32; 3], Vec<bool>> = HashMap::new();
            for (e, &in_core) in is_core.iter().enumerate() {
                for f in 0..4 {
                    let mut k = m.local_face_nodes(e, f);
                    k.sort_unstable();
                    owners.entry(k).or_default().push(in_core);
                }
            }
            let mut area = 0.0;
            for f in iface {
                let mut k = *f;
                k.sort_unstable();
                let mut o = owners[&k].clone();
                o.sort_unstable();
                assert_eq!(o, vec![false, true]);
                let (fa, n) = m.face_area_normal(*f);
                area += fa;
                let p = m.nodes[f[0] as usize];
                let radial = (n[0] * (p[0] - c[0]) + n[1] * (p[1] - c[1])) / a;
                assert!(radial > 0.9, "interface normal {n:?}");
            }
            let perimeter = n_c as f64 * 2.0 * a * (std::f64::consts::PI / n_c as f64).sin();
            assert!(rel(area, perimeter * w) < 1e-12);
            assert_eq!(m, concentric_cylinder_mesh(c, a, b, w, h).unwrap());
            println!(
                "concentric a={a} b={b} height={w} h={h}: {} nodes, {} tets ({} core, {} ring), \
                 min quality {q:.3}",
                m.num_nodes(),
                m.num_elems(),
                core.len(),
                ring.len()
            );
            assert!(q > 0.0);
            if (a, b, w) == (0.03, 0.15, 0.01) {
                assert!(q > 0.2, "h {h}: min quality {q}");
            }
        }
    }

    #[test]
    fn ring_meshes_reject_bad_parameters() {
        for (c, a, b, w, h) in [
            ([0.0; 3], 0.0, 1.0, 0.1, 0.1),
            ([0.0; 3], -0.5, 1.0, 0.1, 0.1),
            ([0.0; 3], 1.0, 1.0, 0.1, 0.1),
            ([0.0; 3], 1.0, 0.5, 0.1, 0.1),
            ([0.0; 3], 0.5, f64::NAN, 0.1, 0.1),
            ([0.0; 3], 0.5, f64::INFINITY, 0.1, 0.1),
            ([0.0; 3], 0.5, 1.0, 0.0, 0.1),
            ([0.0; 3], 0.5, 1.0, 0.1, 0.0),
            ([0.0; 3], 0.5, 1.0, 0.1, -0.1),
            ([f64::NAN, 0.0, 0.0], 0.5, 1.0, 0.1, 0.1),
        ] {
            let e = annulus_mesh(c, a, b, w, h).unwrap_err();
            assert!(matches!(e, MeshError::InvalidParameter(_)), "{e}");
            let e = concentric_cylinder_mesh(c, a, b, w, h).unwrap_err();
            assert!(matches!(e, MeshError::InvalidParameter(_)), "{e}");
        }
        for (a, b, w, h) in [
            (0.5, 1.0, 0.1, 1e-6),
            (0.5, 1.0, 1e12, 1.0),
            (0.5, 1.0, 0.1, 2e-4),
            (1e-3, 1e6, 0.1, 1.0),
        ] {
            let e = annulus_mesh([0.0; 3], a, b, w, h).unwrap_err();
            assert!(matches!(e, MeshError::TooLarge(_)), "{e}");
            let e = concentric_cylinder_mesh([0.0; 3], a, b, w, h).unwrap_err();
            assert!(matches!(e, MeshError::TooLarge(_)), "{e}");
        }
    }
}
