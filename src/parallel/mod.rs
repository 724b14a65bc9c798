//! Parallel plumbing: the partition of the elements, each rank's [`Part`]
//! (its elements and nodes, owners, a global numbering that matches
//! PETSc's ownership ranges), halos, personalised exchanges, and
//! collective error agreement.
//!
//! A node is owned by the lowest-numbered rank among the elements that
//! touch it; rank r's owned nodes get the consecutive global numbers
//! [start_r, end_r), sorted by global id.

mod build;
pub mod exchange;
mod fingerprint;
pub mod ghosts;
mod halo;
mod hexes;
mod part;
mod partition;
pub mod rcb;
mod sphere_slabs;
mod spheres;
mod tied_rows;

pub use build::{element_work, Placement, IMBALANCE};
pub use fingerprint::fingerprint;
pub use halo::Halo;
pub use hexes::{PartHex, PartHexes};
pub use part::{GlobalBcs, LocalBcs, Part, PartJoint, WholeMaps};
pub use partition::{
    dual_graph, dual_graph_with, partition_collective, partition_elements,
    partition_elements_weighted,
};
pub use sphere_slabs::SphereSlabs;
pub use spheres::PartSpheres;

use mpi::collective::SystemOperation;
use mpi::traits::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Collective. Agree on success: if any rank failed, every rank returns an
/// error (the failing rank its own, the others [`crate::error::Error::OtherRank`]).
pub fn agree<T, C: Communicator>(
    comm: &C,
    local: crate::error::Result<T>,
) -> crate::error::Result<T> {
    let mine: i32 = i32::from(local.is_err());
    let mut any = 0i32;
    comm.all_reduce_into(&mine, &mut any, SystemOperation::max());
    match local {
        Err(e) => Err(e),
        Ok(_) if any != 0 => Err(crate::error::Error::OtherRank),
        Ok(v) => Ok(v),
    }
}

/// Collective. Concatenate every rank's `local` values in rank order.
pub fn all_gather_f64<C: Communicator>(comm: &C, local: &[f64]) -> Vec<f64> {
    let size = comm.size() as usize;
    let n = local.len() as i32;
    let mut counts = vec![0i32; size];
    comm.all_gather_into(&n, &mut counts[..]);
    let displs: Vec<i32> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    let total: i32 = counts.iter().sum();
    let mut out = vec![0.0f64; total as usize];
    {
        let mut part = mpi::datatype::PartitionMut::new(&mut out[..], counts, displs);
        comm.all_gather_varcount_into(local, &mut part);
    }
    out
}

/// Bytes this process has sent to other ranks through the point-to-point
/// and all-to-all exchanges of this module (halo, ghosts, blocks); scalar
/// reductions are not counted.
static BYTES_SENT: AtomicU64 = AtomicU64::new(0);

/// Count `bytes` sent to another rank.
pub(crate) fn count_sent(bytes: usize) {
    BYTES_SENT.fetch_add(bytes as u64, Ordering::Relaxed);
}

/// Bytes sent to other ranks so far by this process.
pub fn bytes_sent() -> u64 {
    BYTES_SENT.load(Ordering::Relaxed)
}
