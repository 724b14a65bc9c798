//! The time loop: model → partition → thermal system → steps → output.
//!
//! Collective: every function here is called by all ranks. Errors that one
//! rank finds alone (an output directory it cannot create) are agreed on
//! before the next collective call so no rank waits for a failed one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::contact::{detect_contacts, BoundaryTets, ContactPair, ContactSet, ContactSurface};
use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::io::checkpoint::Checkpoint;
use crate::io::particles::ParticleReport;
use crate::io::{HistoryWriter, MeshPart, TimeSeriesWriter};
use crate::model::Model;
use crate::parallel::{agree, Layout};
use crate::petsc::Petsc;
use crate::scenario::LoadedScenario;
use crate::thermal::system::EnergyAccount;
use crate::thermal::ThermalSystem;

/// How to run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output directory (overrides the scenario's).
    pub output_dir: Option<PathBuf>,
    /// Show a progress bar on rank 0.
    pub progress: bool,
    /// Continue from this checkpoint (written by a run of the same scenario).
    pub restart: Option<PathBuf>,
    /// Accept PETSc options that no PETSc object reads.
    pub allow_unused_petsc_options: bool,
}

/// Wall-clock seconds spent per phase (rank 0's view, max over ranks).
#[derive(Debug, Clone, Default)]
pub struct PhaseTimes {
    /// Meshes, sets, checks.
    pub model: f64,
    /// METIS partition and numbering.
    pub partition: f64,
    /// Assembly and solver set-up (factorisation).
    pub assembly: f64,
    /// Contact detection and surfaces.
    pub contact: f64,
    /// Time stepping (solves).
    pub stepping: f64,
    /// HDF5/XDMF/CSV output.
    pub output: f64,
    /// Explicit mechanics (set-up and substeps, detection included).
    pub mechanics: f64,
    /// Of which contact detection and halo rebuilds.
    pub mechanics_detect: f64,
    /// Of which the set-up (partition-local arrays, step, first detection).
    pub mechanics_setup: f64,
}

/// What the explicit mechanics did.
#[derive(Debug, Clone, Copy)]
pub struct MechanicsSummary {
    /// Explicit step (s).
    pub dt: f64,
    /// Substeps per thermal step.
    pub substeps_per_step: u64,
    /// Substeps taken.
    pub substeps: u64,
    /// Contact detections (candidate list rebuilds).
    pub detections: u64,
    /// Element updates, all ranks.
    pub element_updates: u64,
    /// Contact pair evaluations, all ranks.
    pub pair_updates: u64,
    /// Of those, exact overlap computations (the rest: boxes apart, or
    /// linearised overlaps).
    pub exact_overlaps: u64,
    /// Smallest (at-rest) contact search margin (m).
    pub margin: f64,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Ranks.
    pub ranks: usize,
    /// Nodes and elements.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// Steps taken.
    pub steps: u64,
    /// Total Krylov iterations.
    pub ksp_iterations: u64,
    /// Solver in use.
    pub solver: String,
    /// Phase times.
    pub times: PhaseTimes,
    /// Output directory.
    pub output_dir: PathBuf,
    /// HDF5 file.
    pub h5: PathBuf,
    /// XDMF file.
    pub xdmf: PathBuf,
    /// History CSV.
    pub history: PathBuf,
    /// Final heat balance.
    pub energy: EnergyAccount,
    /// Peak resident memory per rank, max over ranks (bytes).
    pub peak_memory: u64,
    /// Contact pairs and total contact area at the end.
    pub contacts: (usize, f64),
    /// Contact detections run.
    pub detections: u64,
    /// Times the thermal operator was assembled.
    pub assemblies: u64,
    /// Mechanics, when it ran.
    pub mechanics: Option<MechanicsSummary>,
    /// Step the run started from (0, or a checkpoint's).
    pub start_step: u64,
    /// Step, time and kinetic energy at which the bodies settled (the run stopped there).
    pub settled: Option<(u64, f64, f64)>,
    /// Checkpoint written.
    pub checkpoint: Option<PathBuf>,
    /// Particle statistics files written.
    pub particle_files: Vec<PathBuf>,
    /// Whether heat conduction was solved (else the heat line is left out).
    pub heat: bool,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = &self.times;
        writeln!(f, "fdem run summary")?;
        writeln!(
            f,
            "  mesh        {} nodes, {} Tet4 on {} rank(s)",
            self.nodes, self.elements, self.ranks
        )?;
        writeln!(f, "  solver      {}", self.solver)?;
        writeln!(
            f,
            "  steps       {} ({} KSP iterations, {:.2} per step)",
            self.steps,
            self.ksp_iterations,
            self.ksp_iterations as f64 / self.steps.max(1) as f64
        )?;
        writeln!(
            f,
            "  time [s]    model {:.3} | partition {:.3} | contact {:.3} | assembly+setup {:.3} | stepping {:.3} | output {:.3}",
            t.model, t.partition, t.contact, t.assembly, t.stepping, t.output
        )?;
        writeln!(
            f,
            "  contact     {} pairs, area {:.6e} m^2; {} detection(s), operator assembled {} time(s)",
            self.contacts.0, self.contacts.1, self.detections, self.assemblies
        )?;
        if self.steps > 0 {
            writeln!(
                f,
                "  per step    {:.2} us",
                1e6 * t.stepping / self.steps as f64
            )?;
        }
        if let Some(m) = &self.mechanics {
            let rate = if t.mechanics > 0.0 {
                m.element_updates as f64 / t.mechanics / self.ranks as f64
            } else {
                0.0
            };
            writeln!(
                f,
                "  mechanics   dt {:.4e} s, {} substeps ({} per step), {:.3} s ({:.3} s set-up, {:.3} s detection, {} detections), {:.2} M tet updates/s/rank, {} pair evaluations ({} exact overlaps)",
                m.dt,
                m.substeps,
                m.substeps_per_step,
                t.mechanics,
                t.mechanics_setup,
                t.mechanics_detect,
                m.detections,
                rate / 1e6,
                m.pair_updates,
                m.exact_overlaps
            )?;
        }
        if self.heat {
            writeln!(
                f,
                "  heat        stored change {:.6e}, boundary in {:.6e} (balance {:.2e})",
                self.energy.stored_change,
                self.energy.boundary_in(),
                self.energy.stored_change - self.energy.boundary_in()
            )?;
        }
        writeln!(
            f,
            "  memory      peak {:.1} MiB per rank",
            self.peak_memory as f64 / 1048576.0
        )?;
        if self.start_step > 0 {
            writeln!(f, "  restart     from step {}", self.start_step)?;
        }
        if let Some((step, time, ke)) = self.settled {
            writeln!(
                f,
                "  settled     at step {step}, t = {time:.4} s (kinetic energy {ke:.3e} J)"
            )?;
        }
        writeln!(f, "  output      {}", self.xdmf.display())?;
        for p in self.checkpoint.iter().chain(&self.particle_files) {
            writeln!(f, "              {}", p.display())?;
        }
        write!(f, "              {}", self.history.display())
    }
}

/// Peak resident set size of this process (VmHWM), bytes.
pub fn peak_rss() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// Per-body statistics of the owned nodes.
struct BodyStats {
    body_of_owned: Vec<u32>,
    weight_of_owned: Vec<f64>,
    nbodies: usize,
}

impl BodyStats {
    fn new(model: &Model, layout: &Layout) -> BodyStats {
        let mut w = vec![0.0; model.mesh.nodes.len()];
        for e in 0..model.mesh.tets.len() {
            let v = model.mesh.element_volume(e) / 4.0;
            for &n in &model.mesh.tets[e] {
                w[n as usize] += v;
            }
        }
        BodyStats {
            body_of_owned: layout
                .owned_nodes
                .iter()
                .map(|&n| model.body_of_node(n) as u32)
                .collect(),
            weight_of_owned: layout.owned_nodes.iter().map(|&n| w[n as usize]).collect(),
            nbodies: model.bodies.len(),
        }
    }

    /// Collective. (min, volume-weighted mean, max) per body.
    fn compute(&self, comm: &SimpleCommunicator, t: &[f64]) -> Vec<[f64; 3]> {
        let nb = self.nbodies;
        let mut mins = vec![f64::INFINITY; nb];
        let mut maxs = vec![f64::NEG_INFINITY; nb];
        let mut sums = vec![0.0; 2 * nb];
        for (i, &x) in t.iter().enumerate() {
            let b = self.body_of_owned[i] as usize;
            mins[b] = mins[b].min(x);
            maxs[b] = maxs[b].max(x);
            sums[2 * b] += self.weight_of_owned[i] * x;
            sums[2 * b + 1] += self.weight_of_owned[i];
        }
        let mut gmin = vec![0.0; nb];
        let mut gmax = vec![0.0; nb];
        let mut gsum = vec![0.0; 2 * nb];
        comm.all_reduce_into(&mins[..], &mut gmin[..], SystemOperation::min());
        comm.all_reduce_into(&maxs[..], &mut gmax[..], SystemOperation::max());
        comm.all_reduce_into(&sums[..], &mut gsum[..], SystemOperation::sum());
        (0..nb)
            .map(|b| [gmin[b], gsum[2 * b] / gsum[2 * b + 1], gmax[b]])
            .collect()
    }
}

const PAIR_F64S: usize = 20;

/// Collective. Detect contacts: each rank queries its own boundary tets,
/// then all ranks gather every pair (for preallocation and statistics).
/// `mesh` is the model's mesh at the current positions.
pub fn find_contacts(
    comm: &SimpleCommunicator,
    model: &Model,
    mesh: &crate::mesh::TetMesh,
    layout: &Layout,
    bt: &BoundaryTets,
) -> ContactSet {
    if model.contact.is_none() {
        return ContactSet::default();
    }
    let rank = layout.rank as u32;
    let local = detect_contacts(mesh, bt, |e| layout.elem_part[e as usize] == rank);
    let mut flat = Vec::with_capacity(local.len() * PAIR_F64S);
    for p in &local {
        flat.extend_from_slice(&[
            p.target as f64,
            p.contactor as f64,
            p.surface.s_target,
            p.surface.s_contactor,
        ]);
        flat.extend_from_slice(&p.surface.w_target);
        flat.extend_from_slice(&p.surface.w_contactor);
        flat.extend_from_slice(&p.surface.v_target);
        flat.extend_from_slice(&p.surface.v_contactor);
    }
    let gathered = crate::parallel::all_gather_f64(comm, &flat);
    let mut all: Vec<ContactPair> = gathered
        .chunks_exact(PAIR_F64S)
        .map(|c| ContactPair {
            target: c[0] as u32,
            contactor: c[1] as u32,
            surface: ContactSurface {
                s_target: c[2],
                s_contactor: c[3],
                w_target: [c[4], c[5], c[6], c[7]],
                w_contactor: [c[8], c[9], c[10], c[11]],
                v_target: [c[12], c[13], c[14], c[15]],
                v_contactor: [c[16], c[17], c[18], c[19]],
            },
        })
        .collect();
    all.sort_by_key(|p| (p.target, p.contactor));
    ContactSet { all, local }
}

/// Collective. Run a scenario to the end.
pub fn run(
    petsc: &Petsc,
    comm: &SimpleCommunicator,
    sc: &LoadedScenario,
    opts: &RunOptions,
) -> Result<RunSummary> {
    let rank = comm.rank();
    let mut times = PhaseTimes::default();

    let clock = Instant::now();
    let model = Model::from_scenario(sc)?;
    times.model = clock.elapsed().as_secs_f64();

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

    let restart = match &opts.restart {
        Some(p) => Some(read_restart(p, &model)?),
        None => None,
    };
    let start_step = restart.as_ref().map_or(0, |c| c.step);

    // Mechanics first: its set-up checks the time step before any work.
    let clock = Instant::now();
    let mut mech = match model.mechanics {
        Some(_) => Some(ExplicitDomain::new(comm, &model, &layout, model.dt)?),
        None => None,
    };
    if let (Some(ck), Some((m, _))) = (restart.as_ref(), mech.as_mut()) {
        let (Some(x), Some(v)) = (&ck.positions, &ck.velocities) else {
            return Err(Error::Model {
                path: opts
                    .restart
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                message: "the checkpoint has no mechanical state, the scenario has mechanics"
                    .into(),
            });
        };
        let saved = crate::dynamics::SavedMotion {
            positions: x,
            velocities: v,
            velocities_prev: ck.velocities_prev.as_deref(),
            dissipated: ck.dissipated,
            dissipated_per_rank: ck.dissipated_per_rank.as_deref(),
        };
        m.restore(comm, &model, &layout, saved)?;
        m.counters.substeps = ck.substeps;
    }
    times.mechanics = clock.elapsed().as_secs_f64();
    let mech_setup = times.mechanics;

    let clock = Instant::now();
    let bt = BoundaryTets::new(&model.mesh);
    // Positions of moving bodies are updated at each detection (a copy of
    // the mesh only when something moves).
    let mut moved = (model.has_motion() || mech.is_some()).then(|| model.mesh.clone());
    if let (Some(ck), Some(mesh_now)) = (restart.as_ref(), moved.as_mut()) {
        match &ck.positions {
            Some(x) => mesh_now.nodes.copy_from_slice(x),
            None => model.positions_at(ck.time, &mut mesh_now.nodes),
        }
    }
    let mut contacts = if model.thermal_active {
        find_contacts(
            comm,
            &model,
            moved.as_ref().unwrap_or(&model.mesh),
            &layout,
            &bt,
        )
    } else {
        ContactSet::default()
    };
    let mut detections = u64::from(model.contact.is_some() && model.thermal_active);
    times.contact = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let solver = &sc.scenario.solver;
    let mut sys = if model.thermal_active {
        Some(ThermalSystem::new(
            petsc, &model, &layout, solver, &contacts,
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
    let detect_every = model.contact.as_ref().map_or(0, |c| c.every);
    if let (Some(ck), Some(s)) = (restart.as_ref(), sys.as_mut()) {
        let Some(t) = &ck.temperature else {
            return Err(Error::Model {
                path: opts
                    .restart
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                message: "the checkpoint has no temperatures, the scenario has a thermal problem"
                    .into(),
            });
        };
        let owned: Vec<f64> = layout.owned_nodes.iter().map(|&n| t[n as usize]).collect();
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
                    layout.owned_nodes.iter().map(|&n| v[n as usize]).collect()
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
    }
    if let (Some((m, _)), Some(s)) = (mech.as_mut(), sys.as_ref()) {
        let t = s.t.to_local_vec()?;
        m.set_temperatures(comm, &t, None);
    } else if let (Some((m, _)), Some(ck)) = (mech.as_mut(), restart.as_ref()) {
        if model.has_heating() {
            let t: Vec<f64> = layout
                .owned_nodes
                .iter()
                .map(|&n| model.prescribed_temperature(n, ck.time))
                .collect();
            m.set_temperatures(comm, &t, None);
        }
    }

    // Output: only now that the input is known good are files created.
    let clock = Instant::now();
    let stem = sc.output_stem();
    let dir = opts
        .output_dir
        .clone()
        .or_else(|| sc.scenario.output.directory.as_ref().map(|d| sc.resolve(d)))
        .unwrap_or_else(|| PathBuf::from("output").join(&stem));
    let made = if rank == 0 {
        create_output_dir(&dir)
    } else {
        Ok(())
    };
    agree(comm, made)?;
    // A restart into the directory of the series it continues keeps that
    // series up to the checkpoint and appends; anywhere else it starts one.
    let (h5_path, _) = crate::io::output_paths(&dir, &stem);
    let continues = restart.is_some() && {
        let mut exists = i32::from(rank == 0 && h5_path.is_file());
        comm.process_at_rank(0).broadcast_into(&mut exists);
        exists == 1
    };
    let keep_until = restart.as_ref().map_or(0.0, |c| c.time);
    let mut writer = if continues {
        reopen_writer(comm, &model, &layout, &dir, &stem, keep_until)?
    } else {
        open_writer(comm, &model, &layout, &dir, &stem)?
    };
    let history_path = dir.join(format!("{stem}_history.csv"));
    let mut header: Vec<String> = vec!["step".into(), "time".into()];
    if sys.is_some() {
        for h in [
            "stored_heat",
            "boundary_heat_in",
            "ksp_iterations",
            "contacts",
            "contact_area",
        ] {
            header.push(h.into());
        }
    }
    if mech.is_some() {
        for h in [
            "mech_time",
            "kinetic_energy",
            "strain_energy",
            "contact_energy",
            "dissipated_energy",
            "momentum_x",
            "momentum_y",
            "momentum_z",
            "mech_contacts",
            "mech_candidates",
        ] {
            header.push(h.into());
        }
    }
    // Per-body columns, or per scenario entry when there are many bodies.
    let groups = BodyGroups::new(&model);
    if sys.is_some() {
        for g in &groups.names {
            for s in ["min", "mean", "max"] {
                header.push(format!("{g}_{s}_T"));
            }
        }
    }
    let header_ref: Vec<&str> = header.iter().map(String::as_str).collect();
    let history = if continues {
        HistoryWriter::reopen(&history_path, &header_ref, 1, keep_until)
    } else {
        HistoryWriter::create(&history_path, &header_ref)
    };
    let mut history = agree(comm, history.map_err(Error::from))?;
    let stats = BodyStats::new(&model, &layout);
    let write_output = |sys: &mut Option<ThermalSystem>,
                        mech: &Option<(ExplicitDomain, u64)>,
                        writer: &mut TimeSeriesWriter,
                        history: &mut HistoryWriter,
                        contacts: &ContactSet,
                        step: u64|
     -> Result<()> {
        let time = step as f64 * model.dt;
        let t = match sys.as_ref() {
            Some(s) => Some(s.t.to_local_vec()?),
            None => None,
        };
        let mut node_fields: Vec<(&str, usize, Vec<f64>)> = Vec::new();
        let mut cell_fields: Vec<(&str, usize, Vec<f64>)> = Vec::new();
        if let Some(t) = &t {
            node_fields.push(("temperature", 1, t.clone()));
        }
        if let Some((m, _)) = mech {
            node_fields.push(("displacement", 3, m.displacement()));
            node_fields.push(("velocity", 3, m.velocity()));
            cell_fields.push(("stress", 6, m.stress_tensor6(&layout.owned_elems)));
        } else if model.has_motion() {
            // Rigid displacement of each owned node (ParaView: Warp By Vector).
            let u: Vec<f64> = layout
                .owned_nodes
                .iter()
                .flat_map(|&n| {
                    model.bodies[model.body_of_node(n)]
                        .velocity
                        .map(|v| v * time)
                })
                .collect();
            node_fields.push(("displacement", 3, u));
        }
        let nf: Vec<(&str, usize, &[f64])> = node_fields
            .iter()
            .map(|(n, c, v)| (*n, *c, v.as_slice()))
            .collect();
        let cf: Vec<(&str, usize, &[f64])> = cell_fields
            .iter()
            .map(|(n, c, v)| (*n, *c, v.as_slice()))
            .collect();
        writer.write_step(time, &nf, &cf)?;
        let mut row = vec![step as f64, time];
        if let Some(s) = sys.as_mut() {
            let e = s.energy()?;
            row.extend_from_slice(&[
                e.stored,
                e.boundary_in(),
                s.iterations as f64,
                contacts.all.len() as f64,
                contacts.total_area(),
            ]);
        }
        if let Some((m, n)) = mech {
            let st = m.state(comm);
            row.extend_from_slice(&[
                step as f64 * *n as f64 * m.dt,
                st.kinetic,
                st.strain,
                st.contact,
                st.dissipated,
                st.momentum[0],
                st.momentum[1],
                st.momentum[2],
                st.active_pairs as f64,
                st.candidate_pairs as f64,
            ]);
        }
        if let Some(t) = &t {
            for s in groups.reduce(&stats.compute(comm, t)) {
                row.extend_from_slice(&s);
            }
        }
        history.append(&row)?;
        Ok(())
    };
    if !continues {
        write_output(
            &mut sys,
            &mech,
            &mut writer,
            &mut history,
            &contacts,
            start_step,
        )?;
    }
    // Particle statistics (rank 0 keeps them; every rank takes part in the reductions).
    let mut report = sc.scenario.output.particles.as_ref().and_then(|p| {
        sys.as_ref()?;
        particle_report(&model, p)
    });
    let radial_steps: Vec<u64> = match &sc.scenario.output.particles {
        Some(p) if !p.radial_times.is_empty() => p
            .radial_times
            .iter()
            .map(|&t| (t / model.dt).round() as u64)
            .collect(),
        _ => (1..=4).map(|k| k * model.steps / 4).collect(),
    };
    let record = |sys: &Option<ThermalSystem>,
                  report: &mut Option<ParticleReport>,
                  step: u64|
     -> Result<()> {
        if let (Some(r), Some(s)) = (report.as_mut(), sys.as_ref()) {
            let t = s.t.to_local_vec()?;
            let st = stats.compute(comm, &t);
            let time = step as f64 * model.dt;
            r.record(time, &st);
            if radial_steps.contains(&step) {
                r.record_profile(time, &st);
            }
        }
        Ok(())
    };
    record(&sys, &mut report, start_step)?;
    times.output += clock.elapsed().as_secs_f64();
    let settle = model.mechanics.as_ref().and_then(|m| m.settle);
    // Mass of the free bodies (the settle criterion by rms speed).
    let free_mass: f64 = (0..model.mesh.tets.len())
        .filter(|&e| !model.bodies[model.mesh.body[e] as usize].is_held())
        .map(|e| model.material_of(e).density * model.mesh.element_volume(e))
        .sum();
    let mut peak_ke = restart.as_ref().map_or(0.0, |c| c.peak_kinetic);
    // A restart from a settled run's checkpoint is already done.
    let mut settled = restart
        .as_ref()
        .and_then(|c| c.settled.map(|ke| (c.step, c.time, ke)));
    let ck_every = sc.scenario.output.checkpoint_every;
    let ck_path = dir.join(format!("{stem}_checkpoint.h5"));
    let mut checkpoint = None;

    let bar = if opts.progress && rank == 0 {
        let b = indicatif::ProgressBar::new(model.steps);
        b.set_position(start_step);
        let what = match (sys.is_some(), mech.is_some()) {
            (true, true) => "thermo-mechanics",
            (false, true) => "mechanics",
            _ => "thermal",
        };
        b.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{spinner}} {what} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} steps ({{eta}})"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };
    let tick = (model.steps / 200).max(1);
    let check_every = 1000u64;
    let mut next_out = model
        .output_steps
        .iter()
        .copied()
        .filter(|&s| s > start_step)
        .peekable();
    let mut stepping = 0.0;
    let mut mech_time = 0.0;
    let mut step = start_step;
    let every_step = report.is_some() || settle.is_some();
    while step < model.steps && settled.is_none() {
        // Run uninterrupted until the next output, check or progress tick.
        let next_detect = step
            .checked_div(detect_every)
            .map_or(model.steps, |k| (k + 1) * detect_every);
        let target = [
            next_out.peek().copied().unwrap_or(model.steps),
            (step / check_every + 1) * check_every,
            (step / tick + 1) * tick,
            next_detect,
            if every_step { step + 1 } else { model.steps },
            step.checked_div(ck_every)
                .map_or(model.steps, |k| (k + 1) * ck_every),
        ]
        .into_iter()
        .min()
        .unwrap_or(model.steps)
        .min(model.steps);
        while step < target {
            // Seed 000 sec 3.4: contact detection → thermal step → mechanics substeps.
            let clock = Instant::now();
            if let Some(s) = sys.as_mut() {
                s.step()?;
            }
            stepping += clock.elapsed().as_secs_f64();
            if let Some((m, n)) = mech.as_mut() {
                let clock = Instant::now();
                let span = *n as f64 * m.dt;
                if let Some(s) = sys.as_ref() {
                    let t = s.t.to_local_vec()?;
                    m.set_temperatures(comm, &t, Some(span));
                } else if model.has_heating() {
                    // The ramp's value at the end of this step, reached over the substeps.
                    let time = (step + 1) as f64 * model.dt;
                    let t: Vec<f64> = layout
                        .owned_nodes
                        .iter()
                        .map(|&n| model.prescribed_temperature(n, time))
                        .collect();
                    m.set_temperatures(comm, &t, Some(span));
                }
                m.advance(comm, &model, &layout, *n)?;
                mech_time += clock.elapsed().as_secs_f64();
            }
            step += 1;
        }
        if let Some(b) = &bar {
            b.set_position(step);
        }
        if sys.is_some()
            && detect_every > 0
            && step.is_multiple_of(detect_every)
            && step < model.steps
        {
            // Rebuild the operator only when the contact set or its areas changed.
            let clock = Instant::now();
            if let Some(mesh_now) = moved.as_mut() {
                match mech.as_mut() {
                    Some((m, _)) => {
                        m.gather_positions(comm);
                        mesh_now.nodes.copy_from_slice(m.positions());
                    }
                    None => model.positions_at(step as f64 * model.dt, &mut mesh_now.nodes),
                }
            }
            let mesh_now = moved.as_ref().unwrap_or(&model.mesh);
            let found = find_contacts(comm, &model, mesh_now, &layout, &bt);
            detections += 1;
            times.contact += clock.elapsed().as_secs_f64();
            if !found.same_as(&contacts, 1e-12) {
                let clock = Instant::now();
                contacts = found;
                if let Some(s) = sys.as_mut() {
                    s.rebuild(petsc, &model, &layout, solver, &contacts)?;
                }
                times.assembly += clock.elapsed().as_secs_f64();
            }
        }
        if let Some(s) = sys.as_ref() {
            if step.is_multiple_of(check_every) || Some(step) == next_out.peek().copied() {
                check_finite(comm, s, &layout, step, model.dt)?;
            }
        }
        if let (Some(st), Some((m, _))) = (settle, mech.as_ref()) {
            let ke = m.state(comm).kinetic;
            peak_ke = f64::max(peak_ke, ke);
            let time = step as f64 * model.dt;
            // Settled when below any threshold given.
            let threshold = st
                .kinetic_energy
                .unwrap_or(0.0)
                .max(st.relative.map_or(0.0, |r| r * peak_ke))
                .max(st.rms_speed.map_or(0.0, |v| 0.5 * free_mass * v * v));
            if time >= st.after && peak_ke > 0.0 && ke < threshold {
                settled = Some((step, time, ke));
            }
        }
        let clock = Instant::now();
        record(&sys, &mut report, step)?;
        if Some(step) == next_out.peek().copied() || (settled.is_some() && step < model.steps) {
            next_out.next();
            write_output(&mut sys, &mech, &mut writer, &mut history, &contacts, step)?;
        }
        if ck_every > 0 && step.is_multiple_of(ck_every) && settled.is_none() {
            save_checkpoint(
                comm, &model, &layout, &mut sys, &mut mech, step, peak_ke, &contacts, None,
                &ck_path,
            )?;
            checkpoint = Some(ck_path.clone());
        }
        times.output += clock.elapsed().as_secs_f64();
        if settled.is_some() {
            break;
        }
    }
    if sc.scenario.output.checkpoint || settled.is_some() && ck_every > 0 {
        let clock = Instant::now();
        save_checkpoint(
            comm,
            &model,
            &layout,
            &mut sys,
            &mut mech,
            step,
            peak_ke,
            &contacts,
            settled.map(|s| s.2),
            &ck_path,
        )?;
        checkpoint = Some(ck_path.clone());
        times.output += clock.elapsed().as_secs_f64();
    }
    let mut particle_files = Vec::new();
    if let Some(r) = &report {
        let written = if rank == 0 {
            r.write(&dir, &stem).map_err(Error::from)
        } else {
            Ok(Vec::new())
        };
        particle_files = agree(comm, written)?;
    }
    if model.thermal_active && model.contact.is_some() {
        let path = dir.join(format!("{stem}_body_contacts.csv"));
        let written = if rank == 0 {
            write_body_contacts(&model, &contacts, &path)
        } else {
            Ok(())
        };
        agree(comm, written)?;
        particle_files.push(path);
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    times.stepping = stepping;
    times.mechanics += mech_time;
    let energy = match sys.as_mut() {
        Some(s) => s.energy()?,
        None => EnergyAccount::default(),
    };
    let (h5, xdmf) = crate::io::output_paths(&dir, &stem);
    writer.close()?;

    let mut peak = 0u64;
    comm.all_reduce_into(&peak_rss(), &mut peak, SystemOperation::max());
    let mut tmax = [0.0; 9];
    let (detect_time, mut mech_counts) = match mech.as_ref() {
        Some((m, _)) => (
            m.counters.detect_time,
            [
                m.counters.element_updates as f64,
                m.counters.pair_updates as f64,
                m.counters.exact_overlaps as f64,
            ],
        ),
        None => (0.0, [0.0; 3]),
    };
    let local = [
        times.model,
        times.partition,
        times.assembly,
        times.stepping,
        times.output,
        times.contact,
        times.mechanics,
        detect_time,
        mech_setup,
    ];
    comm.all_reduce_into(&local[..], &mut tmax[..], SystemOperation::max());
    let mine = mech_counts;
    comm.all_reduce_into(&mine[..], &mut mech_counts[..], SystemOperation::sum());
    let times = PhaseTimes {
        model: tmax[0],
        partition: tmax[1],
        assembly: tmax[2],
        stepping: tmax[3],
        output: tmax[4],
        contact: tmax[5],
        mechanics: tmax[6],
        mechanics_detect: tmax[7],
        mechanics_setup: tmax[8],
    };
    let mechanics = mech.as_ref().map(|(m, n)| MechanicsSummary {
        dt: m.dt,
        substeps_per_step: *n,
        substeps: m.counters.substeps,
        detections: m.counters.detections,
        element_updates: mech_counts[0] as u64,
        pair_updates: mech_counts[1] as u64,
        exact_overlaps: mech_counts[2] as u64,
        margin: m.min_margin(),
    });
    Ok(RunSummary {
        ranks: layout.size,
        nodes: model.mesh.nodes.len(),
        elements: model.mesh.tets.len(),
        steps: step - start_step,
        ksp_iterations: sys.as_ref().map_or(0, |s| s.iterations),
        start_step,
        settled,
        checkpoint,
        particle_files,
        heat: sys.is_some(),
        solver: sys
            .as_ref()
            .map_or("none (no thermal problem)".into(), |s| {
                s.solver_name.clone()
            }),
        times,
        output_dir: dir,
        h5,
        xdmf,
        history: history_path,
        energy,
        peak_memory: peak,
        contacts: (contacts.all.len(), contacts.total_area()),
        detections,
        assemblies: sys.as_ref().map_or(0, |s| s.assemblies),
        mechanics,
    })
}

/// This rank's part of the output mesh: owned node coordinates, and cells
/// in the global (PETSc) node numbering.
fn mesh_rows(model: &Model, layout: &Layout) -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let coords = layout
        .owned_nodes
        .iter()
        .map(|&n| model.mesh.nodes[n as usize])
        .collect();
    let cells = layout
        .owned_elems
        .iter()
        .map(|&e| model.mesh.tets[e as usize].map(|n| layout.global_of[n as usize]))
        .collect();
    (coords, cells)
}

/// Collective. Reopen the series in `dir` to continue it after the
/// checkpoint at `keep_until` (same mesh and partition, checked).
fn reopen_writer(
    comm: &SimpleCommunicator,
    model: &Model,
    layout: &Layout,
    dir: &Path,
    stem: &str,
    keep_until: f64,
) -> Result<TimeSeriesWriter> {
    let (coords, cells) = mesh_rows(model, layout);
    let ncells = cells.len() as u64;
    let mut cell_offset = 0u64;
    comm.exclusive_scan_into(&ncells, &mut cell_offset, SystemOperation::sum());
    if comm.rank() == 0 {
        cell_offset = 0;
    }
    let part = MeshPart {
        global_nodes: layout.num_global() as u64,
        node_offset: layout.owned_range().0 as u64,
        coords: &coords,
        global_cells: model.mesh.tets.len() as u64,
        cell_offset,
        cells: &cells,
    };
    let node_id: Vec<i32> = layout.owned_nodes.iter().map(|&n| n as i32).collect();
    Ok(TimeSeriesWriter::reopen(
        comm, dir, stem, &part, &node_id, keep_until,
    )?)
}

fn open_writer(
    comm: &SimpleCommunicator,
    model: &Model,
    layout: &Layout,
    dir: &Path,
    stem: &str,
) -> Result<TimeSeriesWriter> {
    let (coords, cells) = mesh_rows(model, layout);
    let ncells = cells.len() as u64;
    let mut cell_offset = 0u64;
    comm.exclusive_scan_into(&ncells, &mut cell_offset, SystemOperation::sum());
    if comm.rank() == 0 {
        cell_offset = 0;
    }
    let part = MeshPart {
        global_nodes: layout.num_global() as u64,
        node_offset: layout.owned_range().0 as u64,
        coords: &coords,
        global_cells: model.mesh.tets.len() as u64,
        cell_offset,
        cells: &cells,
    };
    let mut w = TimeSeriesWriter::create(comm, dir, stem, &part)?;
    let body_node: Vec<i32> = layout
        .owned_nodes
        .iter()
        .map(|&n| model.body_of_node(n) as i32)
        .collect();
    let node_id: Vec<i32> = layout.owned_nodes.iter().map(|&n| n as i32).collect();
    let body_cell: Vec<i32> = layout
        .owned_elems
        .iter()
        .map(|&e| model.mesh.body[e as usize] as i32)
        .collect();
    let rank_cell: Vec<i32> = vec![comm.rank(); cells.len()];
    w.write_static_node_field_i32("body", &body_node)?;
    w.write_static_node_field_i32("node_id", &node_id)?;
    w.write_static_cell_field_i32("body", &body_cell)?;
    w.write_static_cell_field_i32("rank", &rank_cell)?;
    Ok(w)
}

fn check_finite(
    comm: &SimpleCommunicator,
    sys: &ThermalSystem,
    layout: &Layout,
    step: u64,
    dt: f64,
) -> Result<()> {
    let bad = sys.first_non_finite()?;
    if bad.is_none() {
        return Ok(());
    }
    let local = bad
        .and_then(|i| layout.owned_nodes.get(i))
        .map_or(u64::MAX, |&n| n as u64);
    let mut node = u64::MAX;
    comm.all_reduce_into(&local, &mut node, SystemOperation::min());
    Err(Error::NonFinite {
        step,
        time: step as f64 * dt,
        node: node as usize,
    })
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

/// Collective. Gather the state and write the checkpoint from rank 0.
#[allow(clippy::too_many_arguments)]
fn save_checkpoint(
    comm: &SimpleCommunicator,
    model: &Model,
    layout: &Layout,
    sys: &mut Option<ThermalSystem>,
    mech: &mut Option<(ExplicitDomain, u64)>,
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
        thermal_contacts: contacts.all.len() as u64,
        ..Default::default()
    };
    if let Some((m, _)) = mech.as_mut() {
        m.gather_positions(comm);
        ck.positions = Some(m.positions().to_vec());
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
                .map(|n| all[layout.global_of[n] as usize])
                .collect(),
        );
        ck.ksp_iterations = s.iterations;
        let a = s.account_state()?;
        let per_node = |owned: &[f64]| -> Vec<f64> {
            let all = crate::parallel::all_gather_f64(comm, owned);
            (0..model.mesh.nodes.len())
                .map(|n| all[layout.global_of[n] as usize])
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

/// The particles of `[output.particles]`: their bodies, volumes and
/// distances from the axis.
fn particle_report(
    model: &Model,
    p: &crate::scenario::ParticleOutputSpec,
) -> Option<ParticleReport> {
    let bodies: Vec<usize> = (0..model.bodies.len())
        .filter(|&b| model.bodies[b].template == p.template)
        .collect();
    if bodies.is_empty() {
        return None;
    }
    let mut volumes = Vec::new();
    let mut radii = Vec::new();
    for &b in &bodies {
        let (e0, e1) = model.bodies[b].elem_range;
        let (mut v, mut c) = (0.0, [0.0; 3]);
        for e in e0 as usize..e1 as usize {
            let ve = model.mesh.element_volume(e);
            let x = model.mesh.element_coords(e);
            v += ve;
            for d in 0..3 {
                c[d] += ve * (x[0][d] + x[1][d] + x[2][d] + x[3][d]) / 4.0;
            }
        }
        volumes.push(v);
        radii.push((c[0] / v - p.axis[0]).hypot(c[1] / v - p.axis[1]));
    }
    Some(ParticleReport::new(bodies, volumes, radii, p.radial_bins))
}

/// History columns per body, or per scenario entry (template) when there
/// are more than [`BodyGroups::MAX_BODY_COLUMNS`] bodies.
struct BodyGroups {
    names: Vec<String>,
    /// Group of every body, and each body's volume.
    group: Vec<usize>,
    volume: Vec<f64>,
}

impl BodyGroups {
    const MAX_BODY_COLUMNS: usize = 16;

    fn new(model: &Model) -> BodyGroups {
        let volume: Vec<f64> = model
            .bodies
            .iter()
            .map(|b| {
                (b.elem_range.0..b.elem_range.1)
                    .map(|e| model.mesh.element_volume(e as usize))
                    .sum()
            })
            .collect();
        if model.bodies.len() <= Self::MAX_BODY_COLUMNS {
            return BodyGroups {
                names: model.bodies.iter().map(|b| b.name.clone()).collect(),
                group: (0..model.bodies.len()).collect(),
                volume,
            };
        }
        let mut names: Vec<String> = Vec::new();
        let group = model
            .bodies
            .iter()
            .map(|b| match names.iter().position(|n| *n == b.template) {
                Some(i) => i,
                None => {
                    names.push(b.template.clone());
                    names.len() - 1
                }
            })
            .collect();
        BodyGroups {
            names,
            group,
            volume,
        }
    }

    /// (min, volume-weighted mean, max) per group from per-body values.
    fn reduce(&self, per_body: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let ng = self.names.len();
        let mut out = vec![[f64::INFINITY, 0.0, f64::NEG_INFINITY]; ng];
        let mut vol = vec![0.0; ng];
        for (b, s) in per_body.iter().enumerate() {
            let g = self.group[b];
            out[g][0] = out[g][0].min(s[0]);
            out[g][1] += self.volume[b] * s[1];
            out[g][2] = out[g][2].max(s[2]);
            vol[g] += self.volume[b];
        }
        for (o, v) in out.iter_mut().zip(vol) {
            o[1] /= v;
        }
        out
    }
}

/// Contact area summed per pair of bodies: `body_a,body_b,name_a,name_b,pairs,area`.
fn write_body_contacts(model: &Model, contacts: &ContactSet, path: &Path) -> Result<()> {
    let mut per: std::collections::BTreeMap<(u32, u32), (u64, f64)> = Default::default();
    for p in &contacts.all {
        let a = model.mesh.body[p.target as usize];
        let b = model.mesh.body[p.contactor as usize];
        let e = per.entry((a.min(b), a.max(b))).or_default();
        e.0 += 1;
        e.1 += p.area();
    }
    let mut text = String::from("body_a,body_b,name_a,name_b,pairs,area\n");
    for ((a, b), (n, s)) in per {
        text.push_str(&format!(
            "{a},{b},{},{},{n},{s:.12e}\n",
            model.bodies[a as usize].name, model.bodies[b as usize].name
        ));
    }
    std::fs::write(path, text).map_err(|source| Error::File {
        path: path.display().to_string(),
        source,
    })
}

/// Create the output directory (and its parents), saying that the directory
/// is the problem when a file stands in its place or in a parent's.
fn create_output_dir(dir: &Path) -> Result<()> {
    let bad = |message: String| Error::OutputDir {
        path: dir.display().to_string(),
        message,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(bad(
            "is an existing file, not a directory; name a directory with --output or output.directory"
                .into(),
        ));
    }
    if let Some(file) = dir.ancestors().skip(1).find(|a| a.is_file()) {
        return Err(bad(format!(
            "cannot be created: {} is a file, not a directory",
            file.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| bad(format!("cannot be created: {e}")))
}
