//! Structured Hex8 meshes: the nx × ny × nz box generator, with the node
//! order of seed 002 Table 1 (bottom face counter-clockwise seen from +z,
//! then the top face), so every element has a positive Jacobian.

use std::collections::BTreeMap;

use super::MeshError;

/// A Hex8 mesh of one body.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HexMesh {
    /// Node coordinates (m).
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity (seed 002 Table 1 order).
    pub hexes: Vec<[u32; 8]>,
    /// Named node sets (sorted): `xmin`, `xmax`, `ymin`, `ymax`, `zmin`, `zmax`.
    pub node_sets: BTreeMap<String, Vec<u32>>,
}

impl HexMesh {
    /// Coordinates of the nodes of element `e`.
    pub fn element_coords(&self, e: usize) -> [[f64; 3]; 8] {
        self.hexes[e].map(|n| self.nodes[n as usize])
    }
}

/// The box [lo, hi] cut into n[0] × n[1] × n[2] equal Hex8. Node (i, j, k)
/// has index i + (n0+1)(j + (n1+1) k); element (i, j, k) has index
/// i + n0 (j + n1 k). Errors if a count is zero, the box is empty or not
/// finite, or the mesh would exceed [`super::MAX_ELEMENTS`].
pub fn hex_box(lo: [f64; 3], hi: [f64; 3], n: [usize; 3]) -> Result<HexMesh, MeshError> {
    for a in 0..3 {
        let ordered = hi[a] > lo[a] && lo[a].is_finite() && hi[a].is_finite();
        if n[a] == 0 || !ordered {
            return Err(MeshError::InvalidParameter(format!(
                "Hex8 box: need n >= 1 and lo < hi along each axis, got n = {n:?}, lo = {lo:?}, hi = {hi:?}"
            )));
        }
    }
    super::check_element_count("the Hex8 box", n.iter().map(|&c| c as u128).product())?;
    let np = [n[0] + 1, n[1] + 1, n[2] + 1];
    let node = |i: usize, j: usize, k: usize| (i + np[0] * (j + np[1] * k)) as u32;
    let mut nodes = Vec::with_capacity(np[0] * np[1] * np[2]);
    for k in 0..np[2] {
        for j in 0..np[1] {
            for i in 0..np[0] {
                let c = [i, j, k];
                nodes.push(std::array::from_fn(|a| {
                    if c[a] == n[a] {
                        hi[a]
                    } else {
                        lo[a] + (hi[a] - lo[a]) * c[a] as f64 / n[a] as f64
                    }
                }));
            }
        }
    }
    let mut hexes = Vec::with_capacity(n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                hexes.push([
                    node(i, j, k),
                    node(i + 1, j, k),
                    node(i + 1, j + 1, k),
                    node(i, j + 1, k),
                    node(i, j, k + 1),
                    node(i + 1, j, k + 1),
                    node(i + 1, j + 1, k + 1),
                    node(i, j + 1, k + 1),
                ]);
            }
        }
    }
    let mut node_sets = BTreeMap::new();
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        for (side, at) in [("min", 0), ("max", n[a])] {
            let set: Vec<u32> = (0..nodes.len() as u32)
                .filter(|&p| {
                    let p = p as usize;
                    let c = [p % np[0], (p / np[0]) % np[1], p / (np[0] * np[1])];
                    c[a] == at
                })
                .collect();
            node_sets.insert(format!("{axis}{side}"), set);
        }
    }
    Ok(HexMesh {
        nodes,
        hexes,
        node_sets,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::hex8::hex8_jacobian;
    use nalgebra::Vector3;

    #[test]
    fn box_has_the_right_counts_volume_and_sets() {
        let m = hex_box([0.0, 0.0, 0.0], [2.0, 1.0, 0.5], [4, 2, 3]).unwrap();
        assert_eq!(m.nodes.len(), 5 * 3 * 4);
        assert_eq!(m.hexes.len(), 24);
        let mut volume = 0.0;
        for e in 0..m.hexes.len() {
            let x = m.element_coords(e).map(Vector3::from);
            let det = hex8_jacobian(&x, &Vector3::zeros()).determinant();
            assert!(det > 0.0);
            volume += 8.0 * det;
        }
        assert!((volume - 1.0).abs() < 1e-12);
        assert_eq!(m.node_sets["xmin"].len(), 3 * 4);
        assert_eq!(m.node_sets["zmax"].len(), 5 * 3);
        assert!(m.node_sets["xmax"]
            .iter()
            .all(|&p| m.nodes[p as usize][0] == 2.0));
        assert!(hex_box([0.0; 3], [1.0; 3], [0, 1, 1]).is_err());
        assert!(hex_box([0.0; 3], [1.0, 0.0, 1.0], [1, 1, 1]).is_err());
    }
}
