//! Checkpoints: read one to restart from (checked against the model),
//! restore the mechanics and the thermal state from it, and save the
//! state of every rank into one from rank 0.

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::io::checkpoint::Checkpoint;
use crate::model::Model;
use crate::parallel::{agree, Part};
use crate::thermal::system::EnergyAccount;
use crate::thermal::ThermalSystem;

use super::Mechanics;

/// The checkpoint a run restarts from, and where it was read.
pub(super) struct Restart {
    /// The checkpoint.
    pub checkpoint: Checkpoint,
    /// Its file (`--restart`).
    pub path: PathBuf,
}

impl Restart {
    /// Read the checkpoint at `path` and check it belongs to this model.
    pub fn read(path: &Path, model: &Model) -> Result<Restart> {
        Ok(Restart {
            checkpoint: read_restart(path, model)?,
            path: path.to_path_buf(),
        })
    }
}

/// Read a checkpoint and check it belongs to this model (same mesh).
fn read_restart(path: &Path, model: &Model) -> Result<Checkpoint> {
    // Every rank reads the same file and fails alike: a model error, which
    // rank 0 alone prints.
    let ck = Checkpoint::read(path).map_err(|e| Error::Model {
        path: "--restart".into(),
        message: e.to_string(),
    })?;
    let bad = |m: String| Error::Model {
        path: path.display().to_string(),
        message: format!("the checkpoint does not match the scenario: {m}"),
    };
    if ck.reference.len() != model.mesh.nodes.len() || ck.tets.len() != model.mesh.tets.len() {
        return Err(bad(format!(
            "it has {} nodes and {} elements, the scenario {} and {}",
            ck.reference.len(),
            ck.tets.len(),
            model.mesh.nodes.len(),
            model.mesh.tets.len()
        )));
    }
    if ck.tets != model.mesh.tets || ck.reference != model.mesh.nodes {
        return Err(bad(
            "the meshes differ (another placement seed or mesh size?)".into(),
        ));
    }
    if ck.step > model.steps {
        return Err(bad(format!(
            "it is at step {}, after the scenario's last step {}",
            ck.step, model.steps
        )));
    }
    Ok(ck)
}

/// The error for a checkpoint that lacks what the scenario needs.
fn missing(restart: &Path, message: &str) -> Error {
    Error::Model {
        path: restart.display().to_string(),
        message: message.into(),
    }
}

/// Collective. Put the mechanical state of the checkpoint into the domain.
pub(super) fn restore_mechanics(
    comm: &SimpleCommunicator,
    restart: &Restart,
    mech: &mut Mechanics,
) -> Result<()> {
    let ck = &restart.checkpoint;
    let m = &mut mech.domain;
    let (Some(x), Some(v)) = (&ck.positions, &ck.velocities) else {
        return Err(missing(
            &restart.path,
            "the checkpoint has no mechanical state, the scenario has mechanics",
        ));
    };
    let saved = crate::dynamics::SavedMotion {
        positions: x,
        velocities: v,
        velocities_prev: ck.velocities_prev.as_deref(),
        dissipated: ck.dissipated,
        dissipated_per_rank: ck.dissipated_per_rank.as_deref(),
    };
    m.restore(comm, saved)?;
    m.counters.substeps = ck.substeps;
    Ok(())
}

/// Put the temperatures and the heat account of the checkpoint into the
/// thermal system.
pub(super) fn restore_thermal(part: &Part, restart: &Restart, s: &mut ThermalSystem) -> Result<()> {
    let ck = &restart.checkpoint;
    let Some(t) = &ck.temperature else {
        return Err(missing(
            &restart.path,
            "the checkpoint has no temperatures, the scenario has a thermal problem",
        ));
    };
    let owned: Vec<f64> = part.owned_gids().iter().map(|&n| t[n as usize]).collect();
    let h = ck.heat;
    let account = EnergyAccount {
        stored: h[0],
        stored_change: h[1],
        dirichlet_in: h[2],
        flux_in: h[3],
        convection_in: h[4],
    };
    match &ck.account {
        Some(a) => {
            let owned_of = |v: &[f64]| -> Vec<f64> {
                part.owned_gids().iter().map(|&n| v[n as usize]).collect()
            };
            let b = a.base;
            let state = crate::thermal::system::AccountState {
                base: EnergyAccount {
                    stored: b[0],
                    stored_change: b[1],
                    dirichlet_in: b[2],
                    flux_in: b[3],
                    convection_in: b[4],
                },
                t0: owned_of(&a.t0),
                t_sum: owned_of(&a.t_sum),
                steps: a.steps,
            };
            s.restore_exact(&owned, &state, ck.step)?;
        }
        None => s.restore(&owned, account, ck.step)?,
    }
    s.iterations = ck.ksp_iterations;
    Ok(())
}

/// Collective. Gather the state and write the checkpoint from rank 0.
#[allow(clippy::too_many_arguments)]
pub(super) fn save_checkpoint(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    sys: &mut Option<ThermalSystem>,
    mech: Option<&mut Mechanics>,
    step: u64,
    peak_kinetic: f64,
    contacts: &ContactSet,
    settled: Option<f64>,
    path: &Path,
) -> Result<()> {
    let mut ck = Checkpoint {
        settled,
        step,
        time: step as f64 * model.dt,
        reference: model.mesh.nodes.clone(),
        tets: model.mesh.tets.clone(),
        elem_body: model.mesh.body.clone(),
        body_names: model.bodies.iter().map(|b| b.name.clone()).collect(),
        body_templates: model.bodies.iter().map(|b| b.template.clone()).collect(),
        body_nodes: model
            .bodies
            .iter()
            .map(|b| [b.node_range.0, b.node_range.1])
            .collect(),
        body_elems: model
            .bodies
            .iter()
            .map(|b| [b.elem_range.0, b.elem_range.1])
            .collect(),
        peak_kinetic,
        thermal_contacts: contacts.total_pairs,
        ..Default::default()
    };
    if let Some(Mechanics { domain: m, .. }) = mech {
        ck.positions = Some(m.gather_positions(comm));
        ck.velocities = Some(m.gather_velocities(comm));
        ck.velocities_prev = m.gather_velocities_prev(comm);
        ck.dissipated = m.state(comm).dissipated;
        ck.substeps = m.counters.substeps;
        ck.dissipated_per_rank = Some(m.gather_dissipated(comm));
    } else if model.has_motion() {
        let mut x = model.mesh.nodes.clone();
        model.positions_at(ck.time, &mut x);
        ck.positions = Some(x);
    }
    if let Some(s) = sys.as_mut() {
        let owned = s.t.to_local_vec()?;
        let all = crate::parallel::all_gather_f64(comm, &owned);
        ck.temperature = Some(
            (0..model.mesh.nodes.len())
                .map(|n| all[part.whole().petsc_of[n] as usize])
                .collect(),
        );
        ck.ksp_iterations = s.iterations;
        let a = s.account_state()?;
        let per_node = |owned: &[f64]| -> Vec<f64> {
            let all = crate::parallel::all_gather_f64(comm, owned);
            (0..model.mesh.nodes.len())
                .map(|n| all[part.whole().petsc_of[n] as usize])
                .collect()
        };
        ck.account = Some(crate::io::checkpoint::SavedAccount {
            base: [
                a.base.stored,
                a.base.stored_change,
                a.base.dirichlet_in,
                a.base.flux_in,
                a.base.convection_in,
            ],
            steps: a.steps,
            t0: per_node(&a.t0),
            t_sum: per_node(&a.t_sum),
        });
        let e = s.energy()?;
        ck.heat = [
            e.stored,
            e.stored_change,
            e.dirichlet_in,
            e.flux_in,
            e.convection_in,
        ];
    }
    let written = if comm.rank() == 0 {
        ck.write(path).map_err(Error::from)
    } else {
        Ok(())
    };
    agree(comm, written)
}
