//! Closed-volume check for single-body particle templates
//! ([`TetMesh::check_closed_volume`]).

use super::geometry::cross;
use super::{MeshError, TetMesh, LOCAL_FACES};

/// Relative tolerance of the volume comparison in
/// [`TetMesh::check_closed_volume`].
pub const CLOSED_VOLUME_REL_TOL: f64 = 1e-9;

/// Union-find root of `i` with path halving.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

impl TetMesh {
    /// Checks that the mesh is one closed solid, as a particle template must
    /// be. In order, the first failure is returned as
    /// [`MeshError::NotClosed`] (index errors as
    /// [`MeshError::NodeOutOfRange`]):
    ///
    /// 1. the mesh has elements, and no triangle is a face of more than two
    ///    elements (overlapping copies of an element);
    /// 2. every edge of a boundary face is shared by exactly two boundary
    ///    faces, which traverse it in opposite directions (a consistently
    ///    oriented 2-manifold surface). Elements whose nodes were not merged
    ///    touch along an edge with 4 boundary faces (for instance two parts
    ///    glued along a single line of shared nodes); the error names the
    ///    edge's two node ids and the number of faces;
    /// 3. the elements form one piece, connected through shared faces
    ///    (unmerged parts that are each closed, or disjoint bodies, fail
    ///    here with the number of pieces);
    /// 4. the volume enclosed by the boundary surface (divergence theorem,
    ///    `V_s = sum_f (x0 - o) . ((x1 - x0) x (x2 - x0)) / 6` over the
    ///    outward boundary faces, `o` any reference point) equals the sum of
    ///    the element volumes `V_t`, which must be positive, to
    ///    [`CLOSED_VOLUME_REL_TOL`] relative (an inverted element fails here).
    ///
    /// An internal cavity (elements removed from the inside) is a closed
    /// surface too: such a mesh passes, with `V_s` = outer volume minus the
    /// cavity. Element orientation and quality are not checked beyond 2 and
    /// 4; see [`TetMesh::validate`]. O(n log n).
    pub fn check_closed_volume(&self) -> Result<(), MeshError> {
        let not_closed = |message: String| Err(MeshError::NotClosed { message });
        if self.tets.is_empty() {
            return not_closed("the mesh has no tetrahedra".into());
        }
        self.check_node_indices()?;

        // (1) + (3): element faces keyed by their sorted nodes; equal keys
        // are shared faces and join their elements.
        let mut keys: Vec<([u32; 3], u32)> = Vec::with_capacity(4 * self.tets.len());
        for (e, t) in self.tets.iter().enumerate() {
            for l in LOCAL_FACES {
                let mut k = [t[l[0]], t[l[1]], t[l[2]]];
                k.sort_unstable();
                keys.push((k, e as u32));
            }
        }
        keys.sort_unstable();
        let mut parent: Vec<u32> = (0..self.tets.len() as u32).collect();
        for group in keys.chunk_by(|a, b| a.0 == b.0) {
            if group.len() > 2 {
                let k = group[0].0;
                return not_closed(format!(
                    "the triangle with nodes {},{},{} is a face of {} elements (at most 2 allowed)",
                    k[0],
                    k[1],
                    k[2],
                    group.len()
                ));
            }
            if let [a, b] = group {
                let (ra, rb) = (root(&mut parent, a.1), root(&mut parent, b.1));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }

        // (2): boundary edges as (min, max, +1 if traversed min -> max else -1).
        let faces = self.boundary_faces();
        let mut edges: Vec<(u32, u32, i8)> = Vec::with_capacity(3 * faces.len());
        for f in &faces {
            for k in 0..3 {
                let (u, v) = (f.nodes[k], f.nodes[(k + 1) % 3]);
                edges.push(if u < v { (u, v, 1) } else { (v, u, -1) });
            }
        }
        edges.sort_unstable();
        for group in edges.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
            let (u, v) = (group[0].0, group[0].1);
            if group.len() != 2 {
                return not_closed(format!(
                    "the boundary edge between nodes {u} and {v} is shared by {} boundary faces \
                     (a closed surface needs exactly 2; 1 means an open surface, 4 or more \
                     parts touching along the edge, e.g. nodes that were not merged)",
                    group.len()
                ));
            }
            if group[0].2 == group[1].2 {
                return not_closed(format!(
                    "the two boundary faces at the edge between nodes {u} and {v} traverse it in \
                     the same direction (inconsistently oriented surface: inverted elements?)"
                ));
            }
        }

        // (3): one piece.
        let roots: Vec<u32> = (0..self.tets.len() as u32)
            .map(|e| root(&mut parent, e))
            .collect();
        let pieces = roots
            .iter()
            .enumerate()
            .filter(|&(e, &r)| e == r as usize)
            .count();
        if pieces != 1 {
            let other = roots.iter().position(|&r| r != roots[0]).unwrap_or(0);
            return not_closed(format!(
                "the elements form {pieces} pieces not connected through shared faces \
                 (e.g. elements 0 and {other} are in different pieces)"
            ));
        }

        // (4): V_s = sum_f (x0 - o) . ((x1 - x0) x (x2 - x0)) / 6 (divergence
        // theorem for div(x - o) = 3), o = a node of the mesh to limit cancellation.
        let o = self.nodes[self.tets[0][0] as usize];
        let surface_volume: f64 = faces
            .iter()
            .map(|f| {
                let [p0, p1, p2] = f.nodes.map(|v| self.nodes[v as usize]);
                let a = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
                let b = [p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]];
                let c = cross(a, b);
                ((p0[0] - o[0]) * c[0] + (p0[1] - o[1]) * c[1] + (p0[2] - o[2]) * c[2]) / 6.0
            })
            .sum();
        let elem_volume = self.total_volume();
        if elem_volume.is_nan() || elem_volume <= 0.0 {
            return not_closed(format!(
                "the sum of the element volumes is {elem_volume:e} m^3, not positive"
            ));
        }
        // |V_s - V_t| <= tol * V_t.
        let diff = (surface_volume - elem_volume).abs();
        if diff.is_nan() || diff > CLOSED_VOLUME_REL_TOL * elem_volume {
            return not_closed(format!(
                "the boundary surface encloses {surface_volume:e} m^3 but the elements sum to \
                 {elem_volume:e} m^3 (relative difference {:.3e}, tolerance {CLOSED_VOLUME_REL_TOL:e})",
                diff / elem_volume
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::generate::box_mesh;
    use super::super::testutil::unit_tet;
    use super::*;

    fn message(m: &TetMesh) -> String {
        let e = m.check_closed_volume().unwrap_err();
        assert!(matches!(e, MeshError::NotClosed { .. }), "{e}");
        let s = e.to_string();
        assert!(s.starts_with("mesh is not a closed volume: "), "{s}");
        s
    }

    #[test]
    fn single_tet_and_boxes_pass() {
        unit_tet().check_closed_volume().unwrap();
        box_mesh([0.0; 3], [1.0; 3], 1.0)
            .unwrap()
            .check_closed_volume()
            .unwrap();
        // Far from the origin (the reference point keeps the sum accurate).
        box_mesh([1e4, -2e4, 3e4], [0.3, 0.2, 0.1], 0.05)
            .unwrap()
            .check_closed_volume()
            .unwrap();
    }

    #[test]
    fn empty_mesh_fails() {
        let s = message(&TetMesh::default());
        assert!(s.contains("no tetrahedra"), "{s}");
    }

    #[test]
    fn interior_cavity_passes() {
        // 3x3x3 cells: the centre cell's nodes (grid indices 1..=2) are all
        // interior, so removing one of its tets leaves a closed cavity.
        let mut m = box_mesh([0.0; 3], [3.0; 3], 1.0).unwrap();
        let before = m.total_volume();
        let centre_cell = 1 + 3 * (1 + 3);
        let e = 6 * centre_cell;
        let removed = m.element_volume(e);
        m.tets.remove(e);
        m.body.remove(e);
        m.elem_sets.clear();
        // 4 (n_x n_y + n_y n_z + n_x n_z) outer triangles + the cavity's 4.
        assert_eq!(m.boundary_faces().len(), 4 * 27 + 4);
        m.check_closed_volume().unwrap();
        assert!((m.total_volume() - (before - removed)).abs() < 1e-12);
    }

    /// 2x1x1 box; the elements of the right cell get their own copies of
    /// the nodes on the plane x = 1, except those in `keep`.
    fn split_box(keep: &[u32]) -> TetMesh {
        let mut m = box_mesh([0.0; 3], [2.0, 1.0, 1.0], 1.0).unwrap();
        // Nodes with x = 1: grid index i = 1, node id 1 + 3 (j + 2 k).
        let plane: Vec<u32> = (0..m.num_nodes() as u32)
            .filter(|&v| m.nodes[v as usize][0] == 1.0)
            .collect();
        assert_eq!(plane, [1, 4, 7, 10]);
        let mut copy = std::collections::HashMap::new();
        for &v in &plane {
            if !keep.contains(&v) {
                copy.insert(v, m.nodes.len() as u32);
                m.nodes.push(m.nodes[v as usize]);
            }
        }
        for e in 6..12 {
            for v in m.tets[e].iter_mut() {
                if let Some(&c) = copy.get(v) {
                    *v = c;
                }
            }
        }
        m.validate().unwrap();
        m
    }

    #[test]
    fn unmerged_halves_fail() {
        // Fully duplicated plane: two closed halves, two pieces.
        let s = message(&split_box(&[]));
        assert!(s.contains("2 pieces"), "{s}");
        // Only the edge 1-4 (x = 1, z = 0) shared: 4 boundary faces there.
        let s = message(&split_box(&[1, 4]));
        assert!(
            s.contains("between nodes 1 and 4 is shared by 4 boundary faces"),
            "{s}"
        );
        // Sharing a single node keeps every edge manifold: two pieces.
        let s = message(&split_box(&[7]));
        assert!(s.contains("2 pieces"), "{s}");
    }

    #[test]
    fn disjoint_boxes_fail() {
        let mut m = box_mesh([0.0; 3], [1.0; 3], 0.5).unwrap();
        let n = m.num_elems();
        m.append(box_mesh([2.0, 0.0, 0.0], [1.0; 3], 0.5).unwrap(), 0);
        let s = message(&m);
        assert!(
            s.contains("2 pieces") && s.contains(&format!("elements 0 and {n}")),
            "{s}"
        );
        // Three pieces.
        m.append(box_mesh([4.0, 0.0, 0.0], [1.0; 3], 1.0).unwrap(), 0);
        assert!(message(&m).contains("3 pieces"));
    }

    #[test]
    fn tets_sharing_an_edge_fail() {
        // Two tets touching along the edge 0-1 only.
        let mut m = unit_tet();
        m.nodes.extend([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
        m.tets.push([0, 1, 4, 5]);
        m.body.push(0);
        m.validate().unwrap();
        let s = message(&m);
        assert!(
            s.contains("between nodes 0 and 1 is shared by 4 boundary faces"),
            "{s}"
        );
    }

    #[test]
    fn duplicated_element_fails() {
        let mut m = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
        m.tets.push(m.tets[0]);
        m.tets.push(m.tets[0]);
        m.body.extend([0, 0]);
        let s = message(&m);
        assert!(s.contains("is a face of 3 elements"), "{s}");
    }

    #[test]
    fn inverted_elements_fail_the_volume_check() {
        // An interior element turned inside out: the surface is unchanged,
        // the element volumes are not.
        let mut m = box_mesh([0.0; 3], [3.0; 3], 1.0).unwrap();
        let e = 6 * (1 + 3 * (1 + 3));
        m.tets[e].swap(2, 3);
        let s = message(&m);
        assert!(
            s.contains("boundary surface encloses") && s.contains("elements sum to 2.66"),
            "{s}"
        );
        // All elements inverted: negative volume.
        let mut m = unit_tet();
        m.tets[0].swap(2, 3);
        assert!(message(&m).contains("not positive"));
        // A boundary element inverted: its faces reverse the orientation.
        let mut m = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
        m.tets[0].swap(2, 3);
        assert!(message(&m).contains("same direction"));
    }

    #[test]
    fn out_of_range_node_is_reported() {
        let mut m = unit_tet();
        m.tets[0][2] = 7;
        assert!(matches!(
            m.check_closed_volume().unwrap_err(),
            MeshError::NodeOutOfRange { node: 7, .. }
        ));
    }
}
