//! What a run did: [`RunSummary`] and its printout, the phase times, and
//! the peak memory.

use std::path::PathBuf;

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::error::Result;
use crate::thermal::system::EnergyAccount;

use super::output::Output;
use super::{Mechanics, Stages};

/// Where the bodies settled: step, time and kinetic energy (J).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settled {
    /// Step.
    pub step: u64,
    /// Time (s).
    pub time: f64,
    /// Kinetic energy (J).
    pub kinetic: f64,
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
    /// Thermal contact detections: surfaces, gathering, and the searches
    /// of a thermal run (a coupled run's searches are the mechanics').
    pub contact: f64,
    /// Every contact search (the one search, whoever runs it).
    pub search: f64,
    /// Time stepping (solves).
    pub stepping: f64,
    /// HDF5/XDMF/CSV output.
    pub output: f64,
    /// Explicit mechanics (set-up and substeps, detection included).
    pub mechanics: f64,
    /// Of which contact searches and halo rebuilds.
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
    /// Bytes sent to other ranks per substep: the largest over the ranks,
    /// and the mean.
    pub bytes_per_substep: (f64, f64),
    /// Cohesive joints (issue 19): how many, broken, crack area (m²) and
    /// energy dissipated by their damage (J); zero joints without fracture.
    pub joints: (u64, u64, f64, f64),
    /// Free spheres (issue 21): how many, and the touching pairs and
    /// sphere–face contacts of the last substep; zeros without spheres.
    pub spheres: [u64; 3],
    /// Seconds of the detections by phase (`dynamics::DETECT_PHASES`):
    /// the least and the most over the ranks.
    pub detect_phases: [(f64, f64); 6],
    /// Seconds of the substeps by phase (`dynamics::SUBSTEP_PHASES`): the
    /// least and the most over the ranks.
    pub substep_phases: [(f64, f64); 8],
}

/// The repartitions of a run on several ranks with moving bodies.
#[derive(Debug, Clone, Copy, Default)]
pub struct BalanceSummary {
    /// Checks of the work balance.
    pub checks: u64,
    /// Repartitions done.
    pub repartitions: u64,
    /// Bodies that changed rank, over all repartitions.
    pub bodies_moved: u64,
    /// Largest max/mean work per rank at a check: with the pairs as their
    /// bodies' tets found them, and as evaluated (shared out evenly).
    pub worst_found: f64,
    pub worst_evaluated: f64,
    /// Max/mean work (pairs as found) after the last check.
    pub last: f64,
    /// Time of the checks and repartitions (s, max over ranks).
    pub time: f64,
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
    /// Of the elements, those that are Hex8 tets (six per hex, issue 21).
    pub hex_tets: u64,
    /// Bonded particles (issue 21).
    pub particles: u64,
    /// Steps taken.
    pub steps: u64,
    /// Total Krylov iterations.
    pub ksp_iterations: u64,
    /// Total Newton iterations (radiating runs; 0 when linear).
    pub newton_iterations: u64,
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
    /// Thermal contact detections run.
    pub detections: u64,
    /// Contact searches run (the mechanics' and a thermal run's).
    pub searches: u64,
    /// Candidate tet pairs those searches found (sum over ranks).
    pub candidates: u64,
    /// Times the thermal operator was assembled.
    pub assemblies: u64,
    /// Mechanics, when it ran.
    pub mechanics: Option<MechanicsSummary>,
    /// Repartitions, when the run checked its balance.
    pub balance: Option<BalanceSummary>,
    /// Step the run started from (0, or a checkpoint's).
    pub start_step: u64,
    /// Where the bodies settled (the run stopped there).
    pub settled: Option<Settled>,
    /// Checkpoint written.
    pub checkpoint: Option<PathBuf>,
    /// Particle statistics files written.
    pub particle_files: Vec<PathBuf>,
    /// Whether heat conduction was solved (else the heat line is left out).
    pub heat: bool,
    /// The free spheres' heat account (issue 21), in a thermal run with spheres.
    pub sphere_heat: Option<super::SphereHeatAccount>,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = &self.times;
        writeln!(f, "fdem run summary")?;
        writeln!(
            f,
            "  mesh        {} nodes, {}{} on {} rank(s)",
            self.nodes,
            match self.hex_tets {
                0 => format!("{} Tet4", self.elements),
                n => format!(
                    "{} Tet4, {} Hex8 (as {n} tets)",
                    self.elements as u64 - n,
                    n / 6
                ),
            },
            match self.particles {
                0 => String::new(),
                n => format!(", {n} bonded particles"),
            },
            self.ranks
        )?;
        writeln!(f, "  solver      {}", self.solver)?;
        writeln!(
            f,
            "  steps       {} ({} KSP iterations, {:.2} per step)",
            self.steps,
            self.ksp_iterations,
            self.ksp_iterations as f64 / self.steps.max(1) as f64
        )?;
        if self.newton_iterations > 0 {
            writeln!(
                f,
                "  newton      {} iterations, {:.2} per step",
                self.newton_iterations,
                self.newton_iterations as f64 / self.steps.max(1) as f64
            )?;
        }
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
        if self.searches > 0 {
            writeln!(
                f,
                "  search      {} contact search(es), {:.3} s, {} candidate tet pairs (one search per detection, shared by the penalty and thermal contact)",
                self.searches, t.search, self.candidates
            )?;
        }
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
                "  mechanics   dt {:.4e} s, {} substeps ({} per step), {:.3} s ({:.3} s set-up, {} detections), {:.2} M tet updates/s/rank, {} pair evaluations ({} exact overlaps)",
                m.dt,
                m.substeps,
                m.substeps_per_step,
                t.mechanics,
                t.mechanics_setup,
                m.detections,
                rate / 1e6,
                m.pair_updates,
                m.exact_overlaps
            )?;
            writeln!(
                f,
                "  traffic     {:.0} B sent per substep per rank (max over ranks), {:.0} B mean (halo, ghost refresh, pair balancing)",
                m.bytes_per_substep.0, m.bytes_per_substep.1
            )?;
            let phases = |names: &[&str], times: &[(f64, f64)]| {
                let each: Vec<String> = names
                    .iter()
                    .zip(times)
                    .map(|(name, (lo, hi))| format!("{name} {lo:.3}/{hi:.3}"))
                    .collect();
                each.join(" | ")
            };
            if m.detections > 0 {
                writeln!(
                    f,
                    "  detection   by phase, s (least/most over ranks): {}",
                    phases(&crate::dynamics::DETECT_PHASES, &m.detect_phases)
                )?;
            }
            writeln!(
                f,
                "  substeps    by phase, s (least/most over ranks): {}",
                phases(&crate::dynamics::SUBSTEP_PHASES, &m.substep_phases)
            )?;
            let [n, pairs, faces] = m.spheres;
            if n > 0 {
                let rate = if t.mechanics > 0.0 {
                    (n * m.substeps) as f64 / t.mechanics / self.ranks as f64
                } else {
                    0.0
                };
                writeln!(
                    f,
                    "  spheres     {n} free spheres, {:.2} M sphere updates/s/rank; at the end {pairs} touching pairs, {faces} sphere-face contacts",
                    rate / 1e6
                )?;
            }
            let (n, broken, area, energy) = m.joints;
            if n > 0 {
                writeln!(
                    f,
                    "  fracture    {n} joints, {broken} broken, crack area {area:.4e} m^2, {energy:.4e} J dissipated"
                )?;
            }
        }
        if let Some(b) = &self.balance {
            writeln!(
                f,
                "  balance     {} repartition(s), {} bodies moved, {:.3} s; work max/mean over {} checks: <= {:.3} as found, <= {:.3} as evaluated, {:.3} at the last",
                b.repartitions,
                b.bodies_moved,
                b.time,
                b.checks,
                b.worst_found,
                b.worst_evaluated,
                b.last
            )?;
        }
        if self.heat {
            writeln!(
                f,
                "  heat        stored change {:.6e}, boundary in {:.6e} (balance {:.2e})",
                self.energy.stored_change,
                self.energy.boundary_in(),
                // The free spheres' released heat is the FE's too (issue 21).
                self.energy.stored_change
                    - self.energy.boundary_in()
                    - self.sphere_heat.map_or(0.0, |a| a.released)
            )?;
            if let Some(a) = &self.sphere_heat {
                let s = &a.spheres;
                let all = self.energy.stored_change + a.stored_change() + a.pending;
                writeln!(
                    f,
                    "  spheres     stored change {:.6e}, from the faces {:.6e}, FE's from them {:.6e} (+ pending {:.3e}); T in [{:.6}, {:.6}], explicit Fourier <= {:.2e}; all stored change {:.6e} (balance {:.2e})",
                    a.stored_change(),
                    s.from_faces,
                    a.released,
                    a.pending,
                    s.min,
                    s.max,
                    s.fourier,
                    all,
                    all - self.energy.boundary_in()
                )?;
            }
            if self.energy.radiation_in != 0.0 || self.energy.convection_in != 0.0 {
                writeln!(
                    f,
                    "  ambient     convection in {:.6e}, radiation in {:.6e}",
                    self.energy.convection_in, self.energy.radiation_in
                )?;
            }
        }
        writeln!(
            f,
            "  memory      peak {:.1} MiB per rank",
            self.peak_memory as f64 / 1048576.0
        )?;
        if self.start_step > 0 {
            writeln!(f, "  restart     from step {}", self.start_step)?;
        }
        if let Some(Settled {
            step,
            time,
            kinetic,
        }) = self.settled
        {
            writeln!(
                f,
                "  settled     at step {step}, t = {time:.4} s (kinetic energy {kinetic:.3e} J)"
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
    status_kib("VmHWM:") * 1024
}

/// A `/proc/self/status` figure in KiB (0 where there is none).
fn status_kib(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
        })
        .unwrap_or(0)
}

extern "C" {
    /// glibc: give the free pages of every malloc arena back to the system.
    fn malloc_trim(pad: usize) -> std::os::raw::c_int;
    /// glibc: set an allocator parameter.
    fn mallopt(param: std::os::raw::c_int, value: std::os::raw::c_int) -> std::os::raw::c_int;
    /// glibc: the allocator's statistics.
    fn mallinfo2() -> MallInfo2;
}

/// glibc's `struct mallinfo2` (all `size_t`).
#[repr(C)]
struct MallInfo2 {
    arena: usize,
    ordblks: usize,
    smblks: usize,
    hblks: usize,
    hblkhd: usize,
    usmblks: usize,
    fsmblks: usize,
    uordblks: usize,
    fordblks: usize,
    keepcost: usize,
}

/// Return the heap's free pages to the system (glibc `malloc_trim`), so
/// that blocks freed between live ones do not stay resident under the
/// next large allocations. It costs the page faults of touching them
/// again: called once per output, not at detections (there it cost 5–10 %
/// of a deposition's time on 2 ranks for 10 % less peak memory).
pub fn release_free_memory() {
    // SAFETY: malloc_trim only touches the allocator's own free lists.
    unsafe {
        malloc_trim(0);
    }
}

/// Return the heap's free pages to the system when they are more than a
/// sixth of the memory in use (and at least 4 MiB): called in a contact
/// detection once its search transients are gone, and after it, since
/// those transients leave such holes below the arrays that live on. N =
/// 2000 deposition, first 0.1 s: the busiest of 8 ranks peaked at 94.3
/// MiB with it, 99.9 without; 2 ranks 202.9 against 217.8 MiB, for 35 %
/// more page faults (one alternated pair: 31.0 and 31.9 s of mechanics
/// against 30.0 and 30.1 s).
pub fn release_fragmented_memory() {
    // SAFETY: mallinfo2 only reads the allocator's counters.
    let m = unsafe { mallinfo2() };
    let free = m.fordblks.saturating_sub(m.keepcost);
    let live = m.uordblks + m.hblkhd;
    if free >= 4 << 20 && 6 * free > live {
        release_free_memory();
        tracing::debug!(target: "memory", free, live, "free heap pages returned");
    }
}

/// Fix glibc's allocator thresholds for a long run: arrays of 128 KiB and
/// more (the per-detection arrays and their transients) get pages of their
/// own, returned when freed and grown in place, and free space above 8 MiB
/// at the top of the heap goes back to the system. Left alone, the
/// thresholds rise with the first large block freed (to 32 MiB), after
/// which every per-detection array lands in the heap and leaves holes
/// there that the next, larger, arrays cannot reuse (Open MPI's memory
/// hooks also turn the separate pages off altogether, `M_MMAP_MAX` = 0).
/// Measured on 8 ranks (N = 2000): with 1 MiB instead of 128 KiB the
/// deposition's busiest rank peaked 3 MiB higher and the heat-up's 4 MiB;
/// the extra page faults on 2 ranks were 1.5 %. `FDEM_MMAP_KIB` and
/// `FDEM_TRIM_KIB` override the two values (0: leave glibc's default).
pub fn allocator_settings() {
    const M_TRIM_THRESHOLD: std::os::raw::c_int = -1;
    const M_MMAP_THRESHOLD: std::os::raw::c_int = -3;
    const M_MMAP_MAX: std::os::raw::c_int = -4;
    let kib = |key: &str, default: i32| {
        std::env::var(key)
            .ok()
            .and_then(|v| v.parse::<i32>().ok())
            .unwrap_or(default)
    };
    for (param, value) in [
        (M_MMAP_THRESHOLD, kib("FDEM_MMAP_KIB", 128)),
        (M_TRIM_THRESHOLD, kib("FDEM_TRIM_KIB", 8192)),
    ] {
        if value > 0 {
            // SAFETY: mallopt only sets the allocator's parameters.
            unsafe {
                if param == M_MMAP_THRESHOLD {
                    // The MPI library's memory hooks set it to 0 (no block
                    // gets pages of its own); glibc's default again.
                    mallopt(M_MMAP_MAX, 65536);
                }
                mallopt(param, value.saturating_mul(1024));
            }
        }
    }
}

/// Log this rank's resident and peak memory after `stage` (debug level,
/// target `memory`: `FDEM_LOG=memory=debug`), to find where a peak forms.
pub fn trace_memory(rank: i32, stage: &str) {
    if tracing::enabled!(target: "memory", tracing::Level::DEBUG) {
        let (rss, hwm) = (status_kib("VmRSS:"), status_kib("VmHWM:"));
        // SAFETY: mallinfo2 only reads the allocator's counters.
        let m = unsafe { mallinfo2() };
        let mib = |b: usize| b as f64 / (1024.0 * 1024.0);
        tracing::debug!(
            target: "memory",
            rank,
            stage,
            rss_mib = rss as f64 / 1024.0,
            peak_mib = hwm as f64 / 1024.0,
            // Resident pages by kind: the process's own (anonymous), mapped
            // files (libraries), shared memory (Open MPI's segments).
            anon_mib = status_kib("RssAnon:") as f64 / 1024.0,
            file_mib = status_kib("RssFile:") as f64 / 1024.0,
            shmem_mib = status_kib("RssShmem:") as f64 / 1024.0,
            heap_used_mib = mib(m.uordblks),
            heap_free_mib = mib(m.fordblks),
            heap_top_free_mib = mib(m.keepcost),
            mmapped_mib = mib(m.hblkhd),
        );
    }
}

impl PhaseTimes {
    /// Collective. Each phase's maximum over the ranks.
    pub(super) fn max_over_ranks(&self, comm: &SimpleCommunicator) -> PhaseTimes {
        let local = [
            self.model,
            self.partition,
            self.assembly,
            self.stepping,
            self.output,
            self.contact,
            self.mechanics,
            self.mechanics_detect,
            self.mechanics_setup,
            self.search,
        ];
        let mut tmax = [0.0; 10];
        comm.all_reduce_into(&local[..], &mut tmax[..], SystemOperation::max());
        PhaseTimes {
            model: tmax[0],
            partition: tmax[1],
            assembly: tmax[2],
            stepping: tmax[3],
            output: tmax[4],
            contact: tmax[5],
            mechanics: tmax[6],
            mechanics_detect: tmax[7],
            mechanics_setup: tmax[8],
            search: tmax[9],
        }
    }
}

impl MechanicsSummary {
    /// Collective. The domain's counters, work summed over the ranks.
    pub(super) fn gather(comm: &SimpleCommunicator, mech: &Mechanics) -> MechanicsSummary {
        let m = &mech.domain;
        let mine = [
            m.counters.element_updates as f64,
            m.counters.pair_updates as f64,
            m.counters.exact_overlaps as f64,
            m.num_joints() as f64,
        ];
        let mut counts = [0.0; 4];
        comm.all_reduce_into(&mine[..], &mut counts[..], SystemOperation::sum());
        let sent = m.counters.bytes_sent as f64 / m.counters.substeps_run.max(1) as f64;
        let c = &m.counters;
        let phases: Vec<f64> = c
            .detect_phases
            .iter()
            .chain(&c.substep_phases)
            .copied()
            .collect();
        let (mut least, mut most_phase) = (vec![0.0; phases.len()], vec![0.0; phases.len()]);
        comm.all_reduce_into(&phases[..], &mut least[..], SystemOperation::min());
        comm.all_reduce_into(&phases[..], &mut most_phase[..], SystemOperation::max());
        let (mut most, mut total) = (0.0, 0.0);
        comm.all_reduce_into(&sent, &mut most, SystemOperation::max());
        comm.all_reduce_into(&sent, &mut total, SystemOperation::sum());
        MechanicsSummary {
            dt: m.dt,
            substeps_per_step: mech.substeps_per_step,
            substeps: m.counters.substeps,
            detections: m.counters.detections,
            element_updates: counts[0] as u64,
            pair_updates: counts[1] as u64,
            exact_overlaps: counts[2] as u64,
            margin: m.min_margin(),
            bytes_per_substep: (most, total / comm.size() as f64),
            joints: if counts[3] > 0.0 {
                let st = m.state(comm);
                (
                    counts[3] as u64,
                    st.broken_joints,
                    st.crack_area,
                    st.fracture,
                )
            } else {
                (0, 0, 0.0, 0.0)
            },
            spheres: m.sphere_counts(comm),
            detect_phases: std::array::from_fn(|k| (least[k], most_phase[k])),
            substep_phases: std::array::from_fn(|k| (least[6 + k], most_phase[6 + k])),
        }
    }
}

impl Stages<'_, '_> {
    /// Collective. Close the output and gather what the run did.
    pub(super) fn summary(
        mut self,
        out: Output,
        start_step: u64,
        step: u64,
        settled: Option<Settled>,
        checkpoint: Option<PathBuf>,
        particle_files: Vec<PathBuf>,
    ) -> Result<RunSummary> {
        let comm = self.comm;
        let energy = match self.sys.as_mut() {
            Some(s) => s.energy()?,
            None => EnergyAccount::default(),
        };
        let (h5, xdmf) = crate::io::output_paths(&out.dir, &out.stem);
        let (output_dir, history) = (out.dir.clone(), out.history_path.clone());
        out.close()?;

        let mut peak_memory = 0u64;
        comm.all_reduce_into(&peak_rss(), &mut peak_memory, SystemOperation::max());
        self.times.mechanics_detect = self
            .mech
            .as_ref()
            .map_or(0.0, |m| m.domain.counters.detect_time);
        let c = &self.contacts;
        self.times.contact = c.search_time + c.surface_time;
        self.times.search = c.search_time + self.times.mechanics_detect;
        let searches = c.searches
            + self
                .mech
                .as_ref()
                .map_or(0, |m| m.domain.counters.detections);
        let local_candidates = c.candidates
            + self
                .mech
                .as_ref()
                .map_or(0, |m| m.domain.counters.candidates);
        let mut candidates = 0u64;
        comm.all_reduce_into(&local_candidates, &mut candidates, SystemOperation::sum());
        let times = self.times.max_over_ranks(comm);
        let mechanics = self
            .mech
            .as_ref()
            .map(|m| MechanicsSummary::gather(comm, m));
        let sys = self.sys.as_ref();
        let sphere_heat = super::SphereHeatAccount::now(comm, sys, self.mech.as_ref());
        let b = &self.balance;
        let balance = (b.checks > 0).then(|| {
            let mut time = 0.0;
            comm.all_reduce_into(&b.time, &mut time, SystemOperation::max());
            BalanceSummary {
                checks: b.checks,
                repartitions: b.repartitions,
                bodies_moved: b.bodies_moved,
                worst_found: b.worst_found,
                worst_evaluated: b.worst_evaluated,
                last: b.last,
                time,
            }
        });
        Ok(RunSummary {
            ranks: self.part.size,
            nodes: self.model.totals().0 as usize,
            elements: self.model.totals().1 as usize,
            hex_tets: self.model.hex_tets(),
            particles: self.model.particle_offsets().1,
            steps: step - start_step,
            ksp_iterations: sys.map_or(0, |s| s.iterations),
            newton_iterations: sys.map_or(0, |s| s.newton_iterations),
            start_step,
            settled,
            checkpoint,
            particle_files,
            heat: sys.is_some(),
            solver: sys.map_or("none (no thermal problem)".into(), |s| {
                s.solver_name.clone()
            }),
            times,
            output_dir,
            h5,
            xdmf,
            history,
            energy,
            peak_memory,
            contacts: (
                self.contacts.set.total_pairs as usize,
                self.contacts.set.total_area,
            ),
            detections: self.contacts.detections,
            searches,
            candidates,
            assemblies: sys.map_or(0, |s| s.assemblies),
            mechanics,
            balance,
            sphere_heat,
        })
    }
}
