//! A mesh with some of its elements taken out (the element set of a body
//! that becomes particles, issue 21): nodes no remaining element uses go,
//! the others are numbered again in their old order, and the named sets
//! follow (node sets keep their remaining nodes, face sets the faces of a
//! remaining element, element sets their remaining elements; sets left
//! empty are dropped).

use std::collections::HashSet;

use super::TetMesh;

/// The elements of `mesh` that `drop` does not mark, and for every old
/// element its new index (`u32::MAX`: taken out).
pub fn without_elements(mesh: &TetMesh, drop: &[bool]) -> (TetMesh, Vec<u32>) {
    let mut new_node = vec![u32::MAX; mesh.nodes.len()];
    let mut new_elem = vec![u32::MAX; mesh.tets.len()];
    let mut out = TetMesh::default();
    for (e, t) in mesh.tets.iter().enumerate() {
        if drop[e] {
            continue;
        }
        new_elem[e] = out.tets.len() as u32;
        out.tets.push(*t);
        out.body.push(mesh.body[e]);
        for &v in t {
            new_node[v as usize] = 0;
        }
    }
    for (v, slot) in new_node.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = out.nodes.len() as u32;
            out.nodes.push(mesh.nodes[v]);
        }
    }
    for t in &mut out.tets {
        *t = t.map(|v| new_node[v as usize]);
    }
    for (name, nodes) in &mesh.node_sets {
        let kept: Vec<u32> = nodes
            .iter()
            .map(|&v| new_node[v as usize])
            .filter(|&v| v != u32::MAX)
            .collect();
        if !kept.is_empty() {
            out.node_sets.insert(name.clone(), kept);
        }
    }
    // A face stays when a remaining element has all three of its nodes.
    let mut faces: HashSet<[u32; 3]> = HashSet::new();
    for t in &out.tets {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut k = 0;
            for (i, &v) in t.iter().enumerate() {
                if i != skip {
                    f[k] = v;
                    k += 1;
                }
            }
            f.sort_unstable();
            faces.insert(f);
        }
    }
    for (name, tris) in &mesh.face_sets {
        let kept: Vec<[u32; 3]> = tris
            .iter()
            .map(|f| f.map(|v| new_node[v as usize]))
            .filter(|f| {
                let mut s = *f;
                s.sort_unstable();
                !f.contains(&u32::MAX) && faces.contains(&s)
            })
            .collect();
        if !kept.is_empty() {
            out.face_sets.insert(name.clone(), kept);
        }
    }
    for (name, elems) in &mesh.elem_sets {
        let kept: Vec<u32> = elems
            .iter()
            .map(|&e| new_elem[e as usize])
            .filter(|&e| e != u32::MAX)
            .collect();
        if !kept.is_empty() {
            out.elem_sets.insert(name.clone(), kept);
        }
    }
    (out, new_elem)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_follow_the_remaining_elements() {
        let mut m = crate::mesh::generate::box_mesh([0.0; 3], [2.0, 1.0, 1.0], 0.5).unwrap();
        m.add_box_set("left", [0.0; 3], [1.0, 1.0, 1.0]).unwrap();
        let drop: Vec<bool> = m
            .tets
            .iter()
            .map(|t| t.iter().map(|&v| m.nodes[v as usize][0]).sum::<f64>() / 4.0 > 1.0)
            .collect();
        let (out, map) = without_elements(&m, &drop);
        assert_eq!(out.tets.len(), drop.iter().filter(|&&d| !d).count());
        assert_eq!(out.elem_sets["left"].len(), out.tets.len());
        assert!(out.nodes.iter().all(|x| x[0] <= 1.0));
        for (e, &n) in map.iter().enumerate() {
            if n != u32::MAX {
                let old = m.tets[e].map(|v| m.nodes[v as usize]);
                let new = out.tets[n as usize].map(|v| out.nodes[v as usize]);
                assert_eq!(old, new);
            }
        }
        for (name, faces) in &out.face_sets {
            for f in faces {
                assert!(f.iter().all(|&v| (v as usize) < out.nodes.len()), "{name}");
            }
        }
    }
}
