//! Coulomb friction with stick (`mechanics.contact.tangential_stiffness`,
//! issue 22): a tangential spring per touching tet pair, carried across
//! detections, ranks and restarts. A block on an incline below its
//! friction angle stays put (the regularised law lets it creep); above
//! it, the block still slides at g (sin θ − μ cos θ); a packing with
//! springs follows the same trajectories on 1 and 2 ranks and after a
//! restart.

use crate::common::*;
use fdem::io::checkpoint::Checkpoint;

fn incline(out: &std::path::Path, friction: f64, spring: f64, steps: u32) {
    run_ok(
        1,
        &root().join("scenarios/incline.toml"),
        out,
        &[
            "--set",
            &format!("mechanics.contact.friction={friction}"),
            "--set",
            &format!("mechanics.contact.tangential_stiffness={spring}"),
            "--set",
            &format!("time.steps={steps}"),
        ],
    );
}

/// The largest displacement of any node between output steps `i` and `j`.
fn moved(m: &Mech, i: usize, j: usize) -> f64 {
    m.disp[i]
        .iter()
        .zip(&m.disp[j])
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// tan 30° = 0.577 < μ = 0.7: the block must stick. Between t = 0.15 s
/// and 0.5 s (after it has settled onto the plane), the regularised law
/// lets it creep by millimetres; with the spring it moves by less than a
/// hundredth of that.
#[test]
fn a_block_below_its_friction_angle_sticks_with_the_spring() {
    let (creep_dir, stick_dir) = (out_dir("stick/creep"), out_dir("stick/stick"));
    incline(&creep_dir, 0.7, 0.0, 100);
    incline(&stick_dir, 0.7, 0.8, 100);
    let (creep, stick) = (
        read_mech(&creep_dir, "incline"),
        read_mech(&stick_dir, "incline"),
    );
    assert_eq!(creep.times[3], 0.15);
    let last = creep.times.len() - 1;
    assert_eq!(creep.times[last], 0.5);
    let (c, s) = (moved(&creep, 3, last), moved(&stick, 3, last));
    eprintln!(
        "incline at mu = 0.7, t 0.15 -> 0.5 s: regularised {c:.3e} m, with the spring {s:.3e} m"
    );
    assert!(c > 1e-3, "the regularised law should creep: {c}");
    assert!(
        s < 1e-2 * c,
        "with the spring the block moved {s} m (creep {c} m)"
    );
    // The energy balance of the run with springs.
    let (h, rows) = history(&stick_dir, "incline");
    let r = rows.last().unwrap();
    let w = r[col(&h, "external_work")];
    let sum: f64 = [
        "kinetic_energy",
        "strain_energy",
        "contact_energy",
        "dissipated_energy",
    ]
    .iter()
    .map(|c| r[col(&h, c)])
    .sum();
    eprintln!("energy balance with springs: work {w:.4e} J, accounted {sum:.4e} J");
    assert!((w - sum).abs() < 0.05 * w, "work {w} against {sum}");
}

/// μ = 0.3 < tan 30°: with the spring the block slides at g (sin θ − μ cos θ).
#[test]
fn a_sliding_block_keeps_the_coulomb_rate_with_the_spring() {
    let out = out_dir("stick/slide");
    incline(&out, 0.3, 0.8, 60);
    let (h, rows) = history(&out, "incline");
    let (th, mu, g) = (30f64.to_radians(), 0.3, 9.81);
    let exact = g * (th.sin() - mu * th.cos());
    let mass = 2.0;
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r[1] >= 0.05)
        .map(|r| {
            let p = ["momentum_x", "momentum_y", "momentum_z"].map(|c| r[col(&h, c)]);
            (
                r[1],
                (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() / mass,
            )
        })
        .collect();
    let n = pts.len() as f64;
    let (mt, mv) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let num: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
    let den: f64 = pts.iter().map(|p| (p.0 - mt).powi(2)).sum();
    let acc = num / den;
    eprintln!("incline with the spring: acceleration {acc:.4} m/s^2, exact {exact:.4}");
    assert!((acc / exact - 1.0).abs() < 0.02, "{acc} against {exact}");
}

fn packing(ranks: usize, dir: &std::path::Path, extra: &[&str]) -> Checkpoint {
    let mut args = vec![
        "--set",
        "bodies.1.pack.count=50",
        "--set",
        "mechanics.contact.tangential_stiffness=0.8",
    ];
    args.extend_from_slice(extra);
    run_ok(
        ranks,
        &root().join("scenarios/nut-packing-deposit.toml"),
        dir,
        &args,
    );
    Checkpoint::read(&dir.join("nut-packing-deposit_checkpoint.h5")).unwrap()
}

/// The springs follow their pairs: a 50-nut deposition with springs gives
/// the same positions and velocities on 1 and 2 ranks, and restarted
/// (from 2 ranks onto 1, and onto 2) as straight through.
#[test]
fn springs_follow_their_pairs_across_ranks_and_restarts() {
    let end = ["--set", "time.end_time=0.12"];
    let one = packing(1, &out_dir("stick/pack-1"), &end);
    let two = packing(2, &out_dir("stick/pack-2"), &end);
    assert_eq!(one.positions, two.positions, "1 and 2 ranks differ");
    assert_eq!(one.velocities, two.velocities, "1 and 2 ranks differ");
    let first = out_dir("stick/pack-first");
    packing(2, &first, &["--set", "time.end_time=0.06"]);
    let ck = first.join("nut-packing-deposit_checkpoint.h5");
    // The checkpoint holds the springs of the touching pairs.
    let file = fdem::io::checkpoint::CheckpointFile::open(&ck).unwrap();
    let springs = file.spring_block(0, 1).unwrap();
    eprintln!("{} springs in the checkpoint at 0.06 s", springs.len());
    assert!(springs.len() > 100, "{} springs", springs.len());
    assert!(
        springs.windows(2).all(|w| w[0].0 < w[1].0),
        "rows not sorted by pair"
    );
    for ranks in [1, 2] {
        let again = packing(
            ranks,
            &out_dir(&format!("stick/pack-restart-{ranks}")),
            &[end[0], end[1], "--restart", ck.to_str().unwrap()],
        );
        assert_eq!(
            one.positions, again.positions,
            "restart on {ranks} rank(s) differs"
        );
        assert_eq!(
            one.velocities, again.velocities,
            "restart on {ranks} rank(s) differs"
        );
    }
}
