//! The contact status of every boundary face (issue 20, seed 001 sec
//! 7.1.1): `<stem>_status.h5` and `<stem>_status.xdmf`, a time series
//! beside the bodies' whose cells are the bodies' boundary triangles, with
//! the cell field `status`: 0 free, 1 near-field (across a gap within the
//! pinball), 2 closed (the face has contact surface), 3 sliding (closed,
//! with a slip speed above `contact.sliding_speed`), and a point field
//! `displacement` (ParaView: Warp By Vector). The faces are those of the
//! bodies' boundaries at the start (crack faces opened later are not in
//! the grid).
//!
//! Rows follow the element ids: the faces of elements in the block
//! [`block`] of ids that rank r holds are rank r's rows, in (element id,
//! local face) order, so the files do not depend on the number of ranks
//! and nothing of the size of the mesh is held on one rank. Each output,
//! element owners send their boundary elements' corners, and the ranks
//! that found pairs and gap links send the faces' status bits, to the
//! block holders.

use std::path::{Path, PathBuf};

use mpi::collective::SystemOperation;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::*;

use crate::contact::ContactSet;
use crate::error::Result;
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::mesh::LOCAL_FACES;
use crate::model::Model;
use crate::parallel::exchange::{all_gather, all_to_all, block_owner, Received};
use crate::parallel::Part;

/// Status codes of the `status` field.
pub const FREE: u8 = 0;
/// Across a gap within the pinball distance.
pub const NEAR_FIELD: u8 = 1;
/// Touching: the face has contact surface.
pub const CLOSED: u8 = 2;
/// Closed and slipping.
pub const SLIDING: u8 = 3;

/// The status of a face from its bits (closed, sliding, near-field).
pub fn face_status(closed: bool, sliding: bool, near: bool) -> u8 {
    match (closed, sliding, near) {
        (true, true, _) => SLIDING,
        (true, false, _) => CLOSED,
        (false, _, true) => NEAR_FIELD,
        _ => FREE,
    }
}

/// Per boundary element of this rank's block: its id and face mask.
struct Block {
    gid: Vec<u32>,
    mask: Vec<u8>,
}

impl Block {
    fn faces(&self) -> usize {
        self.mask.iter().map(|m| m.count_ones() as usize).sum()
    }

    fn find(&self, gid: u32) -> Option<usize> {
        self.gid.binary_search(&gid).ok()
    }
}

/// Collective. Send rows (id first) to the holders of their ids' blocks;
/// what arrived here, by source rank (no row is a heap allocation, and
/// what arrives is not copied again).
fn to_holders<const W: usize>(
    comm: &SimpleCommunicator,
    total: u64,
    rows: impl Iterator<Item = [f64; W]>,
) -> Received<f64> {
    let size = comm.size() as usize;
    let mut send: Vec<Vec<f64>> = vec![Vec::new(); size];
    for r in rows {
        send[block_owner(r[0] as u64, total, size)].extend_from_slice(&r);
    }
    all_to_all(comm, send)
}

/// The rows of `W` values that arrived.
fn rows_of<const W: usize>(got: &Received<f64>) -> impl Iterator<Item = &[f64]> + '_ {
    got.iter().flat_map(|list| list.chunks_exact(W))
}

/// The open status series.
pub(super) struct StatusOutput {
    writer: TimeSeriesWriter,
    block: Block,
    elements: u64,
    /// The paths of the series.
    pub xdmf: PathBuf,
    /// The last statuses, with a hash of this rank's status rows they came
    /// from: while no rank's rows change (a thermal run between
    /// detections), the history rows and outputs reuse them.
    last: std::cell::RefCell<Option<(u64, Vec<u8>)>>,
}

/// Boundary faces by status over the ranks (free, near-field, closed, sliding).
pub type StatusCounts = [u64; 4];

impl StatusOutput {
    /// Collective. Create `<dir>/<stem>_status.h5` with the boundary faces
    /// at their reference positions (or reopen it to continue after the
    /// checkpoint at `continue_after`).
    pub fn open(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        dir: &Path,
        stem: &str,
        continue_after: Option<f64>,
    ) -> Result<StatusOutput> {
        let elements = model.totals().1;
        let rows = (0..part.num_elements())
            .filter(|&e| part.face_mask[e] != 0)
            .map(|e| {
                let mut r = [0.0; 15];
                r[0] = f64::from(part.elem_gid[e]);
                r[1] = f64::from(part.face_mask[e]);
                r[2] = f64::from(part.mesh.body[e]);
                for (k, &n) in part.mesh.tets[e].iter().enumerate() {
                    r[3 + 3 * k..6 + 3 * k].copy_from_slice(&part.mesh.nodes[n as usize]);
                }
                r
            });
        let got = to_holders(comm, elements, rows);
        let mut recs: Vec<&[f64]> = rows_of::<15>(&got).collect();
        recs.sort_by_key(|r| r[0] as u32);
        let block = Block {
            gid: recs.iter().map(|r| r[0] as u32).collect(),
            mask: recs.iter().map(|r| r[1] as u8).collect(),
        };
        let mine = block.faces() as u64;
        let mut coords: Vec<[f64; 3]> = Vec::with_capacity(3 * mine as usize);
        let mut body = Vec::with_capacity(mine as usize);
        for r in &recs {
            let m = r[1] as u8;
            for (f, face) in LOCAL_FACES.iter().enumerate() {
                if m & (1 << f) != 0 {
                    for &k in face {
                        coords.push([r[3 + 3 * k], r[4 + 3 * k], r[5 + 3 * k]]);
                    }
                    body.push(r[2] as i32);
                }
            }
        }
        drop(recs);
        drop(got);
        let counts = all_gather(comm, &[mine]);
        let offset: u64 = counts[..comm.rank() as usize].iter().sum();
        let total: u64 = counts.iter().sum();
        let cells: Vec<u32> = (0..3 * mine).map(|p| (3 * offset + p) as u32).collect();
        let mesh = MeshPart {
            global_nodes: 3 * total,
            node_offset: 3 * offset,
            coords: &coords,
            global_cells: total,
            cell_offset: offset,
            cells: &cells,
            nodes_per_cell: 3,
            hexes: None,
        };
        let name = format!("{stem}_status");
        let point_row: Vec<i32> = (0..3 * mine).map(|p| (3 * offset + p) as i32).collect();
        let writer = match continue_after {
            Some(t) => TimeSeriesWriter::reopen(comm, dir, &name, &mesh, &point_row, t)?,
            None => {
                let mut w = TimeSeriesWriter::create(comm, dir, &name, &mesh)?;
                // A restart in place checks the rows against these ids.
                w.write_static_node_field_i32("node_id", &point_row)?;
                w.write_static_cell_field_i32("body", &body)?;
                w
            }
        };
        let xdmf = writer.xdmf_path().to_path_buf();
        Ok(StatusOutput {
            writer,
            block,
            elements,
            xdmf,
            last: std::cell::RefCell::new(None),
        })
    }

    /// Collective. The status of each face of the block, from the pairs'
    /// and gap links' faces (any rank's).
    fn statuses(&self, comm: &SimpleCommunicator, contacts: &ContactSet, sliding: f64) -> Vec<u8> {
        let hash = crate::parallel::fingerprint(status_words(contacts, sliding));
        let mine = u8::from(self.last.borrow().as_ref().is_some_and(|(k, _)| *k == hash));
        let mut all = 0u8;
        comm.all_reduce_into(&mine, &mut all, SystemOperation::min());
        if all == 1 {
            return self.last.borrow().as_ref().expect("kept").1.clone();
        }
        let out = self.compute_statuses(comm, status_rows(contacts, sliding));
        *self.last.borrow_mut() = Some((hash, out.clone()));
        out
    }

    /// Collective. [`StatusOutput::statuses`] from this rank's status rows.
    fn compute_statuses(&self, comm: &SimpleCommunicator, rows: Vec<u64>) -> Vec<u8> {
        let size = comm.size() as usize;
        let mut send: Vec<Vec<u64>> = vec![Vec::new(); size];
        for w in rows {
            send[block_owner(w >> 32, self.elements, size)].push(w);
        }
        let got = all_to_all(comm, send);
        let n = self.block.gid.len();
        let mut bits = vec![[0u8; 3]; n];
        for &w in got.iter().flatten() {
            if let Some(i) = self.block.find((w >> 32) as u32) {
                for (k, b) in bits[i].iter_mut().enumerate() {
                    *b |= (w >> (8 * k)) as u8;
                }
            }
        }
        let mut out = Vec::with_capacity(self.block.faces());
        for (i, &m) in self.block.mask.iter().enumerate() {
            for f in (0..4).filter(|f| m & (1 << f) != 0) {
                let b = |k: usize| bits[i][k] & (1 << f) != 0;
                out.push(face_status(b(0), b(1), b(2)));
            }
        }
        out
    }

    /// Collective. The faces by status over the ranks.
    pub fn counts(
        &self,
        comm: &SimpleCommunicator,
        contacts: &ContactSet,
        sliding: f64,
    ) -> StatusCounts {
        count(comm, &self.statuses(comm, contacts, sliding))
    }

    /// Collective. Write the faces' status and displacement at `time`, the
    /// part's nodes at `positions` (part order; the displacement is taken
    /// from the part's reference coordinates by the element's owner);
    /// returns the counts.
    pub fn write(
        &mut self,
        comm: &SimpleCommunicator,
        part: &Part,
        positions: &[[f64; 3]],
        contacts: &ContactSet,
        sliding: f64,
        time: f64,
    ) -> Result<StatusCounts> {
        let status = self.statuses(comm, contacts, sliding);
        // No node moved on any rank (a heat-up): the displacements are zero
        // and nothing is sent.
        let moved = positions
            .iter()
            .zip(&part.mesh.nodes)
            .any(|(x, x0)| x != x0);
        let mut any = 0u8;
        comm.all_reduce_into(&u8::from(moved), &mut any, SystemOperation::max());
        let u = if any == 0 {
            vec![0.0; 9 * self.block.faces()]
        } else {
            self.displacements(comm, part, positions)
        };
        let s: Vec<f64> = status.iter().map(|&v| f64::from(v)).collect();
        self.writer.write_step(
            time,
            &[("displacement", 3, &u[..])],
            &[("status", 1, &s[..])],
        )?;
        Ok(count(comm, &status))
    }

    /// Collective. The displacements of the block's faces' corners (9 a
    /// face, in block order), sent by the elements' owners.
    fn displacements(
        &self,
        comm: &SimpleCommunicator,
        part: &Part,
        positions: &[[f64; 3]],
    ) -> Vec<f64> {
        let rows = (0..part.num_elements())
            .filter(|&e| part.face_mask[e] != 0)
            .map(|e| {
                let mut r = [0.0; 13];
                r[0] = f64::from(part.elem_gid[e]);
                for (k, &n) in part.mesh.tets[e].iter().enumerate() {
                    let (x, x0) = (positions[n as usize], part.mesh.nodes[n as usize]);
                    for d in 0..3 {
                        r[1 + 3 * k + d] = x[d] - x0[d];
                    }
                }
                r
            });
        let got = to_holders(comm, self.elements, rows);
        // Each arriving element's place in the block, then the faces' corners
        // in block order.
        let mut at = vec![u32::MAX; self.block.gid.len()];
        let got_rows: Vec<&[f64]> = rows_of::<13>(&got).collect();
        for (j, r) in got_rows.iter().enumerate() {
            if let Some(i) = self.block.find(r[0] as u32) {
                at[i] = j as u32;
            }
        }
        let mut u = Vec::with_capacity(9 * self.block.faces());
        // (Every boundary element of the block arrives from its owner.)
        let none = [0.0; 13];
        for (i, &m) in self.block.mask.iter().enumerate() {
            let r = got_rows.get(at[i] as usize).copied().unwrap_or(&none);
            for (f, face) in LOCAL_FACES.iter().enumerate() {
                if m & (1 << f) != 0 {
                    for &k in face {
                        u.extend_from_slice(&r[1 + 3 * k..4 + 3 * k]);
                    }
                }
            }
        }
        u
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        Ok(())
    }
}

/// Collective. Faces by status over the ranks.
fn count(comm: &SimpleCommunicator, status: &[u8]) -> StatusCounts {
    let mut mine = [0u64; 4];
    for &s in status {
        mine[s as usize] += 1;
    }
    let mut all = [0u64; 4];
    comm.all_reduce_into(&mine[..], &mut all[..], SystemOperation::sum());
    all
}

/// The faces that this rank's pairs and gap links touch, one word per
/// pair's tet and gap link's side: the element id in the high 32 bits,
/// then its closed, sliding and near-field face bits in bytes 0, 1 and 2.
fn status_words(contacts: &ContactSet, sliding: f64) -> impl Iterator<Item = u64> + '_ {
    let word = |gid: u32, closed: u8, slides: u8, near: u8| {
        u64::from(gid) << 32 | u64::from(closed) | u64::from(slides) << 8 | u64::from(near) << 16
    };
    let pairs = contacts
        .local
        .iter()
        .zip(&contacts.dofs)
        .flat_map(move |(p, d)| {
            let s = |faces: u8| if d.slip > sliding { faces } else { 0 };
            let (t, c) = (p.surface.faces_target, p.surface.faces_contactor);
            [word(p.target, t, s(t), 0), word(p.contactor, c, s(c), 0)]
        });
    let gaps = contacts
        .gaps
        .iter()
        .flat_map(move |l| [0, 1].map(|k| word(l.tets[k], 0, 0, 1u8 << l.faces[k])));
    pairs.chain(gaps)
}

/// [`status_words`] merged to one word per element, ascending (rows of
/// four floats a pair's tet, sent unmerged, were the peak of the N = 2000
/// heat-up on 8 ranks).
fn status_rows(contacts: &ContactSet, sliding: f64) -> Vec<u64> {
    let mut rows: Vec<u64> = status_words(contacts, sliding).collect();
    rows.sort_unstable();
    // One word per element: the bits of its rows or'ed.
    rows.dedup_by(|next, kept| {
        let same = *next >> 32 == *kept >> 32;
        if same {
            *kept |= *next;
        }
        same
    });
    rows.shrink_to_fit();
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_wins_over_near_and_sliding_needs_closed() {
        assert_eq!(face_status(false, false, false), FREE);
        assert_eq!(face_status(false, false, true), NEAR_FIELD);
        assert_eq!(face_status(true, false, true), CLOSED);
        assert_eq!(face_status(true, true, false), SLIDING);
        assert_eq!(face_status(false, true, true), NEAR_FIELD);
    }
}
