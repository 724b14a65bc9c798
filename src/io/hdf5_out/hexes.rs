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
/// index or before its cell fields `/static/hex`, `/fields/hex`, and the
/// index is then left out), or other ones (`Err` saying so).
pub(super) fn in_file(
    file: &File,
    h5: &Path,
    h: &HexRows,
) -> Result<Result<bool, String>, IoError> {
    if !file.link_exists("mesh/hexes") || !file.link_exists("static/hex") {
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

/// The hexes' cell values a rank writes (`/static/hex/*`, `/fields/hex/*`):
/// a hex's row is its first tet's (the six tets of a hex carry the hex's
/// values), written by the rank whose cell rows hold that tet. The hexes
/// are numbered body by body as their first tets are, so a rank's hexes
/// are one contiguous block of rows and the ranks' blocks tile the hexes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Sample {
    /// Number of hexes over all ranks.
    pub(super) global: u64,
    /// This rank's hex rows are `offset .. offset + local.len()`.
    pub(super) offset: u64,
    /// Each of them as an index into this rank's cell rows.
    pub(super) local: Vec<usize>,
}

impl Sample {
    /// The hexes of `blocks` whose first tet lies in the cell rows
    /// `c0 .. c0 + count`.
    pub(super) fn new(global: u64, blocks: &[super::super::HexBlock], c0: u64, count: u64) -> Self {
        // Hexes k of a block with first tet first_tet + 6 k < t: ⌈(t − first_tet)/6⌉, clamped.
        let before = |b: &super::super::HexBlock, t: u64| {
            t.saturating_sub(b.first_tet).div_ceil(6).min(b.count)
        };
        let mut offset = 0;
        let mut local = Vec::new();
        for b in blocks {
            let (k0, k1) = (before(b, c0), before(b, c0 + count));
            offset += k0;
            local.extend((k0..k1).map(|k| (b.first_tet + 6 * k - c0) as usize));
        }
        Self {
            global,
            offset,
            local,
        }
    }

    /// This rank's hex rows of a cell field of `comps` components.
    pub(super) fn pick<T: Copy>(&self, values: &[T], comps: usize) -> Vec<T> {
        let mut out = Vec::with_capacity(self.local.len() * comps);
        for &r in &self.local {
            out.extend_from_slice(&values[r * comps..(r + 1) * comps]);
        }
        out
    }

    /// Collective. Creates `<group>/<name>` (`[H]`, or `[H, comps]`) and
    /// writes this rank's hex rows of the cell field `values`.
    pub(super) fn write<T: hdf5::H5Type + Copy>(
        &self,
        part: &Path,
        group: &Group,
        xfer: &CollectiveXfer,
        (name, comps, values): (&str, usize, &[T]),
    ) -> Result<(), IoError> {
        let what = format!("writing the hexes' {name}");
        let n = self.local.len() as u64;
        let c = comps as u64;
        let (shape, start, count) = if comps == 1 {
            (vec![self.global], vec![self.offset], vec![n])
        } else {
            (vec![self.global, c], vec![self.offset, 0], vec![n, c])
        };
        let ds = fixed_dataset::<T>(group, name, &shape)
            .map_err(|e| IoError::hdf5(part, what.clone(), e))?;
        ffi::write_block(&ds, xfer, &start, &count, &self.pick(values, comps)).map_err(|call| {
            IoError::Hdf5Call {
                path: part.to_path_buf(),
                call,
                what,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::HexBlock;

    #[test]
    fn ranks_sample_each_hex_once_at_its_first_tet_whatever_the_cut() {
        // Hexes of body a on tets 6..24 (3 hexes), a Tet4 body on 24..30,
        // body b on tets 30..42 (2 hexes); 45 tets in all.
        let block = |body: &str, first_tet, first_hex, count| HexBlock {
            body: body.into(),
            first_tet,
            first_hex,
            count,
        };
        let blocks = [block("a", 6, 0, 3), block("b", 30, 3, 2)];
        let first_tets = [6, 12, 18, 30, 36];
        for cuts in [
            vec![0, 45],
            vec![0, 13, 45],
            vec![0, 7, 12, 31, 31, 45],
            vec![0, 20, 20, 25, 44, 45],
        ] {
            let mut next = 0;
            for w in cuts.windows(2) {
                let (c0, c1) = (w[0], w[1]);
                let s = Sample::new(5, &blocks, c0, c1 - c0);
                // The ranks' blocks follow one another.
                assert_eq!(s.offset, next, "{cuts:?}");
                for (k, &r) in s.local.iter().enumerate() {
                    assert_eq!(c0 + r as u64, first_tets[s.offset as usize + k], "{cuts:?}");
                }
                next += s.local.len() as u64;
            }
            assert_eq!(next, 5, "{cuts:?}");
        }
        let s = Sample::new(5, &blocks, 10, 25);
        assert_eq!((s.offset, s.local.clone()), (1, vec![2, 8, 20]));
        let values: Vec<f64> = (0..50).map(f64::from).collect();
        assert_eq!(s.pick(&values, 2), [4.0, 5.0, 16.0, 17.0, 40.0, 41.0]);
    }
}
