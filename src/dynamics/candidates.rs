//! Contact candidates of the explicit dynamics: the one contact search
//! ([`crate::contact::search`]) at each detection over this rank's tets and
//! the ghost copies of other ranks' tets within the margin
//! ([`crate::parallel::ghosts`]), the penalty candidates pruned by face
//! planes and their balancing over the ranks (`pair_balance`), the
//! thermal-only candidates of a coupled run, the ghosts and halo they
//! need, and the thermal narrow phase on them (`thermal_contacts`, seed 000
//! sec 3.1). The penalty potential itself is `contact::penalty`.

use std::collections::HashMap;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Matrix3;

use super::domain::PairTet;
use super::{ExplicitDomain, NONE};
use crate::contact::penalty::pair_stiffness;
use crate::contact::{
    tet_pair_contact, ContactPair, ContactSurface, OwnAndGhosts, PairDofs, SearchOptions, TetFaces,
};
use crate::contact::{tet_tet_penalty, PenaltyParams};
use crate::error::{Error, Result};
use crate::geometry::{face_planes, planes_within};
use crate::parallel::ghosts::exchange_ghosts;
use crate::parallel::Halo;

/// Substeps the fastest node should need before contact re-detection.
const DETECT_EVERY: f64 = 10.0;
/// Largest search margin, as a multiple of the configured one.
const MARGIN_GROWTH: f64 = 4.0;
/// Work of a candidate pair whose tets' boxes overlap at detection (it
/// likely runs the overlap kernel each substep), in units of one whose
/// boxes are apart (a box test and zeroed forces).
const HOT_PAIR_WEIGHT: u64 = 32;

/// A tet's corners and face planes ([`face_planes`]).
type TetCorners = ([[f64; 3]; 4], [[f64; 4]; 4]);

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

/// A tet of a pair as it travels between ranks: what the pair's rank
/// keeps of it, and its nodes (global id, owner, PETSc number).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct TetRecord {
    info: PairTet,
    nodes: [[u32; 3]; 4],
}

/// Values per tet record and per pair (two tet slots, stiffness and
/// reduced mass) in an `f64` message.
pub(super) const TET_F64S: usize = 5 + 12;
pub(super) const PAIR_F64S: usize = 4;

impl TetRecord {
    pub(super) fn of(og: &OwnAndGhosts, h: u32) -> TetRecord {
        let n = og.own.len() as u32;
        let (s, t) = if h < n {
            (og.own, h as usize)
        } else {
            (og.ghosts, (h - n) as usize)
        };
        TetRecord {
            info: PairTet {
                gid: s.gid[t],
                body: s.body[t],
                material: s.material[t],
                mask: s.mask[t],
                bits: s.node_bits(t),
            },
            nodes: s.tets[t].map(|k| {
                let k = k as usize;
                [s.node_gid[k], s.node_owner[k], s.node_petsc[k]]
            }),
        }
    }

    pub(super) fn push(&self, out: &mut Vec<f64>) {
        let i = &self.info;
        out.extend_from_slice(&[
            f64::from(i.gid),
            f64::from(i.body),
            f64::from(i.material),
            f64::from(i.mask),
            f64::from(i.bits),
        ]);
        for n in &self.nodes {
            out.extend(n.iter().map(|&v| f64::from(v)));
        }
    }

    pub(super) fn read(v: &[f64]) -> TetRecord {
        let mut r = TetRecord {
            info: PairTet {
                gid: v[0] as u32,
                body: v[1] as u32,
                material: v[2] as u32,
                mask: v[3] as u8,
                bits: v[4] as u8,
            },
            ..Default::default()
        };
        for k in 0..4 {
            for j in 0..3 {
                r.nodes[k][j] = v[5 + 3 * k + j] as u32;
            }
        }
        r
    }
}

/// The penalty pairs other ranks passed this one: their tets (each once
/// per source rank) and, per pair, its two tets' indices in `tets`,
/// stiffness and reduced mass.
#[derive(Default)]
pub(super) struct ReceivedPairs {
    pub(super) tets: Vec<TetRecord>,
    pub(super) pairs: Vec<(u32, u32, f64, f64)>,
}

/// Local index of a node of the part by global id (`gids`: owned ones
/// ascending, then ghosts ascending, `n_owned` of them owned).
fn part_local(gids: &[u32], n_owned: usize, gid: u32) -> Option<u32> {
    let (owned, ghosts) = gids.split_at(n_owned);
    owned
        .binary_search(&gid)
        .map(|i| i as u32)
        .or_else(|_| ghosts.binary_search(&gid).map(|i| (n_owned + i) as u32))
        .ok()
}

/// The tets of the pairs with their local nodes and what the narrow
/// phase needs of them.
#[derive(Default)]
struct TetSlots {
    tets: Vec<[u32; 4]>,
    info: Vec<PairTet>,
}

impl TetSlots {
    /// List a tet; its slot.
    fn push(&mut self, nodes: [u32; 4], info: PairTet) -> u32 {
        self.tets.push(nodes);
        self.info.push(info);
        (self.tets.len() - 1) as u32
    }
}

impl ExplicitDomain {
    /// Free the arrays sized by the last detection's pairs before the
    /// search allocates its own: they are rebuilt for the new pairs, and
    /// kept alive through the search they would add to its peak (about a
    /// fifth of a busy rank's memory in a deposition).
    fn release_pair_arrays(&mut self) {
        self.send_buf = Vec::new();
        self.pair_forces = Default::default();
        self.candidates = Vec::new();
        self.contrib = Vec::new();
        self.gather_slot = Vec::new();
        self.pair_geometry = Vec::new();
        self.pair_planes = Vec::new();
        self.planes_of = Vec::new();
        self.lin_of = Vec::new();
        self.linearized = Vec::new();
        self.witness = Vec::new();
    }

    /// Collective. Rebuild the contact candidates from the one contact
    /// search over this rank's tets and the ghost copies of the tets of
    /// other ranks within the margin, the contact ghosts and the halo;
    /// reorder elements so those touching the halo come first.
    pub(super) fn detect(&mut self, comm: &SimpleCommunicator) -> Result<()> {
        self.flush_friction();
        self.cracks_marked = false;
        // Within a step only, with linearised models to keep in place, pairs
        // go back to the rank that evaluated them (`pair_balance`).
        self.last_detect_fresh = !(self.sticky_detect && self.linear_tolerance > 0.0);
        let clock = std::time::Instant::now();
        let mut lap = clock;
        let mut phase = |k: usize, c: &mut super::MechanicsCounters| {
            let now = std::time::Instant::now();
            c.detect_phases[k] += (now - lap).as_secs_f64();
            lap = now;
        };
        let carried = self.contacts_before_detection(comm.size() as usize);
        let springs = self.has_springs().then(|| self.springs_before_detection());
        let planes_before = self.pair_planes.len();
        self.release_pair_arrays();
        self.thermal_only.clear();
        self.margin = self.adapted_margin(comm);
        // The contact ghosts of the last detection go.
        let np = self.n_part_nodes;
        self.node_gid.truncate(np);
        self.node_owner.truncate(np);
        self.node_petsc.truncate(np);
        self.contact_local.clear();
        self.x.truncate(np);
        self.v.truncate(np);
        if self.penalty.is_some() || self.thermal {
            for (p, x) in self.part_tets.x.iter_mut().zip(&self.x) {
                *p = [x.x, x.y, x.z];
            }
            let own = std::mem::take(&mut self.part_tets);
            let r = comm.rank();
            crate::run::trace_memory(r, "detect start");
            let itself = self.self_contact.split_bodies();
            phase(0, &mut self.counters);
            let ghosts = exchange_ghosts(
                comm,
                &own,
                &mut self.pieces,
                self.margin,
                self.thermal,
                &itself,
            );
            crate::run::trace_memory(r, "detect ghosts");
            phase(1, &mut self.counters);
            let og = OwnAndGhosts {
                own: &own,
                ghosts: &ghosts,
            };
            let (kept, weights, thermal) = self.find_pairs(&og);
            crate::run::trace_memory(r, "detect found");
            self.count_pair_work(&og, &kept, &weights);
            phase(2, &mut self.counters);
            let (here, received) = self.balance_pairs(comm, &og, &kept, &weights, &carried);
            crate::run::trace_memory(r, "detect balanced");
            phase(3, &mut self.counters);
            crate::run::release_fragmented_memory();
            self.install(&og, &here, &received, &thermal);
            crate::run::trace_memory(r, "detect installed");
            self.part_tets = own;
        } else {
            phase(0, &mut self.counters);
            self.install_none();
        }
        self.refresh_local_arrays();
        phase(4, &mut self.counters);
        // Fresh candidates: planes rebuilt on demand; the touching pairs
        // keep their linearised overlaps (`carry`).
        let nt = self.pair_tets.len();
        self.planes_of = vec![super::NONE; nt];
        self.pair_planes = Vec::with_capacity(planes_before + planes_before / 4);
        self.contacts_after_detection(comm, carried);
        if let Some(held) = springs {
            self.springs_after_detection(comm, held);
        }
        let ghosts: Vec<(u32, u32, u32)> = (self.n_owned..self.node_gid.len())
            .map(|l| (self.node_gid[l], self.node_owner[l], l as u32))
            .collect();
        let owned = &self.node_gid[..self.n_owned];
        let halo = Halo::new(comm, &ghosts, |g| {
            owned.binary_search(&g).ok().map(|i| i as u32)
        });
        self.halo = crate::parallel::agree(comm, halo.map_err(Error::Partition))?;
        // Ghost positions and velocities from their owners.
        self.forward_state(comm);
        self.order_elements();
        crate::run::trace_memory(comm.rank(), "detect halo");
        self.build_assembly(comm);
        crate::run::trace_memory(comm.rank(), "detect assembly");
        crate::run::release_fragmented_memory();
        self.x_detect = self.x[..self.n_owned].to_vec();
        self.detected_at = Some(self.counters.substeps);
        self.counters.detections += 1;
        phase(5, &mut self.counters);
        self.counters.detect_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// Elements touching a ghost node first (their contributions are
    /// sent), each group by element id: the two id-ordered groups of the
    /// last detection merged back into id order, then split anew, in
    /// linear time.
    fn order_elements(&mut self) {
        let n_owned = self.n_owned;
        let (ids, ne, nb_old) = (&self.elem_ids, self.elem_ids.len(), self.n_boundary);
        let hexes = &self.hexes;
        let touches = |i: usize| hexes.touches(&self.elements[i], ids[i], n_owned);
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
        let mut order: Vec<usize> = by_id.iter().copied().filter(|&i| touches(i)).collect();
        self.n_boundary = order.len();
        order.extend(by_id.iter().copied().filter(|&i| !touches(i)));
        drop(by_id);
        // Only a repartition changes the order (contact ghosts come after
        // the part's nodes, so no element touches them): keep the arrays.
        if order.iter().enumerate().all(|(k, &i)| k == i) {
            self.stress.resize(self.elements.len(), Matrix3::zeros());
            self.hexes.locate(&self.elem_ids, &self.elements);
            return;
        }
        self.elements = order.iter().map(|&i| self.elements[i]).collect();
        self.elem_ids = order.iter().map(|&i| self.elem_ids[i]).collect();
        self.elem_tref = order.iter().map(|&i| self.elem_tref[i]).collect();
        if self.elem_dt.len() == order.len() {
            self.elem_dt = order.iter().map(|&i| self.elem_dt[i]).collect();
            self.elem_rate = order.iter().map(|&i| self.elem_rate[i]).collect();
        }
        // Every substep writes every element's stress: no need to permute it.
        self.stress.resize(self.elements.len(), Matrix3::zeros());
        self.hexes.locate(&self.elem_ids, &self.elements);
    }

    /// This rank's candidates from the one contact search over own and
    /// ghost tets (handles of `og`), with their estimated costs (see
    /// `pair_balance`). Pairs of two boundary tets of bodies not
    /// both held are the penalty candidates, pruned by face planes; when
    /// the thermal contact is coupled, the search also returns a boundary
    /// tet against another body's interior tets and pairs of two held
    /// bodies, kept for the thermal contact only (`thermal`).
    #[allow(clippy::type_complexity)]
    fn find_pairs(&mut self, og: &OwnAndGhosts) -> (Vec<(u32, u32)>, Vec<u64>, Vec<(u32, u32)>) {
        let margin = self.margin;
        let opts = SearchOptions {
            margin,
            pad: 0.0,
            interior: self.thermal,
            held_pairs: self.thermal,
        };
        let (held, fixed) = (&self.body_held, &self.body_fixed);
        let tets = og.body_tets(|b| held[b as usize], |b| fixed[b as usize]);
        let mut found = og.search(&mut self.search, &tets, opts);
        found.extend(self.self_contact.candidates(og, &tets, margin));
        // Not in the seeds: the penalty potential sums over pairs of
        // boundary tets (a face on the surface), like the contact
        // surface of seed 000 sec 3.1; a tet that meets the surface only
        // at an edge or corner overlaps a shallow intruder by O(δ²).
        let penalty = self.penalty.is_some();
        // Each tet's corners and face planes, gathered once (on first use)
        // into one place: a tet is in several candidates.
        let mut geo_at: Vec<u32> = vec![NONE; og.len()];
        let mut geo: Vec<TetCorners> = Vec::new();
        let mut geometry = |geo: &mut Vec<TetCorners>, h: u32| -> usize {
            let at = &mut geo_at[h as usize];
            if *at == NONE {
                *at = geo.len() as u32;
                let x = og.corners(h);
                geo.push((x, face_planes(&x)));
            }
            *at as usize
        };
        let body_of = |h: u32| {
            let n = og.own.len() as u32;
            if h < n {
                og.own.body[h as usize]
            } else {
                og.ghosts.body[(h - n) as usize]
            }
        };
        let mut kept: Vec<(u32, u32)> = Vec::with_capacity(found.len());
        let mut weights: Vec<u64> = Vec::with_capacity(found.len());
        let mut thermal: Vec<(u32, u32)> = Vec::new();
        for c in found {
            let both_held = held[body_of(c.a) as usize] && held[body_of(c.b) as usize];
            if penalty && c.b_boundary && !both_held {
                let (ga, gb) = (geometry(&mut geo, c.a), geometry(&mut geo, c.b));
                let ((xa, pa), (xb, pb)) = (&geo[ga], &geo[gb]);
                if planes_within((xa, pa), (xb, pb), margin) {
                    kept.push((c.a, c.b));
                    weights.push(if c.hot { HOT_PAIR_WEIGHT } else { 1 });
                }
            } else if self.thermal {
                thermal.push((c.a, c.b));
            }
        }
        (kept, weights, thermal)
    }

    /// Note the work of the `kept` pairs (`weights`) by the body of their
    /// own tet (the first when both are own), for the repartition.
    fn count_pair_work(&mut self, og: &OwnAndGhosts, kept: &[(u32, u32)], weights: &[u64]) {
        self.body_pair_work.clear();
        let n = og.own.len() as u32;
        for (&(a, b), &w) in kept.iter().zip(weights) {
            let own = if a < n { a } else { b };
            if own < n {
                *self
                    .body_pair_work
                    .entry(og.own.body[own as usize])
                    .or_insert(0.0) += w as f64;
            }
        }
    }

    /// The bodies, stiffness and reduced mass of the penalty pair of tets
    /// `a` (of a free body) and `b`, handles of `og`.
    pub(super) fn pair_record_values(
        &self,
        og: &OwnAndGhosts,
        a: u32,
        b: u32,
    ) -> (u32, u32, f64, f64) {
        let (sa, ia) = og.locate(a);
        let (sb, ib) = og.locate(b);
        let (ra, rb) = (
            (sa.body[ia], sa.material[ia]),
            (sb.body[ib], sb.material[ib]),
        );
        let (va, vb) = (sa.volume0[ia], sb.volume0[ib]);
        let (ma, mb) = (
            self.density[ra.1 as usize] * va,
            self.density[rb.1 as usize] * vb,
        );
        // a is never held (held bodies do not search).
        let reduced_mass = if self.body_held[rb.0 as usize] {
            ma
        } else {
            ma * mb / (ma + mb)
        };
        let penalty = self.penalty.map_or(0.0, |(_, pn)| pn);
        (ra.0, rb.0, pair_stiffness(penalty, va, vb), reduced_mass)
    }

    /// No contact: no pairs, no contact ghosts.
    fn install_none(&mut self) {
        self.candidates.clear();
        self.pair_tets.clear();
        self.pair_info.clear();
        self.thermal_only.clear();
        self.thermal_tets.clear();
        self.thermal_info.clear();
    }

    /// Install the pairs this rank evaluates: its own (`here`, handles of
    /// `og`), those other ranks passed it (`received`), and the
    /// thermal-only ones; their tets (each once per source), the contact
    /// ghosts their nodes need, and the candidates.
    fn install(
        &mut self,
        og: &OwnAndGhosts,
        here: &[(u32, u32)],
        received: &ReceivedPairs,
        thermal: &[(u32, u32)],
    ) {
        let (np, no) = (self.n_part_nodes, self.n_owned);
        let n_own = og.own.len() as u32;
        // Local node of each ghost tet node, made on first use.
        let mut ghost_local: Vec<u32> = vec![NONE; og.ghosts.node_gid.len()];
        let mut node_of = |dom: &mut ExplicitDomain, g: usize| -> u32 {
            if ghost_local[g] == NONE {
                let gid = og.ghosts.node_gid[g];
                ghost_local[g] = match part_local(&dom.node_gid[..np], no, gid) {
                    Some(l) => l,
                    None => {
                        dom.contact_ghost(gid, og.ghosts.node_owner[g], og.ghosts.node_petsc[g])
                    }
                };
            }
            ghost_local[g]
        };
        let mut slot_of: Vec<u32> = vec![NONE; og.len()];
        let mut pt = TetSlots::default();
        let mut slot = |dom: &mut ExplicitDomain, h: u32, pt: &mut TetSlots| -> u32 {
            if slot_of[h as usize] == NONE {
                let nodes = if h < n_own {
                    og.own.tets[h as usize]
                } else {
                    og.ghosts.tets[(h - n_own) as usize].map(|g| node_of(dom, g as usize))
                };
                slot_of[h as usize] = pt.push(nodes, TetRecord::of(og, h).info);
            }
            slot_of[h as usize]
        };
        let mut candidates: Vec<Candidate> = Vec::with_capacity(here.len() + received.pairs.len());
        for &(a, b) in here {
            let r = self.pair_record_values(og, a, b);
            let (ta, tb) = (slot(self, a, &mut pt), slot(self, b, &mut pt));
            candidates.push(Candidate {
                a: og.gid(a),
                b: og.gid(b),
                ta,
                tb,
                body_a: r.0,
                body_b: r.1,
                stiffness: r.2,
                reduced_mass: r.3,
            });
        }
        // Pairs from other ranks: their tets by global id.
        let mut by_gid: HashMap<u32, u32> = HashMap::new();
        for &(a, b, stiffness, reduced_mass) in &received.pairs {
            let (a, b) = (&received.tets[a as usize], &received.tets[b as usize]);
            let mut tslot = |dom: &mut ExplicitDomain, t: &TetRecord| -> u32 {
                *by_gid.entry(t.info.gid).or_insert_with(|| {
                    let nodes = t.nodes.map(|[gid, owner, petsc]| {
                        part_local(&dom.node_gid[..np], no, gid).unwrap_or_else(|| {
                            match dom.contact_local.get(&gid) {
                                Some(&l) => l,
                                None => dom.contact_ghost(gid, owner, petsc),
                            }
                        })
                    });
                    pt.push(nodes, t.info)
                })
            };
            let (ta, tb) = (tslot(self, a), tslot(self, b));
            candidates.push(Candidate {
                a: a.info.gid,
                b: b.info.gid,
                ta,
                tb,
                body_a: a.info.body,
                body_b: b.info.body,
                stiffness,
                reduced_mass,
            });
        }
        let mut tt = TetSlots::default();
        let mut tslot_of: Vec<u32> = vec![NONE; og.len()];
        let mut thermal_only = Vec::with_capacity(thermal.len());
        for &(a, b) in thermal {
            let mut one = |h: u32, dom: &mut ExplicitDomain| -> u32 {
                if tslot_of[h as usize] == NONE {
                    let nodes = if h < n_own {
                        og.own.tets[h as usize]
                    } else {
                        og.ghosts.tets[(h - n_own) as usize].map(|g| node_of(dom, g as usize))
                    };
                    tslot_of[h as usize] = tt.push(nodes, TetRecord::of(og, h).info);
                }
                tslot_of[h as usize]
            };
            let (ta, tb) = (one(a, self), one(b, self));
            thermal_only.push((ta, tb));
        }
        // In key order, so each node's pair forces arrive in the order
        // they are summed in (`pair_sum`), and the state of the pairs
        // merges across detections (`carry`).
        super::carry::in_key_order(&mut candidates);
        self.counters.candidates += candidates.len() as u64;
        self.candidates = candidates;
        self.pair_tets = pt.tets;
        self.pair_info = pt.info;
        self.thermal_only = thermal_only;
        self.thermal_tets = tt.tets;
        self.thermal_info = tt.info;
    }

    /// A new contact ghost node; its local index.
    fn contact_ghost(&mut self, gid: u32, owner: u32, petsc: u32) -> u32 {
        let l = self.node_gid.len() as u32;
        self.contact_local.insert(gid, l);
        self.node_gid.push(gid);
        self.node_owner.push(owner);
        self.node_petsc.push(petsc);
        l
    }

    /// Issue 20, frictional heating (seed 001 sec 7.1.7, FHTG and FWGT):
    /// hand each candidate pair's friction work since the last call, times
    /// η, to the PETSc rows of its tets' boundary nodes, w to the searching
    /// tet's and 1 − w to the other's, in equal shares.
    fn flush_friction(&mut self) {
        let Some((eta, w)) = self.friction_heating else {
            return;
        };
        for (j, c) in self.candidates.iter().enumerate() {
            let e = self.pair_friction.get(j).copied().unwrap_or(0.0) * eta;
            if e == 0.0 {
                continue;
            }
            for (t, share) in [(c.ta as usize, w), (c.tb as usize, 1.0 - w)] {
                let (tet, bits) = (&self.pair_tets[t], self.pair_info[t].bits);
                let bits = if bits == 0 { 0b1111 } else { bits };
                let each = e * share / f64::from(bits.count_ones());
                for (_, &l) in tet.iter().enumerate().filter(|(k, _)| bits & (1 << k) != 0) {
                    *self
                        .friction_rows
                        .entry(self.node_petsc[l as usize])
                        .or_default() += each;
                }
            }
        }
        self.pair_friction.iter_mut().for_each(|x| *x = 0.0);
    }

    /// The frictional heat (J) per PETSc row since the last call (issue 20;
    /// empty without frictional heating), in row order.
    pub fn take_friction_heat(&mut self) -> Vec<(u32, f64)> {
        self.flush_friction();
        std::mem::take(&mut self.friction_rows)
            .into_iter()
            .collect()
    }

    /// Collective. The thermal contact pairs this rank holds at the
    /// current positions (seed 000 sec 3.1), each with its dofs: the
    /// narrow phase on its candidates, penalty and thermal-only, so a
    /// coupled run searches once per detection. When the candidates are
    /// due for renewal (a node has used up half the margin) they are
    /// renewed first, as the next substep would; every pair of tets that
    /// overlaps now is among them.
    pub fn thermal_contacts(
        &mut self,
        comm: &SimpleCommunicator,
    ) -> Result<Vec<(ContactPair, PairDofs)>> {
        if self.redetect {
            self.detect(comm)?;
            self.redetect = false;
        }
        let x = &self.x;
        let corners = |t: &[u32; 4]| {
            t.map(|l| {
                let p = &x[l as usize];
                [p.x, p.y, p.z]
            })
        };
        let petsc = &self.node_petsc;
        let one = |(ta, ia): (&[u32; 4], &PairTet), (tb, ib): (&[u32; 4], &PairTet)| {
            let faces = |i: &PairTet| TetFaces {
                id: i.gid,
                mask: i.mask,
                bits: i.bits,
            };
            let p = tet_pair_contact((faces(ia), &corners(ta)), (faces(ib), &corners(tb)))?;
            let ((tt, it), (tc, ic)) = if ia.gid < ib.gid {
                ((ta, ia), (tb, ib))
            } else {
                ((tb, ib), (ta, ia))
            };
            let mut d = PairDofs {
                materials: [it.material, ic.material],
                bodies: [it.body, ic.body],
                ..Default::default()
            };
            for j in 0..4 {
                d.petsc[j] = petsc[tt[j] as usize];
                d.petsc[4 + j] = petsc[tc[j] as usize];
            }
            d.slip = crate::contact::slip_speed(
                &corners(tt),
                p.surface.faces_target,
                &tt.map(|l| self.v[l as usize].into()),
                &tc.map(|l| self.v[l as usize].into()),
            );
            Some((p, d))
        };
        let mut pairs: Vec<(ContactPair, PairDofs)> = self
            .candidates
            .iter()
            .filter_map(|c| {
                let (a, b) = (c.ta as usize, c.tb as usize);
                let (p, mut d) = one(
                    (&self.pair_tets[a], &self.pair_info[a]),
                    (&self.pair_tets[b], &self.pair_info[b]),
                )?;
                if let (true, Some((params, _))) = (self.contact_pressure, &self.penalty) {
                    // The penalty's normal force now over the pair's surface.
                    let (la, lb) = (&self.pair_tets[a], &self.pair_tets[b]);
                    let at = |t: &[u32; 4], f: &dyn Fn(u32) -> [f64; 3]| t.map(f);
                    let xf = |l: u32| -> [f64; 3] { self.x[l as usize].into() };
                    let vf = |l: u32| -> [f64; 3] { self.v[l as usize].into() };
                    let pp = PenaltyParams {
                        stiffness: c.stiffness,
                        reduced_mass: c.reduced_mass,
                        time_step: self.dt,
                        ..*params
                    };
                    let r = tet_tet_penalty(
                        &at(la, &xf),
                        &at(lb, &xf),
                        &at(la, &vf),
                        &at(lb, &vf),
                        &pp,
                    );
                    d.pressure = r.map_or(0.0, |r| r.normal_force / p.area());
                }
                if self.penetration {
                    let (la, lb) = (&self.pair_tets[a], &self.pair_tets[b]);
                    d.penetration =
                        crate::contact::penetration(&corners(la), &corners(lb), p.area());
                }
                Some((p, d))
            })
            .chain(self.thermal_only.iter().filter_map(|&(a, b)| {
                let (a, b) = (a as usize, b as usize);
                one(
                    (&self.thermal_tets[a], &self.thermal_info[a]),
                    (&self.thermal_tets[b], &self.thermal_info[b]),
                )
            }))
            .collect();
        pairs.extend(self.closed_crack_pairs());
        pairs.sort_by_key(|(p, _)| (p.target, p.contactor));
        Ok(pairs)
    }

    /// The thermal contact of each crack whose faces touched at the last
    /// substep: S = the face's area, the corners a third each
    /// ([`ContactSurface::coincident_faces`]). Its conductance is S / Rc of
    /// the material with itself, like any contact pair.
    fn closed_crack_pairs(&self) -> Vec<(ContactPair, PairDofs)> {
        let own = &self.part_tets;
        let petsc = &self.node_petsc;
        self.joints
            .closed_cracks()
            .into_iter()
            .map(|(tets, sides, area)| {
                // Per side: its tet's gid, material, body, corner rows and face.
                let side = |k: usize| {
                    if let Ok(e) = own.gid.binary_search(&tets[k]) {
                        let face = own.tets[e]
                            .iter()
                            .position(|n| !sides[k].contains(n))
                            .expect("a face of its tet");
                        let rows = own.tets[e].map(|n| petsc[n as usize]);
                        return (tets[k], own.material[e], Some(own.body[e]), rows, face);
                    }
                    // The other tet of a joint across a cut, owned here:
                    // its face's corners are ghosts here, and the corner
                    // off the face weighs nothing (any row stands for it).
                    let (corners, material) = self.joints.remote_tets[&tets[k]];
                    let on_face = sides[k].map(|n| self.node_gid[n as usize]);
                    let face = corners
                        .iter()
                        .position(|g| !on_face.contains(g))
                        .expect("a face of its tet");
                    let rows = corners.map(|g| {
                        let i = on_face.iter().position(|&x| x == g).unwrap_or(0);
                        petsc[sides[k][i] as usize]
                    });
                    (tets[k], material, None, rows, face)
                };
                let (mut t, mut c) = (side(0), side(1));
                if tets[0] > tets[1] {
                    std::mem::swap(&mut t, &mut c);
                }
                // A joint's two tets are of one body.
                let body = t.2.or(c.2).expect("a crack's tet is here");
                let mut d = PairDofs {
                    materials: [t.1, c.1],
                    bodies: [body, body],
                    ..Default::default()
                };
                d.petsc[..4].copy_from_slice(&t.3);
                d.petsc[4..].copy_from_slice(&c.3);
                let p = ContactPair {
                    target: t.0,
                    contactor: c.0,
                    surface: ContactSurface::coincident_faces(area, t.4, c.4),
                };
                (p, d)
            })
            .collect()
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
