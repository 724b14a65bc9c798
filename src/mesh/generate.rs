//! Structured mesh generators (no external mesher needed): [`box_mesh`].

use std::collections::BTreeMap;

use super::{MeshError, TetMesh};

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
fn cells(len: f64, h: f64) -> Result<usize, MeshError> {
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
/// ([`MeshError::InvalidParameter`]); more than `u32::MAX` nodes or elements
/// ([`MeshError::TooLarge`]).
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
    let ne = tets.len();
    let mut mesh = TetMesh {
        nodes,
        tets,
        body: vec![0; ne],
        node_sets: BTreeMap::new(),
        face_sets: BTreeMap::new(),
        elem_sets: BTreeMap::new(),
    };

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
    mesh.elem_sets
        .insert("all".to_string(), (0..ne as u32).collect());
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::tet_signed_volume;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
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
}
