//! Bodies follow their ranks: the repartition of a running mechanics run
//! on several ranks. Every `mechanics.rebalance.every` steps, at a stop,
//! the ranks compare their work (elements and the contact pairs their
//! bodies found at the last detection, [`crate::dynamics::BodyLoad`]); when
//! the largest exceeds `threshold` × the mean, the whole bodies are cut
//! again by recursive coordinate bisection over their current centres,
//! weighted by their work ([`Part::build_placed`]), and the run continues
//! on the new parts as a restart would: the state moves by global node id
//! through a [`Snapshot`] in blocks over the ranks, and the mechanics
//! domain, the contacts and the thermal system (its PETSc layout on the
//! new ownership) are rebuilt and restored from it. Trajectories do not
//! depend on the partition (pair ownership and the global-order force
//! sum), so they continue bitwise; sums over ranks (energies, heat) may
//! change in their last bits.
//!
//! Collective: every rank calls these at the same stops.

use std::collections::HashMap;
use std::time::Instant;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::parallel::exchange::{all_to_all, block_owner};
use crate::parallel::{Part, Placement};
use crate::scenario::RebalanceSpec;

use super::checkpoint::{self, Restart, Saved, Snapshot};
use super::output::Output;
use super::setup::{self, Contacts};
use super::{Mechanics, Stages};

/// The repartitions of a run, and the balance of the work seen at the checks.
#[derive(Debug, Clone, Default)]
pub(super) struct Balance {
    /// When to check (None: one rank, no mechanics, or `every = 0`).
    spec: Option<RebalanceSpec>,
    /// Repartitions done.
    pub repartitions: u64,
    /// Bodies that changed rank, summed over the repartitions.
    pub bodies_moved: u64,
    /// Checks made.
    pub checks: u64,
    /// Largest max/mean work per rank seen at a check, before a
    /// repartition there (pairs as found) and as evaluated (the pairs
    /// shared out evenly by the detection).
    pub worst_found: f64,
    pub worst_evaluated: f64,
    /// Max/mean work per rank at the last check, after its repartition.
    pub last: f64,
    /// Time spent in checks and repartitions (s).
    pub time: f64,
}

/// Work per rank at a check: max/mean as found, and as evaluated.
struct Imbalance {
    found: f64,
    evaluated: f64,
    /// The heaviest whole body's work over the mean work per rank: no
    /// partition into whole bodies does better.
    heaviest: f64,
}

impl Balance {
    /// Collective. The repartition schedule of `model` on the ranks of
    /// `comm`, cut into parts like `part`. None without whole bodies on
    /// any rank: a repartition moves whole bodies only (a split body's
    /// elements keep their model places), so a check could only detect.
    pub fn new(comm: &SimpleCommunicator, model: &Model, part: &Part) -> Balance {
        let size = comm.size() as usize;
        let mine = i32::from(!part.whole_bodies.is_empty());
        let mut any = 0i32;
        comm.all_reduce_into(&mine, &mut any, SystemOperation::max());
        let spec = model
            .mechanics
            .as_ref()
            .map(|m| m.rebalance)
            .filter(|r| r.every > 0 && size > 1 && any != 0);
        Balance {
            spec,
            ..Balance::default()
        }
    }

    /// Count a repartition at set-up (a thermal run's, after its first
    /// detection found the work `ratio` × the mean on its busiest rank).
    pub fn set_up_repartition(&mut self, moved: u64, ratio: f64, after: f64, time: f64) {
        self.checks += 1;
        self.last = after;
        self.repartitions += 1;
        self.bodies_moved += moved;
        self.worst_found = self.worst_found.max(ratio);
        self.worst_evaluated = self.worst_evaluated.max(ratio);
        self.time += time;
    }

    /// Whether `step` is a check.
    fn due(&self, step: u64) -> bool {
        self.spec.is_some_and(|s| step.is_multiple_of(s.every))
    }
}

/// Collective. Max/mean of the ranks' work: elements and the pairs their
/// tets found (before the detection shares them out), and elements and
/// the pairs each evaluates (its share).
fn imbalance(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    m: &ExplicitDomain,
) -> Imbalance {
    let found = m.found_work();
    let evaluated = m.evaluated_work();
    let mut total = 0.0;
    comm.all_reduce_into(&found, &mut total, SystemOperation::sum());
    let size = comm.size() as f64;
    let heaviest = m
        .body_loads(model, part)
        .iter()
        .map(|l| l.work)
        .fold(0.0, f64::max);
    let local = [found, evaluated, heaviest];
    let mut most = [0.0; 3];
    comm.all_reduce_into(&local[..], &mut most[..], SystemOperation::max());
    let mean_found = total / size;
    let ratio = |m: f64| {
        if mean_found > 0.0 {
            m / mean_found
        } else {
            1.0
        }
    };
    Imbalance {
        found: ratio(most[0]),
        evaluated: ratio(most[1]),
        heaviest: ratio(most[2]),
    }
}

/// Collective. The current centre and work of every whole body on this
/// rank, sent to the rank whose block of body ids holds it (where
/// [`Part::build_placed`] reads it).
fn placements(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    m: &ExplicitDomain,
) -> HashMap<u32, ([f64; 3], f64)> {
    let loads = m.body_loads(model, part);
    to_body_blocks(
        comm,
        model,
        loads.iter().map(|l| (l.body, l.centre, l.work)),
    )
}

/// Collective. (body, centre, work) records sent to the rank whose block
/// of body ids holds each body.
fn to_body_blocks(
    comm: &SimpleCommunicator,
    model: &Model,
    loads: impl Iterator<Item = (u32, [f64; 3], f64)>,
) -> HashMap<u32, ([f64; 3], f64)> {
    let size = comm.size() as usize;
    let nb = model.bodies.len() as u64;
    let mut send: Vec<Vec<f64>> = vec![Vec::new(); size];
    for (body, c, work) in loads {
        send[block_owner(u64::from(body), nb, size)].extend_from_slice(&[
            f64::from(body),
            c[0],
            c[1],
            c[2],
            work,
        ]);
    }
    all_to_all(comm, send)
        .iter()
        .flat_map(|v| v.chunks_exact(5))
        .map(|r| (r[0] as u32, ([r[1], r[2], r[3]], r[4])))
        .collect()
}

/// Work of one thermal contact pair against one element (1), in the
/// partition's units: measured on the N = 2000 heat-up on 8 ranks, the
/// ranks with 27 k more pairs peaked 10.3 MiB higher (~390 B a pair)
/// against ~1.5 kB for an element with its nodes and matrix rows.
pub(super) const THERMAL_PAIR_WORK: f64 = 0.25;

/// Max/mean work per rank past which a thermal run's first detection
/// cuts the bodies again: the cut costs one more detection (about 2 % of
/// the N = 2000 heat-up), the imbalance costs its share of every step.
const SETUP_THRESHOLD: f64 = 1.05;

/// Every how many candidates of a thermal run's first detection on several
/// ranks one is made a pair to estimate the ranks' work before all are
/// (the estimate of a rank's pairs is within about 1 % at the N = 2000
/// heat-up's 185 k pairs a rank).
const PROBE_SAMPLE: usize = 8;

/// What a thermal run's first detection on several ranks found when the
/// estimated work was past [`SETUP_THRESHOLD`] × the mean: the pair work
/// of each whole body of this rank, and the max/mean work over the ranks.
pub(super) struct Probe {
    body_work: HashMap<u32, f64>,
    ratio: f64,
}

/// Whether a run detects its contacts again at `step` because it may
/// repartition there: a thermal run with a contact model and
/// `mechanics.rebalance.every` = N (N > 0), at a multiple of N before its
/// last step, on any number of ranks. A repartition finds the thermal contacts afresh at the current
/// positions; detecting at every step where one may happen, on one rank
/// too, keeps the contact set, and so the temperatures, independent of
/// the ranks and the repartitions (with `contact.every = 0` a one-rank
/// run would otherwise keep the contacts of its last crack event while a
/// repartitioned one found the blocks touching the floor a step earlier,
/// 6e-5 relative apart on the jointed drop of tests/joint_rebalance.rs).
pub(super) fn finds_contacts_again(model: &Model, step: u64) -> bool {
    model.thermal_active
        && model.contact.is_some()
        && step < model.steps
        && model
            .mechanics
            .as_ref()
            .is_some_and(|m| m.rebalance.every > 0 && step.is_multiple_of(m.rebalance.every))
}

/// Collective. Max/mean over the ranks of a thermal run's work:
/// `elements` and [`THERMAL_PAIR_WORK`] per contact pair.
fn thermal_imbalance(comm: &SimpleCommunicator, elements: usize, pairs: f64) -> f64 {
    let mine = elements as f64 + THERMAL_PAIR_WORK * pairs;
    let (mut total, mut most) = (0.0f64, 0.0f64);
    comm.all_reduce_into(&mine, &mut total, SystemOperation::sum());
    comm.all_reduce_into(&mine, &mut most, SystemOperation::max());
    most * f64::from(comm.size()) / total.max(f64::MIN_POSITIVE)
}

/// Collective. A thermal run's first detection on several ranks, from its
/// `candidates` (over `og`) before their pairs are made: the pairs of
/// every [`PROBE_SAMPLE`]-th candidate estimate each rank's work (its
/// `elements` and pairs) and each whole body's. Some when the work is past
/// [`SETUP_THRESHOLD`] × the mean (a settled packing has far more
/// contacts at its bottom): the bodies are cut again before the pairs
/// are made, which spares making them twice.
pub(super) fn probe_work(
    comm: &SimpleCommunicator,
    elements: usize,
    whole_bodies: &[u32],
    og: &crate::contact::OwnAndGhosts,
    candidates: &[crate::contact::Candidate],
) -> Option<Probe> {
    let sample: Vec<_> = candidates.iter().step_by(PROBE_SAMPLE).copied().collect();
    let pairs = og.contact_pairs(&sample, false);
    let scale = PROBE_SAMPLE as f64;
    let ratio = thermal_imbalance(comm, elements, scale * pairs.len() as f64);
    if ratio <= SETUP_THRESHOLD {
        return None;
    }
    // Each pair's work to the body of its tet on this rank held whole.
    let mut body_work: HashMap<u32, f64> = HashMap::new();
    for (_, d) in &pairs {
        if let Some(&b) = d
            .bodies
            .iter()
            .find(|b| whole_bodies.binary_search(b).is_ok())
        {
            *body_work.entry(b).or_default() += scale * THERMAL_PAIR_WORK;
        }
    }
    Some(Probe { body_work, ratio })
}

/// Collective. The centre and work (elements, and `body_work` of their
/// pairs) of every whole body of `part`, for [`Part::build_placed`].
fn thermal_placements(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    body_work: &HashMap<u32, f64>,
) -> HashMap<u32, ([f64; 3], f64)> {
    // Centres of the whole bodies: the mean of their elements' nodes.
    let mut sum: HashMap<u32, ([f64; 3], f64)> = HashMap::new();
    for (e, t) in part.mesh.tets.iter().enumerate() {
        let b = part.mesh.body[e];
        if part.whole_bodies.binary_search(&b).is_err() {
            continue;
        }
        let (c, n) = sum.entry(b).or_insert(([0.0; 3], 0.0));
        for &v in t {
            let x = part.mesh.nodes[v as usize];
            for d in 0..3 {
                c[d] += x[d];
            }
        }
        *n += 4.0;
    }
    let loads = part.whole_bodies.iter().map(|&b| {
        let (c, n) = sum.get(&b).copied().unwrap_or(([0.0; 3], 1.0));
        let body = &model.bodies[b as usize];
        let elements = f64::from(body.elem_range.1 - body.elem_range.0);
        let work = elements + body_work.get(&b).copied().unwrap_or(0.0);
        (b, c.map(|v| v / n), work)
    });
    to_body_blocks(comm, model, loads)
}

/// Collective. A thermal run on several ranks whose first detection
/// estimated the work (elements + pairs / 4) past the set-up threshold on
/// some rank ([`probe_work`]): drop the part, cut the whole bodies again
/// weighted by that work, and detect on the new parts before the thermal
/// system exists. Counted on the summary's `balance` line.
pub(super) fn set_up_thermal_balance(
    comm: &SimpleCommunicator,
    model: &Model,
    restart: Option<&Restart>,
    part: &mut Part,
    contacts: &mut Contacts,
    mech: Option<&mut Mechanics>,
    balance: &mut Balance,
) -> Result<()> {
    let clock = Instant::now();
    let Some(probe) = contacts.probe.take() else {
        return Ok(());
    };
    let placed = thermal_placements(comm, model, part, &probe.body_work);
    drop(probe.body_work);
    // The probe's search and the old part go before the new ones are
    // made (their memory is reused).
    let earlier = std::mem::replace(contacts, Contacts::empty());
    let mut counts = Contacts::empty();
    counts.add_counts(&earlier);
    drop(earlier);
    let before = std::mem::take(&mut part.whole_bodies);
    *part = Part::default();
    *part = Part::build_placed(comm, model, Placement::Moved(&placed))?;
    drop(placed);
    let moved = bodies_moved(comm, &before, part);
    *contacts = Contacts::new(comm, model, part, restart, mech, false)?;
    contacts.add_counts(&counts);
    let after = thermal_imbalance(comm, part.elem_gid.len(), contacts.set.local.len() as f64);
    let time = clock.elapsed().as_secs_f64();
    balance.set_up_repartition(moved, probe.ratio, after, time);
    super::summary::trace_memory(comm.rank(), "contacts after the set-up repartition");
    Ok(())
}

/// Collective. How many whole bodies changed rank from `before` (this
/// rank's whole bodies, ascending) to `part`, over all ranks.
pub(super) fn bodies_moved(comm: &SimpleCommunicator, before: &[u32], part: &Part) -> u64 {
    let moved = part
        .whole_bodies
        .iter()
        .filter(|b| before.binary_search(b).is_err())
        .count() as u64;
    let mut all_moved = 0u64;
    comm.all_reduce_into(&moved, &mut all_moved, SystemOperation::sum());
    all_moved
}

impl Stages<'_, '_> {
    /// Collective. At a check (after the stop's output, before its
    /// checkpoint, so a restart continues on the new parts): detect at the
    /// current positions, measure the balance, and repartition when it is
    /// past the threshold.
    pub(super) fn rebalance(&mut self, step: u64, out: &mut Output) -> Result<()> {
        if !self.balance.due(step) {
            return Ok(());
        }
        let Some(mech) = self.mech.as_mut() else {
            return Ok(());
        };
        let clock = Instant::now();
        let (comm, model) = (self.comm, self.model);
        mech.domain.detect_now(comm)?;
        let before = imbalance(comm, model, &self.part, &mech.domain);
        let b = &mut self.balance;
        b.checks += 1;
        b.worst_found = b.worst_found.max(before.found);
        b.worst_evaluated = b.worst_evaluated.max(before.evaluated);
        b.last = before.found;
        let threshold = b.spec.map_or(f64::INFINITY, |s| s.threshold);
        // Past the threshold, and not only because one body outweighs a rank's share.
        if before.found > threshold && before.found > 1.05 * before.heaviest {
            self.repartition(step, out)?;
            let m = &self.mech.as_ref().expect("mechanics").domain;
            self.balance.last = imbalance(comm, model, &self.part, m).found;
        }
        self.balance.time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// Collective. Cut the bodies again at their current centres and
    /// continue on the new parts: the state of `step` through a snapshot,
    /// the mechanics domain, contacts and thermal system rebuilt on the
    /// new parts and restored, the output's per-node tables renewed.
    fn repartition(&mut self, step: u64, out: &mut Output) -> Result<()> {
        let (comm, model) = (self.comm, self.model);
        let Some(mech) = self.mech.as_mut() else {
            return Ok(());
        };
        let placed = placements(comm, model, &self.part, &mech.domain);
        let clock = Instant::now();
        let part = Part::build_placed(comm, model, Placement::Moved(&placed))?;
        self.times.partition += clock.elapsed().as_secs_f64();
        // The same elements on every rank: nothing to move.
        let same = i32::from(part.elem_gid == self.part.elem_gid);
        let mut all_same = 0i32;
        comm.all_reduce_into(&same, &mut all_same, SystemOperation::min());
        if all_same == 1 {
            return Ok(());
        }
        // The bonded particles travel by global number (issue 21).
        let particles = super::particle_checkpoint::ParticleSnapshot::take(
            comm,
            model,
            &self.part,
            self.sys.as_ref(),
            Some(&*mech),
        )?;
        let captured = checkpoint::capture(
            comm,
            model,
            &self.part,
            &mut self.sys,
            Some(mech),
            step,
            &self.contacts.set,
        )?;
        let mut snapshot = Snapshot::take(comm, model, &self.part, captured);
        snapshot.particles = particles;
        snapshot.springs = mech.domain.held_springs();
        // The joints' damage travels by joint number (issue 19).
        let joints = super::joint_migration::JointSnapshot::take(comm, model, mech);
        // What the old stages counted goes on with the new ones.
        let mut old = self.mech.take().expect("mechanics");
        let spheres = old.domain.take_spheres();
        let (counters, substeps_per_step) = (old.domain.counters, old.substeps_per_step);
        let friction_work = old.domain.friction_work_share();
        drop(old);
        // Frictional heat handed over and not yet released travels with
        // its nodes in the snapshot (`state/pending_heat`, as a checkpoint).
        let old_sys = self.sys.take();
        let (iterations, assemblies) = old_sys
            .as_ref()
            .map_or((0, 0), |s| (s.iterations, s.assemblies));
        let sphere_source = old_sys.as_ref().map(|s| s.sphere_source());
        drop(old_sys);

        let all_moved = bodies_moved(comm, &self.part.whole_bodies, &part);
        self.part = part;

        let clock = Instant::now();
        let (domain, n) = ExplicitDomain::new(comm, model, &self.part, model.dt)?;
        if n != substeps_per_step {
            return Err(Error::Mechanics(format!(
                "the repartition at step {step} changed the substeps per step from \
                 {substeps_per_step} to {n}"
            )));
        }
        let mut mech = Mechanics {
            domain,
            substeps_per_step: n,
        };
        // The free spheres keep their slabs (issue 21).
        mech.domain.put_spheres(spheres, &self.part);
        checkpoint::restore_mechanics(comm, &self.part, Saved::Memory(&snapshot), &mut mech)?;
        if let Some(p) = &snapshot.particles {
            p.restore_motion(comm, &mut mech);
        }
        if let Some(j) = &joints {
            j.restore(comm, model, &mut self.part, &mut mech);
        }
        let part = &self.part;
        // The counts go on; the detections of the rebuild are added.
        let fresh = mech.domain.counters;
        mech.domain.counters = counters;
        mech.domain.counters.detections += fresh.detections;
        mech.domain.counters.detect_time += fresh.detect_time;
        for (a, b) in mech
            .domain
            .counters
            .detect_phases
            .iter_mut()
            .zip(fresh.detect_phases)
        {
            *a += b;
        }
        for (a, b) in mech
            .domain
            .counters
            .substep_phases
            .iter_mut()
            .zip(fresh.substep_phases)
        {
            *a += b;
        }
        mech.domain.set_friction_work(friction_work);
        self.times.mechanics += clock.elapsed().as_secs_f64();

        let mut contacts = Contacts::new(comm, model, part, None, Some(&mut mech), false)?;
        contacts.add_counts(&self.contacts);
        let clock = Instant::now();
        let mut sys = setup::thermal_system(self.petsc, comm, model, part, &contacts.set)?;
        if let Some(s) = sys.as_mut() {
            checkpoint::restore_thermal(comm, model, part, Saved::Memory(&snapshot), s)?;
            s.iterations = iterations;
            s.assemblies += assemblies;
            // The free spheres' share of it stays theirs (issue 21).
            if let Some(src) = sphere_source {
                s.set_sphere_source(src);
            }
        }
        self.times.assembly += clock.elapsed().as_secs_f64();
        setup::couple_temperatures(
            comm,
            model,
            part,
            sys.as_ref(),
            Some(&mut mech),
            Some(&snapshot.head),
        )?;
        self.mech = Some(mech);
        self.sys = sys;
        self.contacts = contacts;
        out.repartitioned(comm, model, part)?;
        self.balance.repartitions += 1;
        self.balance.bodies_moved += all_moved;
        Ok(())
    }
}
