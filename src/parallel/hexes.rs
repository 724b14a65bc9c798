//! The Hex8 elements of a rank's part (issue 21). A Hex8 body's hex `h`
//! is its tets `6 h .. 6 h + 6` (`mesh::hex_tets`), which the partition
//! keeps together, so a hex is six consecutive local elements. The tets
//! serve contact, output and the per-corner sums; the hex's kernels give
//! each of its eight nodes one corner of one of its tets (`corner`), the
//! other sixteen corners nothing.

use crate::model::Model;

/// [`crate::io::checkpoint_hexes::NO_CORNER`] as a part stores it.
const NO_CORNER: u8 = crate::io::checkpoint_hexes::NO_CORNER as u8;

use super::Part;

/// One hex of the part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartHex {
    /// Local element index of its first tet.
    pub first: u32,
    /// Its local nodes, seed 002 Table 1 order.
    pub nodes: [u32; 8],
    /// Per node: (tet 0..6 after `first`, corner 0..4) that carries it.
    pub corner: [(u8, u8); 8],
}

/// The part's hexes, by ascending first element.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PartHexes {
    /// The hexes.
    pub hexes: Vec<PartHex>,
    /// Per local element: the hex it belongs to, or [`PartHexes::NONE`].
    pub of_element: Vec<u32>,
}

impl PartHexes {
    /// Not a hex's tet.
    pub const NONE: u32 = u32::MAX;

    /// The hexes of `part` (empty when no body is Hex8): from the part's
    /// hex corners where it has them (a part built from the model's
    /// bodies, checkpoint bodies included), else from the model's meshes.
    pub fn new(model: &Model, part: &Part) -> PartHexes {
        let mut out = PartHexes::default();
        if !model.has_hexes() {
            return out;
        }
        let ne = part.num_elements();
        out.of_element = vec![Self::NONE; ne];
        let from_corners = part.hex_corner.len() == ne;
        let mut e = 0;
        while e < ne {
            let gid = part.elem_gid[e];
            let hex = if from_corners {
                (part.hex_corner[e][0] != NO_CORNER).then(|| (gid, Self::corner_nodes(part, e)))
            } else {
                model.element_hex(gid)
            };
            let Some((first, nodes)) = hex else {
                e += 1;
                continue;
            };
            assert!(
                gid == first && e + 6 <= ne && part.elem_gid[e + 5] == first + 5,
                "the six tets of the hex at element {first} are on one rank, in order"
            );
            let mut hex = PartHex {
                first: e as u32,
                nodes: [0; 8],
                corner: [(0, 0); 8],
            };
            for (k, &n) in nodes.iter().enumerate() {
                let (t, c) = (0..6)
                    .flat_map(|t| (0..4).map(move |c| (t, c)))
                    .find(|&(t, c)| part.node_gid[part.mesh.tets[e + t][c] as usize] == n)
                    .expect("each node of a hex is a corner of one of its tets");
                hex.nodes[k] = part.mesh.tets[e + t][c];
                hex.corner[k] = (t as u8, c as u8);
            }
            let h = out.hexes.len() as u32;
            out.of_element[e..e + 6].fill(h);
            out.hexes.push(hex);
            e += 6;
        }
        out
    }

    /// The eight nodes (global ids) of the hex whose first tet is local
    /// element `e`, from the part's hex corners.
    fn corner_nodes(part: &Part, e: usize) -> [u32; 8] {
        let mut nodes = [u32::MAX; 8];
        for t in e..(e + 6).min(part.num_elements()) {
            for (c, &k) in part.hex_corner[t].iter().enumerate() {
                if let Some(n) = nodes.get_mut(k as usize) {
                    *n = part.node_gid[part.mesh.tets[t][c] as usize];
                }
            }
        }
        nodes
    }

    /// Whether the part has no hexes.
    pub fn is_empty(&self) -> bool {
        self.hexes.is_empty()
    }

    /// The hex's `values` (one per node) as its six tets' corner values:
    /// tet `t` of the hex, corner `c`.
    pub fn corner_values(hex: &PartHex, values: &[f64; 8], t: usize) -> [f64; 4] {
        let mut out = [0.0; 4];
        for (k, &(tk, c)) in hex.corner.iter().enumerate() {
            if tk as usize == t {
                out[c as usize] = values[k];
            }
        }
        out
    }
}
