//! Contact heat transfer, seed 000 secs 3–5: two bars in near-perfect
//! contact against the slab series; two discs against the circle-overlap
//! surface and the pipe-network model; conservation, symmetry, and one rank
//! against two on a stack of cubes.

use crate::common::*;
use fdem::validation::{circle_overlap_surface, PipeNetwork, SlabProblem};

fn sets(list: &[String]) -> Vec<&str> {
    list.iter().flat_map(|s| ["--set", s.as_str()]).collect()
}

/// Mean |T − T_a| in percent against the equivalent slab: heat runs through
/// the left bar to its end at x = 0.5, across Rc = 0.001 m²K/W (worth 1 mm of
/// the k = 1 material), then through the right bar from its start at
/// x = 0.499. A point of the right bar at x is thus x + 0.002 from the
/// insulated end, and the held face at 0.999 is at L = 1.001.
fn two_bar_errors(h: f64, tag: &str) -> [f64; 3] {
    let out = out_dir(tag);
    let s = [
        format!("bodies.left.mesh.element_size={h}"),
        format!("bodies.right.mesh.element_size={h}"),
    ];
    let stdout = run_ok(1, &root().join("scenarios/two-bars.toml"), &out, &sets(&s));
    assert!(
        stdout.contains("area 1.000000e-2"),
        "contact surface must be the cross-section:\n{stdout}"
    );
    assert!(stdout.contains("assembled 1 time"), "{stdout}");
    let r = read_results(&out, "two-bars");
    assert_within_bounds(&r, 0.0, 1.0, &format!("two bars at h = {h}"));
    let p = SlabProblem {
        length: 1.001,
        ..SlabProblem::seed_000()
    };
    let ids = fdem::io::read_static_node_field_i32(&out.join("two-bars.h5"), "body").unwrap();
    let node_ids =
        fdem::io::read_static_node_field_i32(&out.join("two-bars.h5"), "node_id").unwrap();
    let mut body_of = vec![0; ids.len()];
    for (row, &id) in node_ids.iter().enumerate() {
        body_of[id as usize] = ids[row];
    }
    [10.0, 50.0, 100.0].map(|t| {
        let k = step_at(&r, t);
        let sum: f64 = r
            .coords
            .iter()
            .enumerate()
            .map(|(n, x)| {
                let xu = if body_of[n] == 1 { x[0] + 0.002 } else { x[0] };
                (r.temperature[k][n] - p.temperature(xu, t)).abs()
            })
            .sum();
        100.0 * sum / r.coords.len() as f64
    })
}

/// Seed 000 Table 2, FDEM columns.
#[test]
fn two_bars_match_table_2_fdem_errors() {
    let e1 = two_bar_errors(0.1, "bars-0.1");
    let e2 = two_bar_errors(0.05, "bars-0.05");
    eprintln!("two bars h = 0.1 : {e1:?} %");
    eprintln!("two bars h = 0.05: {e2:?} %");
    let paper1: [f64; 3] = [0.489, 0.098, 0.035];
    let paper2: [f64; 3] = [0.167, 0.050, 0.018];
    for i in 0..3 {
        assert!(
            e1[i] <= paper1[i],
            "h=0.1 output {i}: {} % > paper {} %",
            e1[i],
            paper1[i]
        );
        assert!(
            e2[i] <= paper2[i],
            "h=0.05 output {i}: {} % > paper {} %",
            e2[i],
            paper2[i]
        );
    }
}

/// Insulated bodies at different temperatures: what one loses through
/// contact the other gains, and the total is constant, for θ = 0, 0.5, 1.
#[test]
fn contact_heat_is_conserved_for_every_theta() {
    for (theta, cap) in [(0.0, "lumped"), (0.5, "consistent"), (1.0, "lumped")] {
        let out = out_dir(&format!("conserve-{theta}"));
        let s = [
            "thermal.bc=[]".to_string(),
            "bodies.right.initial_temperature=1.0".to_string(),
            format!("thermal.theta={theta}"),
            format!("thermal.capacity={cap}"),
            "time.end_time=20".to_string(),
            "output.times=[]".to_string(),
            "output.every=4000".to_string(),
        ];
        run_ok(1, &root().join("scenarios/two-bars.toml"), &out, &sets(&s));
        let (h, rows) = history(&out, "two-bars");
        let (e, la, ra) = (
            col(&h, "stored_heat"),
            col(&h, "left_mean_T"),
            col(&h, "right_mean_T"),
        );
        // Equal bodies: the heat of each is C × mean T with the same C.
        let c = rows[0][e] / (rows[0][la] + rows[0][ra]);
        let first = &rows[0];
        let last = rows.last().unwrap();
        let gain_left = c * (last[la] - first[la]);
        let loss_right = c * (first[ra] - last[ra]);
        assert!(
            gain_left > 1e-3 * rows[0][e],
            "theta {theta}: no heat flowed"
        );
        assert!(
            (gain_left - loss_right).abs() < 1e-10 * gain_left,
            "theta {theta}: left gains {gain_left}, right loses {loss_right}"
        );
        for r in &rows {
            assert!(
                (r[e] - first[e]).abs() < 1e-11 * first[e],
                "theta {theta}: total heat drifts"
            );
        }
    }
}

/// Swapping which body comes first (so which tet is target and which
/// contactor) gives the same surface and the same temperatures.
#[test]
fn swapping_target_and_contactor_changes_nothing() {
    let text = std::fs::read_to_string(root().join("scenarios/two-bars.toml")).unwrap();
    let a = text.find("[[bodies]]").unwrap();
    let b = text[a + 1..].find("[[bodies]]").unwrap() + a + 1;
    let c = text.find("[thermal]").unwrap();
    let swapped = format!("{}{}{}{}", &text[..a], &text[b..c], &text[a..b], &text[c..]);
    let dir = out_dir("swap");
    let scen = dir.join("two-bars-swapped.toml");
    std::fs::write(&scen, swapped).unwrap();
    let short = ["--set", "time.end_time=10", "--set", "output.times=[10.0]"];
    let o1 = out_dir("swap-a");
    let o2 = out_dir("swap-b");
    let s1 = run_ok(1, &root().join("scenarios/two-bars.toml"), &o1, &short);
    let s2 = run_ok(1, &scen, &o2, &short);
    let area = |s: &str| {
        summary_line(s, "contact")
            .unwrap()
            .split("area ")
            .nth(1)
            .unwrap()[..12]
            .to_string()
    };
    assert_eq!(area(&s1), area(&s2));
    let r1 = read_results(&o1, "two-bars");
    let r2 = read_results(&o2, "two-bars-swapped");
    // Match nodes by position (and side of the interface by temperature order).
    let key = |x: &[f64; 3], t: f64| {
        (
            (x[0] * 1e6).round() as i64,
            (x[1] * 1e6).round() as i64,
            (x[2] * 1e6).round() as i64,
            (t * 1e3).round() as i64,
        )
    };
    let last = |r: &Results| {
        let k = r.temperature.len() - 1;
        let mut v: Vec<_> = r
            .coords
            .iter()
            .zip(&r.temperature[k])
            .map(|(x, &t)| (key(x, t), t))
            .collect();
        v.sort_by_key(|a| a.0);
        v.into_iter().map(|(_, t)| t).collect::<Vec<f64>>()
    };
    let d = rel_diff(&last(&r1), &last(&r2));
    assert!(d < 1e-10, "swapped order changes temperatures by {d:e}");
}

/// The 2×2×2 stack of overlapping cubes on 1 and 2 ranks, METIS cutting
/// through bodies and contacts: the same temperatures and contact set.
#[test]
fn cube_stack_one_vs_two_ranks() {
    let scen = root().join("scenarios/cube-stack.toml");
    let o1 = out_dir("stack-np1");
    let o2 = out_dir("stack-np2");
    let s1 = run_ok(1, &scen, &o1, &[]);
    let s2 = run_ok(2, &scen, &o2, &[]);
    assert_eq!(
        summary_line(&s1, "contact"),
        summary_line(&s2, "contact"),
        "same contact set"
    );
    let r1 = read_results(&o1, "cube-stack");
    let r2 = read_results(&o2, "cube-stack");
    assert_same_temperatures(&r1, &r2, 1e-8, "cube stack, 1 vs 2 ranks");
    // Between the convection ambient (0) and the held face (100).
    for r in [&r1, &r2] {
        assert_within_bounds(r, 0.0, 100.0, "cube stack");
    }
    let ranks = fdem::io::read_static_cell_field_i32(&o2.join("cube-stack.h5"), "rank").unwrap();
    let bodies = fdem::io::read_static_cell_field_i32(&o2.join("cube-stack.h5"), "body").unwrap();
    // Each rank holds some cubes; every cube touches three others, so
    // contacts cross the partition.
    let on = |r: i32| -> Vec<i32> {
        let mut v: Vec<i32> = ranks
            .iter()
            .zip(&bodies)
            .filter(|(&x, _)| x == r)
            .map(|(_, &b)| b)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    assert!(
        !on(0).is_empty() && !on(1).is_empty(),
        "both ranks must own cubes"
    );
    // Heat balance with contacts.
    let (h, rows) = history(&o2, "cube-stack");
    let (e, q) = (col(&h, "stored_heat"), col(&h, "boundary_heat_in"));
    let last = rows.last().unwrap();
    let change = last[e] - rows[0][e];
    assert!(
        (change - last[q]).abs() < 1e-8 * change.abs(),
        "balance {change} vs {}",
        last[q]
    );
}

fn disc_area(stdout: &str) -> f64 {
    let l = summary_line(stdout, "contact").unwrap();
    l.split("area ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// The computed surface of the two discs of `scenarios/two-discs.toml` at
/// element size `h`, with disc A turned by `rot_a` and disc B by `rot_b`
/// degrees about their axes, and any further settings.
fn disc_surface(h: f64, rot_a: f64, rot_b: f64, extra: &[String], tag: &str) -> f64 {
    let out = out_dir(tag);
    let mut s = vec![
        format!("bodies.A.mesh.element_size={h}"),
        format!("bodies.B.mesh.element_size={h}"),
        format!("bodies.A.rotate=[0.0,0.0,{rot_a}]"),
        format!("bodies.B.rotate=[0.0,0.0,{rot_b}]"),
        "time.end_time=0.001".to_string(),
        "output.every=0".to_string(),
    ];
    s.extend_from_slice(extra);
    let stdout = run_ok(1, &root().join("scenarios/two-discs.toml"), &out, &sets(&s));
    let _ = std::fs::remove_dir_all(&out);
    disc_area(&stdout)
}

/// Seed 000 eqs 41–42 against the computed surface of the two discs (issue:
/// within 4 % at mesh 0.08 m and 0.5 % at 0.04 m; the paper 4 % and 0.4 %).
///
/// The lens of two discs overlapping by p = 0.01 m is ~2.5 boundary segments
/// long at 0.08 m, and a segment's sagitta is a tenth of p, so the surface
/// depends on where the boundary nodes fall. Besides the scenario as it is,
/// the test turns each disc by quarter segments (16 alignments per size) and
/// asserts the alignment average (what a packing of randomly oriented discs
/// sees) and the envelope. With nodes on the circle (inscribed polygons) the
/// surface is short for every alignment, which the last check shows.
#[test]
fn disc_contact_surface_against_circle_overlap() {
    let theory = circle_overlap_surface(1.0, 1.0, 0.01, 0.1);
    let err = |s: f64| (s - theory) / theory;
    for (h, bound) in [(0.08, 0.04), (0.04, 0.005)] {
        let scenario = err(disc_surface(h, 0.0, 0.0, &[], &format!("disc-area-{h}")));
        // Boundary segments and their angle, as cylinder_mesh makes them.
        let n_b = (std::f64::consts::TAU / h).round();
        let seg = 360.0 / n_b;
        let mut sweep = Vec::new();
        for a in 0..4 {
            for b in 0..4 {
                let (ra, rb) = (seg * a as f64 / 4.0, seg * b as f64 / 4.0);
                let tag = format!("disc-sweep-{h}-{a}-{b}");
                sweep.push(err(disc_surface(h, ra, rb, &[], &tag)));
            }
        }
        let mean = sweep.iter().sum::<f64>() / sweep.len() as f64;
        let (lo, hi) = sweep
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &e| {
                (l.min(e), u.max(e))
            });
        eprintln!(
            "disc contact surface at h = {h} (theory {theory:.6e}): scenario {:+.2} %, \
             over 16 alignments {:+.2} .. {:+.2} %, mean {:+.2} %",
            100.0 * scenario,
            100.0 * lo,
            100.0 * hi,
            100.0 * mean
        );
        assert!(
            scenario.abs() < bound,
            "h = {h}: scenario {:.2} %",
            100.0 * scenario
        );
        assert!(
            mean.abs() < 0.005,
            "h = {h}: alignment mean {:.2} %",
            100.0 * mean
        );
        // Measured envelope (docs/validation.md): within 1.2 % at both sizes.
        assert!(
            lo > -0.015 && hi < 0.015,
            "h = {h}: envelope {:.2} .. {:.2} %",
            100.0 * lo,
            100.0 * hi
        );
    }
    // The inscribed polygons' bias: short by more than 4 % at 0.08 m.
    let inscribed = ["A", "B"].map(|b| format!("bodies.{b}.mesh.boundary=inscribed"));
    let e = err(disc_surface(0.08, 0.0, 0.0, &inscribed, "disc-inscribed"));
    eprintln!("inscribed boundary nodes at h = 0.08: {:+.2} %", 100.0 * e);
    assert!(e < -0.04, "inscribed: {:.2} %", 100.0 * e);
}

/// Mean temperature of disc B against the pipe-network model (eqs 33–40,
/// 43) built from the computed surface. Error: mean over outputs of
/// |ΔT_B(FDEM) − ΔT_B(pipe)| / |ΔT_B(pipe)|, ΔT_B the change since t = 0.
fn disc_vs_pipe(delta_t: &str, k: f64, tag: &str) -> f64 {
    let out = out_dir(tag);
    let s = [
        format!("contact.delta_t={delta_t}"),
        format!("materials.disc.conductivity={k}"),
        "time.end_time=50".to_string(),
        "output.every=5000".to_string(),
    ];
    let stdout = run_ok(1, &root().join("scenarios/two-discs.toml"), &out, &sets(&s));
    let s_c = disc_area(&stdout);
    // Discs at 0 and 1: every node stays in [0, 1] (cylinder meshes have a
    // few positive couplings, too small to break the bounds here).
    let r = read_results(&out, "two-discs");
    assert_within_bounds(&r, 0.0, 1.0, &format!("two discs, {delta_t} dT, k = {k}"));
    let pipe = PipeNetwork::fdem_adjusted(100.0, 1.0, k, k, 1.0, 1.0, 0.1, s_c, 1.0);
    let (h, rows) = history(&out, "two-discs");
    let (t, b) = (col(&h, "time"), col(&h, "B_mean_T"));
    let tb0 = rows[0][b];
    let errs: Vec<f64> = rows[1..]
        .iter()
        .map(|r| {
            let (_, pb) = pipe.exact(0.0, tb0, r[t]);
            ((r[b] - tb0) - (pb - tb0)).abs() / (pb - tb0).abs()
        })
        .collect();
    errs.iter().sum::<f64>() / errs.len() as f64
}

#[test]
fn discs_against_pipe_network() {
    let avg = disc_vs_pipe("average", 1.0, "disc-avg");
    let local = disc_vs_pipe("local", 1.0, "disc-local");
    let avg100 = disc_vs_pipe("average", 100.0, "disc-avg-k100");
    let local100 = disc_vs_pipe("local", 100.0, "disc-local-k100");
    eprintln!(
        "discs vs pipe network: average-dT {:.3} %, local-dT {:.3} % (paper 0.63 %, 7.6 %); k x 100: {:.3} %, {:.3} % (paper 0.7 %)",
        100.0 * avg,
        100.0 * local,
        100.0 * avg100,
        100.0 * local100
    );
    assert!(
        avg < 0.01,
        "average-dT vs pipe network {:.3} %",
        100.0 * avg
    );
    assert!(
        avg100 < 0.01 && local100 < 0.01,
        "k x 100: {avg100}, {local100}"
    );
    // Local ΔT exchanges less heat than the mean temperatures suggest when
    // conduction inside the discs is slow: a clearly larger error.
    assert!(local > 2.0 * avg && local > 0.01, "local-dT {local}");
}

/// Detection at a cadence: the contact set of the static bars never
/// changes, so the operator is assembled once however often it is checked;
/// the histories carry the contact count and area.
#[test]
fn redetection_keeps_the_operator_when_contacts_are_unchanged() {
    let out = out_dir("redetect");
    let s = [
        "contact.every=1000".to_string(),
        "time.end_time=5".to_string(),
        "output.times=[]".to_string(),
        "output.every=2000".to_string(),
    ];
    let stdout = run_ok(2, &root().join("scenarios/two-bars.toml"), &out, &sets(&s));
    let line = summary_line(&stdout, "contact").unwrap();
    assert!(
        line.contains("10 detection(s)") && line.contains("assembled 1 time(s)"),
        "{line}"
    );
    let (h, rows) = history(&out, "two-bars");
    for r in &rows {
        assert!(r[col(&h, "contacts")] > 0.0);
        assert!((r[col(&h, "contact_area")] - 0.01).abs() < 1e-12);
    }
}

/// A punch moved into a plate: no contact, then contact over the punch's
/// face and the part of its side walls inside the plate; the operator is rebuilt as the set changes, heat is conserved
/// across rebuilds, temperatures stay within the initial bounds (lumped
/// capacity), and 1 and 2 ranks agree.
#[test]
fn moving_punch_rebuilds_on_contact_changes() {
    let scen = root().join("scenarios/moving-punch.toml");
    let o1 = out_dir("punch-np1");
    let o2 = out_dir("punch-np2");
    let s1 = run_ok(1, &scen, &o1, &[]);
    run_ok(2, &scen, &o2, &[]);
    let line = summary_line(&s1, "contact").unwrap();
    let assembled: u32 = line
        .split("assembled ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(assembled > 1, "{line}");
    let (h, rows) = history(&o1, "moving-punch");
    let (nc, area, e) = (
        col(&h, "contacts"),
        col(&h, "contact_area"),
        col(&h, "stored_heat"),
    );
    let (t, pmin, pmax) = (
        col(&h, "time"),
        col(&h, "plate_min_T"),
        col(&h, "punch_max_T"),
    );
    for r in &rows {
        if r[t] < 0.5 {
            assert_eq!(r[nc], 0.0, "contact before the gap closes at t = {}", r[t]);
        } else if r[t] > 0.55 {
            // The punch face (0.0025 m^2), plus half its side walls sunk
            // into the plate by delta = 0.01 (t - 0.5) (eq 25: they are
            // S_con, and the plate's grid planes they lie in count once),
            // at the last detection (every 10 steps of 0.01 s, not at the
            // final step 200).
            let step = (r[t] / 0.01).round() as u64;
            let detected = (step.min(199) / 10 * 10) as f64 * 0.01;
            let delta = 0.01 * (detected - 0.5);
            let exact = 0.0025 + 0.5 * 4.0 * 0.05 * delta;
            assert!(
                (r[area] - exact).abs() < 1e-12,
                "area {} at t = {} (exact {exact})",
                r[area],
                r[t]
            );
        }
        assert!(
            (r[e] - rows[0][e]).abs() < 1e-10 * rows[0][e],
            "heat not conserved at t = {}",
            r[t]
        );
        assert!(
            r[pmin] >= -1e-9 && r[pmax] <= 100.0 + 1e-9,
            "bounds violated at t = {}",
            r[t]
        );
    }
    let last = rows.last().unwrap();
    // About 2.5 W/K × 100 K × 1.5 s over the plate's 15.6 kJ/K: a rise of order 0.02.
    assert!(
        last[col(&h, "plate_mean_T")] > 0.01,
        "heat reached the plate"
    );
    let r1 = read_results(&o1, "moving-punch");
    let r2 = read_results(&o2, "moving-punch");
    assert_same_temperatures(&r1, &r2, 1e-8, "moving punch, 1 vs 2 ranks");
    for r in [&r1, &r2] {
        assert_within_bounds(r, 0.0, 100.0, "moving punch");
    }
}

/// Issue 16: a thermal run restarted in its own output directory continues
/// the series: the same output times and temperatures as the uninterrupted
/// run, and the history's cumulative KSP iterations carry on.
#[test]
fn restart_in_place_continues_the_thermal_series() {
    let scen = root().join("scenarios/two-bars.toml");
    let common = [
        "--set",
        "output.every=1000",
        "--set",
        "output.times=[]",
        "--set",
        "output.checkpoint=true",
    ];
    let full = out_dir("inplace-bars-full");
    run_ok(
        2,
        &scen,
        &full,
        &[&common[..], &["--set", "time.end_time=10"]].concat(),
    );
    let dir = out_dir("inplace-bars");
    run_ok(
        2,
        &scen,
        &dir,
        &[&common[..], &["--set", "time.end_time=5"]].concat(),
    );
    let ck = dir.join("two-bars_checkpoint.h5");
    let restart = [
        "--set",
        "time.end_time=10",
        "--restart",
        ck.to_str().unwrap(),
    ];
    run_ok(2, &scen, &dir, &[&common[..], &restart[..]].concat());
    let a = read_results(&full, "two-bars");
    let b = read_results(&dir, "two-bars");
    assert_eq!(a.times, b.times);
    assert_eq!(a.temperature, b.temperature, "temperatures differ");
    let (ha, ra) = history(&full, "two-bars");
    let (hb, rb) = history(&dir, "two-bars");
    assert_eq!(ha, hb);
    let its = col(&ha, "ksp_iterations");
    for (x, y) in ra.iter().zip(&rb) {
        assert_eq!(x[its], y[its], "cumulative KSP iterations at t = {}", x[1]);
        for (c, (u, v)) in x.iter().zip(y).enumerate() {
            assert!(
                (u - v).abs() <= 1e-12 * u.abs().max(1.0),
                "column {} at t = {}: {u} vs {v}",
                ha[c],
                x[1]
            );
        }
    }
    assert!(rb.last().unwrap()[its] > rb[rb.len() / 2][its]);
}
