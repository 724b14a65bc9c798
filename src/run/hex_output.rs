//! The hexes of the Hex8 bodies for the series' hexahedral index (issue
//! 21, `<stem>_hex8.xdmf`): each rank lists the hexes of its part and
//! moves them to its block of the global hex numbering (hexes numbered
//! body by body, each body's in its own order), like the cell fields.

use mpi::topology::SimpleCommunicator;

use crate::io::{HexBlock, HexRows};
use crate::model::Model;
use crate::parallel::exchange::to_blocks;
use crate::parallel::{Part, PartHexes};

/// This rank's rows of `/mesh/hexes` and the per-body blocks.
pub(super) struct HexOutput {
    /// Global node ids, eight per hex of this rank's block.
    rows: Vec<u32>,
    /// Global number of this rank's first row.
    offset: u64,
    /// Number of hexes over all ranks.
    global: u64,
    /// Per Hex8 body: where its tets and hexes are.
    blocks: Vec<HexBlock>,
}

impl HexOutput {
    /// Collective. The hexes of `part` in global rows; `None` (on every
    /// rank) when no body is Hex8.
    pub(super) fn new(comm: &SimpleCommunicator, model: &Model, part: &Part) -> Option<Self> {
        if !model.has_hexes() {
            return None;
        }
        // O(bodies), the same on every rank.
        let mut blocks = Vec::new();
        let mut block_of_body = vec![usize::MAX; model.bodies.len()];
        let mut next = 0u64;
        for (b, body) in model.bodies.iter().enumerate() {
            if model.body_is_hex8(b) {
                let (e0, e1) = body.elem_range;
                let count = u64::from(e1 - e0) / 6;
                block_of_body[b] = blocks.len();
                blocks.push(HexBlock {
                    body: body.name.clone(),
                    first_tet: u64::from(e0),
                    first_hex: next,
                    count,
                });
                next += count;
            }
        }
        let hexes = PartHexes::new(model, part);
        let mut ids = Vec::with_capacity(hexes.hexes.len());
        let mut nodes = Vec::with_capacity(8 * hexes.hexes.len());
        for h in &hexes.hexes {
            let gid = part.elem_gid[h.first as usize];
            let b = &blocks[block_of_body[model.body_of_elem(gid)]];
            ids.push((b.first_hex + (u64::from(gid) - b.first_tet) / 6) as u32);
            nodes.extend(h.nodes.map(|l| f64::from(part.node_gid[l as usize])));
        }
        let (offset, rows) = to_blocks(comm, &ids, &nodes, 8, next);
        Some(Self {
            rows: rows.iter().map(|&n| n as u32).collect(),
            offset,
            global: next,
            blocks,
        })
    }

    /// As the writer takes them.
    pub(super) fn rows(&self) -> HexRows<'_> {
        HexRows {
            global: self.global,
            offset: self.offset,
            rows: &self.rows,
            blocks: &self.blocks,
        }
    }
}
