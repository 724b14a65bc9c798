//! The time loop: model → partition → thermal system → steps → output.
//!
//! Collective: every function here is called by all ranks. Errors that one
//! rank finds alone (an output directory it cannot create) are agreed on
//! before the next collective call so no rank waits for a failed one.
//!
//! [`run`] calls the stages in order: [`setup`] (layout, mechanics domain,
//! contacts, thermal system, each restored from a checkpoint on a
//! restart), [`output`] (series, history, particle statistics), then the
//! steps, stopping where [`schedule`] says for detection, checks, output
//! and [`checkpoint`]s, and ends with the [`summary`].

mod checkpoint;
mod output;
mod schedule;
mod setup;
mod summary;

use std::path::{Path, PathBuf};
use std::time::Instant;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::dynamics::ExplicitDomain;
use crate::error::{Error, Result};
use crate::io::checkpoint::Checkpoint;
use crate::model::Model;
use crate::parallel::Layout;
use crate::petsc::Petsc;
use crate::scenario::{LoadedScenario, SettleSpec};
use crate::thermal::ThermalSystem;

use checkpoint::Restart;
use output::Output;
use schedule::Schedule;
pub use setup::find_contacts;
use setup::Contacts;
pub use summary::{peak_rss, MechanicsSummary, PhaseTimes, RunSummary, Settled};

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

/// Collective. Run a scenario to the end.
pub fn run(
    petsc: &Petsc,
    comm: &SimpleCommunicator,
    sc: &LoadedScenario,
    opts: &RunOptions,
) -> Result<RunSummary> {
    let mut times = PhaseTimes::default();
    let clock = Instant::now();
    let model = Model::from_scenario(sc)?;
    times.model = clock.elapsed().as_secs_f64();

    let layout = setup::partition(comm, &model, &mut times)?;
    let restart = match &opts.restart {
        Some(p) => Some(Restart::read(p, &model)?),
        None => None,
    };
    let ck = restart.as_ref().map(|r| &r.checkpoint);
    let start_step = ck.map_or(0, |c| c.step);
    // Mechanics first: its set-up checks the time step before any work.
    let mut mech = setup::mechanics(comm, &model, &layout, restart.as_ref(), &mut times)?;
    let contacts = Contacts::new(comm, &model, &layout, ck, mech.is_some(), &mut times);
    let sys = setup::thermal(
        petsc,
        &model,
        &layout,
        &contacts.set,
        opts,
        restart.as_ref(),
        &mut times,
    )?;
    setup::couple_temperatures(comm, &model, &layout, sys.as_ref(), mech.as_mut(), ck)?;
    let mut st = Stages {
        petsc,
        comm,
        model: &model,
        layout,
        sys,
        mech,
        contacts,
        times,
    };

    // Output: only now that the input is known good are files created.
    let clock = Instant::now();
    let mut out = st.open_output(opts.output_dir.as_deref(), ck)?;
    if !out.continues {
        st.write(&mut out, start_step)?;
    }
    st.record(&mut out, start_step)?;
    st.times.output += clock.elapsed().as_secs_f64();

    let mut settling = Settling::new(&model, ck);
    let mut schedule = Schedule::new(
        model.steps,
        &model.output_steps,
        start_step,
        model.contact.as_ref().map_or(0, |c| c.every),
        model.output.checkpoint_every,
        out.every_step() || settling.spec.is_some(),
    );
    let ck_path = out.dir.join(format!("{}_checkpoint.h5", out.stem));
    let mut checkpoint = None;
    let show = opts.progress && comm.rank() == 0;
    let bar = output::progress_bar(
        show,
        model.steps,
        start_step,
        st.sys.is_some(),
        st.mech.is_some(),
    );
    let mut step = start_step;
    while step < model.steps && settling.settled.is_none() {
        // Run uninterrupted until the next output, check or progress tick.
        let target = schedule.next_stop(step);
        st.advance(step, target)?;
        step = target;
        if let Some(b) = &bar {
            b.set_position(step);
        }
        if st.sys.is_some() && schedule.is_detection(step) {
            st.redetect(step)?;
        }
        if schedule.is_finite_check(step) {
            st.check_finite(step)?;
        }
        if let Some(m) = &st.mech {
            settling.check(comm, m, step, model.dt);
        }
        let settled = settling.settled.is_some();
        let clock = Instant::now();
        st.record(&mut out, step)?;
        if schedule.is_output(step) || (settled && step < model.steps) {
            schedule.output_written();
            st.write(&mut out, step)?;
        }
        if schedule.is_checkpoint(step) && !settled {
            st.save(step, settling.peak_kinetic, None, &ck_path)?;
            checkpoint = Some(ck_path.clone());
        }
        st.times.output += clock.elapsed().as_secs_f64();
        if settled {
            break;
        }
    }
    let settled = settling.settled;
    if model.output.checkpoint || settled.is_some() && model.output.checkpoint_every > 0 {
        let clock = Instant::now();
        st.save(
            step,
            settling.peak_kinetic,
            settled.map(|s| s.kinetic),
            &ck_path,
        )?;
        checkpoint = Some(ck_path.clone());
        st.times.output += clock.elapsed().as_secs_f64();
    }
    let particle_files = out.finish(comm, &model, &st.contacts.set)?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    st.summary(out, start_step, step, settled, checkpoint, particle_files)
}

/// The stages on this rank, between set-up and summary: what the time
/// loop advances, detects, checks and writes.
struct Stages<'a, 'p> {
    petsc: &'p Petsc,
    comm: &'a SimpleCommunicator,
    model: &'a Model,
    layout: Layout,
    sys: Option<ThermalSystem<'p>>,
    mech: Option<Mechanics>,
    contacts: Contacts,
    times: PhaseTimes,
}

impl Stages<'_, '_> {
    /// Collective. Open the output files.
    fn open_output(&self, dir: Option<&Path>, restart: Option<&Checkpoint>) -> Result<Output> {
        let (heat, mechanics) = (self.sys.is_some(), self.mech.is_some());
        Output::open(
            self.comm,
            self.model,
            &self.layout,
            dir,
            heat,
            mechanics,
            restart,
        )
    }

    /// Collective. Write the fields and the history row of `step`.
    fn write(&mut self, out: &mut Output, step: u64) -> Result<()> {
        let (mech, contacts) = (self.mech.as_ref(), &self.contacts.set);
        out.write(
            self.comm,
            self.model,
            &self.layout,
            &mut self.sys,
            mech,
            contacts,
            step,
        )
    }

    /// Collective. Record the particle statistics of `step`.
    fn record(&self, out: &mut Output, step: u64) -> Result<()> {
        out.record(self.comm, self.model, &self.sys, step)
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
            &self.layout,
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
        let (comm, model, layout) = (self.comm, self.model, &self.layout);
        while step < target {
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
                if let Some(s) = self.sys.as_ref() {
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
                m.advance(comm, model, layout, *n)?;
                self.times.mechanics += clock.elapsed().as_secs_f64();
            }
            step += 1;
        }
        Ok(())
    }

    /// Collective. Detect contacts again; rebuild the operator only when
    /// the contact set or its areas changed.
    fn redetect(&mut self, step: u64) -> Result<()> {
        let clock = Instant::now();
        let (comm, model, layout) = (self.comm, self.model, &self.layout);
        let found = self
            .contacts
            .redetect(comm, model, layout, self.mech.as_mut(), step);
        self.times.contact += clock.elapsed().as_secs_f64();
        if let Some(found) = found {
            let clock = Instant::now();
            self.contacts.set = found;
            if let Some(s) = self.sys.as_mut() {
                s.rebuild(self.petsc, model, layout, &model.solver, &self.contacts.set)?;
            }
            self.times.assembly += clock.elapsed().as_secs_f64();
        }
        Ok(())
    }

    /// Collective. Fail naming a node whose temperature is not finite.
    fn check_finite(&self, step: u64) -> Result<()> {
        match &self.sys {
            Some(s) => check_finite(self.comm, s, &self.layout, step, self.model.dt),
            None => Ok(()),
        }
    }
}

/// The settle criterion of a deposition: the peak kinetic energy so far,
/// and where the bodies came to rest.
struct Settling {
    spec: Option<SettleSpec>,
    /// Mass of the free bodies (the settle criterion by rms speed).
    free_mass: f64,
    /// Largest kinetic energy seen (J).
    peak_kinetic: f64,
    settled: Option<Settled>,
}

impl Settling {
    fn new(model: &Model, restart: Option<&Checkpoint>) -> Settling {
        let free_mass: f64 = (0..model.mesh.tets.len())
            .filter(|&e| !model.bodies[model.mesh.body[e] as usize].is_held())
            .map(|e| model.material_of(e).density * model.mesh.element_volume(e))
            .sum();
        Settling {
            spec: model.mechanics.as_ref().and_then(|m| m.settle),
            free_mass,
            peak_kinetic: restart.map_or(0.0, |c| c.peak_kinetic),
            // A restart from a settled run's checkpoint is already done.
            settled: restart.and_then(|c| {
                c.settled.map(|kinetic| Settled {
                    step: c.step,
                    time: c.time,
                    kinetic,
                })
            }),
        }
    }

    /// Collective. Whether the bodies have settled at `step`.
    fn check(&mut self, comm: &SimpleCommunicator, mech: &Mechanics, step: u64, dt: f64) {
        let Some(st) = self.spec else {
            return;
        };
        let ke = mech.domain.state(comm).kinetic;
        self.peak_kinetic = f64::max(self.peak_kinetic, ke);
        let peak_ke = self.peak_kinetic;
        let time = step as f64 * dt;
        // Settled when below any threshold given.
        let threshold = st
            .kinetic_energy
            .unwrap_or(0.0)
            .max(st.relative.map_or(0.0, |r| r * peak_ke))
            .max(st.rms_speed.map_or(0.0, |v| 0.5 * self.free_mass * v * v));
        if time >= st.after && peak_ke > 0.0 && ke < threshold {
            self.settled = Some(Settled {
                step,
                time,
                kinetic: ke,
            });
        }
    }
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
