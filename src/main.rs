//! The `fdem` command: `run`, `check`, `info`.
//!
//! PETSc options (single dash, e.g. `-ksp_type cg -pc_type gamg -log_view`)
//! may appear anywhere on the command line; they are handed to
//! `PetscInitialize` and override the scenario's solver settings.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use mpi::traits::*;

use fdem::error::Error;
use fdem::model::Model;
use fdem::petsc::Petsc;
use fdem::run::{run, RunOptions};
use fdem::scenario;

#[derive(Parser)]
#[command(
    name = "fdem",
    version,
    about = "FDEM heat transfer and thermo-mechanics of 3D particle systems"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario (use under mpirun for several ranks).
    Run {
        /// Scenario TOML file.
        scenario: PathBuf,
        /// Output directory (default: the scenario's, or output/<stem>).
        #[arg(long)]
        output: Option<PathBuf>,
        /// Override a scenario value by dotted path, e.g. --set bodies.bar.mesh.element_size=0.05; VALUE none removes the key (--set time.end_time=none)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Read bodies of mesh kind "checkpoint" from this directory (an
        /// earlier stage's --output) by their file name, or from this .h5 file.
        #[arg(long, value_name = "DIR")]
        from: Option<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Continue from a checkpoint written by this scenario
        /// (`[output] checkpoint = true`).
        #[arg(long, value_name = "CHECKPOINT.h5")]
        restart: Option<PathBuf>,
        /// Accept PETSc options that no PETSc object reads (by default an
        /// error naming them).
        #[arg(long)]
        allow_unused_petsc_options: bool,
    },
    /// Validate a scenario and its meshes without running.
    Check {
        /// Scenario TOML file.
        scenario: PathBuf,
        /// Override a scenario value by dotted path.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Read bodies of mesh kind "checkpoint" from this directory (an
        /// earlier stage's --output) by their file name, or from this .h5 file.
        #[arg(long, value_name = "DIR")]
        from: Option<PathBuf>,
    },
    /// Print the PETSc, MPI and HDF5 versions in use.
    Info,
    /// Generate a box Tet4 mesh and write it as Gmsh MSH 4.1 (ASCII), with
    /// face groups xmin..zmax; `--jitter` makes it irregular.
    Mesh {
        /// Edge lengths (m).
        #[arg(long, num_args = 3, value_names = ["LX", "LY", "LZ"])]
        size: Vec<f64>,
        /// Lower corner (m).
        #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], default_values_t = [0.0, 0.0, 0.0])]
        origin: Vec<f64>,
        /// Element size h (m).
        #[arg(long)]
        h: f64,
        /// Move interior nodes randomly by up to this fraction of h.
        #[arg(long, default_value_t = 0.0)]
        jitter: f64,
        /// Seed of the jitter.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output .msh file.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Split PETSc options (`-name [value]`) from fdem's own arguments.
fn split_args(args: &[String]) -> (Vec<String>, Vec<String>) {
    let is_petsc_opt = |a: &str| {
        a.len() > 2
            && a.starts_with('-')
            && !a.starts_with("--")
            && a.as_bytes()[1].is_ascii_alphabetic()
    };
    let mut ours = vec![args[0].clone()];
    let mut petsc = vec![args[0].clone()];
    let mut i = 1;
    while i < args.len() {
        let a = &args[i];
        if is_petsc_opt(a) {
            petsc.push(a.clone());
            if let Some(v) = args.get(i + 1) {
                if !is_petsc_opt(v) && !v.starts_with("--") {
                    // A value, unless it is fdem's subcommand or positional
                    // argument: PETSc values never end in `.toml`.
                    if !v.ends_with(".toml") && !["run", "check", "info"].contains(&v.as_str()) {
                        petsc.push(v.clone());
                        i += 1;
                    }
                }
            }
        } else {
            ours.push(a.clone());
        }
        i += 1;
    }
    (ours, petsc)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (ours, petsc_args) = split_args(&args);
    let cli = Cli::parse_from(ours);
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("FDEM_LOG")
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();

    // Open MPI's shared-file-pointer component `sm` keeps a named
    // semaphore per file name in /dev/shm while MPI_File_open runs; a rank
    // killed inside it (a crash, a job's time limit) leaves it taken, and
    // the next open of that name (the restart's checkpoint) waits forever
    // (met in scripts/fault-check.sh). fdem never uses shared file
    // pointers: leave `sm` out unless the user chose the components.
    if std::env::var_os("OMPI_MCA_sharedfp").is_none() {
        std::env::set_var("OMPI_MCA_sharedfp", "^sm");
    }
    let Some(universe) = mpi::initialize() else {
        eprintln!("error: MPI could not be initialised");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    let rank = world.rank();
    abort_every_rank_on_panic();
    let result = match Petsc::init(&world, &petsc_args) {
        Err(e) => Err(Error::from(e)),
        Ok(petsc) => {
            fdem::run::allocator_settings();
            let r = dispatch(&cli.command, &petsc, &world);
            drop(petsc);
            r
        }
    };
    let code = match &result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Error::OtherRank) => ExitCode::FAILURE,
        Err(e) => {
            if deterministic(e) {
                if rank == 0 {
                    eprintln!("error: {e}");
                }
            } else if world.size() > 1 {
                // Only this rank met it: say which (the others stop with it).
                eprintln!("error: {e} (on rank {rank} of {})", world.size());
            } else {
                eprintln!("error: {e}");
            }
            ExitCode::FAILURE
        }
    };
    // Every rank returns here (errors are agreed collectively), so wait for
    // all before leaving: a rank exiting non-zero early makes mpirun kill
    // the others, possibly before rank 0 has printed the message.
    if result.is_err() {
        use std::io::Write;
        let _ = std::io::stderr().flush();
        world.barrier();
    }
    drop(universe);
    code
}

/// A panic (a bug, not an input error) on one rank would leave the others
/// waiting in their next collective call, and mpirun waits with them:
/// after the panic's own message, say which rank it was and abort every
/// rank (exit status 101, Rust's for a panic). `FDEM_FAULT_PANIC_RANK=r`
/// makes rank r panic at start (fault injection for the tests).
fn abort_every_rank_on_panic() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        default(info);
        let world = mpi::topology::SimpleCommunicator::world();
        eprintln!(
            "error: fdem panicked on rank {} of {} (a bug; please report it with the \
             scenario); stopping every rank",
            world.rank(),
            world.size()
        );
        world.abort(101);
    }));
    let world = mpi::topology::SimpleCommunicator::world();
    if std::env::var("FDEM_FAULT_PANIC_RANK").is_ok_and(|r| r == world.rank().to_string()) {
        panic!("fault injection (FDEM_FAULT_PANIC_RANK)");
    }
}

/// Errors every rank finds identically are printed by rank 0 only.
fn deterministic(e: &Error) -> bool {
    matches!(
        e,
        Error::Scenario(_)
            | Error::Mesh { .. }
            | Error::Model { .. }
            | Error::Petsc(_)
            | Error::NonFinite { .. }
            | Error::Partition(_)
            | Error::UnusedPetscOptions(_)
            | Error::TimeStep(_)
    )
}

fn dispatch(
    cmd: &Command,
    petsc: &Petsc,
    world: &mpi::topology::SimpleCommunicator,
) -> fdem::error::Result<()> {
    let rank = world.rank();
    match cmd {
        Command::Info => {
            if rank == 0 {
                println!("fdem {}", env!("CARGO_PKG_VERSION"));
                println!("PETSc: {}", petsc.version()?);
                println!(
                    "MPI:   {}",
                    mpi::environment::library_version()
                        .unwrap_or_default()
                        .trim_matches(|c: char| c == '\0' || c.is_whitespace())
                );
                let v = hdf5::library_version();
                println!("HDF5:  {}.{}.{} (MPI-IO driver)", v.0, v.1, v.2);
                println!("ranks: {}", world.size());
            }
            Ok(())
        }
        Command::Mesh {
            size,
            origin,
            h,
            jitter,
            seed,
            out,
        } => {
            if rank == 0 {
                let ctx = |source| Error::Mesh {
                    context: out.display().to_string(),
                    source,
                };
                let mut m = fdem::mesh::generate::box_mesh(
                    [origin[0], origin[1], origin[2]],
                    [size[0], size[1], size[2]],
                    *h,
                )
                .map_err(ctx)?;
                if *jitter > 0.0 {
                    fdem::mesh::generate::jitter_interior(&mut m, jitter * h, *seed)
                        .map_err(ctx)?;
                }
                fdem::mesh::gmsh::write_msh_ascii(&m, out).map_err(ctx)?;
                println!(
                    "{}: {} nodes, {} Tet4",
                    out.display(),
                    m.nodes.len(),
                    m.tets.len()
                );
            }
            Ok(())
        }
        Command::Check {
            scenario: path,
            set,
            from,
        } => {
            let mut sc = scenario::load(path, set)?;
            if let Some(d) = from {
                sc.take_checkpoints_from(d)?;
            }
            let model = Model::from_scenario(&sc)?;
            // Every body made on this process: the meshes, sets and
            // conditions checked as a run would make them.
            let whole = model.whole_mesh()?;
            if rank == 0 {
                let q = whole.mesh.min_quality();
                println!("{}: ok", path.display());
                let scheme = if model.thermal_active {
                    format!("theta = {}", model.thermal.theta)
                } else {
                    "mechanics only, no heat conduction".to_string()
                };
                let hex_tets = model.hex_tets() as usize;
                let hexes = match hex_tets {
                    0 => String::new(),
                    n => format!(" ({} of them split {} Hex8)", n, n / 6),
                };
                println!(
                    "  {} bodies, {} nodes, {} Tet4{hexes}, {} steps of {} s ({scheme})",
                    model.bodies.len(),
                    whole.mesh.nodes.len(),
                    whole.mesh.tets.len(),
                    model.steps,
                    model.dt,
                );
                if let Some((q, e)) = q {
                    println!("  worst element quality {q:.3} (element {e})");
                }
                if model.thermal_active {
                    println!(
                        "  {} prescribed-temperature nodes, {} flux faces, {} convection faces",
                        whole.dirichlet.len(),
                        whole.flux.len(),
                        whole.convection.len()
                    );
                }
            }
            Ok(())
        }
        Command::Run {
            scenario: path,
            output,
            set,
            quiet,
            restart,
            allow_unused_petsc_options,
            from,
        } => {
            let mut sc = scenario::load(path, set)?;
            if let Some(d) = from {
                sc.take_checkpoints_from(d)?;
            }
            let opts = RunOptions {
                output_dir: output.clone(),
                progress: !quiet,
                restart: restart.clone(),
                allow_unused_petsc_options: *allow_unused_petsc_options,
            };
            let summary = run(petsc, world, &sc, &opts)?;
            if rank == 0 {
                println!("{summary}");
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::split_args;

    #[test]
    fn petsc_options_are_split_off() {
        let a: Vec<String> =
            "fdem run -ksp_type cg s.toml --set a=1 -ksp_monitor -ksp_rtol 1e-12 --quiet"
                .split(' ')
                .map(String::from)
                .collect();
        let (ours, petsc) = split_args(&a);
        assert_eq!(ours, ["fdem", "run", "s.toml", "--set", "a=1", "--quiet"]);
        assert_eq!(
            petsc,
            [
                "fdem",
                "-ksp_type",
                "cg",
                "-ksp_monitor",
                "-ksp_rtol",
                "1e-12"
            ]
        );
    }
}
