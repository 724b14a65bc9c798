//! Checks that every rank of a collective write passes the same thing
//! (names, shapes, times: an FNV-1a signature agreed over the ranks), that
//! the row blocks tile the global arrays, and that a mesh part is sound;
//! and the agreement on a local step's outcome.

use std::path::Path;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};

use super::super::check_name;
use super::super::xdmf::{self, FieldDesc};
use super::super::IoError;
use super::{FieldLists, Inner, MeshPart};

/// FNV-1a, used to check that all ranks pass the same names, shapes and times.
#[derive(Clone, Copy)]
pub(super) struct Fnv(pub(super) u64);

impl Fnv {
    pub(super) fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    pub(super) fn bytes(mut self, b: &[u8]) -> Self {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }
    pub(super) fn u64(self, v: u64) -> Self {
        self.bytes(&v.to_le_bytes())
    }
    pub(super) fn str(self, s: &str) -> Self {
        self.u64(s.len() as u64).bytes(s.as_bytes())
    }
}

/// Agrees on the outcome of a local step: returns the local error, or
/// [`IoError::OtherRank`] if this rank succeeded but another did not.
pub(super) fn agree<T>(
    comm: &SimpleCommunicator,
    path: &Path,
    what: &str,
    local: Result<T, IoError>,
) -> Result<T, IoError> {
    let ok = i32::from(local.is_ok());
    let mut all_ok = 0_i32;
    comm.all_reduce_into(&ok, &mut all_ok, SystemOperation::min());
    match local {
        Err(e) => Err(e),
        Ok(_) if all_ok == 0 => Err(IoError::OtherRank {
            path: path.to_path_buf(),
            what: what.to_string(),
        }),
        Ok(v) => Ok(v),
    }
}

/// Like [`agree`], and also checks that every rank passed the same `signature`.
pub(super) fn agree_signature(
    comm: &SimpleCommunicator,
    path: &Path,
    what: &str,
    local: Result<(), IoError>,
    signature: u64,
) -> Result<(), IoError> {
    let mine = [u64::from(local.is_ok()), signature];
    let mut all = vec![0_u64; 2 * comm.size() as usize];
    comm.all_gather_into(&mine[..], &mut all[..]);
    local?;
    if all.chunks(2).any(|r| r[0] == 0) {
        return Err(IoError::OtherRank {
            path: path.to_path_buf(),
            what: what.to_string(),
        });
    }
    if all.chunks(2).any(|r| r[1] != signature) {
        return Err(IoError::invalid(
            path,
            format!("{what}: ranks passed different names, component counts or times"),
        ));
    }
    Ok(())
}

/// Checks that the non-empty blocks `(offset, count)` tile `0..global` exactly.
pub(super) fn check_tiling(
    kind: &str,
    global: u64,
    mut blocks: Vec<(u64, u64)>,
) -> Result<(), String> {
    blocks.retain(|b| b.1 > 0);
    blocks.sort_unstable();
    let mut next = 0_u64;
    for (offset, count) in blocks {
        if offset != next {
            return Err(format!(
                "{kind} blocks of the ranks do not tile 0..{global}: expected a block at row {next}, found one at {offset}"
            ));
        }
        next = offset + count;
    }
    if next != global {
        return Err(format!(
            "{kind} blocks of the ranks cover 0..{next}, but the global count is {global}"
        ));
    }
    Ok(())
}

/// Local checks of a mesh part (no communication).
pub(super) fn check_mesh_local(mesh: &MeshPart) -> Result<(), String> {
    let n = mesh.coords.len() as u64;
    let npc = mesh.nodes_per_cell;
    if !(npc == 1 || npc == 3 || npc == 4) || !mesh.cells.len().is_multiple_of(npc) {
        return Err(format!(
            "cells of {npc} nodes ({} entries): only points (1), triangles (3) and Tet4 (4)",
            mesh.cells.len()
        ));
    }
    let e = (mesh.cells.len() / npc) as u64;
    if mesh
        .node_offset
        .checked_add(n)
        .is_none_or(|end| end > mesh.global_nodes)
    {
        return Err(format!(
            "owned nodes {}..{}+{n} exceed global_nodes = {}",
            mesh.node_offset, mesh.node_offset, mesh.global_nodes
        ));
    }
    if mesh
        .cell_offset
        .checked_add(e)
        .is_none_or(|end| end > mesh.global_cells)
    {
        return Err(format!(
            "owned cells {}..{}+{e} exceed global_cells = {}",
            mesh.cell_offset, mesh.cell_offset, mesh.global_cells
        ));
    }
    for (i, cell) in mesh.cells.chunks_exact(npc).enumerate() {
        if let Some(&bad) = cell.iter().find(|&&v| u64::from(v) >= mesh.global_nodes) {
            return Err(format!(
                "cell {} refers to node {bad}, but global_nodes = {}",
                mesh.cell_offset + i as u64,
                mesh.global_nodes
            ));
        }
    }
    Ok(())
}

impl Inner {
    /// Local validation of a step's arguments.
    pub(super) fn check_step(&self, time: f64, lists: FieldLists<'_, '_>) -> Result<(), String> {
        if !time.is_finite() {
            return Err(format!("time {time} is not finite"));
        }
        if let Some(&last) = self.model.times.last() {
            if time <= last {
                return Err(format!(
                    "time {time:e} is not larger than the previous step's time {last:e}"
                ));
            }
        }
        for (center, list) in lists {
            let rows = self.rows(center).count;
            let kind = center.group();
            for (i, &(name, comps, values)) in list.iter().enumerate() {
                check_name(&format!("{kind} field"), name)?;
                if xdmf::attribute_type(comps).is_none() {
                    return Err(format!(
                        "{kind} field {name:?}: {comps} components (supported: 1, 3, 6, 9)"
                    ));
                }
                if list[..i].iter().any(|f| f.0 == name) {
                    return Err(format!("{kind} field {name:?} is given twice"));
                }
                if values.len() as u64 != rows * comps as u64 {
                    return Err(format!(
                        "{kind} field {name:?} has {} values on rank {}, expected {rows} rows x {comps} = {}",
                        values.len(),
                        self.rank,
                        rows * comps as u64
                    ));
                }
            }
            if let Some(fields) = &self.fields {
                let known: Vec<&FieldDesc> = fields.iter().filter(|d| d.center == center).collect();
                for d in &known {
                    match list.iter().find(|f| f.0 == d.name) {
                        None => {
                            return Err(format!(
                                "{kind} field {:?} is missing (the first step fixes the field set)",
                                d.name
                            ))
                        }
                        Some(f) if f.1 != d.components => {
                            return Err(format!(
                                "{kind} field {:?} has {} components, the first step had {}",
                                d.name, f.1, d.components
                            ))
                        }
                        Some(_) => {}
                    }
                }
                if let Some(extra) = list.iter().find(|f| !known.iter().any(|d| d.name == f.0)) {
                    return Err(format!(
                        "{kind} field {:?} was not in the first step (the first step fixes the field set)",
                        extra.0
                    ));
                }
            }
        }
        Ok(())
    }
}
