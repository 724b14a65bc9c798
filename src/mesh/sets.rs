//! Named sets: node sets derived from face sets, and merging of meshes
//! ([`TetMesh::append`]) for multi-body models.

use std::collections::BTreeMap;

use super::TetMesh;

fn sort_dedup(v: &mut Vec<u32>) {
    v.sort_unstable();
    v.dedup();
}

/// Checked `u32` conversion used by [`TetMesh::append`].
fn to_u32(v: usize, what: &str) -> u32 {
    u32::try_from(v).unwrap_or_else(|_| panic!("TetMesh::append: {what} {v} exceeds u32 range"))
}

impl TetMesh {
    /// Adds the element set `name`: the tets whose centroid lies in the box
    /// `min..=max`. Errors (as text) if the set exists already, the box is
    /// empty or not finite, or no centroid lies in it; returns its size.
    pub fn add_box_set(
        &mut self,
        name: &str,
        min: [f64; 3],
        max: [f64; 3],
    ) -> Result<usize, String> {
        if self.elem_sets.contains_key(name) {
            return Err(format!(
                "`{name}`: the mesh has an element set of that name already"
            ));
        }
        if !(0..3).all(|d| min[d].is_finite() && max[d].is_finite() && min[d] <= max[d]) {
            return Err(format!(
                "`{name}`: min {min:?} must be finite and not above max {max:?}"
            ));
        }
        let inside: Vec<u32> = (0..self.tets.len())
            .filter(|&e| {
                let c = self.tets[e].iter().fold([0.0; 3], |mut c, &v| {
                    (0..3).for_each(|d| c[d] += 0.25 * self.nodes[v as usize][d]);
                    c
                });
                (0..3).all(|d| c[d] >= min[d] && c[d] <= max[d])
            })
            .map(|e| e as u32)
            .collect();
        if inside.is_empty() {
            return Err(format!(
                "`{name}`: no element centroid lies in the box {min:?}..{max:?}"
            ));
        }
        let n = inside.len();
        self.elem_sets.insert(name.to_string(), inside);
        Ok(n)
    }

    /// Sorted, unique nodes of the face set `name`; `None` if there is no
    /// such face set.
    pub fn nodes_of_face_set(&self, name: &str) -> Option<Vec<u32>> {
        let faces = self.face_sets.get(name)?;
        let mut v: Vec<u32> = faces.iter().flatten().copied().collect();
        sort_dedup(&mut v);
        Some(v)
    }

    /// Nodes of the set `name`: the node set of that name if there is one,
    /// otherwise the nodes of the face set of that name (sorted, unique);
    /// `None` if neither exists.
    pub fn set_nodes(&self, name: &str) -> Option<Vec<u32>> {
        match self.node_sets.get(name) {
            Some(s) => Some(s.clone()),
            None => self.nodes_of_face_set(name),
        }
    }

    /// Appends `other` to this mesh: its node indices are shifted by
    /// `self.num_nodes()`, its element indices by `self.num_elems()`, and its
    /// body ids by `body_offset`. A named set `s` of `other` is merged into
    /// this mesh's set `s` of the same kind (created if absent); node and
    /// element sets stay sorted and unique. Nodes are not merged, so the two
    /// meshes stay topologically disconnected.
    ///
    /// # Panics
    /// If the merged mesh exceeds the `u32` index range or a body id overflows.
    pub fn append(&mut self, other: TetMesh, body_offset: u32) {
        let noff = to_u32(self.nodes.len(), "node count");
        let eoff = to_u32(self.tets.len(), "element count");
        to_u32(self.nodes.len() + other.nodes.len(), "merged node count");
        to_u32(self.tets.len() + other.tets.len(), "merged element count");

        self.nodes.extend(other.nodes);
        self.tets
            .extend(other.tets.iter().map(|t| t.map(|v| v + noff)));
        self.body.extend(other.body.iter().map(|&b| {
            b.checked_add(body_offset)
                .unwrap_or_else(|| panic!("TetMesh::append: body id {b} + {body_offset} overflows"))
        }));

        merge(&mut self.node_sets, other.node_sets, |v| v + noff);
        merge(&mut self.elem_sets, other.elem_sets, |v| v + eoff);
        for (name, faces) in other.face_sets {
            self.face_sets
                .entry(name)
                .or_default()
                .extend(faces.iter().map(|f| f.map(|v| v + noff)));
        }
    }
}

fn merge(
    dst: &mut BTreeMap<String, Vec<u32>>,
    src: BTreeMap<String, Vec<u32>>,
    shift: impl Fn(u32) -> u32,
) {
    for (name, items) in src {
        let d = dst.entry(name).or_default();
        d.extend(items.into_iter().map(&shift));
        sort_dedup(d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_sets_take_the_tets_whose_centroid_is_inside() {
        let mut m = tet(0.0);
        m.append(tet(2.0), 1);
        // Centroids at x = 0.25 and 2.25.
        assert_eq!(
            m.add_box_set("right", [2.0, -1.0, -1.0], [3.0, 1.0, 1.0]),
            Ok(1)
        );
        assert_eq!(m.elem_sets["right"], vec![1]);
        let e = m.add_box_set("right", [0.0; 3], [1.0; 3]).unwrap_err();
        assert!(e.contains("already"), "{e}");
        let e = m.add_box_set("none", [5.0; 3], [6.0; 3]).unwrap_err();
        assert!(e.contains("no element centroid"), "{e}");
        let e = m.add_box_set("bad", [1.0; 3], [0.0; 3]).unwrap_err();
        assert!(e.contains("not above max"), "{e}");
    }

    fn tet(offset: f64) -> TetMesh {
        let mut m = TetMesh {
            nodes: vec![
                [offset, 0.0, 0.0],
                [offset + 1.0, 0.0, 0.0],
                [offset, 1.0, 0.0],
                [offset, 0.0, 1.0],
            ],
            tets: vec![[0, 1, 2, 3]],
            body: vec![0],
            ..Default::default()
        };
        m.face_sets.insert("bottom".into(), vec![[0, 2, 1]]);
        m.node_sets.insert("apex".into(), vec![3]);
        m.elem_sets.insert("all".into(), vec![0]);
        m
    }

    #[test]
    fn node_sets_from_face_sets() {
        let mut m = tet(0.0);
        assert_eq!(m.nodes_of_face_set("bottom"), Some(vec![0, 1, 2]));
        assert_eq!(m.nodes_of_face_set("apex"), None);
        assert_eq!(m.set_nodes("apex"), Some(vec![3]));
        assert_eq!(m.set_nodes("bottom"), Some(vec![0, 1, 2]));
        assert_eq!(m.set_nodes("nothing"), None);
        // Node set takes precedence over face set.
        m.node_sets.insert("bottom".into(), vec![1]);
        assert_eq!(m.set_nodes("bottom"), Some(vec![1]));
    }

    #[test]
    fn append_renumbers_and_merges() {
        let mut a = tet(0.0);
        let mut b = tet(5.0);
        b.face_sets.insert("only_b".into(), vec![[1, 2, 3]]);
        a.append(b, 3);
        a.validate().unwrap();
        assert_eq!(a.num_nodes(), 8);
        assert_eq!(a.tets, vec![[0, 1, 2, 3], [4, 5, 6, 7]]);
        assert_eq!(a.body, vec![0, 3]);
        assert_eq!(a.face_sets["bottom"], vec![[0, 2, 1], [4, 6, 5]]);
        assert_eq!(a.face_sets["only_b"], vec![[5, 6, 7]]);
        assert_eq!(a.node_sets["apex"], vec![3, 7]);
        assert_eq!(a.elem_sets["all"], vec![0, 1]);
        assert_eq!(a.boundary_faces().len(), 8);
    }
}
