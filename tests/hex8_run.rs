//! Hex8 bodies in `fdem run` (issue 21): the box generator's
//! `element = "hex8"` through the distributed mechanics and heat
//! conduction. References are computed here: the seed 002 cantilever's
//! Timoshenko tip deflection, the seed 000 slab series, the free cube's
//! (1 + α ΔT)³.

mod common;

use common::*;
use fdem::validation::cantilever::Cantilever;
use fdem::validation::SlabProblem;

/// The tip (x = L) nodes' mean displacement along −z at output `k` (m).
fn tip_deflection(m: &Mech, k: usize, length: f64) -> f64 {
    let tip: Vec<f64> = m
        .coords
        .iter()
        .zip(&m.disp[k])
        .filter(|(c, _)| (c[0] - length).abs() < 1e-9)
        .map(|(_, u)| -u[2])
        .collect();
    assert!(!tip.is_empty());
    tip.iter().sum::<f64>() / tip.len() as f64
}

/// Seed 002 sec 4.1, FE alone, Hex8 of 0.5 mm (4 through the thickness)
/// by damped explicit dynamics: the static tip deflection within 3 % of
/// P L³/(3EI) + P L/(κ G A) = 0.403 mm (measured −1.4 %: 0.3974 mm), the
/// beam at rest, the root's bending stress antisymmetric about the
/// mid-plane, and the same bits on 1 and 2 ranks (the beam, 1845 nodes,
/// is cut over the two, its hexes whole).
#[test]
fn hex8_cantilever_deflects_as_timoshenko_on_one_and_two_ranks() {
    let beam = Cantilever::seed002();
    let expected = beam.deflection(beam.length);
    let scen = root().join("scenarios/cantilever-hex8.toml");
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("cantilever-hex8-{ranks}"));
        let stdout = run_ok(ranks, &scen, &out, &[]);
        assert!(stdout.contains("1280 Hex8 (as 7680 tets)"), "{stdout}");
        runs.push(read_mech(&out, "cantilever-hex8"));
    }
    let m = &runs[0];
    let k = m.times.len() - 1;
    let tip = tip_deflection(m, k, beam.length);
    let err = tip / expected - 1.0;
    eprintln!(
        "Hex8 cantilever: tip {:.4} mm, Timoshenko {:.4} mm ({:+.2} %)",
        tip * 1e3,
        expected * 1e3,
        100.0 * err
    );
    assert!(err.abs() < 0.03, "tip {tip:e} m vs {expected:e} m");
    // Static: the last two outputs (0.5 ms apart) agree to 1e-4.
    let before = tip_deflection(m, k - 1, beam.length);
    assert!((tip - before).abs() < 1e-4 * tip, "{before:e} -> {tip:e}");
    // Bending: σ_xx of the root cells above and below the mid-plane are
    // opposite (their centroids mirror each other).
    let centroid = |c: &[usize; 4]| -> [f64; 3] {
        std::array::from_fn(|d| c.iter().map(|&n| m.coords[n][d]).sum::<f64>() / 4.0)
    };
    let (mut top, mut bottom) = (0.0, 0.0);
    for (c, s) in m.cells.iter().zip(&m.stress[k]) {
        let x = centroid(c);
        if x[0] < 0.5e-3 {
            if x[2] > beam.height / 2.0 {
                top += s[0][0];
            } else {
                bottom += s[0][0];
            }
        }
    }
    assert!(top < 0.0 && bottom > 0.0, "top {top:e}, bottom {bottom:e}");
    assert!(
        (top + bottom).abs() < 0.02 * bottom,
        "top {top:e}, bottom {bottom:e}"
    );
    // 1 and 2 ranks: the same bits.
    for (a, b) in runs[0].disp.iter().zip(&runs[1].disp) {
        assert!(a == b, "displacements differ between 1 and 2 ranks");
    }
    assert!(runs[0].stress == runs[1].stress);
}

/// Mean over nodes of |T − T_analytic| / (T_D − T_i), in percent.
fn slab_error_percent(r: &Results, k: usize) -> f64 {
    let p = SlabProblem::seed_000();
    let t = r.times[k];
    let sum: f64 = r
        .coords
        .iter()
        .zip(&r.temperature[k])
        .map(|(x, &v)| (v - p.temperature(x[0], t)).abs())
        .sum();
    100.0 * sum / r.coords.len() as f64 / (p.t_dirichlet - p.t_initial).abs()
}

/// Seed 000 sec 4.2 with Hex8 (`thermal::hex8` matrices in the one PETSc
/// system): the slab series at h = 0.1 and 0.05 m, its error falling
/// about fourfold as h halves, within the measured errors + 10 %
/// (0.104 / 0.0112 / 0.0204 % and 0.0259 / 0.0030 / 0.0052 % at 10 / 50 /
/// 100 s; the Tet4 split of the same cells: 0.106 / 0.0163 / 0.0213 %),
/// every temperature within [0, 1]; and 2 ranks (the bar cut over them)
/// as 1 to 1e-9.
#[test]
fn hex8_slab_matches_the_series_at_second_order() {
    let measured = [[0.104, 0.0112, 0.0204], [0.0259, 0.0030, 0.0052]];
    let mut errors = Vec::new();
    for (i, h) in [0.1, 0.05].into_iter().enumerate() {
        let mut finals = Vec::new();
        for ranks in [1, 2] {
            let out = out_dir(&format!("slab-hex8-{h}-{ranks}"));
            let size = format!("bodies.bar.mesh.element_size={h}");
            let args = ["--set", "bodies.bar.mesh.element=hex8", "--set", &size];
            run_ok(ranks, &root().join("scenarios/slab-1d.toml"), &out, &args);
            let r = read_results(&out, "slab-1d");
            let e = [10.0, 50.0, 100.0].map(|t| slab_error_percent(&r, step_at(&r, t)));
            eprintln!("Hex8 slab h = {h}, {ranks} rank(s): errors {e:?} %");
            for (j, &x) in e.iter().enumerate() {
                assert!(x <= 1.1 * measured[i][j], "h = {h}, output {j}: {x} %");
            }
            for t in &r.temperature {
                assert!(t.iter().all(|&v| (-1e-12..=1.0 + 1e-12).contains(&v)));
            }
            if ranks == 1 {
                errors.push(e);
            }
            finals.push(r.temperature.last().unwrap().clone());
        }
        let d = rel_diff(&finals[0], &finals[1]);
        assert!(d < 1e-9, "h = {h}: 1 vs 2 ranks differ by {d:e}");
    }
    for j in 0..3 {
        let ratio = errors[0][j] / errors[1][j];
        assert!(ratio > 3.0, "output {j}: ratio {ratio}");
    }
}

/// Seed 004 sec 3.2 with Hex8: a free cube heated by 100 °C (α = 1e-5)
/// grows to (1 + αΔT)³ without stress, at h = 0.1 m on 2 ranks.
#[test]
fn hex8_free_cube_expands_without_stress() {
    let (alpha, dt, young, nu): (f64, f64, f64, f64) = (1e-5, 100.0, 20e9, 0.2);
    let expected = (1.0 + alpha * dt).powi(3);
    let constrained = young * alpha * dt / (1.0 - 2.0 * nu);
    let out = out_dir("cube-expansion-hex8");
    let args = [
        "--set",
        "bodies.cube.mesh.element=hex8",
        "--set",
        "bodies.cube.mesh.element_size=0.1",
    ];
    let stdout = run_ok(
        2,
        &root().join("scenarios/cube-expansion.toml"),
        &out,
        &args,
    );
    assert!(stdout.contains("1000 Hex8"), "{stdout}");
    let m = read_mech(&out, "cube-expansion");
    let k = m.times.len() - 1;
    let v: f64 = m
        .cells
        .iter()
        .map(|c| {
            let p = c.map(|n| [0, 1, 2].map(|d| m.coords[n][d] + m.disp[k][n][d]));
            let e = |i: usize| [0, 1, 2].map(|d| p[i][d] - p[0][d]);
            let (a, b, c) = (e(1), e(2), e(3));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum();
    assert!(
        (v / expected - 1.0).abs() < 1e-4,
        "volume {v:.7} m^3, expected {expected:.7}"
    );
    let smax = m.stress[k]
        .iter()
        .flat_map(|s| s.iter().flatten())
        .fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(smax < 0.01 * constrained, "max |stress| {smax:.3e} Pa");
}
