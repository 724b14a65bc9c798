//! Set-up: the model partitioned into a [`Layout`], the explicit mechanics
//! domain, the first contact detection and the thermal system, each
//! restored from the checkpoint on a restart.
//!
//! Collective: every rank calls these in the same order.

use std::time::Instant;

use mpi::topology::SimpleCommunicator;

use crate::contact::{detect_contacts, pairs_from_f64s, pairs_to_f64s, BoundaryTets, ContactSet};
use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::io::checkpoint::Checkpoint;
use crate::mesh::TetMesh;
use crate::model::Model;
use crate::parallel::Layout;
use crate::petsc::Petsc;
use crate::thermal::ThermalSystem;

use super::checkpoint::{self, Restart};
use super::{Mechanics, PhaseTimes, RunOptions};

/// Collective. Partition the model over the ranks.
pub(super) fn partition(
    comm: &SimpleCommunicator,
    model: &Model,
    times: &mut PhaseTimes,
) -> Result<Layout> {
    let clock = Instant::now();
    // With mechanics, elements of held bodies (a container) cost only their
    // thermal share: weight the partition by the explicit work.
    let weights: Option<Vec<i32>> = model.mechanics.as_ref().map(|_| {
        model
            .mesh
            .body
            .iter()
            .map(|&b| {
                let body = &model.bodies[b as usize];
                if body.is_held() {
                    1
                } else {
                    8
                }
            })
            .collect()
    });
    let layout =
        Layout::new_weighted(comm, &model.mesh, weights.as_deref()).map_err(Error::Partition)?;
    times.partition = clock.elapsed().as_secs_f64();
    Ok(layout)
}

/// Collective. The explicit mechanics domain (when the model has
/// mechanics), at the checkpoint's state on a restart. Its set-up checks
/// the time step before any other work.
pub(super) fn mechanics(
    comm: &SimpleCommunicator,
    model: &Model,
    layout: &Layout,
    restart: Option<&Restart>,
    times: &mut PhaseTimes,
) -> Result<Option<Mechanics>> {
    let clock = Instant::now();
    let mut mech = match model.mechanics {
        Some(_) => {
            let (domain, substeps_per_step) = ExplicitDomain::new(comm, model, layout, model.dt)?;
            Some(Mechanics {
                domain,
                substeps_per_step,
            })
        }
        None => None,
    };
    if let (Some(r), Some(m)) = (restart, mech.as_mut()) {
        checkpoint::restore_mechanics(comm, model, layout, r, m)?;
    }
    times.mechanics = clock.elapsed().as_secs_f64();
    times.mechanics_setup = times.mechanics;
    Ok(mech)
}

/// Thermal contact detection: the boundary tets searched, the current
/// positions, and the pairs the thermal operator is assembled with.
pub(super) struct Contacts {
    bt: BoundaryTets,
    /// Positions of moving bodies are updated at each detection (a copy of
    /// the mesh only when something moves).
    moved: Option<TetMesh>,
    /// The pairs in use.
    pub set: ContactSet,
    /// Detections run.
    pub detections: u64,
}

impl Contacts {
    /// Collective. The first detection (at the checkpoint's positions on a
    /// restart), when the thermal problem is solved.
    pub fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
        restart: Option<&Checkpoint>,
        mechanics: bool,
        times: &mut PhaseTimes,
    ) -> Contacts {
        let clock = Instant::now();
        let bt = BoundaryTets::new(&model.mesh);
        let mut moved = (model.has_motion() || mechanics).then(|| model.mesh.clone());
        if let (Some(ck), Some(mesh_now)) = (restart, moved.as_mut()) {
            match &ck.positions {
                Some(x) => mesh_now.nodes.copy_from_slice(x),
                None => model.positions_at(ck.time, &mut mesh_now.nodes),
            }
        }
        let set = if model.thermal_active {
            find_contacts(
                comm,
                model,
                moved.as_ref().unwrap_or(&model.mesh),
                layout,
                &bt,
            )
        } else {
            ContactSet::default()
        };
        let detections = u64::from(model.contact.is_some() && model.thermal_active);
        times.contact = clock.elapsed().as_secs_f64();
        Contacts {
            bt,
            moved,
            set,
            detections,
        }
    }

    /// Collective. Detect again at the positions of `step`: the new set
    /// when its pairs or their areas changed, else None.
    pub fn redetect(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
        mech: Option<&mut Mechanics>,
        step: u64,
    ) -> Option<ContactSet> {
        if let Some(mesh_now) = self.moved.as_mut() {
            match mech {
                Some(Mechanics { domain: m, .. }) => {
                    m.gather_positions(comm);
                    mesh_now.nodes.copy_from_slice(m.positions());
                }
                None => model.positions_at(step as f64 * model.dt, &mut mesh_now.nodes),
            }
        }
        let mesh_now = self.moved.as_ref().unwrap_or(&model.mesh);
        let found = find_contacts(comm, model, mesh_now, layout, &self.bt);
        self.detections += 1;
        (!found.same_as(&self.set, 1e-12)).then_some(found)
    }
}

/// Collective. The thermal system (when the thermal problem is solved),
/// at the checkpoint's temperatures on a restart. Every PETSc object
/// exists after it: unless allowed, an option none of them read is an error.
pub(super) fn thermal<'p>(
    petsc: &'p Petsc,
    model: &Model,
    layout: &Layout,
    contacts: &ContactSet,
    opts: &RunOptions,
    restart: Option<&Restart>,
    times: &mut PhaseTimes,
) -> Result<Option<ThermalSystem<'p>>> {
    let clock = Instant::now();
    let mut sys = if model.thermal_active {
        Some(ThermalSystem::new(
            petsc,
            model,
            layout,
            &model.solver,
            contacts,
        )?)
    } else {
        None
    };
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
        checkpoint::restore_thermal(layout, r, s)?;
    }
    Ok(sys)
}

/// Collective. Give the mechanics its first temperatures: the thermal
/// solution's, or on a restart without one the prescribed heating's.
pub(super) fn couple_temperatures(
    comm: &SimpleCommunicator,
    model: &Model,
    layout: &Layout,
    sys: Option<&ThermalSystem>,
    mech: Option<&mut Mechanics>,
    restart: Option<&Checkpoint>,
) -> Result<()> {
    let Some(Mechanics { domain: m, .. }) = mech else {
        return Ok(());
    };
    if let Some(s) = sys {
        let t = s.t.to_local_vec()?;
        m.set_temperatures(comm, &t, None);
    } else if let Some(ck) = restart {
        if model.has_heating() {
            let t: Vec<f64> = layout
                .owned_nodes
                .iter()
                .map(|&n| model.prescribed_temperature(n, ck.time))
                .collect();
            m.set_temperatures(comm, &t, None);
        }
    }
    Ok(())
}

/// Collective. Detect contacts: each rank queries its own boundary tets,
/// then all ranks gather every pair (for preallocation and statistics).
/// `mesh` is the model's mesh at the current positions.
pub fn find_contacts(
    comm: &SimpleCommunicator,
    model: &Model,
    mesh: &TetMesh,
    layout: &Layout,
    bt: &BoundaryTets,
) -> ContactSet {
    if model.contact.is_none() {
        return ContactSet::default();
    }
    let rank = layout.rank as u32;
    let local = detect_contacts(mesh, bt, |e| layout.elem_part[e as usize] == rank);
    let gathered = crate::parallel::all_gather_f64(comm, &pairs_to_f64s(&local));
    let mut all = pairs_from_f64s(&gathered);
    all.sort_by_key(|p| (p.target, p.contactor));
    ContactSet { all, local }
}
