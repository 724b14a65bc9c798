//! Hex8 meshes in the Tet4 world (issue 21): every hexahedron is also six
//! tets, `6 h .. 6 h + 6` for hex `h`, so that contact (search, penalty,
//! thermal clipping), the partition and the output, which all read tets,
//! read a Hex8 body unchanged, while its kernels (mechanics and heat) use
//! the hexes. The split must conform between neighbours, or shared faces
//! would look like boundary faces: each quadrilateral face is cut along
//! the diagonal through its lowest node number, and the hex is coned from
//! its lowest node over the three faces that do not contain it (those
//! that do are cut through it by the same rule). Pure: no MPI, no PETSc.

use super::{MeshError, TetMesh};
use crate::mesh::hex8::HexMesh;

/// The faces of a Hex8 in seed 002 Table 1 order, each counter-clockwise
/// seen from outside (bottom, top, then the four sides).
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// A Tet4 mesh whose tets `6 h .. 6 h + 6` split hex `h` of `hexes`.
#[derive(Debug, Clone, PartialEq)]
pub struct SplitHexes {
    /// The tets, with the hex mesh's nodes and node sets; face sets for
    /// the node sets that hold boundary faces; element set `all`.
    pub mesh: TetMesh,
    /// The hexes (Table 1 order), over the same nodes.
    pub hexes: Vec<[u32; 8]>,
}

/// The six tets of `hex` (Table 1 order, global node numbers), positively
/// oriented for a convex hex: cones from the lowest node over the two
/// triangles of each face not containing it, each face cut through its
/// own lowest node.
pub fn split_hex(hex: &[u32; 8]) -> [[u32; 4]; 6] {
    let apex = (0..8).min_by_key(|&k| hex[k]).expect("eight nodes");
    let mut out = [[0u32; 4]; 6];
    let mut t = 0;
    for f in HEX_FACES.iter().filter(|f| !f.contains(&apex)) {
        let q = f.map(|k| hex[k]);
        let low = (0..4).min_by_key(|&i| q[i]).expect("four nodes");
        // Triangles (p, a, b) counter-clockwise from outside, cut through q[low].
        let (p, a, b, c) = (q[low], q[(low + 1) % 4], q[(low + 2) % 4], q[(low + 3) % 4]);
        for (x, y) in [(a, b), (b, c)] {
            // The apex is inside: (p, y, x, apex) is positively oriented.
            out[t] = [p, y, x, hex[apex]];
            t += 1;
        }
    }
    out
}

/// Split a Hex8 mesh into tets by [`split_hex`] (conforming between
/// neighbours), keeping its node sets and adding, for each node set, the
/// boundary triangles whose three nodes all lie in it as a face set of
/// the same name. Errors name the hex whose tets are inverted or
/// degenerate (a non-convex hex).
pub fn split_hex_mesh(hm: &HexMesh) -> Result<SplitHexes, MeshError> {
    let tets: Vec<[u32; 4]> = hm.hexes.iter().flat_map(split_hex).collect();
    let mut mesh = TetMesh::one_body(hm.nodes.clone(), tets);
    mesh.node_sets = hm.node_sets.clone();
    mesh.validate().map_err(|e| match e {
        MeshError::Inverted { elem, .. } | MeshError::Degenerate { elem, .. } => {
            MeshError::InvalidParameter(format!(
                "Hex8 element {} (nodes {:?}) is not convex enough to split into tets: {e}",
                elem / 6,
                hm.hexes[elem / 6]
            ))
        }
        other => other,
    })?;
    let boundary = mesh.boundary_faces();
    for (name, set) in &hm.node_sets {
        let mut in_set = vec![false; hm.nodes.len()];
        set.iter().for_each(|&n| in_set[n as usize] = true);
        let faces: Vec<[u32; 3]> = boundary
            .iter()
            .filter(|f| f.nodes.iter().all(|&n| in_set[n as usize]))
            .map(|f| f.nodes)
            .collect();
        if !faces.is_empty() {
            mesh.face_sets.insert(name.clone(), faces);
        }
    }
    Ok(SplitHexes {
        mesh,
        hexes: hm.hexes.clone(),
    })
}

/// The Tet4 box of [`super::generate::box_mesh`] with its hexes: that
/// generator cuts cell `c` (x fastest) into tets `6 c .. 6 c + 6` over
/// the nodes of [`super::hex8::hex_box`], so the hexes are that box's.
pub fn box_hex8(origin: [f64; 3], size: [f64; 3], h: f64) -> Result<SplitHexes, MeshError> {
    let mesh = super::generate::box_mesh(origin, size, h)?;
    let cells = |d: usize| super::generate::cells(size[d], h);
    let n = [cells(0)?, cells(1)?, cells(2)?];
    let hi = std::array::from_fn(|d| origin[d] + size[d]);
    let hm = super::hex8::hex_box(origin, hi, n)?;
    Ok(SplitHexes {
        mesh,
        hexes: hm.hexes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::hex8::hex_box;

    fn contains_all(hex: &[u32; 8], tets: &[[u32; 4]]) -> bool {
        tets.iter().flatten().all(|n| hex.contains(n))
    }

    #[test]
    fn box_tets_lie_in_their_hexes_and_fill_them() {
        let s = box_hex8([0.1, 0.2, 0.3], [2.0, 1.0, 0.5], 0.25).unwrap();
        assert_eq!(s.mesh.tets.len(), 6 * s.hexes.len());
        assert_eq!(s.hexes.len(), 8 * 4 * 2);
        for (h, hex) in s.hexes.iter().enumerate() {
            let tets = &s.mesh.tets[6 * h..6 * h + 6];
            assert!(contains_all(hex, tets), "hex {h}");
            let v: f64 = (6 * h..6 * h + 6).map(|e| s.mesh.element_volume(e)).sum();
            assert!((v - 0.25f64.powi(3)).abs() < 1e-15, "hex {h}: {v}");
        }
        assert!(s.mesh.face_sets.contains_key("xmax"));
    }

    #[test]
    fn split_conforms_and_keeps_volume_on_a_shuffled_numbering() {
        // A 3 x 2 x 2 box with its node numbers permuted: the faces two
        // hexes share must be cut the same way from both sides, so the
        // boundary is the box's surface only.
        let mut hm = hex_box([0.0; 3], [3.0, 2.0, 2.0], [3, 2, 2]).unwrap();
        let nn = hm.nodes.len() as u32;
        let perm: Vec<u32> = (0..nn).map(|i| (i * 7 + 3) % nn).collect();
        let mut nodes = vec![[0.0; 3]; nn as usize];
        for (i, &p) in perm.iter().enumerate() {
            nodes[p as usize] = hm.nodes[i];
        }
        hm.nodes = nodes;
        hm.hexes
            .iter_mut()
            .for_each(|h| *h = h.map(|n| perm[n as usize]));
        for s in hm.node_sets.values_mut() {
            *s = s.iter().map(|&n| perm[n as usize]).collect();
            s.sort_unstable();
        }
        let s = split_hex_mesh(&hm).unwrap();
        let volume: f64 = (0..s.mesh.tets.len())
            .map(|e| s.mesh.element_volume(e))
            .sum();
        assert!((volume - 12.0).abs() < 1e-12, "{volume}");
        // Surface: 2 (3·2 + 3·2 + 2·2) = 32 unit squares, 64 triangles.
        assert_eq!(s.mesh.boundary_faces().len(), 64);
        assert_eq!(s.mesh.face_sets["xmax"].len(), 2 * 4);
        for (h, hex) in s.hexes.iter().enumerate() {
            assert!(contains_all(hex, &s.mesh.tets[6 * h..6 * h + 6]));
        }
    }

    #[test]
    fn an_inverted_hex_is_named() {
        let mut hm = hex_box([0.0; 3], [1.0; 3], [2, 1, 1]).unwrap();
        hm.hexes[1].swap(0, 4);
        hm.hexes[1].swap(1, 5);
        hm.hexes[1].swap(2, 6);
        hm.hexes[1].swap(3, 7);
        let e = split_hex_mesh(&hm).unwrap_err().to_string();
        assert!(e.contains("Hex8 element 1"), "{e}");
    }
}
