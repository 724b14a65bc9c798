//! The global-order force summation: each owned node's force is summed
//! from its contributions in a fixed global key order (element id; pairs
//! after all elements, by (a, b)), whichever rank computed them, so the
//! trajectories are bitwise the same on any number of ranks. The
//! elements' contributions have fixed slots, built here at each
//! detection; the touching pairs' are routed each substep
//! ([`super::pair_sum`]).

use mpi::topology::SimpleCommunicator;
use nalgebra::Vector3;

use super::ExplicitDomain;

impl ExplicitDomain {
    /// Collective over the neighbours. The order in which each owned
    /// node's element forces are summed: its contributions sorted by the
    /// element id, whichever rank computed them. Ghost contributions
    /// travel one by one, not pre-summed, so the sums, and hence the
    /// trajectories, are bitwise the same on any number of ranks.
    pub(super) fn build_assembly(&mut self, comm: &SimpleCommunicator) {
        let ne = self.elements.len();
        let nbrs: Vec<i32> = self.halo.neighbours().to_vec();
        let n_owned = self.n_owned as u32;
        // Pass 1: each owned node's count of contributions, and the
        // contributions to ghost nodes listed by owner as (gid, key, slot).
        let mut count = vec![0u32; self.n_owned + 1];
        let mut ghost: Vec<Vec<(u32, u64, u32)>> = vec![Vec::new(); nbrs.len()];
        self.for_each_slot(|l, key, slot| {
            if l < n_owned {
                count[l as usize + 1] += 1;
            } else {
                let g = self.node_gid[l as usize];
                let r = self.node_owner[l as usize] as i32;
                let i = nbrs
                    .binary_search(&r)
                    .expect("owner of a ghost is a neighbour");
                ghost[i].push((g, key, slot as u32));
            }
        });
        // Tell each owner which contributions (node, key) it will receive.
        let mut counts_out = Vec::with_capacity(nbrs.len());
        let mut keys_out = Vec::with_capacity(nbrs.len());
        self.send_slots = ghost
            .iter()
            .map(|list| {
                // Any order: the owner sums by key.
                counts_out.push(vec![f64::from_bits(list.len() as u64)]);
                keys_out.push(
                    list.iter()
                        .flat_map(|&(g, key, _)| {
                            [f64::from_bits(u64::from(g)), f64::from_bits(key)]
                        })
                        .collect::<Vec<f64>>(),
                );
                list.iter().map(|&(_, _, s)| s).collect()
            })
            .collect();
        drop(ghost);
        let mut counts_in = vec![vec![0.0]; nbrs.len()];
        self.halo.exchange(comm, &counts_out, &mut counts_in, || {});
        let mut keys_in: Vec<Vec<f64>> = counts_in
            .iter()
            .map(|c| vec![0.0; 2 * c[0].to_bits() as usize])
            .collect();
        self.halo.exchange(comm, &keys_out, &mut keys_in, || {});
        drop(keys_out);
        // Received contributions land after the elements' slots, by neighbour.
        let recv_base = 4 * ne;
        let n_recv: usize = keys_in.iter().map(|k| k.len() / 2).sum();
        let mut recv_node: Vec<u32> = Vec::with_capacity(n_recv);
        let mut recv_key: Vec<u64> = Vec::with_capacity(n_recv);
        let mut next = recv_base;
        self.recv_at = keys_in
            .iter()
            .map(|keys| {
                let start = next;
                for pair in keys.chunks_exact(2) {
                    let g = pair[0].to_bits() as u32;
                    let l = self.node_gid[..self.n_owned]
                        .binary_search(&g)
                        .expect("contributions arrive for owned nodes");
                    count[l + 1] += 1;
                    recv_node.push(l as u32);
                    recv_key.push(pair[1].to_bits());
                }
                next += keys.len() / 2;
                (start, keys.len() / 2)
            })
            .collect();
        drop(keys_in);
        // Pass 2: bucket the slots by node (counting sort), then each
        // node's few slots by key: the order of a full sort of (node,
        // key), in linear time (keys are unique per node).
        for i in 0..self.n_owned {
            count[i + 1] += count[i];
        }
        let total = count[self.n_owned] as usize;
        let mut slots = std::mem::take(&mut self.gather_slot);
        refill(&mut slots, total, 0u32);
        let mut fill: Vec<u32> = count[..self.n_owned].to_vec();
        self.for_each_slot(|l, _, slot| {
            if l < n_owned {
                let at = &mut fill[l as usize];
                slots[*at as usize] = slot as u32;
                *at += 1;
            }
        });
        for (i, &l) in recv_node.iter().enumerate() {
            let at = &mut fill[l as usize];
            slots[*at as usize] = (recv_base + i) as u32;
            *at += 1;
        }
        drop((fill, recv_node));
        let key_of = |s: u32| -> u64 {
            let s = s as usize;
            if s < recv_base {
                u64::from(self.elem_ids[s / 4])
            } else {
                recv_key[s - recv_base]
            }
        };
        for w in count.windows(2) {
            slots[w[0] as usize..w[1] as usize].sort_unstable_by_key(|&s| key_of(s));
        }
        self.gather_slot = slots;
        self.gather_off = count;
        // Reuse the allocation (hundreds of MB in a large packing).
        refill(&mut self.contrib, next, Vector3::zeros());
    }

    /// Every contribution slot of the elements, in slot order, as (local
    /// node, global key, slot): 4 per element, keyed by its id.
    fn for_each_slot(&self, mut f: impl FnMut(u32, u64, usize)) {
        for (i, el) in self.elements.iter().enumerate() {
            for k in 0..4 {
                f(el.nodes[k], u64::from(self.elem_ids[i]), 4 * i + k);
            }
        }
    }

    /// The force on every owned node: its element contributions summed in
    /// key order (see [`Self::build_assembly`]), then its touching pairs'
    /// in key order (pair keys follow all element keys), plus the external
    /// load. The pair forces must have been routed and received.
    pub(super) fn sum_owned_forces(&mut self) {
        let no = self.n_owned;
        for i in 0..no {
            let mut f = Vector3::zeros();
            for &s in
                &self.gather_slot[self.gather_off[i] as usize..self.gather_off[i + 1] as usize]
            {
                f += self.contrib[s as usize];
            }
            self.f[i] = f;
        }
        self.pair_forces.add_all(&mut self.f[..no]);
        for (f, e) in self.f[..no].iter_mut().zip(&self.ext[..no]) {
            *f += *e;
        }
    }
}

/// The summation key of a pair's contributions: after every element's
/// (the top bit), by (a, b).
pub(super) fn pair_key(c: &super::candidates::Candidate) -> u64 {
    key_of(c.a, c.b)
}

/// The summation key of the pair of tets `a` and `b` (global ids).
pub(super) fn key_of(a: u32, b: u32) -> u64 {
    const PAIR: u64 = 1 << 63;
    PAIR | (u64::from(a) << 31) | u64::from(b)
}

/// Make `v` hold `n` copies of `value`, keeping its allocation when it is
/// large enough; else a new one with 1/16 to spare (not the doubling of
/// a growing vector, and never the old and new allocations at once).
fn refill<T: Clone>(v: &mut Vec<T>, n: usize, value: T) {
    v.clear();
    if v.capacity() < n {
        *v = Vec::new();
        v.reserve_exact(n + n / 16);
    }
    v.resize(n, value);
}
