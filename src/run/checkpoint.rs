//! Checkpoints: open one to restart from (checked against the model),
//! restore the mechanics and the thermal state of each rank's part from
//! it, and save every rank's part into one (parallel HDF5, by global id).

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::io::checkpoint::{CheckpointFile, CheckpointHead, CheckpointRows};
use crate::model::Model;
use crate::parallel::{agree, Part};
use crate::thermal::system::EnergyAccount;
use crate::thermal::ThermalSystem;

use super::Mechanics;

/// The checkpoint a run restarts from, open for reading in pieces.
pub(super) struct Restart {
    /// The file, its head read.
    pub file: CheckpointFile,
    /// Its path (`--restart`).
    pub path: PathBuf,
}

impl Restart {
    /// Open the checkpoint at `path` and check it belongs to this model
    /// (the same bodies; each rank checks its part's mesh when restoring).
    pub fn read(path: &Path, model: &Model) -> Result<Restart> {
        // Every rank reads the same head and fails alike: a model error,
        // which rank 0 alone prints.
        let file = CheckpointFile::open(path).map_err(|e| Error::Model {
            path: "--restart".into(),
            message: e.to_string(),
        })?;
        let bad = |m: String| Error::Model {
            path: path.display().to_string(),
            message: format!("the checkpoint does not match the scenario: {m}"),
        };
        let ck = &file.head;
        let (nodes, elems) = model.totals();
        if ck.nodes != nodes || ck.elems != elems || ck.body_names.len() != model.bodies.len() {
            return Err(bad(format!(
                "it has {} nodes, {} elements and {} bodies, the scenario {nodes}, {elems} and {}",
                ck.nodes,
                ck.elems,
                ck.body_names.len(),
                model.bodies.len()
            )));
        }
        let same_bodies = model
            .bodies
            .iter()
            .zip(&ck.body_nodes)
            .zip(&ck.body_elems)
            .all(|((b, n), e)| {
                [b.node_range.0, b.node_range.1] == *n && [b.elem_range.0, b.elem_range.1] == *e
            });
        if !same_bodies {
            return Err(bad("the bodies differ (another scenario?)".into()));
        }
        if ck.step > model.steps {
            return Err(bad(format!(
                "it is at step {}, after the scenario's last step {}",
                ck.step, model.steps
            )));
        }
        Ok(Restart {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Collective. Check that the part's mesh is the checkpoint's (the
    /// same elements over the same reference nodes).
    pub fn check_part(&self, comm: &SimpleCommunicator, part: &Part) -> Result<()> {
        let read = || -> std::result::Result<bool, crate::io::IoError> {
            let x = self.file.node_rows3("mesh/reference", &part.node_gid)?;
            let t = self.file.elem_tets(&part.elem_gid)?;
            let same_tets = t
                .iter()
                .zip(&part.mesh.tets)
                .all(|(a, b)| *a == b.map(|l| part.node_gid[l as usize]));
            Ok(x == part.mesh.nodes && same_tets)
        };
        let local = match read() {
            Ok(true) => Ok(()),
            Ok(false) => Err(Error::Model {
                path: self.path.display().to_string(),
                message: "the checkpoint does not match the scenario: the meshes differ \
                          (another placement seed or mesh size?)"
                    .into(),
            }),
            Err(e) => Err(Error::Model {
                path: "--restart".into(),
                message: e.to_string(),
            }),
        };
        agree(comm, local)
    }
}

/// The error for a checkpoint that lacks what the scenario needs.
fn missing(restart: &Path, message: &str) -> Error {
    Error::Model {
        path: restart.display().to_string(),
        message: message.into(),
    }
}

/// The error for a checkpoint that cannot be read.
fn unreadable(restart: &Path, e: crate::io::IoError) -> Error {
    Error::Model {
        path: restart.display().to_string(),
        message: e.to_string(),
    }
}

/// Collective. Put the mechanical state of the checkpoint into the domain.
pub(super) fn restore_mechanics(
    comm: &SimpleCommunicator,
    part: &Part,
    restart: &Restart,
    mech: &mut Mechanics,
) -> Result<()> {
    let ck = &restart.file.head;
    let m = &mut mech.domain;
    if !(ck.has_positions && ck.has_velocities) {
        return Err(missing(
            &restart.path,
            "the checkpoint has no mechanical state, the scenario has mechanics",
        ));
    }
    let f = &restart.file;
    let read = || -> std::result::Result<_, crate::io::IoError> {
        let x = f.node_rows3("state/positions", &part.node_gid)?;
        let v = f.node_rows3("state/velocities", &part.node_gid)?;
        let vp = if ck.has_velocities_prev {
            Some(f.node_rows3("state/velocities_prev", part.owned_gids())?)
        } else {
            None
        };
        Ok((x, v, vp))
    };
    let (x, v, vp) = agree(comm, read().map_err(|e| unreadable(&restart.path, e)))?;
    let saved = crate::dynamics::SavedMotion {
        positions: &x,
        velocities: &v,
        velocities_prev: vp.as_deref(),
        dissipated: ck.dissipated,
        dissipated_per_rank: ck.dissipated_per_rank.as_deref(),
    };
    m.restore(comm, saved)?;
    m.counters.substeps = ck.substeps;
    Ok(())
}

/// Collective. Put the temperatures and the heat account of the
/// checkpoint into the thermal system.
pub(super) fn restore_thermal(
    comm: &SimpleCommunicator,
    part: &Part,
    restart: &Restart,
    s: &mut ThermalSystem,
) -> Result<()> {
    let ck = &restart.file.head;
    if !ck.has_temperature {
        return Err(missing(
            &restart.path,
            "the checkpoint has no temperatures, the scenario has a thermal problem",
        ));
    }
    let f = &restart.file;
    let owned = part.owned_gids();
    let read = || -> std::result::Result<_, crate::io::IoError> {
        let t = f.node_rows1("state/temperature", owned)?;
        let account = match ck.account {
            Some(_) => Some((
                f.node_rows1("state/account_t0", owned)?,
                f.node_rows1("state/account_t_sum", owned)?,
            )),
            None => None,
        };
        Ok((t, account))
    };
    let (t, account) = agree(comm, read().map_err(|e| unreadable(&restart.path, e)))?;
    let h = ck.heat;
    let heat = EnergyAccount {
        stored: h[0],
        stored_change: h[1],
        dirichlet_in: h[2],
        flux_in: h[3],
        convection_in: h[4],
    };
    match (ck.account, account) {
        (Some((b, steps)), Some((t0, t_sum))) => {
            let state = crate::thermal::system::AccountState {
                base: EnergyAccount {
                    stored: b[0],
                    stored_change: b[1],
                    dirichlet_in: b[2],
                    flux_in: b[3],
                    convection_in: b[4],
                },
                t0,
                t_sum,
                steps,
            };
            s.restore_exact(&t, &state, ck.step)?;
        }
        _ => s.restore(&t, heat, ck.step)?,
    }
    s.iterations = ck.ksp_iterations;
    Ok(())
}

/// Collective. Write the checkpoint: every rank its part's rows.
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
    let (nodes, elems) = model.totals();
    let mut head = CheckpointHead {
        settled,
        step,
        time: step as f64 * model.dt,
        nodes,
        elems,
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
    let no = part.num_owned();
    let tets: Vec<[u32; 4]> = part
        .mesh
        .tets
        .iter()
        .map(|t| t.map(|l| part.node_gid[l as usize]))
        .collect();
    let (mut positions, mut velocities, mut velocities_prev) = (None, None, None);
    if let Some(Mechanics { domain: m, .. }) = mech {
        positions = Some(m.owned_positions());
        velocities = Some(m.owned_velocities());
        velocities_prev = m.owned_velocities_prev(comm);
        head.dissipated = m.state(comm).dissipated;
        head.substeps = m.counters.substeps;
        head.dissipated_per_rank = Some(m.gather_dissipated(comm));
    } else if model.has_motion() {
        let x: Vec<[f64; 3]> = part.mesh.nodes[..no]
            .iter()
            .zip(part.owned_gids())
            .map(|(p, &g)| {
                let v = model.bodies[model.body_of_node(g)].velocity;
                std::array::from_fn(|d| p[d] + v[d] * head.time)
            })
            .collect();
        positions = Some(x);
    }
    let (mut temperature, mut t0, mut t_sum) = (None, None, None);
    if let Some(s) = sys.as_mut() {
        temperature = Some(s.t.to_local_vec()?);
        head.ksp_iterations = s.iterations;
        let a = s.account_state()?;
        head.account = Some((
            [
                a.base.stored,
                a.base.stored_change,
                a.base.dirichlet_in,
                a.base.flux_in,
                a.base.convection_in,
            ],
            a.steps,
        ));
        t0 = Some(a.t0);
        t_sum = Some(a.t_sum);
        let e = s.energy()?;
        head.heat = [
            e.stored,
            e.stored_change,
            e.dirichlet_in,
            e.flux_in,
            e.convection_in,
        ];
    }
    let rows = CheckpointRows {
        node_gid: part.owned_gids(),
        reference: &part.mesh.nodes[..no],
        elem_gid: &part.elem_gid,
        tets: &tets,
        elem_body: &part.mesh.body,
        positions: positions.as_deref(),
        velocities: velocities.as_deref(),
        velocities_prev: velocities_prev.as_deref(),
        temperature: temperature.as_deref(),
        account_t0: t0.as_deref(),
        account_t_sum: t_sum.as_deref(),
    };
    crate::io::checkpoint::write_parallel(comm, path, &head, &rows).map_err(Error::from)
}
