//! Issue 20, free surfaces: convection h (T − T_env) and radiation
//! ε σ (T⁴ − T_env⁴) to an ambient on the faces not in contact, against
//! the lumped solutions of a body with Bi ≪ 1 (computed in
//! `fdem::validation::ambient`), on one and two ranks; the heat account
//! (stored change = heat in by convection and radiation) and a restart.

use std::path::Path;

use crate::common::*;
use fdem::validation::ambient::{convective_cooling, radiative_cooling};

/// Cube side (m), heat capacity of one cube (J/K), emissivity, T0 (K):
/// the scenarios' values.
const L: f64 = 0.1;
const CAPACITY: f64 = 1000.0 * 1000.0 * L * L * L;
const EPS: f64 = 0.8;
const T0: f64 = 1000.0;

/// Mean temperature of `body` at each output of the history in `dir`, at
/// the scenarios' output times 50, 100 and 200 s.
fn means(dir: &Path, stem: &str, body: &str) -> Vec<(f64, f64)> {
    let (h, rows) = history(dir, stem);
    let (t, m) = (col(&h, "time"), col(&h, &format!("{body}_mean_T")));
    rows.iter()
        .filter(|r| [50.0, 100.0, 200.0].contains(&r[t]))
        .map(|r| (r[t], r[m]))
        .collect()
}

/// Every output's mean temperature within `tol` (relative) of `exact`,
/// and the heat account closed to 1e-9 of the heat exchanged.
fn assert_follows(dir: &Path, stem: &str, body: &str, exact: impl Fn(f64) -> f64, tol: f64) {
    let m = means(dir, stem, body);
    assert_eq!(m.len(), 3, "{stem}: outputs at 50, 100 and 200 s");
    for (t, got) in m {
        let want = exact(t);
        let err = (got - want).abs() / want;
        eprintln!(
            "{stem} {body}: t = {t} s, T = {got:.4} K, lumped {want:.4} K ({:.4} %)",
            100.0 * err
        );
        assert!(err < tol, "{stem} {body} at t = {t}: {got} against {want}");
    }
    let (h, rows) = history(dir, stem);
    let (first, last) = (&rows[0], rows.last().unwrap());
    let stored = last[col(&h, "stored_heat")] - first[col(&h, "stored_heat")];
    let inflow = last[col(&h, "boundary_heat_in")];
    let ambient = last[col(&h, "convection_heat_in")] + last[col(&h, "radiation_heat_in")];
    assert!(
        (stored - inflow).abs() < 1e-9 * stored.abs(),
        "{stem}: balance {stored} vs {inflow}"
    );
    assert!(
        (ambient - inflow).abs() < 1e-9 * stored.abs(),
        "{stem}: all heat leaves to the ambient"
    );
}

#[test]
fn a_radiating_cube_follows_the_lumped_solution_on_one_and_two_ranks() {
    let scen = root().join("scenarios/radiating-cube.toml");
    let exact = |t: f64| radiative_cooling(T0, EPS, 6.0 * L * L, CAPACITY, t);
    let mut results = Vec::new();
    for ranks in [1, 2] {
        let dir = out_dir(&format!("ambient/radiating-{ranks}"));
        let out = run_ok(ranks, &scen, &dir, &[]);
        assert!(
            out.contains("newtonls"),
            "the radiating step is a Newton solve: {out}"
        );
        let its = number_before(summary_line(&out, "newton").unwrap(), "per step");
        assert!(
            (1.0..=4.0).contains(&its),
            "Newton iterations per step: {its}"
        );
        assert_follows(&dir, "radiating-cube", "cube", exact, 0.005);
        let png = std::fs::read(dir.join("radiating-cube_heat.png")).expect("the heat PNG");
        assert!(
            png.starts_with(b"\x89PNG") && png.len() > 10_000,
            "a drawn PNG"
        );
        results.push(read_results(&dir, "radiating-cube"));
    }
    assert_same_temperatures(
        &results[0],
        &results[1],
        1e-8,
        "radiating cube, 1 vs 2 ranks",
    );
    // Never below the ambient's 0 K, never above the start.
    assert_within_bounds(&results[1], 0.0, T0, "radiating cube");
}

#[test]
fn a_convecting_cube_follows_the_exponential() {
    let scen = root().join("scenarios/radiating-cube.toml");
    let dir = out_dir("ambient/convecting");
    let set = [
        "--set",
        "thermal.ambient.radiation=false",
        "--set",
        "thermal.ambient.h=50",
    ];
    let out = run_ok(2, &scen, &dir, &set);
    assert!(
        !out.contains("newtonls"),
        "a linear run keeps the KSP path: {out}"
    );
    let exact = |t: f64| convective_cooling(T0, 0.0, 50.0, 6.0 * L * L, CAPACITY, t);
    assert_follows(&dir, "radiating-cube", "cube", exact, 0.005);
}

/// The face of each cube inside the other is in contact: it neither
/// convects nor radiates, so each cube cools through 5 L² only.
#[test]
fn closed_contacts_do_not_exchange_with_the_ambient() {
    let scen = root().join("scenarios/ambient-stack.toml");
    let free = 5.0 * L * L;
    let conv = out_dir("ambient/stack-convection");
    run_ok(2, &scen, &conv, &[]);
    let exact = |t: f64| convective_cooling(T0, 0.0, 50.0, free, CAPACITY, t);
    for body in ["cube_0_0_0", "cube_0_0_1"] {
        assert_follows(&conv, "ambient-stack", body, exact, 0.005);
    }
    // Without the contact the whole 6 L² would cool it: 1.7 % colder at 200 s.
    let open = convective_cooling(T0, 0.0, 50.0, 6.0 * L * L, CAPACITY, 200.0);
    assert!(exact(200.0) / open > 1.01);
    let rad = out_dir("ambient/stack-radiation");
    let set = [
        "--set",
        "thermal.ambient.radiation=true",
        "--set",
        "thermal.ambient.h=0",
    ];
    run_ok(1, &scen, &rad, &set);
    let exact = |t: f64| radiative_cooling(T0, EPS, free, CAPACITY, t);
    for body in ["cube_0_0_0", "cube_0_0_1"] {
        assert_follows(&rad, "ambient-stack", body, exact, 0.005);
    }
}

/// A radiating run restarted from its checkpoint continues the
/// temperatures and the radiated-heat account, to the solver's tolerance:
/// the restart builds the Newton step's preconditioner afresh (the run
/// kept the one of its first step), so the Krylov solves round off
/// differently.
#[test]
fn a_radiating_run_restarts_to_solver_tolerance() {
    let scen = root().join("scenarios/radiating-cube.toml");
    let full = out_dir("ambient/restart-full");
    run_ok(2, &scen, &full, &[]);
    let first = out_dir("ambient/restart-first");
    let ck = [
        "--set",
        "output.checkpoint=true",
        "--set",
        "time.end_time=100.0",
        "--set",
        "output.times=[50.0]",
    ];
    run_ok(2, &scen, &first, &ck);
    let rest = out_dir("ambient/restart-rest");
    let checkpoint = first.join("radiating-cube_checkpoint.h5");
    run_ok(
        2,
        &scen,
        &rest,
        &["--restart", checkpoint.to_str().unwrap()],
    );
    let (h, a) = history(&full, "radiating-cube");
    let (_, b) = history(&rest, "radiating-cube");
    let (ra, rb) = (a.last().unwrap(), b.last().unwrap());
    for name in [
        "time",
        "stored_heat",
        "radiation_heat_in",
        "boundary_heat_in",
        "cube_mean_T",
    ] {
        let c = col(&h, name);
        let tol = 1e-11 * ra[c].abs().max(1.0);
        assert!(
            (ra[c] - rb[c]).abs() <= tol,
            "{name} after the restart: {} vs {}",
            ra[c],
            rb[c]
        );
    }
}

/// In a packing: 50 nuts on a hot plate (the lattice heat-up at 5 × 5 × 2)
/// with free-surface convection and radiation and the CMY conductance. The
/// heat in through the held plate equals the stored heat plus the heat
/// convected and radiated away, to 1e-6 of the radiated heat, and every
/// temperature stays between the room's and the plate's.
#[test]
fn a_radiating_packing_keeps_its_heat_account() {
    let scen = root().join("scenarios/nut-lattice-heatup-20k.toml");
    let set = [
        "bodies.nut.lattice.count=[5,5,2]",
        "time.steps=20",
        "output.every=5",
        "materials.0.emissivity=0.8",
        "thermal.temperature_offset=273.15",
        "thermal.ambient={temperature=20.0, h=5.0, radiation=true}",
        "contact.resistance=none",
        "contact.cmy={roughness=1e-6, slope=0.1, hardness=1e9, pressure=8e8}",
    ];
    let args: Vec<&str> = set.iter().flat_map(|s| ["--set", s]).collect();
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let dir = out_dir(&format!("ambient/packing-{ranks}"));
        run_ok(ranks, &scen, &dir, &args);
        let (h, rows) = history(&dir, "nut-lattice-heatup-20k");
        let last = rows.last().unwrap();
        let c = |name: &str| last[col(&h, name)];
        let stored = c("stored_heat") - rows[0][col(&h, "stored_heat")];
        let (conv, rad) = (c("convection_heat_in"), c("radiation_heat_in"));
        let wall = c("boundary_heat_in") - conv - rad - c("friction_heat_in");
        eprintln!("{ranks} rank(s): wall {wall:.4} J, stored {stored:.4}, convected {conv:.4}, radiated {rad:.4}");
        assert!(rad < 0.0 && conv < 0.0 && wall > 0.0);
        assert!(
            (wall + conv + rad - stored).abs() < 1e-6 * rad.abs(),
            "account"
        );
        let r = read_results(&dir, "nut-lattice-heatup-20k");
        assert_within_bounds(&r, 0.0, 300.0, "radiating packing");
        runs.push(r);
    }
    assert_same_temperatures(&runs[0], &runs[1], 1e-8, "radiating packing, 1 vs 2 ranks");
}
