//! Checkpoints: open one to restart from (checked against the model),
//! restore the mechanics and the thermal state of each rank's part from
//! it, and save every rank's part into one (parallel HDF5, by global id).

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::io::checkpoint::{CheckpointFile, CheckpointHead, CheckpointRows};
use crate::io::checkpoint_heat::PENDING_HEAT;
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
pub(super) fn missing(restart: &Path, message: &str) -> Error {
    Error::Model {
        path: restart.display().to_string(),
        message: message.into(),
    }
}

/// The error for a checkpoint that cannot be read.
pub(super) fn unreadable(restart: &Path, e: crate::io::IoError) -> Error {
    let path = restart.display().to_string();
    // The I/O error names the file already: once is enough.
    let message = e.to_string();
    let message = match message.strip_prefix(&format!("{path}: ")) {
        Some(rest) => rest.to_string(),
        None => message,
    };
    Error::Model { path, message }
}

/// A run's state held in memory by global node id while the ranks
/// repartition: each field in blocks of node ids over the ranks (the
/// rows a checkpoint would hold), read back by the new owners.
pub(super) struct Snapshot {
    /// The head a checkpoint of this state would have.
    pub head: CheckpointHead,
    /// Number of nodes.
    total: u64,
    /// Per field (a checkpoint dataset's name): width, this rank's first
    /// row and its block of rows.
    fields: Vec<(&'static str, usize, u64, Vec<f64>)>,
    /// The bonded particles' rows (issue 21).
    pub particles: Option<super::particle_checkpoint::ParticleSnapshot>,
    /// This rank's tangential springs (any rank's after the repartition).
    pub springs: Vec<crate::io::checkpoint_springs::SavedSpring>,
}

impl Snapshot {
    /// Collective. The state of `captured` (this rank's owned rows of
    /// `part`) moved into blocks of global node ids.
    pub fn take(comm: &SimpleCommunicator, model: &Model, part: &Part, c: Captured) -> Snapshot {
        let total = model.totals().0;
        let ids = part.owned_gids();
        let flat3 = |v: Option<Vec<[f64; 3]>>| v.map(|v| (3, v.concat()));
        let present = [
            ("state/positions", flat3(c.positions)),
            ("state/velocities", flat3(c.velocities)),
            ("state/velocities_prev", flat3(c.velocities_prev)),
            ("state/temperature", c.temperature.map(|v| (1, v))),
            ("state/account_t0", c.account_t0.map(|v| (1, v))),
            ("state/account_t_sum", c.account_t_sum.map(|v| (1, v))),
            ("state/account_rad_sum", c.account_rad_sum.map(|v| (1, v))),
            (PENDING_HEAT, c.pending_heat.map(|v| (1, v))),
        ];
        let fields = present
            .into_iter()
            .filter_map(|(name, f)| {
                let (width, values) = f?;
                let (lo, rows) =
                    crate::parallel::exchange::to_blocks(comm, ids, &values, width, total);
                Some((name, width, lo, rows))
            })
            .collect();
        Snapshot {
            head: c.head,
            total,
            fields,
            particles: None,
            springs: Vec::new(),
        }
    }

    /// Whether the snapshot holds field `name`.
    fn holds(&self, name: &str) -> bool {
        self.fields.iter().any(|f| f.0 == name)
    }

    /// Collective. The rows of field `name` for nodes `ids`.
    fn rows(&self, comm: &SimpleCommunicator, name: &str, ids: &[u32]) -> Vec<f64> {
        let (_, width, lo, rows) = self
            .fields
            .iter()
            .find(|f| f.0 == name)
            .expect("the snapshot holds what its head says");
        crate::parallel::exchange::from_blocks(comm, (*lo, rows), *width, self.total, ids)
    }
}

/// Where a restored state comes from: a checkpoint file (a restart), or
/// the ranks' memory (a repartition).
#[derive(Clone, Copy)]
pub(super) enum Saved<'a> {
    File(&'a Restart),
    Memory(&'a Snapshot),
}

impl Saved<'_> {
    /// The head of the state.
    pub fn head(&self) -> &CheckpointHead {
        match self {
            Saved::File(r) => &r.file.head,
            Saved::Memory(s) => &s.head,
        }
    }

    /// What errors name: the checkpoint's path.
    fn origin(&self) -> &Path {
        match self {
            Saved::File(r) => &r.path,
            Saved::Memory(_) => Path::new("(repartition)"),
        }
    }

    /// Whether the state holds the node field `name`.
    fn holds(&self, name: &str) -> bool {
        match self {
            Saved::File(r) => r.file.holds(name),
            Saved::Memory(s) => s.holds(name),
        }
    }

    /// Collective for a snapshot. Rows of 3 of field `name` for nodes `ids`.
    fn rows3(
        &self,
        comm: &SimpleCommunicator,
        name: &str,
        ids: &[u32],
    ) -> std::result::Result<Vec<[f64; 3]>, crate::io::IoError> {
        match self {
            Saved::File(r) => r.file.node_rows3(name, ids),
            Saved::Memory(s) => Ok(s
                .rows(comm, name, ids)
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect()),
        }
    }

    /// Collective for a snapshot. Rows of 1 of field `name` for nodes `ids`.
    fn rows1(
        &self,
        comm: &SimpleCommunicator,
        name: &str,
        ids: &[u32],
    ) -> std::result::Result<Vec<f64>, crate::io::IoError> {
        match self {
            Saved::File(r) => r.file.node_rows1(name, ids),
            Saved::Memory(s) => Ok(s.rows(comm, name, ids)),
        }
    }
}

/// Collective. Put the saved mechanical state into the domain.
pub(super) fn restore_mechanics(
    comm: &SimpleCommunicator,
    part: &Part,
    saved: Saved,
    mech: &mut Mechanics,
) -> Result<()> {
    let ck = saved.head();
    let m = &mut mech.domain;
    if !(ck.has_positions && ck.has_velocities) {
        return Err(missing(
            saved.origin(),
            "the checkpoint has no mechanical state, the scenario has mechanics",
        ));
    }
    let read = || -> std::result::Result<_, crate::io::IoError> {
        let x = saved.rows3(comm, "state/positions", &part.node_gid)?;
        let v = saved.rows3(comm, "state/velocities", &part.node_gid)?;
        let vp = if ck.has_velocities_prev {
            Some(saved.rows3(comm, "state/velocities_prev", part.owned_gids())?)
        } else {
            None
        };
        Ok((x, v, vp))
    };
    let (x, v, vp) = agree(comm, read().map_err(|e| unreadable(saved.origin(), e)))?;
    // The springs reach their pairs' holders at the restore's detection.
    let springs = match saved {
        Saved::File(r) => r
            .file
            .spring_block(comm.rank() as usize, comm.size() as usize),
        Saved::Memory(s) => Ok(s.springs.clone()),
    };
    m.set_spring_pool(agree(
        comm,
        springs.map_err(|e| unreadable(saved.origin(), e)),
    )?);
    let saved = crate::dynamics::SavedMotion {
        positions: &x,
        velocities: &v,
        velocities_prev: vp.as_deref(),
        dissipated: ck.dissipated,
        dissipated_per_rank: ck.dissipated_per_rank.as_deref(),
        external_work_per_rank: ck.external_work_per_rank.as_deref(),
    };
    m.restore(comm, saved)?;
    m.counters.substeps = ck.substeps;
    // The friction's work so far, summed on rank 0.
    m.set_friction_work(if comm.rank() == 0 {
        ck.friction_work
    } else {
        0.0
    });
    Ok(())
}

/// Collective. Put the checkpoint's free spheres (motion, springs and
/// energy account) into the domain (a model with `[[spheres]]`).
pub(super) fn restore_spheres(
    comm: &SimpleCommunicator,
    r: &Restart,
    mech: &mut Mechanics,
) -> Result<()> {
    let Some((total, sets, heat)) = mech.domain.sphere_totals() else {
        return Ok(());
    };
    if !r.file.has_spheres() {
        return Err(missing(
            r.file.path(),
            "the checkpoint has no free spheres, the scenario has [[spheres]]",
        ));
    }
    let rows = r.file.sphere_rows(
        comm.rank() as usize,
        comm.size() as usize,
        total,
        sets,
        heat,
    );
    let rows = agree(comm, rows.map_err(|e| unreadable(r.file.path(), e)))?;
    mech.domain.restore_spheres(comm, &rows)
}

/// Collective. Put the saved histories of the joints into the domain (a
/// checkpoint of a run with joints; the model must have the same joints).
pub(super) fn restore_joints(
    comm: &SimpleCommunicator,
    model: &Model,
    r: &Restart,
    mech: &mut Mechanics,
) -> Result<()> {
    let total = model.joint_offsets().1;
    if total == 0 {
        return Ok(());
    }
    if !r.file.head.has_joints {
        return Err(missing(
            r.file.path(),
            "the checkpoint has no joint histories, the scenario has joints",
        ));
    }
    let ids = mech.domain.joint_gids();
    let rows = r.file.joint_rows(&ids, total);
    let rows = agree(comm, rows.map_err(|e| unreadable(r.file.path(), e)))?;
    mech.domain.restore_joints(&rows);
    Ok(())
}

/// Collective. Put the saved temperatures and heat account into the
/// thermal system.
pub(super) fn restore_thermal(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    saved: Saved,
    s: &mut ThermalSystem,
) -> Result<()> {
    let ck = saved.head();
    if !ck.has_temperature {
        return Err(missing(
            saved.origin(),
            "the checkpoint has no temperatures, the scenario has a thermal problem",
        ));
    }
    let owned = part.owned_gids();
    let read = || -> std::result::Result<_, crate::io::IoError> {
        let t = saved.rows1(comm, "state/temperature", owned)?;
        let account = match ck.account {
            Some(_) => Some((
                saved.rows1(comm, "state/account_t0", owned)?,
                saved.rows1(comm, "state/account_t_sum", owned)?,
                if ck.has_rad_sum {
                    saved.rows1(comm, "state/account_rad_sum", owned)?
                } else {
                    Vec::new()
                },
            )),
            None => None,
        };
        Ok((t, account))
    };
    let (t, account) = agree(comm, read().map_err(|e| unreadable(saved.origin(), e)))?;
    // Per node in the file; the copies of a node tied by intact joints share a row.
    let mut t = part.nodes_to_rows(&t);
    let mut account = account.map(|(t0, ts, rs)| {
        let rs = if rs.is_empty() {
            rs
        } else {
            part.nodes_to_rows(&rs)
        };
        (part.nodes_to_rows(&t0), part.nodes_to_rows(&ts), rs)
    });
    // The spheres' rows (issue 21).
    let acc = account
        .as_mut()
        .map(|(a, b, c)| (&mut a[..], &mut b[..], &mut c[..]));
    match saved {
        Saved::File(r) => {
            super::particle_checkpoint::restore_heat(comm, model, part, r, &mut t, acc)?;
        }
        Saved::Memory(s) => {
            if let Some(p) = &s.particles {
                p.restore_heat(comm, model, part, &mut t, acc);
            }
        }
    }
    let h = ck.heat;
    let heat = EnergyAccount {
        stored: h[0],
        stored_change: h[1],
        dirichlet_in: h[2],
        flux_in: h[3],
        convection_in: h[4],
        radiation_in: h[5],
        friction_in: h[6],
    };
    match (ck.account, account) {
        (Some((b, steps)), Some((t0, t_sum, rad_sum))) => {
            let state = crate::thermal::system::AccountState {
                base: EnergyAccount {
                    stored: b[0],
                    stored_change: b[1],
                    dirichlet_in: b[2],
                    flux_in: b[3],
                    convection_in: b[4],
                    radiation_in: b[5],
                    friction_in: b[6],
                },
                t0,
                t_sum,
                steps,
                rad_sum,
            };
            s.restore_exact(&t, &state, ck.step)?;
        }
        _ => s.restore(&t, heat, ck.step)?,
    }
    s.iterations = ck.ksp_iterations;
    restore_pending_heat(comm, model, part, saved, s)
}

/// Collective. The heat the mechanics handed over before the save and the
/// next step has not released yet (frictional heat, the free spheres'),
/// back into the rows of `part` (`io::checkpoint_heat`; a repartition's
/// snapshot carries the same field); from a file, the free spheres' share
/// of it and what they gave so far too (a repartition keeps those itself).
fn restore_pending_heat(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    saved: Saved,
    s: &mut ThermalSystem,
) -> Result<()> {
    let spheres = !model.spheres.is_empty();
    if saved.holds(PENDING_HEAT) {
        let q = saved.rows1(comm, PENDING_HEAT, part.owned_gids());
        let q = agree(comm, q.map_err(|e| unreadable(saved.origin(), e)))?;
        let heat: Vec<(u32, f64)> = part.petsc[..part.num_owned()]
            .iter()
            .zip(q)
            .map(|(&r, q)| (r, q))
            .collect();
        s.add_heat(&heat)?;
    } else if spheres {
        return Err(missing(
            saved.origin(),
            "the checkpoint has no state/pending_heat (the free spheres' heat handed to \
             the bodies), the scenario has [[spheres]] with [thermal]",
        ));
    }
    if let (Saved::File(r), true) = (saved, spheres) {
        let fe = agree(
            comm,
            r.file
                .sphere_fe_heat()
                .map_err(|e| unreadable(r.file.path(), e)),
        )?;
        let Some([pending, released]) = fe else {
            return Err(missing(
                r.file.path(),
                "the checkpoint has no spheres/fe_heat, the scenario has [[spheres]] with \
                 [thermal]",
            ));
        };
        s.restore_sphere_source(pending, released);
    }
    Ok(())
}

/// A rank's state as a checkpoint holds it: the head, and the rows of
/// the owned nodes (present when the run has them).
pub(super) struct Captured {
    pub head: CheckpointHead,
    positions: Option<Vec<[f64; 3]>>,
    velocities: Option<Vec<[f64; 3]>>,
    velocities_prev: Option<Vec<[f64; 3]>>,
    temperature: Option<Vec<f64>>,
    account_t0: Option<Vec<f64>>,
    account_t_sum: Option<Vec<f64>>,
    account_rad_sum: Option<Vec<f64>>,
    /// Heat handed over and not yet released, per owned node.
    pending_heat: Option<Vec<f64>>,
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
    let joints = match (&mech, model.has_joints()) {
        (Some(m), true) => Some(m.domain.saved_joints()),
        _ => None,
    };
    let total_joints = model.joint_offsets().1;
    let particles =
        super::particle_checkpoint::capture(model, part, sys.as_ref(), mech.as_deref())?;
    // Tangential springs, sorted by pair over the ranks.
    let springs = match &mech {
        Some(m) if m.domain.tangential_springs() => Some(
            crate::io::checkpoint_springs::sorted_rows(comm, &m.domain.held_springs()),
        ),
        _ => None,
    };
    // Free spheres: their motion and springs, with heat their temperatures,
    // heat account and the FE's side of it (issue 21).
    let mut spheres = mech.as_deref().and_then(|m| m.domain.saved_spheres(comm));
    if let (Some((_, _, fe)), Some(s)) =
        (spheres.as_mut().and_then(|c| c.heat.as_mut()), sys.as_ref())
    {
        let src = s.sphere_source();
        *fe = [src.pending, src.released];
    }
    let mut c = capture(comm, model, part, sys, mech, step, contacts)?;
    c.head.peak_kinetic = peak_kinetic;
    c.head.settled = settled;
    let no = part.num_owned();
    let tets: Vec<[u32; 4]> = part
        .mesh
        .tets
        .iter()
        .map(|t| t.map(|l| part.node_gid[l as usize]))
        .collect();
    // The parts go with the state: a restart on as many ranks continues on them.
    let rank = vec![comm.rank() as u32; part.num_elements()];
    c.head.partition_ranks = Some(comm.size() as u64);
    // Hex8 bodies: their hexes, as each tet node's corner (issue 21).
    let hex_corner: Option<Vec<u32>> = model.has_hexes().then(|| {
        let ne = part.num_elements();
        (0..ne)
            .flat_map(|e| match part.hex_corner.get(e) {
                Some(c) => c.map(u32::from),
                None => [crate::io::checkpoint_hexes::NO_CORNER; 4],
            })
            .collect()
    });
    let rows = CheckpointRows {
        node_gid: part.owned_gids(),
        reference: &part.mesh.nodes[..no],
        elem_gid: &part.elem_gid,
        tets: &tets,
        elem_body: &part.mesh.body,
        elem_rank: Some(&rank),
        positions: c.positions.as_deref(),
        velocities: c.velocities.as_deref(),
        velocities_prev: c.velocities_prev.as_deref(),
        temperature: c.temperature.as_deref(),
        account_t0: c.account_t0.as_deref(),
        account_t_sum: c.account_t_sum.as_deref(),
        account_rad_sum: c.account_rad_sum.as_deref(),
        joints: joints
            .as_ref()
            .map(|(ids, v)| (&ids[..], &v[..], total_joints)),
        particles: particles.as_ref(),
        springs: springs.as_ref().map(|(i, v, t)| (&i[..], &v[..], *t)),
        spheres: spheres.as_ref(),
        pending_heat: c.pending_heat.as_deref(),
        hex_corner: hex_corner.as_deref(),
    };
    crate::io::checkpoint::write_parallel(comm, path, &c.head, &rows).map_err(Error::from)
}

/// Collective. The state of `step` on this rank, as a checkpoint holds it.
pub(super) fn capture(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    sys: &mut Option<ThermalSystem>,
    mech: Option<&mut Mechanics>,
    step: u64,
    contacts: &ContactSet,
) -> Result<Captured> {
    let (nodes, elems) = model.totals();
    let mut head = CheckpointHead {
        step,
        time: step as f64 * model.dt,
        nodes,
        elems,
        body_names: model.bodies.iter().map(|b| b.name.clone()).collect(),
        body_templates: model.bodies.iter().map(|b| b.template.clone()).collect(),
        body_hex8: (0..model.bodies.len())
            .map(|b| model.body_is_hex8(b))
            .collect(),
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
        thermal_contacts: contacts.total_pairs,
        ..Default::default()
    };
    let no = part.num_owned();
    let (mut positions, mut velocities, mut velocities_prev) = (None, None, None);
    if let Some(Mechanics { domain: m, .. }) = mech {
        positions = Some(m.owned_positions());
        velocities = Some(m.owned_velocities());
        velocities_prev = m.owned_velocities_prev(comm);
        let st = m.state(comm);
        head.dissipated = st.dissipated;
        head.friction_work = st.friction_work;
        head.substeps = m.counters.substeps;
        head.dissipated_per_rank = Some(m.gather_dissipated(comm));
        head.external_work_per_rank = Some(m.gather_external_work(comm));
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
    let (mut temperature, mut t0, mut t_sum, mut rad_sum) = (None, None, None, None);
    let mut pending_heat = None;
    if let Some(s) = sys.as_mut() {
        pending_heat = s.pending_heat(part)?;
        // Saved per node: copies tied by intact joints share a row.
        temperature = Some(s.node_temperatures(part)?);
        head.ksp_iterations = s.iterations;
        let a = s.account_state()?;
        head.account = Some((
            [
                a.base.stored,
                a.base.stored_change,
                a.base.dirichlet_in,
                a.base.flux_in,
                a.base.convection_in,
                a.base.radiation_in,
                a.base.friction_in,
            ],
            a.steps,
        ));
        let nodes = |rows: &[f64]| crate::thermal::node_rows::nodes_from_rows(part, &s.t, rows);
        t0 = Some(nodes(&a.t0)?);
        t_sum = Some(nodes(&a.t_sum)?);
        if !a.rad_sum.is_empty() {
            rad_sum = Some(nodes(&a.rad_sum)?);
        }
        let e = s.energy()?;
        head.heat = [
            e.stored,
            e.stored_change,
            e.dirichlet_in,
            e.flux_in,
            e.convection_in,
            e.radiation_in,
            e.friction_in,
        ];
    }
    head.has_positions = positions.is_some();
    head.has_velocities = velocities.is_some();
    head.has_velocities_prev = velocities_prev.is_some();
    head.has_temperature = temperature.is_some();
    head.has_rad_sum = rad_sum.is_some();
    Ok(Captured {
        head,
        positions,
        velocities,
        velocities_prev,
        temperature,
        account_t0: t0,
        account_t_sum: t_sum,
        account_rad_sum: rad_sum,
        pending_heat,
    })
}
