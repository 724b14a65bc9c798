//! The time loop: model → stages → steps from stop to stop → summary.
//!
//! Collective: every function here is called by all ranks. Errors that one
//! rank finds alone (an output directory it cannot create) are agreed on
//! before the next collective call so no rank waits for a failed one.
//!
//! [`run`] reads like a textbook driver: `Stages::set_up` ([`setup`]:
//! part, mechanics domain, contacts, thermal system, each restored from a
//! checkpoint on a restart), `start_output` ([`output`]), then `advance` to
//! each stop the [`schedule`] names and `stop` there (detection, checks,
//! [`settle`], output, [`checkpoint`]), and `finish` with the [`summary`].

mod checkpoint;
mod hex_output;
mod joint_migration;
mod joint_output;
mod output;
mod particle_checkpoint;
mod particle_output;
mod rebalance;
mod schedule;
mod settle;
mod setup;
mod sphere_output;
mod status_output;
mod summary;

use std::path::{Path, PathBuf};
use std::time::Instant;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::io::checkpoint::CheckpointHead;
use crate::model::Model;
use crate::parallel::Part;
use crate::petsc::Petsc;
use crate::scenario::LoadedScenario;
use crate::thermal::ThermalSystem;

use checkpoint::Restart;
use output::Output;
use rebalance::Balance;
use schedule::Schedule;
use settle::Settling;
use setup::Contacts;
pub use sphere_output::SphereHeatAccount;
pub use status_output::face_status;
pub use summary::{
    allocator_settings, peak_rss, release_fragmented_memory, release_free_memory, trace_memory,
    BalanceSummary, MechanicsSummary, PhaseTimes, RunSummary, Settled,
};

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

/// The explicit mechanics of a run: its domain on this rank, and how many
/// explicit substeps it takes per thermal step.
struct Mechanics {
    /// This rank's subdomain.
    domain: ExplicitDomain,
    /// Substeps per thermal step.
    substeps_per_step: u64,
}

/// Collective. Run a scenario to the end: the model, the stages set up
/// on it, the steps from stop to stop (detection, checks, settle check,
/// output, checkpoint at each as the schedule says), then the summary.
pub fn run(
    petsc: &Petsc,
    comm: &SimpleCommunicator,
    sc: &LoadedScenario,
    opts: &RunOptions,
) -> Result<RunSummary> {
    let clock = Instant::now();
    let model = Model::from_scenario_on(sc, comm.size() as usize)?;
    let times = PhaseTimes {
        model: clock.elapsed().as_secs_f64(),
        ..PhaseTimes::default()
    };
    let restart = match &opts.restart {
        Some(p) => Some(Restart::read(p, &model)?),
        None => None,
    };
    let mut st = Stages::set_up(petsc, comm, &model, restart.as_ref(), opts, times)?;
    let ck = restart.as_ref().map(|r| &r.file.head);
    // Output: only now that the input is known good are files created.
    // The set-up's holes go back first: the first output's blocks would
    // otherwise come on top of them (the N = 2000 heat-up's peak on 8 ranks).
    release_free_memory();
    let mut out = st.start_output(opts.output_dir.as_deref(), ck)?;
    release_free_memory();
    summary::trace_memory(comm.rank(), "output");
    let show = opts.progress && comm.rank() == 0;
    let mut at = Position::new(&st, ck, &out, show);
    while let Some(target) = at.next_stop() {
        st.advance(at.step, target)?;
        if tracing::enabled!(target: "memory", tracing::Level::DEBUG) {
            summary::trace_memory(comm.rank(), &format!("advanced to step {target}"));
        }
        at.reached(target);
        st.stop(&mut at, &mut out)?;
        if tracing::enabled!(target: "memory", tracing::Level::DEBUG) {
            summary::trace_memory(comm.rank(), &format!("stop at step {}", at.step));
        }
        trace_held(comm.rank(), st.mech.as_ref());
    }
    st.finish(at, out)
}

/// Where the time loop stands: the step, the schedule of stops, the
/// settle criterion, the progress bar and the checkpoint written.
struct Position {
    step: u64,
    start_step: u64,
    steps: u64,
    schedule: Schedule,
    settling: Settling,
    bar: Option<indicatif::ProgressBar>,
    /// Where checkpoints go, and the last one written.
    checkpoint_path: PathBuf,
    checkpoint: Option<PathBuf>,
}

impl Position {
    /// At the start (the checkpoint's step on a restart).
    fn new(st: &Stages, ck: Option<&CheckpointHead>, out: &Output, show: bool) -> Position {
        let (model, heat, mechanics) = (st.model, st.sys.is_some(), st.mech.is_some());
        let start_step = ck.map_or(0, |c| c.step);
        let settling = Settling::new(st.comm, model, &st.part, ck);
        let schedule = Schedule::new(
            model.steps,
            &model.output_steps,
            start_step,
            model.contact.as_ref().map_or(0, |c| c.every),
            model.output.checkpoint_every,
            out.every_step() || settling.spec.is_some(),
        )
        .with_history_every(model.output.history_every);
        Position {
            step: start_step,
            start_step,
            steps: model.steps,
            schedule,
            settling,
            bar: output::progress_bar(show, model.steps, start_step, heat, mechanics),
            checkpoint_path: out.dir.join(format!("{}_checkpoint.h5", out.stem)),
            checkpoint: None,
        }
    }

    /// The step to run to without a stop; None when the run is over
    /// (the last step, or settled).
    fn next_stop(&self) -> Option<u64> {
        (self.step < self.steps && self.settling.settled.is_none())
            .then(|| self.schedule.next_stop(self.step))
    }

    /// The steps up to `step` are taken.
    fn reached(&mut self, step: u64) {
        self.step = step;
        if let Some(b) = &self.bar {
            b.set_position(step);
        }
    }
}

/// The stages on this rank, between set-up and summary: what the time
/// loop advances, detects, checks and writes.
struct Stages<'a, 'p> {
    petsc: &'p Petsc,
    comm: &'a SimpleCommunicator,
    model: &'a Model,
    part: Part,
    sys: Option<ThermalSystem<'p>>,
    mech: Option<Mechanics>,
    contacts: Contacts,
    times: PhaseTimes,
    /// Repartitions as the bodies move.
    balance: Balance,
    /// The free spheres' series (issue 21), once the output is open.
    spheres_out: Option<sphere_output::SphereOutput>,
}

impl<'a, 'p> Stages<'a, 'p> {
    /// Collective. The stages set up on the model: the partition, the
    /// mechanics domain (first: its set-up checks the time step before
    /// any other work), the first contact detection, the thermal system,
    /// and the mechanics' first temperatures; each at the checkpoint's
    /// state on a restart.
    fn set_up(
        petsc: &'p Petsc,
        comm: &'a SimpleCommunicator,
        model: &'a Model,
        restart: Option<&Restart>,
        opts: &RunOptions,
        mut times: PhaseTimes,
    ) -> Result<Self> {
        let rank = comm.rank();
        summary::trace_memory(rank, "model");
        let mut part = setup::partition(comm, model, restart, &mut times)?;
        summary::trace_memory(rank, "part");
        let ck = restart.map(|r| &r.file.head);
        let mut mech = setup::mechanics(comm, model, &part, restart, &mut times)?;
        if let (Some(r), Some(m)) = (restart, mech.as_mut()) {
            // The joints' histories; the thermal rows of the broken ones split.
            checkpoint::restore_joints(comm, model, r, m)?;
            particle_checkpoint::restore_motion(comm, model, r, m)?;
            checkpoint::restore_spheres(comm, r, m)?;
            if model.has_joints() {
                let broken = m.domain.take_broken_joints();
                part.renumber_rows(comm, model, &broken);
                m.domain.renumber_rows(&part);
            }
        }
        summary::trace_memory(rank, "mechanics");
        trace_held(rank, mech.as_ref());
        let mut contacts = Contacts::new(comm, model, &part, restart, mech.as_mut(), true)?;
        summary::trace_memory(rank, "contacts");
        let mut balance = Balance::new(comm, model, &part);
        rebalance::set_up_thermal_balance(
            comm,
            model,
            restart,
            &mut part,
            &mut contacts,
            mech.as_mut(),
            &mut balance,
        )?;
        tracing::debug!(target: "memory", rank, elements = part.elem_gid.len(), nodes = part.node_gid.len(), owned = part.n_owned, thermal_pairs = contacts.set.local.len(), whole_bodies = part.whole_bodies.len(), joints = part.joints.len());
        let sys = setup::thermal(
            petsc,
            comm,
            model,
            &part,
            &contacts.set,
            opts,
            restart,
            &mut times,
        )?;
        setup::couple_temperatures(comm, model, &part, sys.as_ref(), mech.as_mut(), ck)?;
        summary::trace_memory(rank, "thermal");
        Ok(Stages {
            petsc,
            comm,
            model,
            part,
            sys,
            mech,
            contacts,
            times,
            balance,
            spheres_out: None,
        })
    }
}

impl Stages<'_, '_> {
    /// Collective. Open the output (continued after the checkpoint on a
    /// restart in place) and write the start: its fields unless the
    /// series continues, and its particle statistics.
    fn start_output(&mut self, dir: Option<&Path>, ck: Option<&CheckpointHead>) -> Result<Output> {
        let clock = Instant::now();
        let start_step = ck.map_or(0, |c| c.step);
        let mut out = self.open_output(dir, ck)?;
        if let Some(rows) = self.mech.as_ref().and_then(|m| m.domain.sphere_rows()) {
            let so = sphere_output::SphereOutput::open(self.comm, &rows, &out.dir, &out.stem)?;
            self.spheres_out = Some(so);
        }
        if !out.continues {
            self.write(&mut out, start_step)?;
        }
        self.record(&mut out, start_step)?;
        self.times.output += clock.elapsed().as_secs_f64();
        Ok(out)
    }

    /// Collective. At a stop: re-detect contacts and check the
    /// temperatures when due, check whether the bodies settled, record the
    /// particle statistics, write the fields when due, repartition when
    /// due and needed, and write the checkpoint when due.
    fn stop(&mut self, at: &mut Position, out: &mut Output) -> Result<()> {
        let step = at.step;
        let balance_step = rebalance::finds_contacts_again(self.model, step);
        if self.sys.is_some() && (at.schedule.is_detection(step) || balance_step) {
            self.redetect(step)?;
        }
        if at.schedule.is_finite_check(step) {
            self.check_finite(step)?;
        }
        if let Some(m) = &self.mech {
            at.settling.check(self.comm, m, step, self.model.dt);
        }
        let settled = at.settling.settled.is_some();
        let clock = Instant::now();
        self.record(out, step)?;
        if at.schedule.is_output(step) || (settled && step < self.model.steps) {
            at.schedule.output_written();
            // The substeps' message buffers go, and the free pages go
            // back, before the output allocates its blocks.
            if let Some(m) = self.mech.as_mut() {
                m.domain.release_message_buffers();
            }
            release_free_memory();
            summary::trace_memory(self.comm.rank(), "trimmed for output");
            self.write(out, step)?;
        } else if at.schedule.is_history(step) {
            self.write_history(out, step)?;
        }
        self.times.output += clock.elapsed().as_secs_f64();
        if !settled && step < self.model.steps {
            self.rebalance(step, out)?;
        }
        if at.schedule.is_checkpoint(step) && !settled {
            let clock = Instant::now();
            self.save(step, at.settling.peak_kinetic, None, &at.checkpoint_path)?;
            at.checkpoint = Some(at.checkpoint_path.clone());
            self.times.output += clock.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// Collective. The final checkpoint (when asked for, or when a
    /// deposition settled), the particle statistics, and the summary.
    fn finish(mut self, at: Position, out: Output) -> Result<RunSummary> {
        let settled = at.settling.settled;
        let mut checkpoint = at.checkpoint;
        let output = &self.model.output;
        if output.checkpoint || settled.is_some() && output.checkpoint_every > 0 {
            let clock = Instant::now();
            let kinetic = settled.map(|s| s.kinetic);
            self.save(
                at.step,
                at.settling.peak_kinetic,
                kinetic,
                &at.checkpoint_path,
            )?;
            checkpoint = Some(at.checkpoint_path);
            self.times.output += clock.elapsed().as_secs_f64();
        }
        let mut particle_files = out.finish(self.comm, self.model, &self.contacts.set)?;
        if let (Some(m), true) = (self.mech.as_ref(), out.joints.is_some()) {
            let path = out.dir.join(format!("{}_cracks.csv", out.stem));
            particle_files.extend(joint_output::JointOutput::write_body_table(
                self.comm, self.model, m, &path,
            )?);
        }
        if let Some(so) = self.spheres_out.take() {
            particle_files.push(so.xdmf.clone());
            so.close()?;
        }
        if let Some(b) = at.bar {
            b.finish_and_clear();
        }
        self.summary(
            out,
            at.start_step,
            at.step,
            settled,
            checkpoint,
            particle_files,
        )
    }

    /// Collective. Open the output files.
    fn open_output(&self, dir: Option<&Path>, restart: Option<&CheckpointHead>) -> Result<Output> {
        let (heat, mechanics) = (self.sys.is_some(), self.mech.is_some());
        let mut out = Output::open(
            self.comm, self.model, &self.part, dir, heat, mechanics, restart,
        )?;
        if let Some(m) = self.mech.as_ref() {
            let continue_after = restart.filter(|_| out.continues).map(|c| c.time);
            out.joints = joint_output::JointOutput::open(
                self.comm,
                self.model,
                &out.dir,
                &out.stem,
                m,
                continue_after,
            )?;
        }
        let continue_after = restart.filter(|_| out.continues).map(|c| c.time);
        out.particles = particle_output::ParticleOutput::open(
            self.comm,
            self.model,
            &self.part,
            &out.dir,
            &out.stem,
            self.mech.as_ref(),
            continue_after,
        )?;
        Ok(out)
    }

    /// Collective. Write the fields and the history row of `step`.
    fn write(&mut self, out: &mut Output, step: u64) -> Result<()> {
        let (mech, contacts) = (self.mech.as_ref(), &self.contacts.set);
        out.write(
            self.comm,
            self.model,
            &self.part,
            &mut self.sys,
            mech,
            contacts,
            step,
        )?;
        let rows = self.mech.as_ref().and_then(|m| m.domain.sphere_rows());
        if let (Some(so), Some(rows)) = (self.spheres_out.as_mut(), rows) {
            so.write(self.comm, step as f64 * self.model.dt, &rows)?;
        }
        Ok(())
    }

    /// Collective. Write the history row of `step` alone.
    fn write_history(&mut self, out: &mut Output, step: u64) -> Result<()> {
        let (comm, model, part) = (self.comm, self.model, &self.part);
        let (mech, contacts) = (self.mech.as_ref(), &self.contacts.set);
        out.history_row(comm, model, part, &mut self.sys, mech, contacts, step)
    }

    /// Collective. Record the particle statistics of `step`.
    fn record(&self, out: &mut Output, step: u64) -> Result<()> {
        out.record(self.comm, self.model, &self.part, &self.sys, step)
    }

    /// Collective. Write the checkpoint of `step`.
    fn save(
        &mut self,
        step: u64,
        peak_kinetic: f64,
        settled: Option<f64>,
        path: &Path,
    ) -> Result<()> {
        checkpoint::save_checkpoint(
            self.comm,
            self.model,
            &self.part,
            &mut self.sys,
            self.mech.as_mut(),
            step,
            peak_kinetic,
            &self.contacts.set,
            settled,
            path,
        )
    }

    /// Take the steps from `step` to `target`: each a thermal step, then
    /// the mechanics substeps at the step's temperatures.
    fn advance(&mut self, mut step: u64, target: u64) -> Result<()> {
        let (comm, model) = (self.comm, self.model);
        while step < target {
            let part = &self.part;
            // Seed 000 sec 3.4: contact detection → thermal step → mechanics substeps.
            let clock = Instant::now();
            if let Some(s) = self.sys.as_mut() {
                s.step()?;
            }
            self.times.stepping += clock.elapsed().as_secs_f64();
            if let Some(Mechanics {
                domain: m,
                substeps_per_step: n,
            }) = self.mech.as_mut()
            {
                let clock = Instant::now();
                let span = *n as f64 * m.dt;
                // The ramp's value at the end of this step, reached over the substeps.
                let time = (step + 1) as f64 * model.dt;
                if let Some(s) = self.sys.as_ref() {
                    let t = s.node_temperatures(part)?;
                    m.set_temperatures(comm, &t, Some(span));
                } else if model.has_heating() {
                    let t: Vec<f64> = part
                        .owned_gids()
                        .iter()
                        .zip(&part.bc.initial_t)
                        .map(|(&n, &t0)| model.prescribed_temperature(n, t0, time))
                        .collect();
                    m.set_temperatures(comm, &t, Some(span));
                }
                let sys = self.sys.as_ref();
                particle_output::couple_particle_temperatures(comm, model, part, sys, time, m)?;
                m.advance(comm, *n)?;
                // Issue 20: the friction's heat, released over the next thermal step.
                if let Some(s) = self.sys.as_mut() {
                    if model
                        .contact
                        .as_ref()
                        .is_some_and(|c| c.friction_heating.is_some())
                    {
                        s.add_heat(&m.take_friction_heat())?;
                    }
                    // Issue 21: the free spheres' heat from the faces, released likewise.
                    if let Some((q, gdt)) = m.take_sphere_node_heat() {
                        s.add_sphere_heat(comm, part, &q, &gdt)?;
                    }
                }
                self.times.mechanics += clock.elapsed().as_secs_f64();
            }
            step += 1;
            if self.sys.is_some() && model.has_joints() {
                self.follow_cracks(step)?;
            }
        }
        Ok(())
    }

    /// Collective. When joints broke in a run with a thermal problem: the
    /// copies of a node no longer tied by intact joints get rows of their
    /// own, the contacts are found again on the new rows, and the thermal
    /// system is rebuilt, the nodes keeping their temperatures (issue 19:
    /// heat crosses a broken joint only through the contact model). When
    /// none broke but cracks closed or opened, the contacts are found
    /// again (a crack conducts while its faces touch).
    fn follow_cracks(&mut self, step: u64) -> Result<()> {
        let comm = self.comm;
        let Some(Mechanics { domain: m, .. }) = self.mech.as_mut() else {
            return Ok(());
        };
        let mine = [
            m.joints_broken_since_rows() as u64,
            u64::from(m.crack_contacts_changed() && self.model.contact.is_some()),
        ];
        let mut any = [0u64; 2];
        comm.all_reduce_into(&mine[..], &mut any[..], SystemOperation::sum());
        if any[0] == 0 {
            if any[1] > 0 {
                self.redetect(step)?;
            }
            return Ok(());
        }
        let clock = Instant::now();
        let Some(sys) = self.sys.as_mut() else {
            return Ok(());
        };
        let t_nodes = sys.node_temperatures(&self.part)?;
        let broken = m.take_broken_joints();
        self.part.renumber_rows(comm, self.model, &broken);
        m.renumber_rows(&self.part);
        self.contacts.refind(comm, self.model, self.mech.as_mut())?;
        if let Some(s) = self.sys.as_mut() {
            s.rebuild_rows(
                self.petsc,
                comm,
                self.model,
                &self.part,
                &self.model.solver,
                &self.contacts.set,
                &t_nodes,
            )?;
        }
        self.times.assembly += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// Collective. Detect contacts again; rebuild the operator only when
    /// the contact set or its areas changed.
    fn redetect(&mut self, step: u64) -> Result<()> {
        let (comm, model, part) = (self.comm, self.model, &self.part);
        let found = self
            .contacts
            .redetect(comm, model, part, self.mech.as_mut(), step)?;
        if let Some(found) = found {
            let clock = Instant::now();
            self.contacts.set = found;
            if let Some(s) = self.sys.as_mut() {
                s.rebuild(
                    self.petsc,
                    comm,
                    model,
                    part,
                    &model.solver,
                    &self.contacts.set,
                )?;
            }
            self.times.assembly += clock.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// Collective. Fail naming a node whose temperature is not finite.
    fn check_finite(&self, step: u64) -> Result<()> {
        match &self.sys {
            Some(s) => check_finite(self.comm, s, &self.part, step, self.model.dt),
            None => Ok(()),
        }
    }
}

fn check_finite(
    comm: &SimpleCommunicator,
    sys: &ThermalSystem,
    part: &Part,
    step: u64,
    dt: f64,
) -> Result<()> {
    let bad = sys.first_non_finite()?;
    if bad.is_none() {
        return Ok(());
    }
    // Row i is the first owned node numbered lo + i (copies tied by joints share a row).
    let lo = part.owned_range().0;
    let local = bad
        .and_then(|i| (0..part.num_owned()).find(|&l| part.petsc[l] as usize == lo + i))
        .and_then(|l| part.owned_gids().get(l))
        .map_or(u64::MAX, |&n| n as u64);
    let mut node = u64::MAX;
    comm.all_reduce_into(&local, &mut node, SystemOperation::min());
    Err(Error::NonFinite {
        step,
        time: step as f64 * dt,
        node: node as usize,
    })
}

/// Log what the mechanics domain holds, by array (debug level, target
/// `memory`), after set-up and at each stop.
fn trace_held(rank: i32, mech: Option<&Mechanics>) {
    let Some(m) = mech else { return };
    if !tracing::enabled!(target: "memory", tracing::Level::DEBUG) {
        return;
    }
    let mib: Vec<String> = m
        .domain
        .held_bytes()
        .iter()
        .map(|(n, b)| format!("{n} {:.2}", *b as f64 / 1048576.0))
        .collect();
    let counts: Vec<String> = m
        .domain
        .held_counts()
        .iter()
        .map(|(n, c)| format!("{n} {c}"))
        .collect();
    tracing::debug!(target: "memory", rank, "held MiB: {}; counts: {}", mib.join(", "), counts.join(", "));
}
