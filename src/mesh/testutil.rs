//! Helpers shared by the mesh module's unit tests.

use std::collections::HashMap;

use super::TetMesh;

/// The reference tet (0,0,0), (1,0,0), (0,1,0), (0,0,1) as a one-element mesh.
pub(crate) fn unit_tet() -> TetMesh {
    TetMesh {
        nodes: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        tets: vec![[0, 1, 2, 3]],
        body: vec![0],
        ..Default::default()
    }
}

/// Asserts the mesh is conforming: no face belongs to more than two tets.
pub(crate) fn assert_conforming(m: &TetMesh) {
    let mut faces: HashMap<[u32; 3], usize> = HashMap::new();
    for e in 0..m.num_elems() {
        for f in 0..4 {
            let mut k = m.local_face_nodes(e, f);
            k.sort_unstable();
            *faces.entry(k).or_default() += 1;
        }
    }
    if let Some((k, c)) = faces.iter().find(|(_, &c)| c > 2) {
        panic!("face {k:?} belongs to {c} tets");
    }
}
