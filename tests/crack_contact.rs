//! The faces of a crack in contact (issue 19, "heat across a crack"): a
//! bar cut by an initial crack (`fracture.initial_crack`) and pressed end
//! to end carries the load through the crack's contact and conducts heat
//! across it with the contact resistance, so the temperature jumps by
//! q Rc; pulled apart it conducts none. 1 and 2 ranks alike.

use crate::common::*;

/// Conductivity (W/m/K), contact resistance (m² K/W), length (m),
/// end temperatures (°C) and end traction (Pa, + pulls) of the bar.
const K: f64 = 2.0;
const RC: f64 = 0.05;
const LEN: f64 = 0.1;
const T_HOT: f64 = 100.0;

/// A 0.1 × 0.02 × 0.02 m box bar of 240 Kuhn tets, jointed everywhere
/// with joints far too strong to break, cracked across x = 0.05, on
/// rollers at its x, y, z minimum faces, under the end traction
/// `traction` (Pa) on x = 0.1; held at 0 °C at x = 0 and 100 °C at x =
/// 0.1, steady (θ = 1, Δt = 1e9 s).
fn cracked_bar(traction: f64) -> String {
    format!(
        r#"
[time]
dt = 1e9
steps = 3

[[materials]]
name = "rock"
density = 1000.0
young = 1e9
poisson = 0.25
conductivity = {K}
specific_heat = 800.0
tensile_strength = 1e8
cohesion = 2e8
friction_angle = 30.0
g_i = 1e4
g_ii = 1e5
fracture_penalty = 1e12

[[bodies]]
name = "bar"
material = "rock"
mesh = {{ kind = "box", size = [{LEN}, 0.02, 0.02], element_size = 0.01 }}
fracture = {{ initial_crack = {{ point = [0.05, 0.0, 0.0], normal = [1.0, 0.0, 0.0] }} }}

[contact]
resistance = {RC}

[thermal]
theta = 1.0

[[thermal.bc]]
kind = "temperature"
set = "xmin"
value = 0.0

[[thermal.bc]]
kind = "temperature"
set = "xmax"
value = {T_HOT}

[mechanics]
substeps = 20000
damping = 30000.0

[[mechanics.bc]]
kind = "fixed"
set = "xmin"
components = ["x"]
[[mechanics.bc]]
kind = "fixed"
set = "ymin"
components = ["y"]
[[mechanics.bc]]
kind = "fixed"
set = "zmin"
components = ["z"]
[[mechanics.bc]]
kind = "traction"
set = "xmax"
value = [{traction}, 0.0, 0.0]

[output]
every = 1
"#
    )
}

/// The joint grid's last `status` of the crack's faces (mode 4, an
/// initial crack) and of the other (intact) joints, from run `tag`.
fn crack_statuses(ranks: usize, tag: &str) -> (Vec<f64>, Vec<f64>) {
    let h5 = (root().join("target/test-output"))
        .join(format!("crack-contact-{tag}-{ranks}"))
        .join("bar_joints.h5");
    let k = fdem::io::read_times(&h5).unwrap().len() - 1;
    let mode = fdem::io::read_cell_field_step(&h5, "mode", k).unwrap();
    let status = fdem::io::read_cell_field_step(&h5, "status", k).unwrap();
    let pick = |crack: bool| {
        (mode.iter().zip(&status))
            .filter(|(&m, _)| (m == 4.0) == crack)
            .map(|(_, &s)| s)
            .collect()
    };
    (pick(true), pick(false))
}

/// Runs the cracked bar on `ranks` ranks; its last output and history.
fn run(ranks: usize, traction: f64, tag: &str) -> (Mech, Vec<String>, Vec<Vec<f64>>) {
    let out = out_dir(&format!("crack-contact-{tag}-{ranks}"));
    let scen = out.join("bar.toml");
    std::fs::write(&scen, cracked_bar(traction)).unwrap();
    run_ok(ranks, &scen, &out, &[]);
    let (h, rows) = history(&out, "bar");
    (read_mech(&out, "bar"), h, rows)
}

/// Temperatures of the node copies at x = `x` on the side of the crack
/// where the tets' nodes lie below (`below`) or above it: the copies on
/// the crack plane are told apart by their neighbours, so here simply by
/// all copies at that x, split at the mid temperature.
fn at_x(m: &Mech, k: usize, x: f64) -> Vec<f64> {
    m.coords
        .iter()
        .zip(&m.temperature[k])
        .filter(|(c, _)| (c[0] - x).abs() < 1e-9)
        .map(|(_, &t)| t)
        .collect()
}

/// Pressed by 1 MPa, the crack carries the load (σ_xx = −1 MPa in every
/// element, 1 %; lateral stresses below 2 % of it) and every one of its 8 joint faces is closed; the
/// steady temperatures are linear on each side with the flux
/// q = ΔT / (L/k + Rc), and jump at the crack by q Rc (1e-6 of ΔT). The
/// 1 and 2 rank temperatures agree to 1e-8.
#[test]
fn a_pressed_crack_conducts_with_the_contact_resistance() {
    let t = -1e6;
    let q = T_HOT / (LEN / K + RC);
    let mut temps = Vec::new();
    for ranks in [1, 2] {
        let (m, h, rows) = run(ranks, t, "pressed");
        let k = m.times.len() - 1;
        let last = rows.last().unwrap();
        assert_eq!(last[col(&h, "closed_cracks")], 8.0, "{ranks} rank(s)");
        assert_eq!(last[col(&h, "broken_joints")], 0.0);
        // The joint grid shows the crack's 8 faces closed (status 2, not
        // sliding) and every other joint intact (−1).
        let (crack, intact) = crack_statuses(ranks, "pressed");
        assert_eq!(crack, [2.0; 8], "{ranks} rank(s)");
        assert!(!intact.is_empty() && intact.iter().all(|&s| s == -1.0));
        // The load's work went into strain, joint and crack springs, the
        // mass damping and the crack's friction (1 %).
        assert_energy_balance(&h, &rows, 0.01, &format!("{ranks} rank(s)"));
        // The axial stress is the traction's (1 %); the friction on the
        // crack keeps a little shear from the load's transient (without
        // it the lateral stresses are 2e-4 of t, as in the uncracked bar).
        for s in &m.stress[k] {
            assert!(
                (s[0][0] / t - 1.0).abs() < 0.01
                    && s[1][1].abs() < 0.02 * t.abs()
                    && s[2][2].abs() < 0.02 * t.abs(),
                "{ranks} rank(s): stress {s:?}"
            );
        }
        // Linear on each side, slope q / k.
        for (c, &temp) in m.coords.iter().zip(&m.temperature[k]) {
            if (c[0] - 0.05).abs() < 1e-9 {
                continue;
            }
            let want = if c[0] < 0.05 {
                q * c[0] / K
            } else {
                T_HOT - q * (LEN - c[0]) / K
            };
            assert!(
                (temp - want).abs() < 1e-6 * T_HOT,
                "{ranks} rank(s): T({:?}) = {temp}, want {want}",
                c
            );
        }
        let crack = at_x(&m, k, 0.05);
        let (lo, hi) = crack
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
                (a.min(t), b.max(t))
            });
        let jump = hi - lo;
        eprintln!(
            "{ranks} rank(s): q = {q} W/m^2, jump {jump} (q Rc = {})",
            q * RC
        );
        assert!(
            (jump - q * RC).abs() < 1e-6 * T_HOT,
            "{ranks} rank(s): jump {jump}, q Rc = {}",
            q * RC
        );
        // Each copy on the plane is on one side: at q x / k or above it by q Rc.
        let below = q * 0.05 / K;
        assert!(crack.iter().all(
            |&t| (t - below).abs() < 1e-6 * T_HOT || (t - below - q * RC).abs() < 1e-6 * T_HOT
        ));
        temps.push(m.temperature[k].clone());
    }
    let diff = temps[0]
        .iter()
        .zip(&temps[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-8 * T_HOT, "1 and 2 ranks differ by {diff}");
}

/// Pulled by 1 kPa, the crack (no strength) opens at once and no heat
/// crosses it: each piece takes its end's temperature, no face is closed.
#[test]
fn an_open_initial_crack_conducts_nothing() {
    let (m, h, rows) = run(1, 1e3, "open");
    let k = m.times.len() - 1;
    let last = rows.last().unwrap();
    assert_eq!(last[col(&h, "closed_cracks")], 0.0);
    // The joint grid shows the crack's faces free (status 0).
    let (crack, intact) = crack_statuses(1, "open");
    assert_eq!(crack, [0.0; 8]);
    assert!(intact.iter().all(|&s| s == -1.0));
    for (c, &t) in m.coords.iter().zip(&m.temperature[k]) {
        if (c[0] - 0.05).abs() < 1e-9 {
            assert!(
                t.abs() < 1e-6 || (t - T_HOT).abs() < 1e-6,
                "crack copy at {t}"
            );
        } else if c[0] < 0.05 {
            assert!(t.abs() < 1e-6, "held piece at {t}");
        } else {
            assert!((t - T_HOT).abs() < 1e-6, "pulled piece at {t}");
        }
    }
}

/// A crack plane with a zero normal, or one that holds no joint face (the
/// box's face layers are at multiples of 0.01 m), is an error naming the
/// key, and no output is left.
#[test]
fn a_bad_initial_crack_names_the_key() {
    let cases = [
        (
            "normal = [1.0, 0.0, 0.0]",
            "normal = [0.0, 0.0, 0.0]",
            "initial_crack.normal",
        ),
        (
            "point = [0.05, 0.0, 0.0]",
            "point = [0.055, 0.0, 0.0]",
            "no joint face lies in the plane",
        ),
    ];
    for (i, (from, to, want)) in cases.iter().enumerate() {
        let out = out_dir(&format!("crack-contact-bad-{i}"));
        let scen = out.join("bad.toml");
        std::fs::write(&scen, cracked_bar(-1e6).replace(from, to)).unwrap();
        let dir = out.join("run");
        let o = fdem(
            1,
            &[
                "run",
                scen.to_str().unwrap(),
                "--quiet",
                "--output",
                dir.to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{to}: should fail");
        assert!(err.contains(want), "{to}: {err}");
        assert!(
            err.contains("bad.toml") || err.contains("bodies[0]") || err.contains("`bar`"),
            "{err}"
        );
        let left = std::fs::read_dir(&dir).map_or(0, |d| d.count());
        assert_eq!(left, 0, "{to}: output left behind");
    }
}
