//! The global-order force summation: each owned node's force is summed
//! from its contributions in a fixed global key order (element id; pairs
//! after all elements, by (a, b)), whichever rank computed them, so the
//! trajectories are bitwise the same on any number of ranks.

use mpi::topology::SimpleCommunicator;
use nalgebra::Vector3;

use super::ExplicitDomain;

impl ExplicitDomain {
    /// Collective over the neighbours. The order in which each owned
    /// node's force is summed: its contributions sorted by a global key
    /// (the element id; pairs after all elements, by (a, b)), whichever
    /// rank computed them. Ghost contributions travel one by one, not
    /// pre-summed, so the sums, and hence the trajectories, are bitwise
    /// the same on any number of ranks.
    pub(super) fn build_assembly(&mut self, comm: &SimpleCommunicator) {
        const PAIR: u64 = 1 << 63;
        let ne = self.elements.len();
        let pair_base = 4 * ne;
        let nbrs: Vec<i32> = self.halo.neighbours().to_vec();
        let mut owned: Vec<(u32, u64, u32)> = Vec::with_capacity(4 * ne);
        let mut ghost: Vec<Vec<(u32, u64, u32)>> = vec![Vec::new(); nbrs.len()];
        let n_owned = self.n_owned as u32;
        let mut push = |l: u32, key: u64, slot: usize| {
            if l < n_owned {
                owned.push((l, key, slot as u32));
            } else {
                let g = self.node_gid[l as usize];
                let r = self.node_owner[l as usize] as i32;
                let i = nbrs
                    .binary_search(&r)
                    .expect("owner of a ghost is a neighbour");
                ghost[i].push((g, key, slot as u32));
            }
        };
        for (i, el) in self.elements.iter().enumerate() {
            for k in 0..4 {
                push(el.nodes[k], u64::from(self.elem_ids[i]), 4 * i + k);
            }
        }
        for (j, c) in self.candidates.iter().enumerate() {
            let key = PAIR | (u64::from(c.a) << 31) | u64::from(c.b);
            for k in 0..4 {
                push(self.pair_tets[c.ta as usize][k], key, pair_base + 8 * j + k);
                push(
                    self.pair_tets[c.tb as usize][k],
                    key,
                    pair_base + 8 * j + 4 + k,
                );
            }
        }
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
        let mut counts_in = vec![vec![0.0]; nbrs.len()];
        self.halo.exchange(comm, &counts_out, &mut counts_in, || {});
        let mut keys_in: Vec<Vec<f64>> = counts_in
            .iter()
            .map(|c| vec![0.0; 2 * c[0].to_bits() as usize])
            .collect();
        self.halo.exchange(comm, &keys_out, &mut keys_in, || {});
        let mut next = pair_base + 8 * self.candidates.len();
        self.recv_at = keys_in
            .iter()
            .map(|keys| {
                let start = next;
                for (i, pair) in keys.chunks_exact(2).enumerate() {
                    let g = pair[0].to_bits() as u32;
                    let l = self.node_gid[..self.n_owned]
                        .binary_search(&g)
                        .expect("contributions arrive for owned nodes")
                        as u32;
                    debug_assert!(l < n_owned);
                    owned.push((l, pair[1].to_bits(), (start + i) as u32));
                }
                next += keys.len() / 2;
                (start, keys.len() / 2)
            })
            .collect();
        // Bucket by node (counting sort), then each node's few
        // contributions by key: the order of a full sort of (node, key),
        // in linear time (keys are unique per node).
        self.gather_off = vec![0; self.n_owned + 1];
        for &(l, _, _) in &owned {
            self.gather_off[l as usize + 1] += 1;
        }
        for i in 0..self.n_owned {
            self.gather_off[i + 1] += self.gather_off[i];
        }
        let mut fill: Vec<u32> = self.gather_off[..self.n_owned].to_vec();
        let mut bucket = vec![(0u64, 0u32); owned.len()];
        for &(l, key, s) in &owned {
            let at = &mut fill[l as usize];
            bucket[*at as usize] = (key, s);
            *at += 1;
        }
        for w in self.gather_off.windows(2) {
            bucket[w[0] as usize..w[1] as usize].sort_unstable();
        }
        self.gather_slot = bucket.iter().map(|&(_, s)| s).collect();
        // Reuse the allocation (hundreds of MB in a large packing).
        self.contrib.clear();
        self.contrib.resize(next, Vector3::zeros());
    }

    /// The force on every owned node: its contributions summed in key
    /// order (see [`Self::build_assembly`]), plus the external load.
    pub(super) fn sum_owned_forces(&mut self) {
        let no = self.n_owned;
        for i in 0..no {
            let mut f = Vector3::zeros();
            for &s in
                &self.gather_slot[self.gather_off[i] as usize..self.gather_off[i + 1] as usize]
            {
                f += self.contrib[s as usize];
            }
            self.f[i] = f + self.ext[i];
        }
    }
}
