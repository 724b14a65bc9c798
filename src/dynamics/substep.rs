//! One substep of the explicit dynamics: contact forces of the candidate
//! pairs, element forces (seed 004 eqs 5–35 via
//! [`crate::mechanics::explicit::element_forces`]) with the halo exchange
//! of ghost contributions overlapping the interior elements, and the
//! central-difference update of the owned nodes
//! ([`crate::mechanics::explicit::update_nodes_damped`]).

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::force_sum::pair_key;
use super::pair_sum::NodeRoutes;
use super::{ExplicitDomain, NONE};
use crate::contact::penalty::{
    overlap_state, penalty_forces_with, LinearizedOverlap, PenaltyParams,
};
use crate::error::{Error, Result};
use crate::geometry::{pair_size2, separated_along, separating_axis, tet_bounds, TetPlanes};
use crate::mechanics::explicit::{element_forces, update_nodes_damped, NodeUpdate, ThermalLoad};

/// A candidate's witness before its first evaluation after a detection.
pub(super) const UNSEEN: u8 = 0;
/// A candidate's witness when no axis separated its tets at its last
/// evaluation (they overlapped or touched): the clipping comes first.
pub(super) const OVERLAPPED: u8 = u8::MAX;

/// Corners of a tet and its bounding box (low, high corner).
pub(super) type TetGeometry = ([[f64; 3]; 4], [f64; 3], [f64; 3]);

/// The clock of a substep's phases ([`super::SUBSTEP_PHASES`]).
struct PhaseClock(std::time::Instant);

impl PhaseClock {
    /// Adds the time since the last mark to phase `k`.
    fn mark(&mut self, k: usize, c: &mut super::MechanicsCounters) {
        let now = std::time::Instant::now();
        c.substep_phases[k] += (now - self.0).as_secs_f64();
        self.0 = now;
    }
}

impl ExplicitDomain {
    /// Collective. Advance by `n` substeps.
    pub fn advance(&mut self, comm: &SimpleCommunicator, n: u64) -> Result<()> {
        // Linearised pairs depend on when their models were made: starting
        // every step with fresh candidates and no models makes a restart,
        // which detects afresh, repeat the run bitwise.
        // (A detection at these very positions, by a thermal detection or
        // a restore, already gives those candidates.)
        // The same for the pairs' ranks (`pair_balance`): a detection at
        // a step start shares them by the positions alone.
        if self.linear_tolerance > 0.0 && n > 0 {
            if self.detected_at != Some(self.counters.substeps) || !self.last_detect_fresh {
                self.redetect = true;
            }
            self.drop_models();
        }
        let sent_before = crate::parallel::bytes_sent();
        for i in 0..n {
            if i + 1 == n {
                self.v_prev.clear();
                self.v_prev.extend_from_slice(&self.v[..self.n_owned]);
            }
            if self.redetect {
                self.sticky_detect = i > 0;
                let detected = self.detect(comm);
                self.sticky_detect = false;
                detected?;
                self.redetect = false;
            }
            let local = self.substep(comm);
            // Agree on errors and on the need to re-detect contacts.
            // New crack faces call for candidates at once (as any rank's).
            let moved = if self.penalty.is_some() && self.cracks_marked {
                f64::INFINITY
            } else if self.penalty.is_some() {
                self.x[..self.n_owned]
                    .iter()
                    .zip(&self.x_detect)
                    .map(|(a, b)| (a - b).norm_squared())
                    .fold(0.0, f64::max)
            } else {
                0.0
            };
            let mine = [f64::from(u8::from(local.is_err())), moved];
            let mut any = [0.0; 2];
            comm.all_reduce_into(&mine[..], &mut any[..], SystemOperation::max());
            if any[0] > 0.0 {
                return match local {
                    Err(e) => Err(e),
                    Ok(()) => Err(Error::OtherRank),
                };
            }
            let half = 0.5 * self.margin;
            self.redetect = any[1] >= half * half;
            self.counters.substeps += 1;
            self.counters.substeps_run += 1;
        }
        self.counters.bytes_sent += crate::parallel::bytes_sent() - sent_before;
        Ok(())
    }

    /// One substep (collective: the touching flags' all-reduce, when
    /// free flight has its own damping, and the neighbours' messages).
    /// Errors are returned after the messages are exchanged, so no
    /// neighbour waits.
    pub(super) fn substep(&mut self, comm: &SimpleCommunicator) -> Result<()> {
        let mut clock = PhaseClock(std::time::Instant::now());
        self.pair_phase();
        clock.mark(0, &mut self.counters);
        let mut error = if self.free_damping.is_some() {
            // Which bodies touch something, over all ranks (a body's pairs
            // may be on another rank than its nodes): reduced while the
            // elements are computed and the forces summed.
            let here = std::mem::take(&mut self.touching);
            let mut all = std::mem::take(&mut self.touching_here);
            let error = mpi::request::scope(|scope| {
                let op = SystemOperation::max();
                let flags = comm.immediate_all_reduce_into(scope, &here[..], &mut all[..], op);
                let error = self.element_phase(comm, &mut clock);
                flags.wait();
                error
            });
            self.touching = all;
            self.touching_here = here;
            error
        } else {
            self.element_phase(comm, &mut clock)
        };
        clock.mark(5, &mut self.counters);
        let free = self.free_damping.unwrap_or(self.damping);
        if !self.particles.is_empty() {
            // Bonds and links after the element sum, in each body's fixed order (on any rank).
            let (x, v) = (&self.x, &self.v);
            self.strain_energy += self.particles.add_forces(x, v, self.dt, &mut self.f);
            let (touching, damping) = (&self.touching, self.damping);
            // The packing-stage damping of the nodes below, per body.
            let body_damping = |b: u32| {
                if touching[b as usize] != 0 {
                    damping
                } else {
                    free
                }
            };
            match self.particles.advance(self.dt, body_damping, &self.gravity) {
                Ok(step) => {
                    self.particle_kinetic = step.kinetic;
                    self.particle_momentum = step.momentum;
                    self.dissipated += step.damped;
                }
                Err(e) => {
                    error.get_or_insert(e);
                }
            }
            self.particles.forward_motion(comm);
        }
        if let Some(spheres) = self.spheres.as_mut() {
            // Free spheres (issue 21) after the element sum: their faces'
            // shares land on the owned nodes in (sphere, contact) order.
            let touched = self.damping;
            let step = spheres.substep(
                comm,
                &self.part_tets,
                &self.x,
                &self.v,
                self.dt,
                &self.gravity,
                |touching| if touching { touched } else { free },
                &self.node_t,
                &mut self.f,
            );
            if let Err(e) = step {
                error.get_or_insert(e);
            }
        }
        clock.mark(6, &mut self.counters);
        let no = self.n_owned;
        let p = NodeUpdate {
            dt: self.dt,
            gravity: self.gravity,
            mass_damping: self.damping,
        };
        let (touching, owned_body, damping) = (&self.touching, &self.owned_body, self.damping);
        // Not in the seeds: packing-stage mass damping only on bodies in contact (free flight undamped).
        let node_damping = |i: usize| {
            if touching[owned_body[i] as usize] != 0 {
                damping
            } else {
                free
            }
        };
        match update_nodes_damped(
            &p,
            node_damping,
            &self.mass[..no],
            &self.f[..no],
            Some(&self.ext[..no]),
            &self.bc[..no],
            &mut self.x[..no],
            &mut self.v[..no],
        ) {
            Ok(w) => {
                self.external_work += w.external;
                self.dissipated += w.damping;
            }
            Err(e) => {
                let msg = match e {
                    crate::mechanics::MechanicsError::NonFinite { node } => format!(
                        "node {} became non-finite (NaN or infinite): the explicit step \
                     is unstable or a contact exploded; reduce mechanics.dt or mechanics.safety",
                        self.node_gid[node]
                    ),
                    other => other.to_string(),
                };
                error.get_or_insert(Error::Mechanics(msg));
            }
        }
        self.forward_state(comm);
        clock.mark(7, &mut self.counters);
        match error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Phase 0 of a substep: the contact forces of the candidate pairs
    /// and the touching flags of this rank.
    fn pair_phase(&mut self) {
        // Contact forces of the touching candidate pairs.
        self.pair_forces.clear();
        self.contact_energy = 0.0;
        self.active_pairs = 0;
        self.touching.iter_mut().for_each(|t| *t = 0);
        if let Some((params, _)) = &self.penalty {
            let mut power = 0.0;
            self.pair_geometry.clear();
            self.pair_geometry.extend(self.pair_tets.iter().map(|t| {
                let x: [[f64; 3]; 4] = t.map(|l| self.x[l as usize].into());
                let (lo, hi) = tet_bounds(&x);
                (x, lo, hi)
            }));
            self.substep_id += 1;
            let now = self.substep_id;
            let tolerance = self.linear_tolerance;
            let with_springs = self.has_springs();
            let geo = &self.pair_geometry;
            let (planes_of, planes) = (&mut self.planes_of, &mut self.pair_planes);
            let (lin_of, linearized) = (&mut self.lin_of, &mut self.linearized);
            let witness = &mut self.witness;
            let mut exact = 0u64;
            for (j, c) in self.candidates.iter().enumerate() {
                let (ta, tb) = (c.ta as usize, c.tb as usize);
                let ((xa, lo_a, hi_a), (xb, lo_b, hi_b)) = (&geo[ta], &geo[tb]);
                let slot = lin_of[j] as usize;
                // A contacting pair's linearised overlap, while it holds.
                let lin_volume = linearized
                    .get(slot)
                    .and_then(|m| m.volume_at(xa, xb).map(|v| (m, v)));
                // Most other candidates are apart: their boxes tell, or the
                // axis that separated them when they were last evaluated.
                if lin_volume.is_none()
                    && ((0..3).any(|d| lo_a[d] > hi_b[d] || lo_b[d] > hi_a[d])
                        || separated_along(
                            xa,
                            xb,
                            witness[j],
                            pair_size2((*lo_a, *hi_a), (*lo_b, *hi_b)),
                        ))
                {
                    lin_of[j] = NONE;
                    continue;
                }
                // Not evaluated since the detection: an axis that separates
                // the tets (the clipping would find nothing) costs less
                // than the clipping.
                if lin_volume.is_none() && witness[j] == UNSEEN {
                    if let Some(axis) = separating_axis(xa, xb) {
                        witness[j] = axis;
                        lin_of[j] = NONE;
                        continue;
                    }
                }
                let (la, lb) = (&self.pair_tets[ta], &self.pair_tets[tb]);
                let va = la.map(|l| self.v[l as usize].into());
                let vb = lb.map(|l| self.v[l as usize].into());
                let p = PenaltyParams {
                    stiffness: c.stiffness,
                    reduced_mass: c.reduced_mass,
                    time_step: self.dt,
                    ..*params
                };
                // The pair's tangential spring, when friction sticks.
                let spring = if with_springs {
                    self.spring_seen[j] = now;
                    Some(&mut self.springs[j])
                } else {
                    None
                };
                let result = match lin_volume {
                    Some((m, v)) => Some(penalty_forces_with(&m.state, v, &va, &vb, &p, spring)),
                    None => {
                        for t in [ta, tb] {
                            let at = planes_of[t] as usize;
                            if at >= planes.len() {
                                planes_of[t] = planes.len() as u32;
                                planes.push((now, TetPlanes::new(&geo[t].0)));
                            } else if planes[at].0 != now {
                                planes[at] = (now, TetPlanes::new(&geo[t].0));
                            }
                        }
                        exact += 1;
                        let (pa, pb) = (planes_of[ta] as usize, planes_of[tb] as usize);
                        match overlap_state((xa, &planes[pa].1), (xb, &planes[pb].1)) {
                            Some(s) => {
                                witness[j] = OVERLAPPED;
                                if tolerance > 0.0 {
                                    if slot < linearized.len() {
                                        linearized[slot].set(&s, xa, xb, tolerance);
                                    } else {
                                        lin_of[j] = linearized.len() as u32;
                                        linearized
                                            .push(LinearizedOverlap::new(s, xa, xb, tolerance));
                                    }
                                }
                                Some(penalty_forces_with(&s, s.volume, &va, &vb, &p, spring))
                            }
                            None => {
                                lin_of[j] = NONE;
                                witness[j] = separating_axis(xa, xb).unwrap_or(OVERLAPPED);
                                if let Some(x) = spring {
                                    // The contact ended: its spring's energy is dissipated.
                                    power += x[3] / self.dt;
                                    *x = [0.0; 4];
                                }
                                None
                            }
                        }
                    }
                };
                if let Some(r) = result {
                    self.pair_forces.push(j, &r.forces_a, &r.forces_b);
                    self.contact_energy += r.energy;
                    power += r.dissipation;
                    if self.friction_heating.is_some() {
                        if self.pair_friction.len() != self.candidates.len() {
                            self.pair_friction.resize(self.candidates.len(), 0.0);
                        }
                        self.pair_friction[j] += r.friction_power * self.dt;
                        self.friction_work += r.friction_power * self.dt;
                    }
                    self.active_pairs += 1;
                    // A body touching only itself still touches no other body.
                    if c.body_a != c.body_b {
                        self.touching[c.body_a as usize] = 1;
                        self.touching[c.body_b as usize] = 1;
                    }
                }
            }
            self.dissipated += power * self.dt;
            self.counters.pair_updates += self.candidates.len() as u64;
            self.counters.exact_overlaps += exact;
            if with_springs {
                self.release_apart_springs(now);
            }
        }
    }

    /// Phases 1–4 of a substep: the elements' forces, the exchange of the
    /// ghost contributions with the neighbours (collective over them), the
    /// sum of the owned nodes' forces and the joints'. Returns an
    /// element's error, after the exchange.
    fn element_phase(
        &mut self,
        comm: &SimpleCommunicator,
        clock: &mut PhaseClock,
    ) -> Option<Error> {
        let ne = self.elements.len();
        let pair_base = 4 * ne;
        // Elements next to the halo, then the interior while messages fly.
        let nb = self.n_boundary;
        let (dt_b, dt_i) = self.elem_dt.split_at(nb);
        let (rate_b, rate_i) = self.elem_rate.split_at(nb);
        let (s_b, s_i) = self.stress.split_at_mut(nb);
        let (elem_part, rest) = self.contrib.split_at_mut(pair_base);
        let (f_b, f_i) = elem_part.as_chunks_mut::<4>().0.split_at_mut(nb);
        let mut strain = 0.0;
        let mut elem_error = None;
        match element_forces(
            &self.elements[..nb],
            &self.materials,
            &self.x,
            &self.v,
            ThermalLoad::transient(dt_b, rate_b),
            f_b,
            Some(s_b),
        ) {
            Ok(w) => strain += w,
            Err(e) => elem_error = Some((e, 0)),
        }
        if !self.hexes.is_empty() {
            let (x, v) = (&self.x, &self.v);
            match self
                .hexes
                .forces(0..nb, &self.materials, x, v, dt_b, rate_b, f_b, s_b)
            {
                Ok(w) => strain += w,
                Err(e) => {
                    elem_error.get_or_insert((e, 0));
                }
            }
        }
        // Ghost contributions, one by one, to their owners: the halo
        // elements' (fixed slots), and the touching pairs'.
        let mut send = std::mem::take(&mut self.send_buf);
        send.resize(self.send_slots.len(), Vec::new());
        for (buf, slots) in send.iter_mut().zip(&self.send_slots) {
            buf.clear();
            // Sized once (it is freed at detections and outputs).
            buf.reserve_exact(3 * slots.len());
            for &s in slots {
                let s = s as usize;
                let f = f_b[s / 4][s % 4];
                buf.extend_from_slice(&[f.x, f.y, f.z]);
            }
        }
        let routes = NodeRoutes {
            n_owned: self.n_owned,
            gid: &self.node_gid,
            owner: &self.node_owner,
            neighbours: self.halo.neighbours(),
        };
        let (candidates, pair_tets) = (&self.candidates, &self.pair_tets);
        self.pair_forces.route(&routes, |j| {
            let c = &candidates[j];
            let (a, b) = (pair_tets[c.ta as usize], pair_tets[c.tb as usize]);
            (
                [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]],
                pair_key(c),
            )
        });
        // Contributions from the neighbours land in place, after the pairs'.
        let recv_base = self
            .recv_at
            .first()
            .map_or(rest.len(), |&(s, _)| s - pair_base);
        let mut landing: &mut [f64] = bytemuck::cast_slice_mut(&mut rest[recv_base..]);
        let recv: Vec<&mut [f64]> = self
            .recv_at
            .iter()
            .map(|&(_, n)| {
                let (here, after) = std::mem::take(&mut landing).split_at_mut(3 * n);
                landing = after;
                here
            })
            .collect();
        let interior = &self.elements[nb..];
        let (materials, x, v) = (&self.materials, &self.x, &self.v);
        let hexes = &self.hexes;
        let mut inner: std::result::Result<f64, crate::mechanics::MechanicsError> = Ok(0.0);
        clock.mark(1, &mut self.counters);
        let mut interior_time = 0.0;
        // Without penalty contact no pair forces travel (all ranks agree).
        let pairs = &mut self.pair_forces;
        let sized = (self.penalty.is_some()).then(|| (&pairs.send[..], &mut pairs.recv[..]));
        self.halo.exchange_into_sized(comm, &send, recv, sized, || {
            let clock = std::time::Instant::now();
            let tets = element_forces(
                interior,
                materials,
                x,
                v,
                ThermalLoad::transient(dt_i, rate_i),
                f_i,
                Some(s_i),
            );
            inner = match tets {
                Ok(w) if !hexes.is_empty() => {
                    let range = nb..nb + interior.len();
                    hexes
                        .forces(range, materials, x, v, dt_i, rate_i, f_i, s_i)
                        .map(|h| w + h)
                }
                other => other,
            };
            interior_time = clock.elapsed().as_secs_f64();
        });
        self.send_buf = send;
        self.pair_forces.take_received(&routes);
        self.counters.substep_phases[2] += interior_time;
        clock.mark(3, &mut self.counters);
        self.counters.substep_phases[3] -= interior_time;
        match inner {
            Ok(w) => strain += w,
            Err(e) => {
                elem_error.get_or_insert((e, nb));
            }
        }
        let error = elem_error.map(|(e, offset)| self.element_error(e, offset));
        self.strain_energy = strain;
        self.counters.element_updates += ne as u64;
        // Owned node forces, summed in key order; then the owners advance.
        self.sum_owned_forces();
        if !self.joints.is_empty() {
            // Positions at t_n = substeps × Δt, on the run's clock.
            let t = self.counters.substeps as f64 * self.run_time_per_substep;
            self.joints.add_forces(&self.x, t, &mut self.f);
            self.mark_cracks();
        }
        clock.mark(4, &mut self.counters);
        error
    }

    fn element_error(&self, e: crate::mechanics::MechanicsError, offset: usize) -> Error {
        use crate::mechanics::MechanicsError as M;
        match e {
            M::Inverted {
                elem: Some(i),
                what,
                value,
            } => Error::Mechanics(format!(
                "element {} turned inside out ({what} = {value:.6e}): the run diverged; \
                 reduce mechanics.dt or mechanics.safety, or raise the contact penalty",
                self.elem_ids[offset + i]
            )),
            other => Error::Mechanics(other.to_string()),
        }
    }
}
