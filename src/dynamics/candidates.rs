//! Contact candidates of the explicit dynamics: the one contact search
//! ([`crate::contact::search`]) at each detection, the penalty candidates
//! pruned by face planes and their balancing over the ranks
//! (`balance_pairs`), the thermal-only candidates of a coupled run, the
//! ghosts and halo they need, and the thermal narrow phase on them
//! (`thermal_contacts`, seed 000 sec 3.1). The penalty potential itself is
//! `contact::penalty`.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Matrix3;

use super::{ExplicitDomain, NONE};
use crate::contact::penalty::pair_stiffness;
use crate::contact::{tet_pair_contact, ContactPair, SearchOptions};
use crate::error::{Error, Result};
use crate::geometry::{face_planes, planes_within, TetPlanes};
use crate::mechanics::MechElement;
use crate::model::Model;
use crate::parallel::{Halo, Part};

/// Substeps the fastest node should need before contact re-detection.
const DETECT_EVERY: f64 = 10.0;
/// Largest search margin, as a multiple of the configured one.
const MARGIN_GROWTH: f64 = 4.0;
/// Work of a candidate pair whose tets' boxes overlap at detection (it
/// likely runs the overlap kernel each substep), in units of one whose
/// boxes are apart (a box test and zeroed forces).
const HOT_PAIR_WEIGHT: u64 = 32;

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
        part: &Part,
    ) -> Result<()> {
        let clock = std::time::Instant::now();
        let mesh = &model.mesh;
        // Every node's current position.
        self.gather_positions(comm);
        // Candidate pairs.
        self.candidates.clear();
        self.thermal_only.clear();
        self.margin = self.adapted_margin(comm);
        if self.penalty.is_some() || self.thermal {
            let weights = self.find_pairs(model);
            if let Some((_, penalty)) = self.penalty {
                self.balance_pairs(comm, model, penalty, &weights);
            }
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
        // The thermal-only candidates' nodes are ghosts too (their
        // corners are read at thermal detections).
        for &(a, b) in &self.thermal_only {
            for e in [a, b] {
                for &n in &mesh.tets[e as usize] {
                    if self.local_of[n as usize] == NONE {
                        self.local_of[n as usize] = NONE - 1;
                        contact_nodes.push(n);
                    }
                }
            }
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
                (n, part.whole().node_owner[n as usize], l as u32)
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
        self.build_assembly(comm, part);
        self.x_detect = self.x[..self.n_owned].to_vec();
        self.detected_at = Some(self.counters.substeps);
        self.counters.detections += 1;
        self.counters.detect_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// This rank's candidates from the one contact search
    /// ([`crate::contact::search`]), with their estimated costs (see
    /// [`Self::balance_pairs`]). Pairs of two boundary tets of bodies not
    /// both held are the penalty candidates, pruned by face planes; when
    /// the thermal contact is coupled, the search also returns a boundary
    /// tet against another body's interior tets and pairs of two held
    /// bodies, kept for the thermal contact only.
    fn find_pairs(&mut self, model: &Model) -> Vec<u64> {
        let mesh = &model.mesh;
        let margin = self.margin;
        let x_all = &self.x_all;
        let corners = |e: u32| mesh.tets[e as usize].map(|n| x_all[n as usize]);
        let opts = SearchOptions {
            margin,
            pad: 0.0,
            interior: self.thermal,
            held_pairs: self.thermal,
        };
        let found = self.search.find(
            &self.body_tets,
            corners,
            &self.body_held,
            &self.body_fixed,
            opts,
        );
        // Not in the seeds: the penalty potential sums over pairs of
        // boundary tets (a face on the surface), like the contact
        // surface of seed 000 sec 3.1; a tet that meets the surface only
        // at an edge or corner overlaps a shallow intruder by O(δ²).
        let penalty = self.penalty.map(|(_, pn)| pn);
        let bt = &self.boundary;
        let planes: Vec<[[f64; 4]; 4]> = match penalty {
            Some(_) => bt.elems.iter().map(|&e| face_planes(&corners(e))).collect(),
            None => Vec::new(),
        };
        let mut kept: Vec<(u32, u32, bool)> = Vec::new();
        for c in found {
            let held = |e: u32| self.body_held[mesh.body[e as usize] as usize];
            if penalty.is_some() && c.b_boundary && !(held(c.a) && held(c.b)) {
                let (ia, ib) = (bt.index[c.a as usize], bt.index[c.b as usize]);
                if planes_within(
                    (&corners(c.a), &planes[ia as usize]),
                    (&corners(c.b), &planes[ib as usize]),
                    margin,
                ) {
                    kept.push((c.a, c.b, c.hot));
                }
            } else if self.thermal {
                self.thermal_only.push((c.a, c.b));
            }
        }
        if let Some(pn) = penalty {
            self.candidates = kept
                .iter()
                .map(|&(a, b, _)| self.candidate(model, pn, a, b))
                .collect();
        }
        kept.iter()
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

    /// Collective. The thermal contact pairs this rank holds at the
    /// current positions (seed 000 sec 3.1): the narrow phase on its
    /// candidates, penalty and thermal-only, so a coupled run searches
    /// once per detection. When the candidates are due for renewal (a node
    /// has used up half the margin) they are renewed first, as the next
    /// substep would; every pair of tets that overlaps now is among them.
    pub fn thermal_contacts(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
    ) -> Result<Vec<ContactPair>> {
        if self.redetect {
            self.detect(comm, model, part)?;
            self.redetect = false;
        }
        let mesh = &model.mesh;
        let corners = |e: u32| {
            mesh.tets[e as usize].map(|n| {
                let p = &self.x[self.local_of[n as usize] as usize];
                [p.x, p.y, p.z]
            })
        };
        let mut pairs: Vec<ContactPair> = self
            .candidates
            .iter()
            .map(|c| (c.a, c.b))
            .chain(self.thermal_only.iter().copied())
            .filter_map(|(a, b)| {
                tet_pair_contact(mesh, &self.boundary, (a, &corners(a)), (b, &corners(b)))
            })
            .collect();
        pairs.sort_by_key(|p| (p.target, p.contactor));
        Ok(pairs)
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
