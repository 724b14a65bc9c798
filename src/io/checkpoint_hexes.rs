//! Hex8 bodies in checkpoints (issue 21). A Hex8 body is held as tets
//! (hex `h` is tets `6 h .. 6 h + 6`, `mesh::hex_tets`); its hexes travel
//! with them as each tet corner's place among its hex's eight nodes:
//! - `/mesh/hex_corner` (E×4 u32): for every element, the Table 1 index
//!   (0..8) of each of its four nodes in its hex, [`NO_CORNER`] for the
//!   tets of Tet4 bodies; written only when some body is Hex8;
//! - `/bodies/hex8` (B u64): 1 for the Hex8 bodies.
//!
//! so that a later stage that takes the bodies (`mesh.kind = "checkpoint"`)
//! rebuilds the same hexes, numbered as they were.

use std::path::Path;

use super::checkpoint::CheckpointFile;
use super::IoError;

/// The per-element hex corners.
pub(crate) const HEX_CORNER: &str = "mesh/hex_corner";
/// The per-body Hex8 flags.
pub(crate) const BODY_HEX8: &str = "bodies/hex8";
/// The hex corner of a tet node of a Tet4 body.
pub const NO_CORNER: u32 = 8;

/// Which of the `nb` bodies of checkpoint `file` are Hex8 (none in files
/// without [`BODY_HEX8`]).
pub(super) fn read_body_hex8(
    file: &hdf5::File,
    path: &Path,
    nb: usize,
) -> Result<Vec<bool>, IoError> {
    if !file.link_exists(BODY_HEX8) {
        return Ok(vec![false; nb]);
    }
    let v: Vec<u64> = file
        .dataset(BODY_HEX8)
        .and_then(|d| d.read_raw::<u64>())
        .map_err(|e| IoError::hdf5(path, format!("reading {BODY_HEX8}"), e))?;
    if v.len() != nb {
        return Err(IoError::invalid(
            path,
            format!("{BODY_HEX8} has {} rows for {nb} bodies", v.len()),
        ));
    }
    Ok(v.iter().map(|&x| x != 0).collect())
}

impl CheckpointFile {
    /// The hex corners ([`HEX_CORNER`]) of elements `ids`.
    pub fn elem_hex_corner(&self, ids: &[u32]) -> Result<Vec<[u32; 4]>, IoError> {
        self.rows_of::<u32, 4>(HEX_CORNER, ids, self.head.elems)
    }
}

/// The hexes (Table 1 order) of a Hex8 body from its tets and their hex
/// corners, hex `h` from tets `6 h .. 6 h + 6`; an error names the first
/// element whose corners do not make a hex.
pub fn hexes_from_corners(
    tets: &[[u32; 4]],
    corners: &[[u32; 4]],
) -> Result<Vec<[u32; 8]>, String> {
    if !tets.len().is_multiple_of(6) || corners.len() != tets.len() {
        return Err(format!(
            "{} tets with {} rows of hex corners: not six tets per hex",
            tets.len(),
            corners.len()
        ));
    }
    let mut out = Vec::with_capacity(tets.len() / 6);
    for (h, (t6, c6)) in tets
        .chunks_exact(6)
        .zip(corners.chunks_exact(6))
        .enumerate()
    {
        let mut hex = [u32::MAX; 8];
        for (t, (tet, cs)) in t6.iter().zip(c6).enumerate() {
            for (&n, &k) in tet.iter().zip(cs) {
                let bad = || format!("element {}: node {n} has hex corner {k}", 6 * h + t);
                let slot = hex.get_mut(k as usize).ok_or_else(bad)?;
                if *slot != u32::MAX && *slot != n {
                    return Err(bad());
                }
                *slot = n;
            }
        }
        let mut sorted = hex;
        sorted.sort_unstable();
        if sorted[7] == u32::MAX || sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(format!(
                "elements {}..{}: their hex corners do not name eight distinct nodes",
                6 * h,
                6 * h + 6
            ));
        }
        out.push(hex);
    }
    Ok(out)
}

/// The hex corner of each node of each tet of `tets` (`6 h .. 6 h + 6` in
/// hex `h` of `hexes`, over the same node numbers).
pub fn corners_of(hexes: &[[u32; 8]], tets: &[[u32; 4]]) -> Vec<[u32; 4]> {
    tets.iter()
        .enumerate()
        .map(|(e, t)| {
            let hex = &hexes[e / 6];
            t.map(|n| {
                hex.iter()
                    .position(|&x| x == n)
                    .map_or(NO_CORNER, |k| k as u32)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hexes_come_back_from_their_corners() {
        let s = crate::mesh::hex_tets::box_hex8([0.0; 3], [1.0, 0.5, 0.5], 0.25).unwrap();
        let corners = corners_of(&s.hexes, &s.mesh.tets);
        assert!(corners.iter().flatten().all(|&k| k < 8));
        let back = hexes_from_corners(&s.mesh.tets, &corners).unwrap();
        assert_eq!(back, s.hexes);
        // A corner out of range, or two nodes on one corner, is named.
        let mut bad = corners.clone();
        bad[7][2] = NO_CORNER;
        let e = hexes_from_corners(&s.mesh.tets, &bad).unwrap_err();
        assert!(e.contains("element 7"), "{e}");
        let mut bad = corners;
        bad[6] = [0, 0, 0, 0];
        let e = hexes_from_corners(&s.mesh.tets, &bad).unwrap_err();
        assert!(e.contains("element 6"), "{e}");
        assert!(hexes_from_corners(&s.mesh.tets[..5], &bad[..5]).is_err());
    }
}
