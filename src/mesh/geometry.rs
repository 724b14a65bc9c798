//! Element geometry: signed volume, shape quality, bounding box, and the
//! consistency check [`TetMesh::validate`] (index ranges, finite coordinates,
//! positive orientation, non-degenerate elements, set indices).

use super::{MeshError, TetMesh};

/// Relative tolerance for degenerate elements: |V| <= `DEGENERATE_REL_TOL` * (longest edge)^3.
pub const DEGENERATE_REL_TOL: f64 = 1e-12;

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Signed volume of a tetrahedron: `det[x1-x0, x2-x0, x3-x0] / 6`.
///
/// Positive when `x3` lies on the side of the triangle `(x0, x1, x2)` that
/// its right-hand normal `(x1-x0) x (x2-x0)` points to.
pub fn tet_signed_volume(x: &[[f64; 3]; 4]) -> f64 {
    let a = sub(x[1], x[0]);
    let b = sub(x[2], x[0]);
    let c = sub(x[3], x[0]);
    dot(a, cross(b, c)) / 6.0
}

/// Squared lengths of the 6 edges of a tetrahedron.
fn edge_lengths_sq(x: &[[f64; 3]; 4]) -> [f64; 6] {
    let mut out = [0.0; 6];
    let mut k = 0;
    for i in 0..4 {
        for j in (i + 1)..4 {
            let d = sub(x[j], x[i]);
            out[k] = dot(d, d);
            k += 1;
        }
    }
    out
}

/// Shape quality `6*sqrt(2) * V / l_rms^3`, where `l_rms` is the root mean
/// square of the 6 edge lengths.
///
/// Equals 1 for a regular tetrahedron, tends to 0 for flat or needle-like
/// elements, and is negative for inverted ones. Scale invariant.
pub fn tet_quality(x: &[[f64; 3]; 4]) -> f64 {
    let l2 = edge_lengths_sq(x);
    let l_rms_sq = l2.iter().sum::<f64>() / 6.0;
    if l_rms_sq <= 0.0 {
        return 0.0;
    }
    6.0 * std::f64::consts::SQRT_2 * tet_signed_volume(x) / (l_rms_sq * l_rms_sq.sqrt())
}

impl TetMesh {
    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of elements (tetrahedra).
    pub fn num_elems(&self) -> usize {
        self.tets.len()
    }

    /// Coordinates of the 4 nodes of element `e`, in element node order.
    ///
    /// # Panics
    /// If `e` or one of its node indices is out of range (see [`TetMesh::validate`]).
    pub fn element_coords(&self, e: usize) -> [[f64; 3]; 4] {
        let t = self.tets[e];
        [
            self.nodes[t[0] as usize],
            self.nodes[t[1] as usize],
            self.nodes[t[2] as usize],
            self.nodes[t[3] as usize],
        ]
    }

    /// Signed volume of element `e` (see [`tet_signed_volume`]).
    pub fn element_volume(&self, e: usize) -> f64 {
        tet_signed_volume(&self.element_coords(e))
    }

    /// Sum of the signed element volumes.
    pub fn total_volume(&self) -> f64 {
        (0..self.tets.len()).map(|e| self.element_volume(e)).sum()
    }

    /// Axis-aligned bounding box `(min, max)` of all nodes, `None` if there are no nodes.
    pub fn bounding_box(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.nodes.first()?;
        let mut lo = first;
        let mut hi = first;
        for p in &self.nodes[1..] {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        Some((lo, hi))
    }

    /// Every element's node indices are within the node list
    /// ([`MeshError::NodeOutOfRange`] naming the first that is not).
    pub(crate) fn check_node_indices(&self) -> Result<(), MeshError> {
        let n = self.nodes.len();
        for (e, t) in self.tets.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::NodeOutOfRange {
                    elem: e,
                    gmsh_tag: None,
                    node: bad,
                    num_nodes: n,
                });
            }
        }
        Ok(())
    }

    /// Checks the mesh and returns the first problem found:
    ///
    /// 1. `body.len() == tets.len()`;
    /// 2. all node coordinates finite (error names the node);
    /// 3. all element node indices in range;
    /// 4. every element positively oriented ([`MeshError::Inverted`] if V < 0)
    ///    and not degenerate ([`MeshError::Degenerate`] if
    ///    |V| <= 1e-12 * (longest edge)^3, checked first);
    /// 5. all node/element/face set indices in range.
    ///
    /// Does not modify the mesh; see [`TetMesh::fix_orientation`].
    pub fn validate(&self) -> Result<(), MeshError> {
        self.validate_impl(None)
    }

    /// [`TetMesh::validate`] with optional Gmsh element tags (indexed like
    /// `tets`) to be named in element errors.
    /// `gmsh`: the Gmsh element tags and node tags of an imported mesh, so
    /// that errors name the element and its nodes as the file does.
    pub(crate) fn validate_impl(&self, gmsh: Option<(&[u64], &[u64])>) -> Result<(), MeshError> {
        if self.body.len() != self.tets.len() {
            return Err(MeshError::BodyLength {
                body_len: self.body.len(),
                num_elems: self.tets.len(),
            });
        }
        if let Some((i, p)) = self
            .nodes
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteNode {
                node: i as u32,
                coords: *p,
            });
        }
        let n = self.nodes.len();
        let tag = |e: usize| gmsh.and_then(|(t, _)| t.get(e).copied());
        let node_tags = |t: &[u32; 4]| {
            gmsh.and_then(|(_, nt)| {
                let mut out = [0u64; 4];
                for (o, &v) in out.iter_mut().zip(t) {
                    *o = *nt.get(v as usize)?;
                }
                Some(out)
            })
        };
        for (e, t) in self.tets.iter().enumerate() {
            if let Some(&bad) = t.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::NodeOutOfRange {
                    elem: e,
                    gmsh_tag: tag(e),
                    node: bad,
                    num_nodes: n,
                });
            }
            let x = self.element_coords(e);
            let v = tet_signed_volume(&x);
            let lmax = edge_lengths_sq(&x)
                .iter()
                .fold(0.0_f64, |m, &l| m.max(l))
                .sqrt();
            if v.abs() <= DEGENERATE_REL_TOL * lmax * lmax * lmax {
                return Err(MeshError::Degenerate {
                    elem: e,
                    gmsh_tag: tag(e),
                    volume: v,
                    longest_edge: lmax,
                    nodes: *t,
                    gmsh_nodes: node_tags(t),
                });
            }
            if v < 0.0 {
                return Err(MeshError::Inverted {
                    elem: e,
                    gmsh_tag: tag(e),
                    volume: v,
                    nodes: *t,
                    gmsh_nodes: node_tags(t),
                });
            }
        }
        self.validate_sets()
    }

    fn validate_sets(&self) -> Result<(), MeshError> {
        let n = self.nodes.len();
        let ne = self.tets.len();
        for (name, s) in &self.node_sets {
            if let Some(&bad) = s.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::SetOutOfRange {
                    kind: "node",
                    name: name.clone(),
                    item: "node",
                    index: bad,
                    count: n,
                });
            }
        }
        for (name, s) in &self.face_sets {
            if let Some(&bad) = s.iter().flatten().find(|&&v| v as usize >= n) {
                return Err(MeshError::SetOutOfRange {
                    kind: "face",
                    name: name.clone(),
                    item: "node",
                    index: bad,
                    count: n,
                });
            }
        }
        for (name, s) in &self.elem_sets {
            if let Some(&bad) = s.iter().find(|&&v| v as usize >= ne) {
                return Err(MeshError::SetOutOfRange {
                    kind: "element",
                    name: name.clone(),
                    item: "element",
                    index: bad,
                    count: ne,
                });
            }
        }
        Ok(())
    }

    /// Makes every element with negative signed volume positively oriented by
    /// swapping its local nodes 2 and 3. Returns the number of elements
    /// changed. Degenerate elements are left as they are (and still fail
    /// [`TetMesh::validate`]).
    ///
    /// # Panics
    /// If an element refers to a node index out of range.
    pub fn fix_orientation(&mut self) -> usize {
        let mut count = 0;
        for e in 0..self.tets.len() {
            if self.element_volume(e) < 0.0 {
                self.tets[e].swap(2, 3);
                count += 1;
            }
        }
        count
    }

    /// Smallest element quality ([`tet_quality`]: 1 for a regular
    /// tetrahedron, <= 0 for degenerate/inverted ones) and the element where
    /// it occurs; `None` for a mesh without elements.
    ///
    /// # Panics
    /// If an element refers to a node index out of range.
    pub fn min_quality(&self) -> Option<(f64, u32)> {
        (0..self.tets.len())
            .map(|e| (tet_quality(&self.element_coords(e)), e as u32))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::unit_tet;
    use super::*;

    fn regular() -> [[f64; 3]; 4] {
        let s = 1.0 / 2f64.sqrt();
        [
            [1.0, 0.0, -s],
            [-1.0, 0.0, -s],
            [0.0, 1.0, s],
            [0.0, -1.0, s],
        ]
    }

    #[test]
    fn signed_volume_of_reference_tet() {
        let m = unit_tet();
        assert!((tet_signed_volume(&m.element_coords(0)) - 1.0 / 6.0).abs() < 1e-15);
        let mut x = m.element_coords(0);
        x.swap(2, 3);
        assert!((tet_signed_volume(&x) + 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn quality_regular_is_one_and_scale_invariant() {
        let mut x = regular();
        if tet_signed_volume(&x) < 0.0 {
            x.swap(2, 3);
        }
        assert!((tet_quality(&x) - 1.0).abs() < 1e-12);
        let y = x.map(|p| p.map(|c| 1e-4 * c + 3.0));
        assert!((tet_quality(&y) - 1.0).abs() < 1e-9);
        x.swap(2, 3);
        assert!((tet_quality(&x) + 1.0).abs() < 1e-12);
        let m = unit_tet();
        let (q, e) = m.min_quality().unwrap();
        assert_eq!(e, 0);
        assert!(q > 0.5 && q < 1.0, "{q}");
        assert!(TetMesh::default().min_quality().is_none());
    }

    #[test]
    fn validate_accepts_good_mesh() {
        let m = unit_tet();
        m.validate().unwrap();
        assert_eq!(m.num_nodes(), 4);
        assert_eq!(m.num_elems(), 1);
        assert_eq!(m.bounding_box(), Some(([0.0; 3], [1.0; 3])));
        assert!(TetMesh::default().bounding_box().is_none());
    }

    #[test]
    fn validate_reports_inverted_and_fix_orientation_repairs() {
        let mut m = unit_tet();
        m.tets[0] = [0, 1, 3, 2];
        let err = m.validate().unwrap_err();
        assert!(matches!(err, MeshError::Inverted { elem: 0, .. }));
        let msg = err.to_string();
        assert!(msg.contains("element 0 is inverted"), "{msg}");
        assert!(msg.contains("-1.667e-1"), "{msg}");
        let tagged = m
            .validate_impl(Some((&[123], &[11, 12, 13, 14])))
            .unwrap_err()
            .to_string();
        assert!(
            tagged.contains("element 0 (gmsh tag 123) is inverted")
                && tagged.contains("gmsh node tags 11,12,14,13"),
            "{tagged}"
        );
        assert_eq!(m.fix_orientation(), 1);
        assert_eq!(m.fix_orientation(), 0);
        m.validate().unwrap();
    }

    #[test]
    fn validate_reports_degenerate() {
        let mut m = unit_tet();
        m.nodes[3] = [0.5, 0.5, 1e-14];
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("element 0 is degenerate"), "{msg}");
        assert!(msg.contains("(nodes 0,1,2,3)"), "{msg}");
        // Repeated node.
        let mut m = unit_tet();
        m.tets[0] = [0, 1, 2, 2];
        assert!(matches!(
            m.validate().unwrap_err(),
            MeshError::Degenerate { elem: 0, .. }
        ));
        // A tiny but well-shaped element is fine (relative tolerance).
        let mut m = unit_tet();
        for p in &mut m.nodes {
            *p = p.map(|c| c * 1e-6);
        }
        m.validate().unwrap();
    }

    #[test]
    fn validate_reports_nan_range_body_and_sets() {
        let mut m = unit_tet();
        m.nodes[2][1] = f64::NAN;
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("node 2 has a non-finite coordinate"), "{msg}");

        let mut m = unit_tet();
        m.tets[0][3] = 9;
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("element 0 refers to node 9"), "{msg}");

        let mut m = unit_tet();
        m.body.push(1);
        assert!(matches!(
            m.validate().unwrap_err(),
            MeshError::BodyLength { .. }
        ));

        let mut m = unit_tet();
        m.node_sets.insert("top".into(), vec![3, 4]);
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("node set 'top' refers to node 4"), "{msg}");

        let mut m = unit_tet();
        m.elem_sets.insert("s".into(), vec![1]);
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("element set 's' refers to element 1"), "{msg}");

        let mut m = unit_tet();
        m.face_sets.insert("f".into(), vec![[0, 1, 7]]);
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("face set 'f' refers to node 7"), "{msg}");
    }
}
