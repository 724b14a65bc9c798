//! One rank against two: the same nodal temperatures (relative 1e-8) for
//! the slab (direct, explicit and CG/GAMG paths) and an irregular Gmsh mesh,
//! with the METIS partition cutting through the body.

use crate::common::*;

fn compare(tag: &str, stem: &str, extra1: &[&str], extra2: &[&str], tol: f64) {
    let scen = root().join(format!("scenarios/{stem}.toml"));
    let o1 = out_dir(&format!("np1-{tag}"));
    let o2 = out_dir(&format!("np2-{tag}"));
    run_ok(1, &scen, &o1, extra1);
    run_ok(2, &scen, &o2, extra2);
    let r1 = read_results(&o1, stem);
    let r2 = read_results(&o2, stem);
    assert_eq!(r1.coords, r2.coords, "same mesh in original numbering");
    assert_same_temperatures(&r1, &r2, tol, &format!("{stem} {extra2:?}"));
    // The partition really cuts the mesh: both ranks own elements.
    let ranks =
        fdem::io::read_static_cell_field_i32(&o2.join(format!("{stem}.h5")), "rank").unwrap();
    assert!(
        ranks.contains(&0) && ranks.contains(&1),
        "partition did not split the mesh"
    );
}

#[test]
fn slab_direct_one_vs_two_ranks() {
    let s = [
        "--set",
        "bodies.bar.mesh.element_size=0.05",
        "--set",
        "time.end_time=5",
        "--set",
        "output.times=[1.0, 5.0]",
    ];
    compare("slab-direct", "slab-1d", &s, &s, 1e-8);
}

#[test]
fn slab_explicit_one_vs_two_ranks() {
    let s = [
        "--set",
        "thermal.theta=0",
        "--set",
        "time.end_time=5",
        "--set",
        "output.times=[5.0]",
    ];
    compare("slab-explicit", "slab-1d", &s, &s, 1e-8);
}

#[test]
fn gmsh_block_one_vs_two_ranks() {
    compare("gmsh-direct", "gmsh-block", &[], &[], 1e-8);
}

#[test]
fn gmsh_block_cg_gamg_from_command_line_matches_direct() {
    // PETSc options pass straight through the command line.
    let petsc = ["-ksp_type", "cg", "-pc_type", "gamg", "-ksp_rtol", "1e-13"];
    compare("gmsh-gamg", "gmsh-block", &[], &petsc, 1e-8);
}

/// PETSc's `-malloc_dump` lists every PETSc allocation not freed by
/// `PetscFinalize`; a run on two ranks must list none.
#[test]
fn no_petsc_leaks_under_malloc_dump() {
    let out = out_dir("malloc-dump");
    let scen = root().join("scenarios/gmsh-block.toml");
    let o = fdem(
        2,
        &[
            "run",
            scen.to_str().unwrap(),
            "--quiet",
            "--output",
            out.to_str().unwrap(),
            "-malloc_debug",
            "-malloc_dump",
        ],
    );
    let all = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{all}");
    let leaks: Vec<&str> = all.lines().filter(|l| l.contains(" bytes ")).collect();
    assert!(
        leaks.is_empty(),
        "PETSc reports leaks:\n{}",
        leaks.join("\n")
    );
}

/// Issue 18: a rank that panics (a bug, injected here) says which rank it
/// was, and every rank stops at once with a non-zero status, instead of
/// the others waiting in their next collective call until killed (the
/// `timeout` of 120 s would give status 124).
#[test]
fn a_panic_on_one_rank_stops_every_rank() {
    let out = out_dir("panic-on-rank-1");
    let scenario = root().join("scenarios/thermal-stress-element.toml");
    let o = std::process::Command::new("timeout")
        .args(["120", "mpirun", "-n", "2", "--oversubscribe"])
        .args([
            "-x",
            "FDEM_FAULT_PANIC_RANK",
            env!("CARGO_BIN_EXE_fdem"),
            "run",
        ])
        .arg(&scenario)
        .args(["--quiet", "--output"])
        .arg(&out)
        .env("FDEM_FAULT_PANIC_RANK", "1")
        .envs(MPI_ENV)
        .output()
        .expect("cannot start mpirun");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let code = o.status.code();
    assert!(
        code.is_some_and(|c| c != 0 && c != 124),
        "status {code:?}:\n{stderr}"
    );
    assert!(
        stderr.contains("fdem panicked on rank 1 of 2"),
        "status {code:?}:\n{stderr}"
    );
}
