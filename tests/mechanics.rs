//! Explicit finite-strain mechanics with thermal expansion and penalty
//! contact (seed 004 secs 3–4; issue 4): the heated fixed element (eq 38),
//! free cube expansion, the hollow cylinder and steel-in-concrete stresses
//! against plane-stress solutions, a head-on collision (momentum, energy),
//! a block sliding on an incline with friction, and an eight-body drop on
//! one and two ranks.

use crate::common::*;

fn tet_volume(p: [[f64; 3]; 4]) -> f64 {
    let a = [0, 1, 2].map(|d| p[1][d] - p[0][d]);
    let b = [0, 1, 2].map(|d| p[2][d] - p[0][d]);
    let c = [0, 1, 2].map(|d| p[3][d] - p[0][d]);
    (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]))
        / 6.0
}

impl Mech {
    fn deformed(&self, k: usize, n: usize) -> [f64; 3] {
        [0, 1, 2].map(|d| self.coords[n][d] + self.disp[k][n][d])
    }

    fn volume(&self, k: usize) -> f64 {
        self.cells
            .iter()
            .map(|c| tet_volume(c.map(|n| self.deformed(k, n))))
            .sum()
    }
}

/// Seed 004 sec 3.1, Table 1: every element of a fixed cube heated by
/// 100 °C carries σ = −3.332 MPa in x, y and z (eq 38).
#[test]
fn heated_fixed_element_matches_eq_38() {
    let (young, nu, alpha, dt): (f64, f64, f64, f64) = (20e9, 0.2, 1e-6, 100.0);
    let mu = young / (2.0 * (1.0 + nu));
    let lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    // Seed 004 eq 38 with F = I: F_e = I/s, s = 1 + αΔT, J_e = s⁻³, B_e = I/s².
    let s = 1.0 + alpha * dt;
    let je = s.powi(-3);
    let exact = mu / je * (1.0 / (s * s) - 1.0) + lambda / je * je.ln();
    assert!(
        (exact.abs() / 3.332e6 - 1.0).abs() < 1e-3,
        "closed form {exact} vs the paper's 3.332 MPa"
    );
    for ranks in [1, 2] {
        let out = out_dir(&format!("element-{ranks}"));
        run_ok(
            ranks,
            &root().join("scenarios/thermal-stress-element.toml"),
            &out,
            &[],
        );
        let m = read_mech(&out, "thermal-stress-element");
        let k = m.times.len() - 1;
        assert_eq!(m.stress[k].len(), 6);
        for s in &m.stress[k] {
            for d in 0..3 {
                assert!(
                    (s[d][d] / exact - 1.0).abs() < 1e-3,
                    "{ranks} rank(s): sigma = {s:?}, eq 38: {exact}"
                );
                let shear = s[d][(d + 1) % 3];
                assert!(shear.abs() < 1e-6 * exact.abs(), "shear {s:?}");
            }
        }
    }
}

/// Seed 004 sec 3.2: a free 1 m cube heated by 100 °C (α = 1e-5) grows to
/// (1 + αΔT)³ = 1.003003 m³ without significant stress, at h = 1 and 0.1 m.
#[test]
fn free_cube_expands_without_stress() {
    let (alpha, dt, young, nu): (f64, f64, f64, f64) = (1e-5, 100.0, 20e9, 0.2);
    let expected = (1.0 + alpha * dt).powi(3);
    let constrained = young * alpha * dt / (1.0 - 2.0 * nu);
    for (h, ranks) in [(1.0, 1), (0.1, 2)] {
        let out = out_dir(&format!("cube-expansion-{h}"));
        let set = format!("bodies.cube.mesh.element_size={h}");
        run_ok(
            ranks,
            &root().join("scenarios/cube-expansion.toml"),
            &out,
            &["--set", &set],
        );
        let m = read_mech(&out, "cube-expansion");
        let k = m.times.len() - 1;
        let v = m.volume(k);
        assert!(
            (v / expected - 1.0).abs() < 1e-4,
            "h = {h}: volume {v:.7} m^3, expected {expected:.7}"
        );
        let smax = m.stress[k]
            .iter()
            .flat_map(|s| s.iter().flatten())
            .fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(
            smax < 0.01 * constrained,
            "h = {h}: max |stress| {smax:.3e} Pa vs constrained {constrained:.3e} Pa"
        );
        eprintln!("cube h = {h}: V = {v:.8} (exact {expected:.8}), max |sigma| = {smax:.3e} Pa");
    }
}

/// Seed 004 sec 3.3: the steady temperature of the hollow cylinder and its
/// plane-stress thermal stresses (radial and hoop), one and two ranks.
#[test]
fn hollow_cylinder_matches_plane_stress_solution() {
    use fdem::validation::thermoelastic::HollowCylinder;
    let hc = HollowCylinder::seed_004();
    let (a, b) = (hc.inner_radius, hc.outer_radius);
    let peak = (0..=200)
        .map(|i| hc.stress(a + (b - a) * i as f64 / 200.0).1.abs())
        .fold(0.0, f64::max);
    let mut finals = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("hollow-cylinder-{ranks}"));
        run_ok(
            ranks,
            &root().join("scenarios/hollow-cylinder.toml"),
            &out,
            &[],
        );
        let m = read_mech(&out, "hollow-cylinder");
        let k = m.times.len() - 1;
        // Steady temperature: the FE solution of the log profile, 0.5 % of T_b.
        let terr = m
            .coords
            .iter()
            .zip(&m.temperature[k])
            .map(|(x, t)| (t - hc.temperature(x[0].hypot(x[1]))).abs())
            .fold(0.0, f64::max);
        assert!(terr < 0.5, "{ranks} rank(s): max |T - T_exact| = {terr}");
        // Stresses, averaged in radial bins, away from the edges.
        let margin = 0.1 * (b - a);
        let bins = binned(&m.polar_stress(k, 0.0, 0.0), a + margin, b - margin, 12);
        assert!(bins.len() == 12);
        for &(r, srr, stt) in &bins {
            let (er, et) = hc.stress(r);
            eprintln!("r = {r:.4}: s_rr {srr:.4e} ({er:.4e}), s_tt {stt:.4e} ({et:.4e})");
            assert!(
                (srr - er).abs() < 0.05 * peak && (stt - et).abs() < 0.05 * peak,
                "{ranks} rank(s), r = {r}: sigma_rr {srr:.4e} vs {er:.4e}, \
                 sigma_tt {stt:.4e} vs {et:.4e} (5 % of {peak:.4e})"
            );
        }
        finals.push(m.disp[k].concat());
    }
    let d = rel_diff(&finals[0], &finals[1]);
    assert!(d < 1e-8, "1 vs 2 ranks: displacements differ by {d:e}");
}

/// Seed 004 sec 4, eq 40: the hoop stress in the concrete around a heated
/// steel core, against the bonded plane-stress solution.
#[test]
fn steel_in_concrete_hoop_stress_matches_eq_40() {
    use fdem::validation::thermoelastic::BondedDisc;
    let bd = BondedDisc::seed_004_sec4();
    let (a, b) = (bd.core_radius, bd.outer_radius);
    let out = out_dir("steel-in-concrete");
    run_ok(
        2,
        &root().join("scenarios/steel-in-concrete.toml"),
        &out,
        &[],
    );
    let m = read_mech(&out, "steel-in-concrete");
    let k = m.times.len() - 1;
    let polar = m.polar_stress(k, 0.0, 0.0);
    // Concrete ring, one element length clear of the interface and the edge.
    let bins = binned(&polar, a + 0.005, b - 0.005, 10);
    assert_eq!(bins.len(), 10);
    for &(r, _, stt) in &bins {
        let (_, et) = bd.stress(r);
        eprintln!("r = {r:.4}: s_tt {stt:.4e} (eq 40: {et:.4e})");
        assert!(
            (stt / et - 1.0).abs() < 0.05,
            "r = {r}: hoop stress {stt:.4e} vs eq 40 {et:.4e}"
        );
    }
}

/// Runs `scenarios/collision.toml` on `ranks` ranks with `extra` settings
/// and checks its history: momentum conserved to round-off, energy within
/// 1 %, the cubes touched and parted. Returns (header, rows, stdout).
fn collision(ranks: usize, tag: &str, extra: &[&str]) -> (Vec<String>, Vec<Vec<f64>>, String) {
    let out = out_dir(tag);
    let stdout = run_ok(ranks, &root().join("scenarios/collision.toml"), &out, extra);
    let (h, rows) = history(&out, "collision");
    let (px, ke, se, ce) = (
        col(&h, "momentum_x"),
        col(&h, "kinetic_energy"),
        col(&h, "strain_energy"),
        col(&h, "contact_energy"),
    );
    let (p0, e0) = (rows[0][px], rows[0][ke]);
    // m = 1000 kg/m^3 × 0.001 m^3 per cube: p0 = 1·1 − 0.5·1, E0 = ½(1 + 0.25).
    assert!(
        (p0 - 0.5).abs() < 1e-12 && (e0 - 0.625).abs() < 1e-12,
        "{:?}",
        rows[0]
    );
    let mut touched = false;
    for r in &rows {
        assert!(
            (r[px] - p0).abs() < 1e-12 * p0,
            "{tag}: momentum {} vs {p0}",
            r[px]
        );
        assert!(r[col(&h, "momentum_y")].abs() < 1e-12 && r[col(&h, "momentum_z")].abs() < 1e-12);
        let e = r[ke] + r[se] + r[ce];
        assert!(
            (e / e0 - 1.0).abs() < 0.01,
            "{tag}, t = {}: energy {e} vs {e0}",
            r[1]
        );
        touched |= r[ce] > 1e-3 * e0;
    }
    assert!(touched, "{tag}: the cubes never touched");
    // After the impact they move apart.
    let last = rows.last().unwrap();
    assert!(
        last[col(&h, "mech_contacts")] == 0.0,
        "{tag}: still in contact at the end"
    );
    (h, rows, stdout)
}

/// Two elastic cubes colliding head-on, no friction or damping: momentum is
/// conserved to round-off and energy within 1 %, on one and two ranks.
#[test]
fn head_on_collision_conserves_momentum_and_energy() {
    for ranks in [1, 2] {
        collision(ranks, &format!("collision-{ranks}"), &[]);
    }
}

/// The head-on collision with linearised contact (`linear_tolerance`
/// 0.02): momentum still conserved to round-off, energy within 1 %, the
/// rebound within 1 % of the exact contact's, and one and two ranks
/// identical. (A 1.5 m/s impact deforms the overlaps faster than the
/// tolerance allows, so nearly every evaluation is exact here; the saving
/// is in slowly deforming beds, see tests/packing.rs.)
#[test]
fn linearised_contact_follows_the_exact_collision() {
    let lin = ["--set", "mechanics.contact.linear_tolerance=0.02"];
    let (h, exact_rows, exact_out) = collision(1, "collision-exact-ref", &[]);
    let count = |s: &str| -> (f64, f64) {
        let l = summary_line(s, "mechanics").unwrap();
        (
            number_before(l, " pair evaluations"),
            number_before(l, " exact overlaps"),
        )
    };
    let mut lin_rows = Vec::new();
    for ranks in [1, 2] {
        let (_, rows, stdout) = collision(ranks, &format!("collision-linear-{ranks}"), &lin);
        let ((pairs, exact), (_, exact_ref)) = (count(&stdout), count(&exact_out));
        eprintln!(
            "collision, {ranks} rank(s): {exact} exact overlaps of {pairs} evaluations \
             (exact contact: {exact_ref})"
        );
        lin_rows.push(rows);
    }
    // Same trajectories; the history's sums over ranks differ by round-off.
    for (a, b) in lin_rows[0].iter().zip(&lin_rows[1]) {
        for (x, y) in a.iter().zip(b) {
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(y.abs()) + 1e-13,
                "1 and 2 ranks differ at t = {}: {x} vs {y}",
                a[1]
            );
        }
    }
    // The rebound: the kinetic energy after the impact.
    let (l, e) = (lin_rows[0].last().unwrap(), exact_rows.last().unwrap());
    let ke = col(&h, "kinetic_energy");
    assert!(
        (l[ke] / e[ke] - 1.0).abs() < 0.01,
        "final KE {} vs exact {}",
        l[ke],
        e[ke]
    );
}

/// A block sliding down a fixed 30° incline with μ = 0.3 accelerates at
/// g (sin θ − μ cos θ).
#[test]
fn block_slides_down_incline_at_coulomb_rate() {
    let out = out_dir("incline");
    run_ok(1, &root().join("scenarios/incline.toml"), &out, &[]);
    let (h, rows) = history(&out, "incline");
    let (th, mu, g) = (30f64.to_radians(), 0.3, 9.81);
    let exact = g * (th.sin() - mu * th.cos());
    // The block: 0.1 m cube of density 2000 → m = 2 kg; its speed along the slope.
    let mass = 2.0;
    let speed = |r: &Vec<f64>| {
        let p = [
            r[col(&h, "momentum_x")],
            r[col(&h, "momentum_y")],
            r[col(&h, "momentum_z")],
        ];
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() / mass
    };
    // Least-squares slope of speed against time after the first 0.05 s.
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[1] >= 0.05)
        .map(|r| (r[1], speed(r)))
        .collect();
    let n = pts.len() as f64;
    let (st, sv) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mt, mv) = (st / n, sv / n);
    let num: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mt).powi(2)).sum();
    let acc = num / den;
    eprintln!("incline: acceleration {acc:.4} m/s^2, exact {exact:.4}");
    assert!(
        (acc / exact - 1.0).abs() < 0.02,
        "acceleration {acc} vs g(sin - mu cos) = {exact}"
    );
}

/// Eight blocks dropped onto a fixed floor: one and two ranks follow the
/// same trajectories.
#[test]
fn eight_body_drop_same_on_one_and_two_ranks() {
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("drop8-{ranks}"));
        let stdout = run_ok(ranks, &root().join("scenarios/drop8.toml"), &out, &[]);
        assert!(stdout.contains("mechanics"), "{stdout}");
        runs.push(read_mech(&out, "drop8"));
        let (h, rows) = history(&out, "drop8");
        let contacts = rows
            .iter()
            .map(|r| r[col(&h, "mech_contacts")])
            .fold(0.0, f64::max);
        assert!(contacts > 0.0, "the blocks never touched anything");
    }
    let (a, b) = (&runs[0], &runs[1]);
    assert_eq!(a.times, b.times);
    for k in 0..a.times.len() {
        let d = rel_diff(&a.disp[k].concat(), &b.disp[k].concat());
        assert!(
            d < 1e-10,
            "t = {}: 1 vs 2 ranks differ by {d:e}",
            a.times[k]
        );
    }
    // The blocks fell: the lowest block moved down by about the initial gap.
    let k = a.times.len() - 1;
    let dz = a.disp[k].iter().map(|u| u[2]).fold(0.0, f64::min);
    assert!(dz < -0.04, "largest drop {dz}");
}

/// A bar on rollers pulled by a traction on its end settles to the uniaxial
/// state: σ_xx = t everywhere, end displacement t L / E (small strain).
#[test]
fn traction_on_a_bar_gives_uniaxial_stress() {
    let (t, young, len) = (1e6, 1e9, 1.0);
    let text = traction_bar(0, t, young, len);
    for ranks in [1, 2] {
        let out = out_dir(&format!("traction-{ranks}"));
        let scen = out.join("bar.toml");
        std::fs::write(&scen, &text).unwrap();
        run_ok(ranks, &scen, &out, &[]);
        let m = read_mech(&out, "bar");
        assert_uniaxial_bar(&m, t, len, t * len / young, &format!("{ranks} rank(s)"));
    }
}

/// The stress rows of the HDF5 file are in XDMF `Tensor6` order (xx, xy,
/// xz, yy, yz, zz), the order ParaView's XDMF readers expand: a bar pulled
/// along z carries σ_zz = t, which must be the sixth value of every row
/// (the third in fdem's old xx, yy, zz, xy, yz, xz order), and a bar pulled
/// along y σ_yy = t in the fourth. Read raw, without `read_mech`.
#[test]
fn uniaxial_stress_lands_in_its_tensor6_component() {
    let (t, young, len) = (1e6, 1e9, 1.0);
    for (axis, index) in [(1, 3), (2, 5)] {
        let out = out_dir(&format!("tensor6-{axis}"));
        let scen = out.join("bar.toml");
        std::fs::write(&scen, traction_bar(axis, t, young, len)).unwrap();
        run_ok(1, &scen, &out, &[]);
        let h5 = out.join("bar.h5");
        let k = fdem::io::read_times(&h5).unwrap().len() - 1;
        let rows = fdem::io::read_cell_field_step(&h5, "stress", k).unwrap();
        assert!(!rows.is_empty());
        for row in rows.chunks_exact(6) {
            for (c, v) in row.iter().enumerate() {
                let want = if c == index { t } else { 0.0 };
                assert!(
                    (v - want).abs() < 0.01 * t,
                    "pulled along axis {axis}: stress row {row:?}, expected {t:e} at index \
                     {index} (xx, xy, xz, yy, yz, zz) and ~0 elsewhere"
                );
            }
        }
    }
}

/// Thermo-mechanics with contact heat: a hot block resting on a cold
/// floor exchanges heat through the contact its weight makes; heat is
/// conserved, and one and two ranks agree.
#[test]
fn hot_block_on_floor_conducts_through_its_contact() {
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("hot-block-{ranks}"));
        let stdout = run_ok(
            ranks,
            &root().join("scenarios/hot-block-on-floor.toml"),
            &out,
            &[],
        );
        let (h, rows) = history(&out, "hot-block-on-floor");
        let last = rows.last().unwrap();
        let area = last[col(&h, "contact_area")];
        // The block still rocks a little on its penalty springs: 10 %.
        assert!(
            (area / 0.01 - 1.0).abs() < 0.1,
            "{ranks} rank(s): contact area {area} vs the block's base 0.01 m^2\n{stdout}"
        );
        assert!(last[col(&h, "mech_contacts")] > 0.0);
        let (b0, b1) = (
            rows[0][col(&h, "block_mean_T")],
            last[col(&h, "block_mean_T")],
        );
        let f1 = last[col(&h, "floor_mean_T")];
        assert!(b1 < b0 - 5.0 && f1 > 1.0, "block {b0} -> {b1}, floor {f1}");
        // Insulated: the stored heat does not change.
        let (s0, s1) = (
            rows[0][col(&h, "stored_heat")],
            last[col(&h, "stored_heat")],
        );
        assert!(
            ((s1 - s0) / s0).abs() < 1e-9,
            "{ranks} rank(s): stored heat {s0} -> {s1}"
        );
        // Discrete maximum principle (issue 15): the pair starts at 0 and
        // 100 °C, insulated; as shipped (lumped capacity) no node leaves
        // [0, 100] (the consistent capacity reached -11.4 and 118.2 °C).
        let r = read_results(&out, "hot-block-on-floor");
        let (lo, hi) = assert_within_bounds(&r, 0.0, 100.0, "hot block on floor");
        println!("hot block, {ranks} rank(s): T in [{lo:.3e}, {hi:.4}]");
        runs.push(read_mech(&out, "hot-block-on-floor"));
    }
    let (a, b) = (&runs[0], &runs[1]);
    for k in 0..a.times.len() {
        let d = rel_diff(&a.temperature[k], &b.temperature[k]);
        assert!(d < 1e-8, "t = {}: temperatures differ by {d:e}", a.times[k]);
    }
}

/// Packing-stage damping (`mechanics.free_damping = 0`): a block alone in
/// the air falls freely, x = ½ g t² (the explicit sum g Δt² n(n+1)/2 is
/// within Δt/t of it), while a block sliding on the floor (frictionless)
/// is damped, its slide x = v0 (1 − e^{−ct})/c; one and two ranks agree.
#[test]
fn free_damping_spares_bodies_in_free_flight() {
    let (c, v0, t_end, g) = (20.0, 0.1, 0.1, 9.81);
    let text = format!(
        r#"
[time]
dt = 0.02
steps = 5

[[materials]]
name = "soft"
density = 1500.0
young = 5e6
poisson = 0.3

[[bodies]]
name = "floor"
material = "soft"
fixed = true
mesh = {{ kind = "box", origin = [-0.1, -0.1, -0.05], size = [0.5, 0.3, 0.05], element_size = 0.05 }}

[[bodies]]
name = "slider"
material = "soft"
initial_velocity = [{v0}, 0.0, 0.0]
mesh = {{ kind = "box", origin = [0.0, 0.0, -1e-5], size = [0.1, 0.1, 0.1], element_size = 0.05 }}

[[bodies]]
name = "lone"
material = "soft"
mesh = {{ kind = "box", origin = [1.0, 0.0, 1.0], size = [0.1, 0.1, 0.1], element_size = 0.05 }}

[mechanics]
gravity = [0.0, 0.0, -{g}]
damping = {c}
free_damping = 0.0

[mechanics.contact]
penalty = 5e7
friction = 0.0
damping_ratio = 0.2
slip_velocity = 1e-3
"#
    );
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("free-damping-{ranks}"));
        let scen = out.join("free.toml");
        std::fs::write(&scen, &text).unwrap();
        run_ok(ranks, &scen, &out, &[]);
        let m = read_mech(&out, "free");
        let k = m.times.len() - 1;
        assert!((m.times[k] - t_end).abs() < 1e-12);
        let mean = |pick: &dyn Fn(&[f64; 3]) -> bool, d: usize| {
            let v: Vec<f64> = m
                .coords
                .iter()
                .zip(&m.disp[k])
                .filter(|(x, _)| pick(x))
                .map(|(_, u)| u[d])
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        // Not in the seeds: free fall ½ g t²; damped slide v0 (1 − e^{−ct})/c.
        let fall = mean(&|x| x[0] > 0.9, 2);
        let want = -0.5 * g * t_end * t_end;
        assert!(
            (fall / want - 1.0).abs() < 0.01,
            "{ranks} rank(s): lone block fell {fall}, free fall {want}"
        );
        let slide = mean(&|x| x[0] < 0.5 && x[2] > 0.01, 0);
        let damped = v0 * (1.0 - (-c * t_end).exp()) / c;
        assert!(
            (slide / damped - 1.0).abs() < 0.02,
            "{ranks} rank(s): slider moved {slide}, damped slide {damped} (undamped {})",
            v0 * t_end
        );
        runs.push(m.disp[k].concat());
    }
    let d = rel_diff(&runs[0], &runs[1]);
    assert!(d < 1e-10, "1 vs 2 ranks differ by {d:e}");
}
