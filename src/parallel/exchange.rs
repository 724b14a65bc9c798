//! Personalised all-to-all exchanges: each rank sends a list of values to
//! each other rank and receives theirs, in one `MPI_Alltoall` of counts and
//! one `MPI_Alltoallv` of values. The plumbing under migration, ghost
//! exchange and the rendezvous directory.

use mpi::datatype::{Equivalence, Partition, PartitionMut};
use mpi::traits::*;

fn displacements(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

/// Collective. `send[r]` goes to rank r; returns what each rank sent here,
/// by source rank.
pub fn all_to_all<T, C>(comm: &C, send: &[Vec<T>]) -> Vec<Vec<T>>
where
    T: Equivalence + Copy + Default,
    C: Communicator,
{
    let size = comm.size() as usize;
    assert_eq!(send.len(), size, "one send list per rank");
    let send_counts: Vec<i32> = send.iter().map(|v| v.len() as i32).collect();
    let mut recv_counts = vec![0i32; size];
    comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
    let flat: Vec<T> = send.iter().flatten().copied().collect();
    let total: usize = recv_counts.iter().map(|&c| c as usize).sum();
    let mut recv = vec![T::default(); total];
    {
        let s = Partition::new(&flat[..], send_counts.clone(), displacements(&send_counts));
        let mut r = PartitionMut::new(
            &mut recv[..],
            recv_counts.clone(),
            displacements(&recv_counts),
        );
        comm.all_to_all_varcount_into(&s, &mut r);
    }
    let mut out = Vec::with_capacity(size);
    let mut at = 0usize;
    for &c in &recv_counts {
        out.push(recv[at..at + c as usize].to_vec());
        at += c as usize;
    }
    out
}

/// Collective. Every rank's `local` values, concatenated in rank order.
pub fn all_gather<T, C>(comm: &C, local: &[T]) -> Vec<T>
where
    T: Equivalence + Copy + Default,
    C: Communicator,
{
    let size = comm.size() as usize;
    let n = local.len() as i32;
    let mut counts = vec![0i32; size];
    comm.all_gather_into(&n, &mut counts[..]);
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    let mut out = vec![T::default(); total];
    {
        let mut part = PartitionMut::new(&mut out[..], counts.clone(), displacements(&counts));
        comm.all_gather_varcount_into(local, &mut part);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::displacements;

    #[test]
    fn displacements_are_prefix_sums() {
        assert_eq!(displacements(&[3, 0, 2, 5]), vec![0, 3, 3, 5]);
        assert!(displacements(&[]).is_empty());
    }
}
