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

/// What every rank sent here, one list per source rank, in one array
/// (not one allocation per list).
pub struct Received<T> {
    data: Vec<T>,
    start: Vec<usize>,
}

impl<T> Received<T> {
    /// The lists by source rank.
    pub fn iter(&self) -> impl Iterator<Item = &[T]> + '_ {
        self.start.windows(2).map(|w| &self.data[w[0]..w[1]])
    }
}

impl<T> std::ops::Index<usize> for Received<T> {
    type Output = [T];
    fn index(&self, r: usize) -> &[T] {
        &self.data[self.start[r]..self.start[r + 1]]
    }
}

impl<'a, T> IntoIterator for &'a Received<T> {
    type Item = &'a [T];
    type IntoIter = Box<dyn Iterator<Item = &'a [T]> + 'a>;
    fn into_iter(self) -> Self::IntoIter {
        Box::new(self.iter())
    }
}

/// Collective. `send[r]` goes to rank r; returns what each rank sent here,
/// by source rank. Each list is freed as it is packed, so the exchange
/// holds about one copy of what is sent and one of what is received.
pub fn all_to_all<T, C>(comm: &C, send: Vec<Vec<T>>) -> Received<T>
where
    T: Equivalence + Copy + Default,
    C: Communicator,
{
    let size = comm.size() as usize;
    assert_eq!(send.len(), size, "one send list per rank");
    let send_counts: Vec<i32> = send.iter().map(|v| v.len() as i32).collect();
    let mut flat: Vec<T> = Vec::with_capacity(send_counts.iter().map(|&c| c as usize).sum());
    for list in send {
        flat.extend_from_slice(&list);
    }
    let (data, recv_counts) = all_to_all_flat(comm, &flat, &send_counts);
    drop(flat);
    let mut start = Vec::with_capacity(size + 1);
    start.push(0usize);
    for &c in &recv_counts {
        start.push(start.last().copied().unwrap_or(0) + c as usize);
    }
    Received { data, start }
}

/// Collective. `flat` holds the lists for ranks 0, 1, … one after the
/// other, `send_counts[r]` values for rank r; returns what every rank sent
/// here, one after the other by source rank, and the counts. No list is
/// copied: the caller fills `flat` in place.
pub fn all_to_all_flat<T, C>(comm: &C, flat: &[T], send_counts: &[i32]) -> (Vec<T>, Vec<i32>)
where
    T: Equivalence + Copy + Default,
    C: Communicator,
{
    let size = comm.size() as usize;
    assert_eq!(send_counts.len(), size, "one send count per rank");
    let me = comm.rank() as usize;
    super::count_sent(
        send_counts
            .iter()
            .enumerate()
            .filter(|&(r, _)| r != me)
            .map(|(_, &c)| c as usize * std::mem::size_of::<T>())
            .sum(),
    );
    let mut recv_counts = vec![0i32; size];
    comm.all_to_all_into(send_counts, &mut recv_counts[..]);
    let total: usize = recv_counts.iter().map(|&c| c as usize).sum();
    let mut recv = vec![T::default(); total];
    {
        let s = Partition::new(flat, send_counts.to_vec(), displacements(send_counts));
        let mut r = PartitionMut::new(
            &mut recv[..],
            recv_counts.clone(),
            displacements(&recv_counts),
        );
        comm.all_to_all_varcount_into(&s, &mut r);
    }
    (recv, recv_counts)
}

/// Collective. Every rank's `local` values, concatenated in rank order.
pub fn all_gather<T, C>(comm: &C, local: &[T]) -> Vec<T>
where
    T: Equivalence + Copy + Default,
    C: Communicator,
{
    let size = comm.size() as usize;
    let n = local.len() as i32;
    super::count_sent(std::mem::size_of_val(local) * (size - 1));
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

/// The block of `total` rows that rank `r` of `size` holds: rows
/// [r·total/size, (r+1)·total/size).
pub fn block(total: u64, size: usize, r: usize) -> (u64, u64) {
    let at = |k: usize| (u128::from(total) * k as u128 / size as u128) as u64;
    (at(r), at(r + 1))
}

/// The rank whose block (see [`block`]) holds row `row` of `total`.
pub fn block_owner(row: u64, total: u64, size: usize) -> usize {
    // The largest r with r·total/size ≤ row.
    let mut r = ((u128::from(row) * size as u128) / u128::from(total.max(1))) as usize;
    r = r.min(size - 1);
    while r + 1 < size && block(total, size, r + 1).0 <= row {
        r += 1;
    }
    while r > 0 && block(total, size, r).0 > row {
        r -= 1;
    }
    r
}

/// Collective. Rows keyed by global id (`ids[i]` with `width` values at
/// `values[width·i..]`), one rank each, moved to contiguous blocks of the
/// `total` ids ([`block`]): returns this rank's block start and its rows
/// in id order. Every id below `total` must be given by exactly one rank.
pub fn to_blocks<C: Communicator>(
    comm: &C,
    ids: &[u32],
    values: &[f64],
    width: usize,
    total: u64,
) -> (u64, Vec<f64>) {
    let size = comm.size() as usize;
    let me = comm.rank() as usize;
    let (lo, hi) = block(total, size, me);
    let mut out = vec![0.0; (hi - lo) as usize * width];
    // In rounds of at most ROUND_BYTES sent per rank, so that what is
    // packed and what arrives stay small beside the block itself (a
    // field's whole send and receive copies were the peak of the N = 2000
    // deposition on 8 ranks, at its outputs).
    let per_round = (ROUND_BYTES / (8 * (width + 1))).max(1);
    let mine = ids.len().div_ceil(per_round) as u64;
    let mut rounds = 0u64;
    comm.all_reduce_into(&mine, &mut rounds, mpi::collective::SystemOperation::max());
    for k in 0..rounds.max(1) as usize {
        let from = (k * per_round).min(ids.len());
        let to = ((k + 1) * per_round).min(ids.len());
        let got = to_blocks_round(
            comm,
            &ids[from..to],
            &values[width * from..width * to],
            width,
            total,
        );
        for rec in got.chunks_exact(width + 1) {
            let row = (rec[0] as u64 - lo) as usize;
            out[width * row..width * (row + 1)].copy_from_slice(&rec[1..]);
        }
    }
    (lo, out)
}

/// Bytes a rank sends per round of [`to_blocks`].
const ROUND_BYTES: usize = 1 << 18;

/// Collective. One round of [`to_blocks`]: these rows, packed by
/// destination in one array (a counting sort), sent to their block
/// owners; returns what arrived, `width + 1` values per row (the id
/// first).
fn to_blocks_round<C: Communicator>(
    comm: &C,
    ids: &[u32],
    values: &[f64],
    width: usize,
    total: u64,
) -> Vec<f64> {
    let size = comm.size() as usize;
    let owners: Vec<u32> = ids
        .iter()
        .map(|&g| block_owner(u64::from(g), total, size) as u32)
        .collect();
    let mut counts = vec![0i32; size];
    for &r in &owners {
        counts[r as usize] += (width + 1) as i32;
    }
    let mut at: Vec<usize> = displacements(&counts).iter().map(|&d| d as usize).collect();
    let mut flat = vec![0.0; ids.len() * (width + 1)];
    for (i, (&g, &r)) in ids.iter().zip(&owners).enumerate() {
        let p = &mut at[r as usize];
        flat[*p] = f64::from(g);
        flat[*p + 1..*p + 1 + width].copy_from_slice(&values[width * i..width * (i + 1)]);
        *p += width + 1;
    }
    drop(owners);
    all_to_all_flat(comm, &flat, &counts).0
}

/// Collective. The rows `ids` (global ids) read from the blocks that
/// [`to_blocks`] made: `(lo, rows)` is this rank's block of `width`
/// values per row, `total` the number of rows. Each rank asks the block
/// owners for its ids and gets the rows back in the order asked.
pub fn from_blocks<C: Communicator>(
    comm: &C,
    (lo, rows): (u64, &[f64]),
    width: usize,
    total: u64,
    ids: &[u32],
) -> Vec<f64> {
    let size = comm.size() as usize;
    let mut ask: Vec<Vec<u32>> = vec![Vec::new(); size];
    for &g in ids {
        ask[block_owner(u64::from(g), total, size)].push(g);
    }
    let asked = all_to_all(comm, ask);
    let reply: Vec<Vec<f64>> = asked
        .iter()
        .map(|list| {
            list.iter()
                .flat_map(|&g| {
                    let row = (u64::from(g) - lo) as usize;
                    rows[width * row..width * (row + 1)].iter().copied()
                })
                .collect()
        })
        .collect();
    let got = all_to_all(comm, reply);
    // Replies come per block owner in the order asked.
    let mut next = vec![0usize; size];
    let mut out = Vec::with_capacity(ids.len() * width);
    for &g in ids {
        let r = block_owner(u64::from(g), total, size);
        let at = next[r];
        out.extend_from_slice(&got[r][width * at..width * (at + 1)]);
        next[r] += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::displacements;

    #[test]
    fn blocks_tile_the_rows_and_owners_find_them() {
        for (total, size) in [(0u64, 1usize), (10, 3), (7, 4), (3, 5), (1000, 7)] {
            let mut next = 0;
            for r in 0..size {
                let (lo, hi) = super::block(total, size, r);
                assert_eq!(lo, next);
                assert!(hi >= lo);
                for row in lo..hi {
                    assert_eq!(super::block_owner(row, total, size), r);
                }
                next = hi;
            }
            assert_eq!(next, total);
        }
    }

    #[test]
    fn displacements_are_prefix_sums() {
        assert_eq!(displacements(&[3, 0, 2, 5]), vec![0, 3, 3, 5]);
        assert!(displacements(&[]).is_empty());
    }
}
