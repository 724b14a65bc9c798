//! Contact detection: the broad phase candidate lists (bodies, then
//! boundary tets within the search margin), the ghosts and halo they need,
//! and the balancing of pair work across ranks (`balance_pairs`). Pairs
//! join boundary tets, like the contact surface of seed 000 sec 3.1; the
//! penalty potential itself is `contact::penalty`.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Matrix3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

use super::{ExplicitDomain, NONE};
use crate::contact::penalty::pair_stiffness;
use crate::error::{Error, Result};
use crate::geometry::{face_planes, planes_within, tet_bounds, TetPlanes};
use crate::mechanics::MechElement;
use crate::model::Model;
use crate::parallel::{Halo, Layout};

/// Substeps the fastest node should need before contact re-detection.
const DETECT_EVERY: f64 = 10.0;
/// Largest search margin, as a multiple of the configured one.
const MARGIN_GROWTH: f64 = 4.0;
/// Work of a candidate pair whose tets' boxes overlap at detection (it
/// likely runs the overlap kernel each substep), in units of one whose
/// boxes are apart (a box test and zeroed forces).
const HOT_PAIR_WEIGHT: u64 = 32;

/// A box (low, high corner) grown by `g` on every side.
fn grown_aabb((lo, hi): &([f64; 3], [f64; 3]), g: f64) -> Aabb {
    Aabb::new(
        Point::new(lo[0] - g, lo[1] - g, lo[2] - g),
        Point::new(hi[0] + g, hi[1] + g, hi[2] + g),
    )
}

/// A candidate contact pair: boundary tets `a` (of a free body) and `b` (of
/// another body) whose boxes, grown by the margin, overlap.
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    pub(super) a: u32,
    pub(super) b: u32,
    /// Indices of a and b in `ExplicitDomain::pair_tets`.
    pub(super) ta: u32,
    pub(super) tb: u32,
    /// Bodies of a and b.
    pub(super) body_a: u32,
    pub(super) body_b: u32,
    pub(super) stiffness: f64,
    pub(super) reduced_mass: f64,
}

impl ExplicitDomain {
    /// Collective. Refresh every node's position, rebuild the contact
    /// candidates, the ghost list and the halo; reorder elements so those
    /// touching the halo come first.
    pub(super) fn detect(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
    ) -> Result<()> {
        let clock = std::time::Instant::now();
        let mesh = &model.mesh;
        // Every node's current position.
        self.gather_positions(comm);
        // Candidate pairs.
        self.candidates.clear();
        self.margin = self.adapted_margin(comm);
        if let Some((_, penalty)) = self.penalty {
            let weights = self.find_pairs(model, penalty);
            self.balance_pairs(comm, model, penalty, &weights);
        }
        // Ghosts: those of the elements, then those of the contacts, in
        // ascending node order. The tets of the pairs are listed once each
        // (their corners and planes are built once per substep, not once
        // per pair). Marks instead of sorting the ~8 nodes per pair.
        for &n in &self.node_of_local[self.n_owned + self.n_elem_ghosts..] {
            self.local_of[n as usize] = NONE;
        }
        self.node_of_local
            .truncate(self.n_owned + self.n_elem_ghosts);
        let mut tets: Vec<u32> = Vec::new();
        let mut contact_nodes: Vec<u32> = Vec::new();
        for c in self.candidates.iter_mut() {
            for (e, slot) in [(c.a, &mut c.ta), (c.b, &mut c.tb)] {
                let s = &mut self.tet_slot[e as usize];
                if *s == NONE {
                    *s = tets.len() as u32;
                    tets.push(e);
                    for &n in &mesh.tets[e as usize] {
                        if self.local_of[n as usize] == NONE {
                            // Marked as taken until numbered below.
                            self.local_of[n as usize] = NONE - 1;
                            contact_nodes.push(n);
                        }
                    }
                }
                *slot = *s;
            }
        }
        for &e in &tets {
            self.tet_slot[e as usize] = NONE;
        }
        contact_nodes.sort_unstable();
        for n in contact_nodes {
            self.local_of[n as usize] = self.node_of_local.len() as u32;
            self.node_of_local.push(n);
        }
        self.refresh_local_arrays();
        self.pair_tets = tets
            .iter()
            .map(|&e| mesh.tets[e as usize].map(|n| self.local_of[n as usize]))
            .collect();
        // Fresh candidates: planes rebuilt on demand, no linearisations.
        self.pair_planes = vec![TetPlanes::new(&[[0.0; 3]; 4]); tets.len()];
        self.planes_stamp = vec![0; tets.len()];
        self.lin_of = vec![NONE; self.candidates.len()];
        self.linearized.clear();
        self.witness = vec![0; self.candidates.len()];
        let ghosts: Vec<(u32, u32, u32)> = (self.n_owned..self.node_of_local.len())
            .map(|l| {
                let n = self.node_of_local[l];
                (n, layout.node_owner[n as usize], l as u32)
            })
            .collect();
        let n_owned = self.n_owned as u32;
        let local_of = &self.local_of;
        let halo = Halo::new(comm, &ghosts, |g| {
            let l = local_of[g as usize];
            (l < n_owned).then_some(l)
        });
        self.halo = crate::parallel::agree(comm, halo.map_err(Error::Partition))?;
        // Ghost positions and velocities from their owners.
        self.forward_state(comm);
        // Elements touching a ghost node first (their contributions are
        // sent), each group by element id: the two id-ordered groups of the
        // last detection merged back into id order, then split anew, in
        // linear time.
        let n_owned = self.n_owned;
        let touches = |el: &MechElement| el.nodes.iter().any(|&l| l as usize >= n_owned);
        let (ids, ne, nb_old) = (&self.elem_ids, self.elem_ids.len(), self.n_boundary);
        let mut by_id: Vec<usize> = Vec::with_capacity(ne);
        let (mut i, mut j) = (0, nb_old);
        while i < nb_old || j < ne {
            if j == ne || (i < nb_old && ids[i] < ids[j]) {
                by_id.push(i);
                i += 1;
            } else {
                by_id.push(j);
                j += 1;
            }
        }
        if !by_id.windows(2).all(|w| ids[w[0]] < ids[w[1]]) {
            by_id.sort_by_key(|&i| ids[i]);
        }
        let mut order: Vec<usize> = by_id
            .iter()
            .copied()
            .filter(|&i| touches(&self.elements[i]))
            .collect();
        self.n_boundary = order.len();
        order.extend(
            by_id
                .iter()
                .copied()
                .filter(|&i| !touches(&self.elements[i])),
        );
        self.elements = order.iter().map(|&i| self.elements[i]).collect();
        self.elem_ids = order.iter().map(|&i| self.elem_ids[i]).collect();
        self.elem_tref = order.iter().map(|&i| self.elem_tref[i]).collect();
        if self.elem_dt.len() == order.len() {
            self.elem_dt = order.iter().map(|&i| self.elem_dt[i]).collect();
            self.elem_rate = order.iter().map(|&i| self.elem_rate[i]).collect();
        }
        // Every substep writes every element's stress: no need to permute it.
        self.stress.resize(self.elements.len(), Matrix3::zeros());
        self.build_assembly(comm, layout);
        self.x_detect = self.x[..self.n_owned].to_vec();
        self.counters.detections += 1;
        self.counters.detect_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// This rank's candidate pairs, with their estimated costs (see
    /// [`Self::balance_pairs`]). Two levels: bodies whose boxes come within
    /// the margin, then, for each such pair, the owned boundary tets of
    /// one tested against a tree of the other's boundary tets, so no query
    /// wades through its own body's tets and a body falling alone costs
    /// one box test. The fixed bodies' trees are built once.
    fn find_pairs(&mut self, model: &Model, penalty: f64) -> Vec<u64> {
        let mesh = &model.mesh;
        let margin = self.margin;
        let x_all = &self.x_all;
        let corners = |e: u32| mesh.tets[e as usize].map(|n| x_all[n as usize]);
        // Not in the seeds: the penalty potential sums over pairs of
        // boundary tets (a face on the surface), like the contact
        // surface of seed 000 sec 3.1; a tet that meets the surface only
        // at an edge or corner overlaps a shallow intruder by O(δ²).
        let bt = &self.boundary.elems;
        let raw: Vec<([f64; 3], [f64; 3])> = bt.iter().map(|&e| tet_bounds(&corners(e))).collect();
        // Face planes of every boundary tet, for the candidates' pruning.
        let planes: Vec<[[f64; 4]; 4]> = bt.iter().map(|&e| face_planes(&corners(e))).collect();
        let nb = model.bodies.len();
        let mut body_box = vec![([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]); nb];
        for (i, &e) in bt.iter().enumerate() {
            let bb = &mut body_box[mesh.body[e as usize] as usize];
            for d in 0..3 {
                bb.0[d] = bb.0[d].min(raw[i].0[d]);
                bb.1[d] = bb.1[d].max(raw[i].1[d]);
            }
        }
        let with_tets: Vec<u32> = (0..nb as u32)
            .filter(|&b| !self.body_bt[b as usize].is_empty())
            .collect();
        let leaves: Vec<Aabb> = with_tets
            .iter()
            .map(|&b| grown_aabb(&body_box[b as usize], 0.0))
            .collect();
        let body_tree = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        let tree_of = |b: usize| {
            let leaves: Vec<Aabb> = self.body_bt[b]
                .iter()
                .map(|&i| grown_aabb(&raw[i as usize], 0.0))
                .collect();
            Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves)
        };
        for b in 0..nb {
            if model.bodies[b].fixed && self.fixed_trees[b].is_none() && !self.body_bt[b].is_empty()
            {
                self.fixed_trees[b] = Some(tree_of(b));
            }
        }
        let mut moving_trees: Vec<Option<Bvh>> = (0..nb).map(|_| None).collect();
        let mut found: Vec<(u32, u32, bool)> = Vec::new();
        for ba in 0..nb {
            // A held body's pairs are found from the free side (the
            // particles' ranks, which the partition balances).
            if self.body_held[ba] || self.my_body_bt[ba].is_empty() {
                continue;
            }
            let mut near: Vec<usize> = body_tree
                .intersect_aabb(&grown_aabb(&body_box[ba], margin))
                .map(|i| with_tets[i as usize] as usize)
                // Of two free bodies, the lower id finds the pairs.
                .filter(|&bb| bb != ba && (self.body_held[bb] || ba < bb))
                .collect();
            near.sort_unstable();
            for bb in near {
                let tree = match &self.fixed_trees[bb] {
                    Some(t) => t,
                    None => moving_trees[bb].get_or_insert_with(|| tree_of(bb)),
                };
                let (lo_b, hi_b) = body_box[bb];
                for &ia in &self.my_body_bt[ba] {
                    let (lo, hi) = raw[ia as usize];
                    if (0..3).any(|d| lo[d] - margin > hi_b[d] || lo_b[d] > hi[d] + margin) {
                        continue;
                    }
                    for leaf in tree.intersect_aabb(&grown_aabb(&raw[ia as usize], margin)) {
                        let ib = self.body_bt[bb][leaf as usize] as usize;
                        let (a, b) = (bt[ia as usize], bt[ib]);
                        if !planes_within(
                            (&corners(a), &planes[ia as usize]),
                            (&corners(b), &planes[ib]),
                            margin,
                        ) {
                            continue;
                        }
                        let (lo_t, hi_t) = raw[ib];
                        let hot = (0..3).all(|d| lo[d] <= hi_t[d] && lo_t[d] <= hi[d]);
                        found.push((a, b, hot));
                    }
                }
            }
        }
        self.candidates = found
            .iter()
            .map(|&(a, b, _)| self.candidate(model, penalty, a, b))
            .collect();
        found
            .iter()
            .map(|&(_, _, hot)| if hot { HOT_PAIR_WEIGHT } else { 1 })
            .collect()
    }

    /// The candidate pair of boundary tets `a` (of a free body) and `b`.
    fn candidate(&self, model: &Model, penalty: f64, a: u32, b: u32) -> Candidate {
        let mesh = &model.mesh;
        let (ba, bb) = (mesh.body[a as usize], mesh.body[b as usize]);
        let (va, vb) = (
            mesh.element_volume(a as usize),
            mesh.element_volume(b as usize),
        );
        let (ma, mb) = (
            model.material_of(a as usize).density * va,
            model.material_of(b as usize).density * vb,
        );
        // a is never held (held bodies do not search).
        let reduced_mass = if self.body_held[bb as usize] {
            ma
        } else {
            ma * mb / (ma + mb)
        };
        Candidate {
            a,
            b,
            ta: NONE,
            tb: NONE,
            body_a: ba,
            body_b: bb,
            stiffness: pair_stiffness(penalty, va, vb),
            reduced_mass,
        }
    }

    /// Collective. Share the pair work evenly over the ranks. Each rank
    /// finds the pairs of the tets it owns, so the ranks holding the
    /// bottom of a settling column (or its contacts) would do all the
    /// contact work while the others wait. With `weights` the estimated
    /// cost of each found pair, the pairs of all ranks, in rank order,
    /// are cut into equal-weight runs and rank r takes run r: an excess
    /// moves to the next ranks as one contiguous, spatially coherent run
    /// (the pair's nodes become ghosts there). The forces do not depend
    /// on which rank evaluates a pair (they are summed by pair key).
    fn balance_pairs(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        penalty: f64,
        weights: &[u64],
    ) {
        let size = comm.size() as usize;
        if size == 1 {
            return;
        }
        let mine: u64 = weights.iter().sum();
        let mut all = vec![0u64; size];
        comm.all_gather_into(&mine, &mut all[..]);
        let total: u64 = all.iter().sum();
        if total == 0 {
            return;
        }
        let mut at: u64 = all[..self.rank as usize].iter().sum();
        let mut out: Vec<Vec<u32>> = vec![Vec::new(); size];
        let mut keep = Vec::with_capacity(self.candidates.len());
        for (c, &w) in self.candidates.iter().zip(weights) {
            // The rank whose equal share holds the pair's mid-point.
            let mid = 2 * u128::from(at) + u128::from(w);
            let dest = ((mid * size as u128) / (2 * u128::from(total))).min(size as u128 - 1);
            at += w;
            if dest == u128::from(self.rank) {
                keep.push(*c);
            } else {
                out[dest as usize].extend_from_slice(&[c.a, c.b]);
            }
        }
        let send_counts: Vec<i32> = out.iter().map(|v| v.len() as i32).collect();
        let mut recv_counts = vec![0i32; size];
        comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let displs = |c: &[i32]| -> Vec<i32> {
            c.iter()
                .scan(0, |acc, &x| {
                    let d = *acc;
                    *acc += x;
                    Some(d)
                })
                .collect()
        };
        let send: Vec<u32> = out.concat();
        let mut recv = vec![0u32; recv_counts.iter().sum::<i32>() as usize];
        {
            let send =
                mpi::datatype::Partition::new(&send[..], send_counts.clone(), displs(&send_counts));
            let mut part = mpi::datatype::PartitionMut::new(
                &mut recv[..],
                recv_counts.clone(),
                displs(&recv_counts),
            );
            comm.all_to_all_varcount_into(&send, &mut part);
        }
        for ab in recv.chunks_exact(2) {
            keep.push(self.candidate(model, penalty, ab[0], ab[1]));
        }
        self.candidates = keep;
    }

    /// Smallest search margin of the contact candidates (m), used at rest
    /// (see [`Self::adapted_margin`]).
    pub fn min_margin(&self) -> f64 {
        self.margin_min
    }

    /// Collective. The margin for the next candidate lists: wide enough
    /// that the fastest node needs [`DETECT_EVERY`] substeps to use up
    /// half of it (re-detection), at least the configured one (half the
    /// smallest element length by default) and at most [`MARGIN_GROWTH`]
    /// times that. Falling particles then re-detect every ~10 substeps
    /// instead of every one or two, and a bed at rest keeps the tight
    /// margin (a wider one only adds candidates). The trajectory does not
    /// depend on it: pairs out of reach have no force.
    fn adapted_margin(&self, comm: &SimpleCommunicator) -> f64 {
        let mine = self.v[..self.n_owned]
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        let mut v_max = 0.0;
        comm.all_reduce_into(&mine, &mut v_max, SystemOperation::max());
        // Not in the seeds: Verlet-list skin, re-detect after the margin/2 a node may move in DETECT_EVERY substeps.
        (2.0 * DETECT_EVERY * v_max * self.dt)
            .clamp(self.margin_min, MARGIN_GROWTH * self.margin_min)
    }
}
