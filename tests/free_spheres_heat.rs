//! Free discrete-element spheres carrying heat in `fdem run` (issue 21,
//! beyond the papers), through the binary:
//! - two spheres stacked on a block (no heat to the block) at 0 and 1:
//!   T_B − T_A relaxes as the lumped two-body pipe model,
//!   exp(−t/τ) with 1/τ = (1/C_A + 1/C_B)/R_AB, R_AB from seed 000 eq 33
//!   carried to spheres at the measured overlap (and Hertz's static one),
//!   and C_A T_A + C_B T_B stays put;
//! - a bed of 40 spheres on a block heated from below
//!   (`scenarios/spheres-heat.toml`): the heat balance of block and
//!   spheres closes, every temperature stays in [T₀, T₁], and 1 and 2
//!   ranks agree (motion bitwise, temperatures to the direct solver's
//!   round-off);
//! - bad heat input for spheres is one clear error naming its key, and
//!   explicit steps too long for a sphere's or a node's capacity stop the
//!   run with a clear error.

use std::f64::consts::PI;
use std::path::Path;

use crate::common::*;

/// A sphere series' output times, centres and temperatures by global
/// sphere number.
struct Series {
    times: Vec<f64>,
    x: Vec<Vec<[f64; 3]>>,
    t: Vec<Vec<f64>>,
}

fn spheres(dir: &Path, stem: &str) -> Series {
    let h5 = dir.join(format!("{stem}_spheres.h5"));
    let times = fdem::io::read_times(&h5).unwrap();
    let x0 = fdem::io::read_mesh(&h5).unwrap().coords;
    let step = |name: &str, k: usize| fdem::io::read_node_field_step(&h5, name, k).unwrap();
    let x = (0..times.len())
        .map(|k| {
            step("displacement", k)
                .chunks_exact(3)
                .zip(&x0)
                .map(|(d, p)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
                .collect()
        })
        .collect();
    let t = (0..times.len()).map(|k| step("temperature", k)).collect();
    Series { times, x, t }
}

/// Seed 000 eq 33 for spheres (`contact::sphere_heat`), written out here:
/// 1/(4 k a) per sphere plus R_c/(π a²).
fn pipe_resistance(k: f64, spheres: f64, a: f64, rc: f64) -> f64 {
    spheres / (4.0 * k * a) + rc / (PI * a * a)
}

const TWO_SPHERES: &str = r#"
[time]
dt = 0.01
steps = 30
[[materials]]
name = "block"
density = 2000.0
specific_heat = 800.0
conductivity = 1.0
young = 1.0e8
poisson = 0.25
[[materials]]
name = "bead"
density = 2500.0
specific_heat = 2.5
conductivity = 100.0
young = 1.0e7
poisson = 0.25
[[bodies]]
name = "block"
material = "block"
fixed = true
mesh = { kind = "box", size = [0.1, 0.1, 0.04], element_size = 0.05 }
[[spheres]]
material = "bead"
radius = 0.005
count = 1
box = { min = [0.045, 0.045, 0.04], max = [0.055, 0.055, 0.0501] }
damping = 0.9
temperature = 0.0
[[spheres]]
material = "bead"
radius = 0.005
count = 1
box = { min = [0.045, 0.045, 0.0501], max = [0.055, 0.055, 0.0602] }
damping = 0.9
temperature = 1.0
[thermal]
theta = 1.0
[contact]
resistance = 1e-6
pair = [{ materials = ["bead", "block"], conductance = 0.0 }]
[mechanics]
gravity = [0.0, 0.0, -9.81]
damping = 50.0
[output]
every = 5
"#;

#[test]
fn two_stacked_spheres_relax_as_the_lumped_pipe_model() {
    let dir = out_dir("sphere-heat-pair");
    let scenario = dir.join("pair.toml");
    std::fs::write(&scenario, TWO_SPHERES).unwrap();
    run_ok(1, &scenario, &dir, &[]);
    let Series { times, x, t } = spheres(&dir, "pair");
    assert_eq!(times.len(), 7);
    let (r, rho, c, k, rc): (f64, f64, f64, f64, f64) = (0.005, 2500.0, 2.5, 100.0, 1e-6);
    let cap = 4.0 / 3.0 * PI * rho * c * r.powi(3);
    // Energy: C (T_A + T_B) = C at every output (no heat to the block).
    for (j, tj) in t.iter().enumerate() {
        let e = cap * (tj[0] + tj[1]);
        assert!(
            (e - cap).abs() < 1e-10 * cap,
            "t = {}: stored {e} against {cap}",
            times[j]
        );
    }
    // The overlap of the settled pair (outputs from 0.1 s on), against
    // Hertz's static one under the top sphere's weight (Johnson 1985 sec
    // 4.2: F = 4/3 E* √R* δ^{3/2}, E* = E/(2(1 − ν²)), R* = r/2).
    let overlap: Vec<f64> = x
        .iter()
        .map(|p| {
            let d: f64 = (0..3).map(|i| (p[1][i] - p[0][i]).powi(2)).sum();
            2.0 * r - d.sqrt()
        })
        .collect();
    let weight = 4.0 / 3.0 * PI * rho * r.powi(3) * 9.81;
    let e_star = 1e7 / (2.0 * (1.0 - 0.25f64.powi(2)));
    let hertz = (3.0 * weight / (4.0 * e_star * (r / 2.0).sqrt())).powf(2.0 / 3.0);
    let settled = 2;
    for (j, d) in overlap.iter().enumerate().skip(settled) {
        assert!(
            (d - hertz).abs() < 1e-2 * hertz,
            "t = {}: overlap {d:e} against Hertz {hertz:e}",
            times[j]
        );
    }
    // The pipe (seed 000 eq 33 with a = √(R* δ)) and the lumped decay of
    // seed 000 eqs 35–36 for two capacities: 1/τ = (1/C_A + 1/C_B)/R_AB.
    let mut worst: f64 = 0.0;
    for j in settled + 1..times.len() {
        let d = 0.5 * (overlap[j - 1] + overlap[j]);
        let a = (r / 2.0 * d).sqrt();
        let tau = pipe_resistance(k, 2.0, a, rc) * cap / 2.0;
        let (d0, d1) = (t[j - 1][1] - t[j - 1][0], t[j][1] - t[j][0]);
        let rate = (d0 / d1).ln() / (times[j] - times[j - 1]);
        let err = (rate * tau - 1.0).abs();
        eprintln!(
            "t = {:.2}: overlap {:.5e} m (Hertz {hertz:.5e}), 1/tau {rate:.5} /s against {:.5} /s ({:.2e})",
            times[j],
            overlap[j],
            1.0 / tau,
            err
        );
        worst = worst.max(err);
    }
    assert!(worst < 5e-3, "decay rate off the lumped model by {worst:e}");
    // And the difference did decay: below e⁻¹.
    let last = t.last().unwrap();
    assert!(last[1] - last[0] < 0.37 && last[1] > last[0]);
}

/// The bed of `scenarios/spheres-heat.toml` on 1 and 2 ranks.
#[test]
fn sphere_bed_on_a_heated_block_balances_within_bounds_on_one_and_two_ranks() {
    let scenario = root().join("scenarios/spheres-heat.toml");
    let stem = "spheres-heat";
    let (o1, o2) = (out_dir("spheres-heat-1"), out_dir("spheres-heat-2"));
    run_ok(1, &scenario, &o1, &[]);
    run_ok(2, &scenario, &o2, &[]);
    let (t0, t1) = (20.0, 100.0);
    let (s1, s2) = (spheres(&o1, stem), spheres(&o2, stem));
    assert_eq!(s1.times, s2.times);
    // Motion: the same bits (the block has no thermal expansion).
    for (a, b) in s1.x.iter().flatten().zip(s2.x.iter().flatten()) {
        assert!(a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits()));
    }
    // Temperatures: the spheres' from the block's, which come from a
    // direct solve on either rank count: round-off apart.
    let mut worst: f64 = 0.0;
    for (a, b) in s1.t.iter().flatten().zip(s2.t.iter().flatten()) {
        worst = worst.max((a - b).abs() / (t1 - t0));
    }
    eprintln!("spheres' temperatures, 1 against 2 ranks: {worst:.2e} of T1 - T0");
    assert!(worst < 1e-10, "{worst:e}");
    let (r1, r2) = (read_results(&o1, stem), read_results(&o2, stem));
    assert_same_temperatures(&r1, &r2, 1e-10, "block, 1 against 2 ranks");
    // The maximum principle (θ = 1): block and spheres within [T₀, T₁].
    let (lo, hi) = assert_within_bounds(&r1, t0, t1, "block");
    let tol = 1e-9 * (t1 - t0);
    for (j, tj) in s1.t.iter().enumerate() {
        for (i, &x) in tj.iter().enumerate() {
            assert!(
                (t0 - tol..=t1 + tol).contains(&x),
                "sphere {i} at t = {}: {x}",
                s1.times[j]
            );
        }
    }
    let warm = s1.t.last().unwrap().iter().cloned().fold(t0, f64::max);
    eprintln!("block in [{lo}, {hi}], warmest sphere {warm}");
    assert!(warm > t0 + 1.0, "the spheres warmed: {warm}");
    // Heat balance every step: boundary heat in = the block's and the
    // spheres' stored change + what the spheres handed over for the next
    // step; the spheres took from the faces what the block gave.
    let (h, rows) = history(&o1, stem);
    let c = |n: &str| col(&h, n);
    let (fe, sp, bin) = (
        c("stored_heat"),
        c("spheres_stored_heat"),
        c("boundary_heat_in"),
    );
    let (taken, given, pending) = (
        c("spheres_heat_from_faces"),
        c("fe_heat_from_spheres"),
        c("spheres_heat_pending"),
    );
    let first = &rows[0];
    let scale = rows.last().unwrap()[bin].abs();
    let mut balance: f64 = 0.0;
    for row in &rows {
        let stored = row[fe] - first[fe] + row[sp] - first[sp];
        balance = balance.max((stored + row[pending] - row[bin]).abs() / scale);
        assert!((row[sp] - first[sp] - row[taken]).abs() < 1e-12 * scale);
        assert!((row[given] + row[pending] + row[taken]).abs() < 1e-12 * scale);
    }
    eprintln!(
        "heat balance: worst {balance:.2e} of the boundary heat {scale:.4e} J; the spheres took {:.4e} J",
        rows.last().unwrap()[taken]
    );
    assert!(balance < 1e-10, "{balance:e}");
    assert!(rows.last().unwrap()[taken] > 0.0);
}

#[test]
fn bad_sphere_heat_input_is_a_clear_error() {
    let dir = out_dir("spheres-heat-bad");
    let base = std::fs::read_to_string(root().join("scenarios/spheres-heat.toml")).unwrap();
    let cases = [
        ("specific_heat = 20.0\n", "", "materials[1].specific_heat"),
        (
            "\ntemperature = 20.0\n",
            "\ntemperature = nan\n",
            "spheres[0].temperature",
        ),
        (
            "resistance = 2e-6",
            "resistance = 2e-6\ncmy = { hardness = 1e9, roughness = 1e-6, slope = 0.1 }",
            "contact",
        ),
        (
            "[contact]",
            "[thermal.ambient]\ntemperature = 20.0\nh = 10.0\n[contact]",
            "thermal.ambient",
        ),
    ];
    for (i, (from, to, key)) in cases.iter().enumerate() {
        assert!(base.contains(from), "{from}");
        let p = dir.join(format!("bad{i}.toml"));
        std::fs::write(&p, base.replacen(from, to, 1)).unwrap();
        let o = fdem(1, &["check", p.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{to}: {err}");
        assert!(err.contains(key), "{to}: the error names {key}: {err}");
    }
    // Explicit steps too long for the capacities: the spheres' (Δt Σg/C
    // > 1) and the block nodes' (Σ N g Δt / C > 1) stop the run at once.
    let scenario = root().join("scenarios/spheres-heat.toml");
    for (set, says) in [
        (
            "materials.1.specific_heat=1e-6",
            "explicit heat step is unstable",
        ),
        ("materials.0.specific_heat=1e-6", "times its heat capacity"),
    ] {
        let args = ["run", scenario.to_str().unwrap(), "--quiet", "--output"];
        let out = dir.join(set);
        let mut args = args.to_vec();
        args.extend_from_slice(&[out.to_str().unwrap(), "--set", set]);
        let o = fdem(1, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{set}: {err}");
        assert!(err.contains(says), "{set}: {err}");
    }
}
