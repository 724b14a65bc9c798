//! The tangential springs' part of a checkpoint
//! (`mechanics.contact.tangential_stiffness`): `state/springs`, one row per
//! touching pair with a spring, (a, b, F_e (N), the energy it holds (J)) by the global numbers
//! of its tets, rows in ascending (a, b) whatever the ranks; each rank
//! writes its block of the sorted rows and reads a block back at a
//! restart (the first detection hands them to the pairs' new holders,
//! `dynamics::springs`).

use std::path::Path;

use hdf5::File;
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::checkpoint::CheckpointFile;
use super::IoError;

/// The dataset.
pub const SPRINGS: &str = "state/springs";
/// Its columns: a, b, F_e, the energy held.
pub const SPRING_COLUMNS: usize = 6;

/// A pair by its tets' global numbers, and its spring's elastic force F_e (N).
pub type SavedSpring = ((u32, u32), crate::contact::penalty::Spring);

/// Collective. This rank's springs `mine` (any order) as rows of the
/// globally sorted list: their row numbers, the rows (flat) and the total.
pub fn sorted_rows(comm: &SimpleCommunicator, mine: &[SavedSpring]) -> (Vec<u32>, Vec<f64>, u64) {
    let flat: Vec<f64> = mine
        .iter()
        .flat_map(|&((a, b), x)| [f64::from(a), f64::from(b), x[0], x[1], x[2], x[3]])
        .collect();
    sorted_by_key(comm, &flat, SPRING_COLUMNS)
}

/// Collective. Rows of `width` values (flat, any order on any rank),
/// keyed by their first two columns (whole numbers), as rows of the list
/// sorted by key over the ranks: this rank's row numbers, its rows of the
/// sorted list (flat) and the total. Each rank takes a range of first keys.
pub fn sorted_by_key(
    comm: &SimpleCommunicator,
    flat: &[f64],
    width: usize,
) -> (Vec<u32>, Vec<f64>, u64) {
    let size = comm.size() as usize;
    // Ranges of the first key by rank: the sort's buckets.
    let local_max = flat
        .chunks_exact(width)
        .map(|r| r[0] as u64 + 1)
        .max()
        .unwrap_or(0);
    let mut end = 0u64;
    comm.all_reduce_into(&local_max, &mut end, SystemOperation::max());
    let bucket = |a: f64| ((a as u64 * size as u64) / end.max(1)) as usize;
    let mut send: Vec<Vec<f64>> = vec![Vec::new(); size];
    for r in flat.chunks_exact(width) {
        send[bucket(r[0])].extend_from_slice(r);
    }
    let got = crate::parallel::exchange::all_to_all(comm, send);
    let mut rows: Vec<&[f64]> = got.iter().flat_map(|m| m.chunks_exact(width)).collect();
    rows.sort_unstable_by(|p, q| {
        (p[0], p[1])
            .partial_cmp(&(q[0], q[1]))
            .expect("finite keys")
    });
    let n = rows.len() as u64;
    let mut before = 0u64;
    comm.exclusive_scan_into(&n, &mut before, SystemOperation::sum());
    if comm.rank() == 0 {
        before = 0;
    }
    let mut total = 0u64;
    comm.all_reduce_into(&n, &mut total, SystemOperation::sum());
    let ids = (0..n).map(|i| (before + i) as u32).collect();
    (ids, rows.concat(), total)
}

/// Collective. Write the sorted rows (`sorted_rows`) into the open checkpoint.
pub(super) fn write(
    comm: &SimpleCommunicator,
    file: &File,
    path: &Path,
    xfer: &super::ffi::CollectiveXfer,
    (ids, values, total): (&[u32], &[f64], u64),
) -> Result<(), IoError> {
    let (lo, block) =
        crate::parallel::exchange::to_blocks(comm, ids, values, SPRING_COLUMNS, total);
    super::checkpoint::dataset_f64(
        file,
        path,
        SPRINGS,
        total as usize,
        SPRING_COLUMNS,
        xfer,
        lo,
        Some(&block),
    )
}

impl CheckpointFile {
    /// This rank's block of the saved springs (none without the dataset).
    pub fn spring_block(&self, rank: usize, size: usize) -> Result<Vec<SavedSpring>, IoError> {
        if !self.file.link_exists(SPRINGS) {
            return Ok(Vec::new());
        }
        let total = self
            .file
            .dataset(SPRINGS)
            .map_err(|e| IoError::hdf5(self.path(), format!("opening {SPRINGS}"), e))?
            .shape()
            .first()
            .copied()
            .unwrap_or(0) as u64;
        let (lo, hi) = crate::parallel::exchange::block(total, size, rank);
        let ids: Vec<u32> = (lo as u32..hi as u32).collect();
        let rows = self.rows_of::<f64, SPRING_COLUMNS>(SPRINGS, &ids, total)?;
        rows.iter()
            .map(|r| {
                let key = (r[0] as u32, r[1] as u32);
                if f64::from(key.0) != r[0] || f64::from(key.1) != r[1] || !r.iter().all(|v| v.is_finite()) {
                    return Err(IoError::invalid(
                        self.path(),
                        format!("{SPRINGS}: a row is not a pair of tet numbers and a finite spring: {r:?}"),
                    ));
                }
                Ok((key, [r[2], r[3], r[4], r[5]]))
            })
            .collect()
    }
}
