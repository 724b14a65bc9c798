//! Halo exchange between ranks for node-based data (the explicit
//! mechanics): each rank holds its owned nodes and ghost copies of nodes
//! owned elsewhere; `forward` copies owned values to their ghosts,
//! `reverse_add` adds ghost contributions into their owners. Both use
//! non-blocking point-to-point messages with neighbours only.
//!
//! Values live in a flat `&mut [f64]` with `width` values per local node
//! (local index = position in the rank's owned-then-ghost node list).

use mpi::datatype::Equivalence;
use mpi::traits::*;

/// The exchange pattern of one rank.
#[derive(Debug, Clone, Default)]
pub struct Halo {
    /// Neighbour ranks, ascending.
    neighbours: Vec<i32>,
    /// Per neighbour: local indices of owned nodes that it ghosts.
    shared: Vec<Vec<u32>>,
    /// Per neighbour: local indices of this rank's ghosts that it owns.
    ghosts: Vec<Vec<u32>>,
}

impl Halo {
    /// Collective. `ghosts` lists this rank's ghost nodes as (global id,
    /// owner rank, local index); `local_of_owned` maps a global id this
    /// rank owns to its local index. Errors if a rank asks for a node its
    /// supposed owner does not own.
    pub fn new<C: Communicator>(
        comm: &C,
        ghosts: &[(u32, u32, u32)],
        local_of_owned: impl Fn(u32) -> Option<u32>,
    ) -> Result<Halo, String> {
        let size = comm.size() as usize;
        let mut by_owner: Vec<Vec<(u32, u32)>> = vec![Vec::new(); size];
        for &(g, owner, local) in ghosts {
            by_owner[owner as usize].push((g, local));
        }
        for v in by_owner.iter_mut() {
            v.sort_unstable();
        }
        let send_counts: Vec<i32> = by_owner.iter().map(|v| v.len() as i32).collect();
        let mut recv_counts = vec![0i32; size];
        comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let send_ids: Vec<u32> = by_owner
            .iter()
            .flat_map(|v| v.iter().map(|&(g, _)| g))
            .collect();
        let displs = |c: &[i32]| -> Vec<i32> {
            c.iter()
                .scan(0, |a, &x| {
                    let d = *a;
                    *a += x;
                    Some(d)
                })
                .collect()
        };
        let total: i32 = recv_counts.iter().sum();
        let mut recv_ids = vec![0u32; total as usize];
        {
            let send = mpi::datatype::Partition::new(
                &send_ids[..],
                send_counts.clone(),
                displs(&send_counts),
            );
            let mut recv = mpi::datatype::PartitionMut::new(
                &mut recv_ids[..],
                recv_counts.clone(),
                displs(&recv_counts),
            );
            comm.all_to_all_varcount_into(&send, &mut recv);
        }
        let me = comm.rank();
        let mut halo = Halo::default();
        let mut offset = 0usize;
        let mut error = None;
        for r in 0..size {
            let asked = &recv_ids[offset..offset + recv_counts[r] as usize];
            offset += recv_counts[r] as usize;
            let mine = &by_owner[r];
            if asked.is_empty() && mine.is_empty() {
                continue;
            }
            let mut shared = Vec::with_capacity(asked.len());
            for &g in asked {
                match local_of_owned(g) {
                    Some(l) => shared.push(l),
                    None => {
                        error.get_or_insert(format!(
                            "rank {r} asked rank {me} for node {g}, which rank {me} does not own"
                        ));
                    }
                }
            }
            halo.neighbours.push(r as i32);
            halo.shared.push(shared);
            halo.ghosts.push(mine.iter().map(|&(_, l)| l).collect());
        }
        match error {
            Some(e) => Err(e),
            None => Ok(halo),
        }
    }

    /// Number of neighbour ranks.
    pub fn num_neighbours(&self) -> usize {
        self.neighbours.len()
    }

    /// Neighbour ranks, ascending.
    pub fn neighbours(&self) -> &[i32] {
        &self.neighbours
    }

    /// Local indices of owned nodes that some other rank ghosts (may repeat).
    pub fn shared_nodes(&self) -> impl Iterator<Item = u32> + '_ {
        self.shared.iter().flatten().copied()
    }

    /// Collective over the neighbours. Copy owned values of every array in
    /// `fields` (each `width` values per local node) to the ghosts, in one
    /// message per neighbour.
    pub fn forward<C: Communicator>(&self, comm: &C, fields: &mut [&mut [f64]], width: usize) {
        let send: Vec<Vec<f64>> = self
            .shared
            .iter()
            .map(|idx| {
                let mut out = Vec::with_capacity(fields.len() * idx.len() * width);
                for f in fields.iter() {
                    out.extend(pack(f, idx, width));
                }
                out
            })
            .collect();
        let mut recv: Vec<Vec<f64>> = self
            .ghosts
            .iter()
            .map(|idx| vec![0.0; fields.len() * idx.len() * width])
            .collect();
        self.exchange(comm, &send, &mut recv, || {});
        for (idx, buf) in self.ghosts.iter().zip(&recv) {
            let per_field = idx.len() * width;
            for (fi, f) in fields.iter_mut().enumerate() {
                let b = &buf[fi * per_field..(fi + 1) * per_field];
                for (k, &l) in idx.iter().enumerate() {
                    let l = l as usize * width;
                    f[l..l + width].copy_from_slice(&b[k * width..(k + 1) * width]);
                }
            }
        }
    }

    /// Collective over the neighbours. Send the ghosts' values to their
    /// owners and add them there, in ascending rank order. `work` runs
    /// while the messages are in flight; it receives `values` (ghost
    /// values are already packed, so it may add to owned nodes and
    /// interior work freely, but changes to ghost entries are not sent).
    pub fn reverse_add<C: Communicator>(
        &self,
        comm: &C,
        values: &mut [f64],
        width: usize,
        work: impl FnOnce(&mut [f64]),
    ) {
        let send: Vec<Vec<f64>> = self
            .ghosts
            .iter()
            .map(|idx| pack(values, idx, width))
            .collect();
        let mut recv: Vec<Vec<f64>> = self
            .shared
            .iter()
            .map(|idx| vec![0.0; idx.len() * width])
            .collect();
        self.exchange(comm, &send, &mut recv, || work(values));
        for (idx, buf) in self.shared.iter().zip(&recv) {
            for (k, &l) in idx.iter().enumerate() {
                let l = l as usize * width;
                for d in 0..width {
                    values[l + d] += buf[k * width + d];
                }
            }
        }
    }

    /// Collective over the neighbours. Send `send[i]` to neighbour i and
    /// receive `recv[i]` (sized by the caller, agreed with the sender) from
    /// it; empty buffers are skipped. `work` runs while messages fly.
    pub fn exchange<C: Communicator>(
        &self,
        comm: &C,
        send: &[Vec<f64>],
        recv: &mut [Vec<f64>],
        work: impl FnOnce(),
    ) {
        let into: Vec<&mut [f64]> = recv.iter_mut().map(|b| &mut b[..]).collect();
        self.exchange_into(comm, send, into, work);
    }

    /// Collective over the neighbours. [`Halo::exchange`] receiving into
    /// slices the caller owns (for example the tail of a larger array), so
    /// no receive buffer is allocated.
    pub fn exchange_into<C: Communicator>(
        &self,
        comm: &C,
        send: &[Vec<f64>],
        recv: Vec<&mut [f64]>,
        work: impl FnOnce(),
    ) {
        self.exchange_into_sized(comm, send, recv, None, work);
    }

    /// Collective over the neighbours. [`Halo::exchange_into`], and with
    /// `sized` = (send, recv) also one message to and from every neighbour
    /// whose length the receiver does not know: each `recv[i]` is resized
    /// to what neighbour i sent (possibly nothing).
    pub fn exchange_into_sized<C: Communicator>(
        &self,
        comm: &C,
        send: &[Vec<f64>],
        mut recv: Vec<&mut [f64]>,
        sized: Option<SizedBuffers>,
        work: impl FnOnce(),
    ) {
        if self.neighbours.is_empty() {
            work();
            return;
        }
        mpi::request::scope(|scope| {
            let mut requests = Vec::with_capacity(2 * self.neighbours.len());
            for (r, buf) in self.neighbours.iter().zip(recv.iter_mut()) {
                if !buf.is_empty() {
                    requests.push(
                        comm.process_at_rank(*r)
                            .immediate_receive_into(scope, &mut **buf),
                    );
                }
            }
            let mut sends = Vec::with_capacity(self.neighbours.len());
            for (r, buf) in self.neighbours.iter().zip(send) {
                if !buf.is_empty() {
                    super::count_sent(std::mem::size_of_val(&buf[..]));
                    sends.push(comm.process_at_rank(*r).immediate_send(scope, &buf[..]));
                }
            }
            let mut sized_recv = None;
            if let Some((out, into)) = sized {
                for (r, buf) in self.neighbours.iter().zip(out) {
                    super::count_sent(std::mem::size_of_val(&buf[..]));
                    sends.push(comm.process_at_rank(*r).immediate_send_with_tag(
                        scope,
                        &buf[..],
                        SIZED_TAG,
                    ));
                }
                sized_recv = Some(into);
            }
            work();
            for q in requests {
                q.wait();
            }
            if let Some(into) = sized_recv {
                for (r, buf) in self.neighbours.iter().zip(into.iter_mut()) {
                    let (msg, status) = comm.process_at_rank(*r).matched_probe_with_tag(SIZED_TAG);
                    let n = status.count(f64::equivalent_datatype()) as usize;
                    buf.clear();
                    // An eighth of headroom, not doubling: held all run.
                    if n > buf.capacity() {
                        buf.reserve_exact(n + n / 8);
                    }
                    buf.resize(n, 0.0);
                    msg.matched_receive_into(&mut buf[..]);
                }
            }
            for q in sends {
                q.wait();
            }
        });
    }
}

/// What [`Halo::exchange_into_sized`] sends to each neighbour, and where
/// what each sends lands (resized to it).
pub type SizedBuffers<'a> = (&'a [Vec<f64>], &'a mut [Vec<f64>]);

/// The tag of [`Halo::exchange_into_sized`]'s messages of unknown length
/// (the others use the default tag), so a probe never meets the others.
const SIZED_TAG: mpi::Tag = 0x5053;

fn pack(values: &[f64], idx: &[u32], width: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(idx.len() * width);
    for &l in idx {
        let l = l as usize * width;
        out.extend_from_slice(&values[l..l + width]);
    }
    out
}
