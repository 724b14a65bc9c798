//! `/mesh/hexes` of a series with Hex8 bodies (issue 21): checked, written
//! with the mesh, and compared with the file when a series is continued.

use std::path::Path;

use hdf5::{File, Group};

use super::super::ffi::{self, CollectiveXfer};
use super::super::IoError;
use super::files::fixed_dataset;
use super::{HexRows, MeshPart};

/// This rank's hex rows: whole rows of eight nodes below `global_nodes`,
/// inside the global count, and blocks inside the tets and the rows.
pub(super) fn check_local(mesh: &MeshPart) -> Result<(), String> {
    let Some(h) = &mesh.hexes else {
        return Ok(());
    };
    let n = h.rows.len() as u64 / 8;
    if !h.rows.len().is_multiple_of(8) || h.offset.checked_add(n).is_none_or(|e| e > h.global) {
        return Err(format!(
            "hex rows {}..+{} entries do not fit {} hexes of eight nodes",
            h.offset,
            h.rows.len(),
            h.global
        ));
    }
    if let Some(k) = h
        .rows
        .iter()
        .position(|&v| u64::from(v) >= mesh.global_nodes)
    {
        return Err(format!(
            "hex {} refers to node {}, but global_nodes = {}",
            h.offset + k as u64 / 8,
            h.rows[k],
            mesh.global_nodes
        ));
    }
    let mut rows = 0;
    for b in h.blocks {
        if b.first_hex != rows || b.first_tet + 6 * b.count > mesh.global_cells {
            return Err(format!(
                "hex block of body {:?} (hexes {}.., tets {}..) is out of order or range",
                b.body, b.first_hex, b.first_tet
            ));
        }
        rows += b.count;
    }
    if rows != h.global {
        return Err(format!(
            "the Hex8 bodies have {rows} hexes, the rows {}",
            h.global
        ));
    }
    Ok(())
}

/// Collective. Creates `/mesh/hexes` `[H, 8]` u32 in `mesh_g` and writes
/// this rank's rows.
pub(super) fn write(
    part: &Path,
    mesh_g: &Group,
    xfer: &CollectiveXfer,
    h: &HexRows,
) -> Result<(), IoError> {
    let what = "writing /mesh/hexes";
    let ds = fixed_dataset::<u32>(mesh_g, "hexes", &[h.global, 8])
        .map_err(|e| IoError::hdf5(part, what, e))?;
    let n = h.rows.len() as u64 / 8;
    ffi::write_block(&ds, xfer, &[h.offset, 0], &[n, 8], h.rows).map_err(|call| IoError::Hdf5Call {
        path: part.to_path_buf(),
        call,
        what: what.into(),
    })
}

/// Whether the mesh file of a series being continued has this rank's hex
/// rows (`Ok(true)`), none (`Ok(false)`: written before the hexahedral
/// index, which is then left out), or other ones (`Err` saying so).
pub(super) fn in_file(
    file: &File,
    h5: &Path,
    h: &HexRows,
) -> Result<Result<bool, String>, IoError> {
    if !file.link_exists("mesh/hexes") {
        return Ok(Ok(false));
    }
    let ds = file
        .dataset("mesh/hexes")
        .map_err(|e| IoError::hdf5(h5, "opening /mesh/hexes", e))?;
    if ds.shape() != [h.global as usize, 8] {
        return Ok(Err(format!(
            "its /mesh/hexes is {:?}, this run has {} hexes",
            ds.shape(),
            h.global
        )));
    }
    let n = h.rows.len() / 8;
    let mine = ds
        .read_slice_2d::<u32, _>((h.offset as usize..h.offset as usize + n, ..))
        .map_err(|e| IoError::hdf5(h5, "reading /mesh/hexes", e))?;
    if mine.as_slice() != Some(h.rows) {
        return Ok(Err(
            "its hexes are another mesh's or in another order".into()
        ));
    }
    Ok(Ok(true))
}
