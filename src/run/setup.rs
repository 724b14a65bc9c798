//! Set-up: the model partitioned into this rank's [`Part`], the explicit mechanics
//! domain, the first contact detection and the thermal system, each
//! restored from the checkpoint on a restart.
//!
//! Collective: every rank calls these in the same order.

use std::time::Instant;

use mpi::topology::SimpleCommunicator;

use mpi::collective::SystemOperation;
use mpi::traits::*;

use crate::contact::{
    ContactPair, ContactSearch, ContactSet, ContactTets, OwnAndGhosts, PairDofs, SearchOptions,
    THERMAL_SEARCH,
};
use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::io::checkpoint::CheckpointHead;
use crate::model::Model;
use crate::parallel::ghosts::{exchange_ghosts, Pieces};
use crate::parallel::{agree, Part};
use crate::petsc::Petsc;
use crate::thermal::ThermalSystem;

use super::checkpoint::{self, Restart};
use super::{Mechanics, PhaseTimes, RunOptions};

/// Collective. Each rank's part of the model: whole bodies, and pieces of
/// the large ones, cut by recursive coordinate bisection; each rank makes
/// only what it holds.
pub(super) fn partition(
    comm: &SimpleCommunicator,
    model: &Model,
    restart: Option<&Restart>,
    times: &mut PhaseTimes,
) -> Result<Part> {
    let clock = Instant::now();
    let placement = match restart {
        Some(r) => crate::parallel::Placement::Saved(&r.file),
        None => crate::parallel::Placement::Model,
    };
    let part = Part::build_placed(comm, model, placement)?;
    times.partition = clock.elapsed().as_secs_f64();
    Ok(part)
}

/// Collective. The explicit mechanics domain (when the model has
/// mechanics), at the checkpoint's state on a restart. Its set-up checks
/// the time step before any other work.
pub(super) fn mechanics(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    restart: Option<&Restart>,
    times: &mut PhaseTimes,
) -> Result<Option<Mechanics>> {
    let clock = Instant::now();
    let mut mech = match model.mechanics {
        Some(_) => {
            let (domain, substeps_per_step) = ExplicitDomain::new(comm, model, part, model.dt)?;
            Some(Mechanics {
                domain,
                substeps_per_step,
            })
        }
        None => None,
    };
    if let Some(r) = restart {
        r.check_part(comm, part)?;
    }
    if let (Some(r), Some(m)) = (restart, mech.as_mut()) {
        checkpoint::restore_mechanics(comm, part, checkpoint::Saved::File(r), m)?;
    }
    times.mechanics = clock.elapsed().as_secs_f64();
    times.mechanics_setup = times.mechanics;
    Ok(mech)
}

/// Where a run's thermal contacts come from.
enum Source {
    /// No thermal contact.
    None,
    /// The mechanics' candidates (a coupled run: one search per
    /// detection), and the pinball distance of near-field gaps.
    Mechanics(Option<f64>),
    /// The contact search at the model's positions (a thermal run; bodies
    /// with a prescribed velocity move between detections).
    Search(Box<ThermalSearch>),
    /// A thermal run's search after its only detection (`contact.every = 0`).
    Spent,
}

/// A thermal run's own contact search: this rank's tets at their current
/// positions, and the search (its trees of bodies that never move kept).
struct ThermalSearch {
    own: ContactTets,
    pieces: Pieces,
    search: ContactSearch,
    /// Whether bodies move (at their prescribed velocities).
    moving: bool,
    /// Margin of the ghost exchange: above the search's padding of any tet
    /// and the pinball distance.
    exchange_margin: f64,
    /// The pinball distance of near-field gaps (issue 20), when computed.
    pinball: Option<f64>,
}

/// Thermal contact detection: where the pairs come from, and the pairs
/// the thermal operator is assembled with.
pub(super) struct Contacts {
    source: Source,
    /// The pairs in use.
    pub set: ContactSet,
    /// Detections run.
    pub detections: u64,
    /// Contact searches this stage ran itself (a thermal run's), and their time (s).
    pub searches: u64,
    pub search_time: f64,
    /// Candidate tet pairs of this rank's thermal searches.
    pub candidates: u64,
    /// Time of the rest of the detections (s): surfaces, gathering,
    /// comparing (the mechanics' searches not included).
    pub surface_time: f64,
    /// Until the first detection: this rank's elements and whole bodies,
    /// when that detection first estimates the ranks' work
    /// ([`super::rebalance::probe_work`]).
    probing: Option<(usize, Vec<u32>)>,
    /// The first detection's estimate, when it asks for a new cut (its
    /// pairs were not made).
    pub probe: Option<super::rebalance::Probe>,
}

impl Contacts {
    /// Collective. The first detection (at the checkpoint's positions on a
    /// restart), when the thermal problem is solved. With `probe`, a
    /// thermal run on several ranks first estimates the ranks' work from
    /// its candidates, and when a new cut is due leaves [`Contacts::probe`]
    /// instead of pairs ([`super::rebalance::set_up_thermal_balance`]).
    pub fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        restart: Option<&Restart>,
        mut mech: Option<&mut Mechanics>,
        probe: bool,
    ) -> Result<Contacts> {
        let source = if !(model.thermal_active && model.contact.is_some()) {
            Source::None
        } else if let Some(m) = mech.as_deref_mut() {
            let gap = model.contact.as_ref().and_then(|c| c.gap.as_ref());
            // Collective where the scenario has gaps (every rank alike).
            let pinball = gap.map(|g| {
                g.pinball
                    .unwrap_or_else(|| 0.5 * max_extent(comm, &part.contact_tets(None)))
            });
            if let Some(p) = pinball {
                // Candidates within the pinball stay among the candidates
                // while nodes use up half the margin.
                m.domain.widen_margin(2.0 * p);
            }
            Source::Mechanics(pinball)
        } else {
            let mut own = part.contact_tets(None);
            let moving = model.has_motion();
            if let (true, Some(r)) = (moving, restart) {
                if r.file.head.has_positions {
                    let x = r.file.node_rows3("state/positions", &part.node_gid);
                    own.x = agree(comm, x.map_err(Error::from))?;
                } else {
                    moved_positions(model, part, r.file.head.time, &mut own.x);
                }
            }
            let max_ext = max_extent(comm, &own);
            let gap = model.contact.as_ref().and_then(|c| c.gap.as_ref());
            let pinball = gap.map(|g| g.pinball.unwrap_or(0.5 * max_ext));
            Source::Search(Box::new(ThermalSearch {
                pieces: Pieces::new(&own),
                own,
                search: ContactSearch::new(),
                moving,
                exchange_margin: (1e-6 * max_ext).max(pinball.unwrap_or(0.0)),
                pinball,
            }))
        };
        let probing = (probe && comm.size() > 1 && matches!(source, Source::Search(_)))
            .then(|| (part.elem_gid.len(), part.whole_bodies.clone()));
        let mut contacts = Contacts {
            source,
            set: ContactSet::default(),
            detections: 0,
            searches: 0,
            search_time: 0.0,
            candidates: 0,
            surface_time: 0.0,
            probing,
            probe: None,
        };
        if !matches!(contacts.source, Source::None) {
            contacts.set = contacts.find(comm, model, mech)?;
            contacts.detections = u64::from(contacts.probe.is_none());
        }
        // A run that never detects again frees its search (the tets'
        // copy, the kept trees) before the thermal system is built.
        if model.contact.as_ref().is_some_and(|c| c.every == 0)
            && matches!(contacts.source, Source::Search(_))
        {
            contacts.source = Source::Spent;
        }
        Ok(contacts)
    }

    /// No contacts (a placeholder while a set is rebuilt).
    pub fn empty() -> Contacts {
        Contacts {
            source: Source::None,
            set: ContactSet::default(),
            detections: 0,
            searches: 0,
            search_time: 0.0,
            candidates: 0,
            surface_time: 0.0,
            probing: None,
            probe: None,
        }
    }

    /// Count the detections and searches of `earlier` (the contacts of
    /// the parts before a repartition) as this one's.
    pub fn add_counts(&mut self, earlier: &Contacts) {
        self.detections += earlier.detections;
        self.searches += earlier.searches;
        self.search_time += earlier.search_time;
        self.candidates += earlier.candidates;
        self.surface_time += earlier.surface_time;
    }

    /// Collective. Detect again at the positions of `step`: the new set
    /// when its pairs or their areas changed, else None.
    pub fn redetect(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        mech: Option<&mut Mechanics>,
        step: u64,
    ) -> Result<Option<ContactSet>> {
        if let Source::Search(ts) = &mut self.source {
            if ts.moving {
                moved_positions(model, part, step as f64 * model.dt, &mut ts.own.x);
            }
        }
        let found = self.find(comm, model, mech)?;
        self.detections += 1;
        // Changed when any rank's pairs changed.
        let mine = i32::from(!found.same_local(&self.set, 1e-12));
        let mut changed = 0i32;
        comm.all_reduce_into(&mine, &mut changed, SystemOperation::max());
        Ok((changed != 0).then_some(found))
    }

    /// Collective. Detect again now, changed or not (the thermal rows were
    /// numbered again, so every pair's rows must be fetched afresh).
    pub fn refind(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        mech: Option<&mut Mechanics>,
    ) -> Result<()> {
        if matches!(self.source, Source::None) {
            return Ok(());
        }
        self.set = self.find(comm, model, mech)?;
        self.detections += 1;
        Ok(())
    }

    /// Collective. This rank's pairs at the current positions, with what
    /// the assembly needs of them, and the totals over the ranks.
    fn find(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        mech: Option<&mut Mechanics>,
    ) -> Result<ContactSet> {
        let clock = Instant::now();
        // Search time, counted once: the mechanics' in its own counters.
        let searched;
        let mut gaps = Vec::new();
        let local = match (&mut self.source, mech) {
            (Source::None, _) => return Ok(ContactSet::default()),
            (Source::Mechanics(pinball), Some(m)) => {
                let before = m.domain.counters.detect_time;
                let pairs = m.domain.thermal_contacts(comm)?;
                if let Some(p) = *pinball {
                    gaps = m.domain.gap_links(comm, gap_range(model, p));
                }
                searched = m.domain.counters.detect_time - before;
                pairs
            }
            (Source::Mechanics(_), None) => unreachable!("a coupled run has mechanics"),
            (Source::Spent, _) => unreachable!("contact.every = 0 detects once"),
            (Source::Search(ts), _) => {
                let t = Instant::now();
                let ghosts =
                    exchange_ghosts(comm, &ts.own, &mut ts.pieces, ts.exchange_margin, true, &[]);
                let og = OwnAndGhosts {
                    own: &ts.own,
                    ghosts: &ghosts,
                };
                let bodies = &model.bodies;
                let tets = og.body_tets(
                    |b| bodies[b as usize].is_held(),
                    |b| bodies[b as usize].velocity == [0.0; 3],
                );
                let opts = SearchOptions {
                    margin: ts.pinball.unwrap_or(0.0),
                    ..THERMAL_SEARCH
                };
                let candidates = og.search(&mut ts.search, &tets, opts);
                searched = t.elapsed().as_secs_f64();
                self.candidates += candidates.len() as u64;
                self.search_time += searched;
                self.searches += 1;
                if let Some((elements, whole)) = self.probing.take() {
                    self.probe =
                        super::rebalance::probe_work(comm, elements, &whole, &og, &candidates);
                    if self.probe.is_some() {
                        self.surface_time += clock.elapsed().as_secs_f64() - searched;
                        return Ok(ContactSet::default());
                    }
                }
                if let Some(p) = ts.pinball {
                    gaps = og.gap_links(&candidates, gap_range(model, p));
                }
                let depth = model
                    .contact
                    .as_ref()
                    .is_some_and(|c| c.needs_penetration());
                og.contact_pairs(&candidates, depth)
            }
        };
        let set = contact_set(comm, local, gaps);
        self.surface_time += clock.elapsed().as_secs_f64() - searched;
        Ok(set)
    }
}

/// The links' range: the pinball `p` and the scenario's smallest gap.
fn gap_range(model: &Model, p: f64) -> crate::contact::gap::GapRange {
    let min = model
        .contact
        .as_ref()
        .and_then(|c| c.gap.as_ref())
        .and_then(|g| g.min_gap);
    crate::contact::gap::GapRange::new(p, min)
}

/// Collective. The largest extent (along x, y or z) of any tet of the ranks.
fn max_extent(comm: &SimpleCommunicator, own: &ContactTets) -> f64 {
    let ext = (0..own.len())
        .map(|t| {
            let (lo, hi) = crate::geometry::tet_bounds(&own.corners(t));
            (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    let mut max_ext = 0.0;
    comm.all_reduce_into(&ext, &mut max_ext, SystemOperation::max());
    max_ext
}

/// Positions of the part's nodes at time `t`: the reference ones, each
/// body translated by its prescribed velocity.
fn moved_positions(model: &Model, part: &Part, t: f64, x: &mut [[f64; 3]]) {
    for ((p, &g), x0) in x.iter_mut().zip(&part.node_gid).zip(&part.mesh.nodes) {
        let v = model.bodies[model.body_of_node(g)].velocity;
        *p = [x0[0] + v[0] * t, x0[1] + v[1] * t, x0[2] + v[2] * t];
    }
}

/// Collective. The contact set of this rank's `local` pairs (each with its
/// nodes' PETSc numbers, materials and bodies), and the totals over the ranks.
fn contact_set(
    comm: &SimpleCommunicator,
    local: Vec<(ContactPair, PairDofs)>,
    gaps: Vec<crate::contact::gap::GapLink>,
) -> ContactSet {
    let (local, dofs): (Vec<ContactPair>, Vec<PairDofs>) = local.into_iter().unzip();
    let mine = [
        local.len() as f64,
        local.iter().map(ContactPair::area).sum::<f64>(),
        gaps.iter().map(|g| g.area).sum::<f64>(),
    ];
    let mut total = [0.0; 3];
    comm.all_reduce_into(&mine[..], &mut total[..], SystemOperation::sum());
    ContactSet {
        local,
        dofs,
        total_pairs: total[0] as u64,
        // + 0.0: an empty sum is −0.0, which the history would print.
        total_area: total[1] + 0.0,
        gaps,
        total_gap_area: total[2] + 0.0,
    }
}

/// Collective. The thermal system (when the thermal problem is solved),
/// at the checkpoint's temperatures on a restart. Every PETSc object
/// exists after it: unless allowed, an option none of them read is an error.
#[allow(clippy::too_many_arguments)]
pub(super) fn thermal<'p>(
    petsc: &'p Petsc,
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    contacts: &ContactSet,
    opts: &RunOptions,
    restart: Option<&Restart>,
    times: &mut PhaseTimes,
) -> Result<Option<ThermalSystem<'p>>> {
    let clock = Instant::now();
    let mut sys = thermal_system(petsc, comm, model, part, contacts)?;
    times.assembly = clock.elapsed().as_secs_f64();
    // Every PETSc object exists now: an option none of them read is a typo
    // (the options database is the same on every rank).
    if !opts.allow_unused_petsc_options {
        let unknown = petsc.unknown_options()?;
        if !unknown.is_empty() {
            return Err(Error::UnusedPetscOptions(unknown.join(", ")));
        }
    }
    if let (Some(r), Some(s)) = (restart, sys.as_mut()) {
        checkpoint::restore_thermal(comm, model, part, checkpoint::Saved::File(r), s)?;
    }
    Ok(sys)
}

/// Collective. The thermal system on `part` with `contacts` (None
/// without a thermal problem).
pub(super) fn thermal_system<'p>(
    petsc: &'p Petsc,
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    contacts: &ContactSet,
) -> Result<Option<ThermalSystem<'p>>> {
    if !model.thermal_active {
        return Ok(None);
    }
    let s = ThermalSystem::new(petsc, comm, model, part, &model.solver, contacts)?;
    Ok(Some(s))
}

/// Collective. Give the mechanics its first temperatures: the thermal
/// solution's, or on a restart without one the prescribed heating's.
pub(super) fn couple_temperatures(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    sys: Option<&ThermalSystem>,
    mech: Option<&mut Mechanics>,
    restart: Option<&CheckpointHead>,
) -> Result<()> {
    let Some(Mechanics { domain: m, .. }) = mech else {
        return Ok(());
    };
    if let Some(s) = sys {
        let t = s.node_temperatures(part)?;
        m.set_temperatures(comm, &t, None);
    } else if let Some(ck) = restart {
        if model.has_heating() {
            let t: Vec<f64> = part
                .owned_gids()
                .iter()
                .zip(&part.bc.initial_t)
                .map(|(&n, &t0)| model.prescribed_temperature(n, t0, ck.time))
                .collect();
            m.set_temperatures(comm, &t, None);
        }
    }
    let time = restart.map_or(0.0, |ck| ck.time);
    super::particle_output::couple_particle_temperatures(comm, model, part, sys, time, m)
}
