//! The contact pairs' share of the global-order force sum, sparse: only
//! the pairs that touch at a substep contribute. Each touching pair's 8
//! nodal forces go to the nodes' owners (a message per neighbour, sized
//! by what touched, keys with them); an owner adds a node's pair forces
//! after its element forces, in pair-key order, whichever rank evaluated
//! them, so the sums stay bitwise the same on any number of ranks.
//!
//! Dense slots for every candidate's 8 contributions, exchanged every
//! substep whether the pair touched or not, were most of a busy rank's
//! memory and traffic in a deposition (about 8 % of the candidates touch
//! at a substep).

use nalgebra::Vector3;

/// Values per pair contribution in a message: global node id and key
/// (as bits), and the force.
const SENT_F64S: usize = 5;

/// Bytes from which glibc gives a block pages of its own (fdem sets the
/// threshold to 128 KiB, `run::allocator_settings`).
const MAPPED_BYTES: usize = 128 << 10;

/// Make room for `extra` more items. These buffers are freed at each
/// detection and output and regrow in the substeps after, so: a small
/// first block, then straight to a mapped block (whose untouched pages
/// cost nothing), then growth by an eighth rather than doubling. Growing
/// through the heap step by step left its old blocks as touched holes,
/// several MiB on the busiest of 8 ranks in the N = 2000 deposition; and
/// doubling left up to half of a block unused (4.3 MiB held there).
fn make_room<T>(v: &mut Vec<T>, extra: usize) {
    if v.len() + extra > v.capacity() {
        let item = std::mem::size_of::<T>().max(1);
        let grow = match v.capacity() {
            0 => 256,
            c if c * item < MAPPED_BYTES => MAPPED_BYTES / item,
            c => c / 8,
        };
        v.reserve_exact(extra.max(grow));
    }
}

/// One pair contribution to an owned node: where its force is held.
#[derive(Debug, Clone, Copy)]
struct Entry {
    key: u64,
    node: u32,
    at: u32,
}

/// The pair forces of one substep and the order they are summed in.
#[derive(Debug, Default)]
pub(super) struct PairForces {
    /// Candidate index of each touching pair, ascending.
    pub(super) active: Vec<u32>,
    /// 8 forces per touching pair (a's nodes, then b's), then the forces
    /// received from neighbours.
    forces: Vec<Vector3<f64>>,
    /// Contributions to owned nodes, in arrival order.
    entries: Vec<Entry>,
    /// Entries bucketed by node, each bucket in key order, and the end of
    /// each node's bucket.
    order: Vec<u32>,
    end: Vec<u32>,
    /// Whether `route` met the touching pairs in ascending key order (the
    /// candidates are sorted by key at each detection), and how many
    /// entries it made: then a bucket needs sorting only where received
    /// entries follow the rank's own.
    own_sorted: bool,
    own_entries: usize,
    /// Per owned node, whether it received entries this substep (all
    /// false between calls of [`Self::add_all`]).
    mixed: Vec<bool>,
    /// Per owned node, its entries among the mixed nodes' and then where
    /// its bucket ends (all zero between calls of [`Self::add_all`]); the
    /// mixed nodes; their entries, and those bucketed by node.
    count: Vec<u32>,
    mixed_nodes: Vec<u32>,
    late: Vec<Entry>,
    bucketed: Vec<Entry>,
    /// Per neighbour: contributions to its nodes, and from it to ours.
    pub(super) send: Vec<Vec<f64>>,
    pub(super) recv: Vec<Vec<f64>>,
}

/// What routing a pair's forces needs to know of the rank's nodes.
pub(super) struct NodeRoutes<'a> {
    pub(super) n_owned: usize,
    pub(super) gid: &'a [u32],
    pub(super) owner: &'a [u32],
    /// Neighbour ranks, ascending (the halo's).
    pub(super) neighbours: &'a [i32],
}

impl PairForces {
    /// Start a substep: no pair touches yet.
    pub(super) fn clear(&mut self) {
        self.active.clear();
        self.forces.clear();
        self.entries.clear();
        self.own_sorted = false;
        self.own_entries = 0;
    }

    /// Pair `j` touches, with these forces on a's and b's nodes.
    pub(super) fn push(&mut self, j: usize, on_a: &[[f64; 3]; 4], on_b: &[[f64; 3]; 4]) {
        make_room(&mut self.active, 1);
        make_room(&mut self.forces, 8);
        self.active.push(j as u32);
        self.forces
            .extend(on_a.iter().chain(on_b).map(|&f| Vector3::from(f)));
    }

    /// Each touching pair's forces: to its owned nodes' buckets, or packed
    /// for the neighbour owning the node. `nodes(j)` gives pair j's 8 local
    /// nodes (a's, then b's) and its key.
    pub(super) fn route(&mut self, routes: &NodeRoutes, nodes: impl Fn(usize) -> ([u32; 8], u64)) {
        let nn = routes.neighbours.len();
        self.send.resize(nn, Vec::new());
        self.recv.resize(nn, Vec::new());
        self.send.iter_mut().for_each(Vec::clear);
        self.own_sorted = true;
        let mut last = None;
        for (a, &j) in self.active.iter().enumerate() {
            let (ls, key) = nodes(j as usize);
            if last.is_some_and(|k| k >= key) {
                self.own_sorted = false;
            }
            last = Some(key);
            for (k, &l) in ls.iter().enumerate() {
                let at = 8 * a + k;
                if (l as usize) < routes.n_owned {
                    make_room(&mut self.entries, 1);
                    self.entries.push(Entry {
                        key,
                        node: l,
                        at: at as u32,
                    });
                } else {
                    let r = routes.owner[l as usize] as i32;
                    let i = routes
                        .neighbours
                        .binary_search(&r)
                        .expect("the owner of a pair node is a halo neighbour");
                    let f = self.forces[at];
                    make_room(&mut self.send[i], SENT_F64S);
                    self.send[i].extend_from_slice(&[
                        f64::from_bits(u64::from(routes.gid[l as usize])),
                        f64::from_bits(key),
                        f.x,
                        f.y,
                        f.z,
                    ]);
                }
            }
        }
        self.own_entries = self.entries.len();
    }

    /// The contributions received from the neighbours (in `recv`), to
    /// their owned nodes' buckets.
    pub(super) fn take_received(&mut self, routes: &NodeRoutes) {
        let owned = &routes.gid[..routes.n_owned];
        let n: usize = self.recv.iter().map(|b| b.len() / SENT_F64S).sum();
        make_room(&mut self.entries, n);
        make_room(&mut self.forces, n);
        for buf in &self.recv {
            for c in buf.chunks_exact(SENT_F64S) {
                let g = c[0].to_bits() as u32;
                let l = owned
                    .binary_search(&g)
                    .expect("pair contributions arrive for owned nodes");
                self.entries.push(Entry {
                    key: c[1].to_bits(),
                    node: l as u32,
                    at: self.forces.len() as u32,
                });
                self.forces.push(Vector3::new(c[2], c[3], c[4]));
            }
        }
    }

    /// Bucket the entries by node (a counting sort, which keeps the
    /// entries' order), each bucket in key order.
    pub(super) fn order(&mut self, n_owned: usize) {
        self.end.clear();
        self.end.resize(n_owned, 0);
        for e in &self.entries {
            self.end[e.node as usize] += 1;
        }
        let mut start = 0u32;
        for c in self.end.iter_mut() {
            let n = *c;
            *c = start;
            start += n;
        }
        self.order.clear();
        make_room(&mut self.order, self.entries.len());
        self.order.resize(self.entries.len(), 0);
        for (i, e) in self.entries.iter().enumerate() {
            let at = &mut self.end[e.node as usize];
            self.order[*at as usize] = i as u32;
            *at += 1;
        }
        // Now end[i] is where node i's bucket ends.
        let entries = &self.entries;
        let (sorted, own) = (self.own_sorted, self.own_entries as u32);
        let mut begin = 0usize;
        for &end in &self.end {
            let bucket = &mut self.order[begin..end as usize];
            // Own entries in key order, and none received after them.
            let in_order = sorted && bucket.last().is_none_or(|&i| i < own);
            if bucket.len() > 1 && !in_order {
                bucket.sort_by_key(|&i| entries[i as usize].key);
            }
            begin = end as usize;
        }
    }

    /// Add node `i`'s pair forces to `f`, in key order.
    pub(super) fn add_to(&self, i: usize, f: &mut Vector3<f64>) {
        let begin = if i == 0 { 0 } else { self.end[i - 1] as usize };
        for &e in &self.order[begin..self.end[i] as usize] {
            *f += self.forces[self.entries[e as usize].at as usize];
        }
    }

    /// Add each owned node's pair forces to `f` (one per owned node,
    /// holding its element sum), in key order. When the rank's own pairs
    /// came in key order, a node without received entries takes them in
    /// arrival order: no buckets, no sort. Nodes with received entries, and
    /// every node otherwise, take the order of [`Self::order`].
    pub(super) fn add_all(&mut self, f: &mut [Vector3<f64>]) {
        if !self.own_sorted {
            self.order(f.len());
            for (i, fi) in f.iter_mut().enumerate() {
                self.add_to(i, fi);
            }
            return;
        }
        let (own, received) = self.entries.split_at(self.own_entries);
        if received.is_empty() {
            for e in own {
                f[e.node as usize] += self.forces[e.at as usize];
            }
            return;
        }
        if self.mixed.len() < f.len() {
            self.mixed.resize(f.len(), false);
            self.count.resize(f.len(), 0);
        }
        let (mixed, count) = (&mut self.mixed, &mut self.count);
        let mixed_nodes = &mut self.mixed_nodes;
        mixed_nodes.clear();
        for e in received {
            if !mixed[e.node as usize] {
                mixed[e.node as usize] = true;
                mixed_nodes.push(e.node);
            }
        }
        // A node's sum depends only on its own entries' order: bucket the
        // mixed nodes' entries by node (a counting sort, keeping the arrival
        // order: own entries, then received), each bucket stably by key, as
        // one stable sort by (node, key) would order them.
        let late = &mut self.late;
        late.clear();
        for e in own {
            if mixed[e.node as usize] {
                make_room(late, 1);
                late.push(*e);
                count[e.node as usize] += 1;
            } else {
                f[e.node as usize] += self.forces[e.at as usize];
            }
        }
        make_room(late, received.len());
        for e in received {
            late.push(*e);
            count[e.node as usize] += 1;
        }
        let mut start = 0u32;
        for &n in mixed_nodes.iter() {
            let c = count[n as usize];
            count[n as usize] = start;
            start += c;
        }
        let bucketed = &mut self.bucketed;
        bucketed.clear();
        make_room(bucketed, late.len());
        bucketed.resize(
            late.len(),
            Entry {
                key: 0,
                node: 0,
                at: 0,
            },
        );
        for e in late.iter() {
            let at = &mut count[e.node as usize];
            bucketed[*at as usize] = *e;
            *at += 1;
        }
        let mut begin = 0usize;
        for &n in mixed_nodes.iter() {
            let n = n as usize;
            let end = count[n] as usize;
            let bucket = &mut bucketed[begin..end];
            // Stable: arrival order among equal keys, as in `order`.
            bucket.sort_by_key(|e| e.key);
            for e in bucket.iter() {
                f[n] += self.forces[e.at as usize];
            }
            count[n] = 0;
            mixed[n] = false;
            begin = end;
        }
    }

    /// Give back the per-neighbour message buffers (and the mixed nodes'
    /// entries). They are held at the
    /// size of the busiest substep for reuse, but only on ranks with
    /// neighbours, on top of their share of the pairs; the next substep
    /// sizes them again (a few page faults), so an output or a detection
    /// need not hold them beside its own arrays.
    pub(super) fn release_messages(&mut self) {
        self.send = Vec::new();
        self.recv = Vec::new();
        self.late = Vec::new();
        self.bucketed = Vec::new();
    }

    /// Bytes held (capacities).
    pub(super) fn held_bytes(&self) -> usize {
        use std::mem::size_of;
        self.active.capacity() * 4
            + self.forces.capacity() * size_of::<Vector3<f64>>()
            + self.entries.capacity() * size_of::<Entry>()
            + (self.order.capacity() + self.end.capacity()) * 4
            + self.mixed.capacity()
            + (self.count.capacity() + self.mixed_nodes.capacity()) * 4
            + (self.late.capacity() + self.bucketed.capacity()) * size_of::<Entry>()
            + self
                .send
                .iter()
                .chain(&self.recv)
                .map(|b| b.capacity() * 8)
                .sum::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Contributions arriving out of key order are added in key order:
    /// 1 + 2^54 − 2^54 is 0 in floating point, while the arrival order
    /// (−2^54 + 2^54 + 1) would give 1.
    #[test]
    fn owned_buckets_sum_in_key_order() {
        let mut p = PairForces::default();
        let gid = [10u32, 11, 12];
        let owner = [0u32, 0, 1];
        let routes = NodeRoutes {
            n_owned: 2,
            gid: &gid,
            owner: &owner,
            neighbours: &[1],
        };
        let big = 2f64.powi(54);
        let one = |x: f64| [[x, 0.0, 0.0], [0.0; 3], [0.0; 3], [0.0; 3]];
        p.clear();
        // Pair 0 (key 7) pushes node 0 by −2^54, pair 1 (key 3) by +2^54;
        // pair 0's b tet is on the neighbour's node 12.
        p.push(0, &one(-big), &[[2.0, 0.0, 0.0]; 4]);
        p.push(1, &one(big), &[[0.0; 3]; 4]);
        let nodes = |j: usize| match j {
            0 => ([0, 1, 1, 1, 2, 2, 2, 2], 7u64),
            _ => ([0, 1, 1, 1, 1, 1, 1, 1], 3u64),
        };
        p.route(&routes, nodes);
        assert_eq!(p.send[0].len(), 4 * SENT_F64S);
        assert_eq!(p.send[0][0].to_bits(), 12);
        assert_eq!(p.send[0][1].to_bits(), 7);
        assert_eq!(p.send[0][2], 2.0);
        // From the neighbour: key 1 adds 1 to node 10 (local 0).
        p.recv[0] = vec![f64::from_bits(10), f64::from_bits(1), 1.0, 0.0, 0.0];
        p.take_received(&routes);
        p.order(2);
        let mut f0 = Vector3::zeros();
        p.add_to(0, &mut f0);
        assert_eq!(f0, Vector3::zeros());
        let mut f1 = Vector3::new(5.0, 0.0, 0.0);
        p.add_to(1, &mut f1);
        assert_eq!(f1, Vector3::new(5.0, 0.0, 0.0));
    }

    /// With the pairs in key order, `add_all` sums each node's forces as
    /// `order` and `add_to` do, bitwise, for nodes with and without
    /// received entries.
    #[test]
    fn add_all_matches_the_bucket_order() {
        let n_owned = 40usize;
        let gid: Vec<u32> = (0..n_owned as u32 + 10).collect();
        let owner: Vec<u32> = (0..gid.len()).map(|l| u32::from(l >= n_owned)).collect();
        let routes = NodeRoutes {
            n_owned,
            gid: &gid,
            owner: &owner,
            neighbours: &[1],
        };
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize
        };
        let mut p = PairForces::default();
        for round in 0..3 {
            p.clear();
            let mut nodes = Vec::new();
            for j in 0..60 {
                let ls: [u32; 8] = std::array::from_fn(|_| (next() % gid.len()) as u32);
                let force = |k: usize| [[(j * 8 + k) as f64 * 0.37 - 50.0, 1e16, -1.0]; 4];
                p.push(j, &force(0), &force(4));
                nodes.push((ls, 3 * j as u64 + 1));
            }
            p.route(&routes, |j| nodes[j]);
            assert!(p.own_sorted);
            // Received: keys between and around ours, on a few nodes.
            let n_recv = if round == 0 { 0 } else { 25 };
            p.recv[0] = (0..n_recv)
                .flat_map(|i| {
                    let g = (next() % n_owned) as u64;
                    let key = (next() % 200) as u64;
                    [g, key]
                        .map(f64::from_bits)
                        .into_iter()
                        .chain([i as f64, -1e16, 0.5])
                })
                .collect();
            p.take_received(&routes);
            let start: Vec<Vector3<f64>> = (0..n_owned)
                .map(|i| Vector3::new(i as f64, 3.0, 1e-3))
                .collect();
            let mut want = start.clone();
            p.order(n_owned);
            for (i, f) in want.iter_mut().enumerate() {
                p.add_to(i, f);
            }
            let mut got = start.clone();
            p.add_all(&mut got);
            assert_eq!(got, want, "round {round}");
            assert!(p.mixed.iter().all(|m| !m));
            assert!(p.count.iter().all(|&c| c == 0));
        }
    }
}
