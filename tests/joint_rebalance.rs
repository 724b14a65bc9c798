//! Repartition with joints (issue 19, `mechanics.rebalance`): eight
//! jointed blocks dropped onto a floor (scenarios/drop8.toml with weak
//! joints) crack where they land, and on 2 ranks the whole blocks change
//! rank during the run (repartitions every 2 steps at any imbalance). The
//! joints' damage travels with their tets, so trajectories, the joint
//! grid and the broken joints are bitwise those of one rank; on a hot
//! floor with thermal contact, temperatures agree with one rank's to 1e-8.

use crate::common::*;

/// drop8 with its blocks jointed: f_t = 20 kPa, p_f = 10 E.
fn scenario() -> String {
    let text = std::fs::read_to_string(root().join("scenarios/drop8.toml")).unwrap();
    let material = "name = \"soft\"\n";
    assert!(text.contains(material));
    let block = "lattice = { count = [2, 2, 2]";
    assert!(text.contains(block));
    text.replacen(
        material,
        "name = \"soft\"\ntensile_strength = 2e4\ncohesion = 4e4\nfriction_angle = 30.0\n\
         g_i = 2.0\ng_ii = 4.0\nfracture_penalty = 5e7\n",
        1,
    )
    .replacen(block, &format!("fracture = {{}}\n{block}"), 1)
}

struct Drop {
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<f64>>,
    joints: Vec<[Vec<f64>; 4]>,
    history: (Vec<String>, Vec<Vec<f64>>),
    summary: String,
    owners: Vec<Vec<f64>>,
    /// A coupled run's temperatures.
    temperatures: Option<Results>,
}

/// The jointed drop `text` on `ranks` ranks, repartitioned every 2 steps.
fn drop(tag: &str, text: &str, ranks: usize) -> Drop {
    let dir = out_dir(&format!("joint-rebalance-{tag}{ranks}"));
    let scen = dir.join("drop.toml");
    std::fs::write(&scen, text).unwrap();
    let out = dir.join("out");
    let summary = run_ok(
        ranks,
        &scen,
        &out,
        &[
            "--set",
            "output.every=2",
            "--set",
            "mechanics.rebalance.every=2",
            "--set",
            "mechanics.rebalance.threshold=1.0",
        ],
    );
    let m = read_mech(&out, "drop");
    let h5 = out.join("drop.h5");
    Drop {
        vel: velocities_by_node_id(&h5, m.times.len()),
        // The field exists where a repartition may move elements.
        owners: (0..m.times.len())
            .filter(|_| ranks > 1)
            .map(|k| fdem::io::read_cell_field_step(&h5, "owner_rank", k).unwrap())
            .collect(),
        disp: m.disp,
        joints: joint_fields(&out, "drop"),
        history: history(&out, "drop"),
        temperatures: text
            .contains("[thermal]")
            .then(|| read_results(&out, "drop")),
        summary,
    }
}

#[test]
fn jointed_blocks_repartitioned_on_two_ranks_fall_and_crack_bitwise_as_on_one() {
    repartitioned_bitwise("", &scenario());
}

/// The jointed blocks at 20 C dropped onto a floor at 300 C with thermal
/// contact (R_c = 1e-3 m² K/W, detected at the start and again when
/// cracks change, `contact.every = 0`) and no expansion: repartitioned on
/// 2 ranks, the trajectories and joints are bitwise those of one rank and
/// the temperatures agree to 1e-8 relative (the direct solver's round-off)
/// before and after joints break. Before the runs detected the contacts
/// at every step where a repartition may happen, the repartitions found
/// the blocks on the floor a step before one rank did (6e-5 apart).
#[test]
fn jointed_blocks_on_a_hot_floor_repartitioned_heat_as_on_one_rank() {
    let text = scenario()
        .replacen(
            "density = 1500.0",
            "density = 1500.0\nconductivity = 2.0\nspecific_heat = 800.0",
            1,
        )
        .replacen(
            "rotate = [3.0, 5.0, 7.0]",
            "rotate = [3.0, 5.0, 7.0]\ninitial_temperature = 20.0",
            1,
        )
        .replacen(
            "fixed = true",
            "fixed = true\ninitial_temperature = 300.0",
            1,
        )
        + "\n[thermal]\ntheta = 1.0\n\n[contact]\nresistance = 1e-3\n";
    assert!(text.contains("conductivity") && text.contains("initial_temperature = 300.0"));
    repartitioned_bitwise("hot-", &text);
}

/// `text` run on 1 and on 2 ranks (repartitioned): the same trajectories,
/// joint grid, broken joints and joint counts, and temperatures to 1e-8.
fn repartitioned_bitwise(tag: &str, text: &str) {
    let one = drop(tag, text, 1);
    let want = broken(&one.joints.last().expect("joint outputs")[1]);
    assert!(
        !want.is_empty(),
        "the blocks must crack where they land: no joint broke"
    );
    let two = drop(tag, text, 2);
    let (done, moved) = repartitions(&two.summary);
    assert!(
        done >= 1 && moved > 0,
        "2 ranks: {done} repartitions, {moved} bodies moved:\n{}",
        two.summary
    );
    let (first, last) = (&two.owners[0], two.owners.last().unwrap());
    let changed = first.iter().zip(last).filter(|(a, b)| a != b).count();
    assert!(changed > 0, "2 ranks: no element changed rank");
    assert_eq!(two.disp.len(), one.disp.len(), "outputs");
    for k in 0..one.disp.len() {
        assert!(
            two.disp[k] == one.disp[k],
            "output {k}: displacements differ"
        );
        assert!(two.vel[k] == one.vel[k], "output {k}: velocities differ");
    }
    assert_eq!(two.joints.len(), one.joints.len(), "joint outputs");
    for (k, (a, b)) in two.joints.iter().zip(&one.joints).enumerate() {
        for (f, name) in ["damage", "mode", "broke_at", "opening"].iter().enumerate() {
            assert!(a[f] == b[f], "joint output {k}: {name} differs");
        }
    }
    let got = broken(&two.joints.last().unwrap()[1]);
    assert_eq!(got, want, "broken joints differ");
    let exact = [
        "step",
        "time",
        "broken_joints",
        "broken_opening",
        "broken_sliding",
        "broken_mixed",
        "closed_cracks",
    ];
    // The counts of joints equal at every step (the candidate counts
    // follow the detections a repartition adds; energies the partition's
    // partial sums).
    let ((h2, r2), (h1, r1)) = (&two.history, &one.history);
    assert_eq!(h2, h1, "history columns");
    assert_eq!(r2.len(), r1.len(), "history rows");
    for name in exact {
        let c = col(h1, name);
        for (a, b) in r2.iter().zip(r1) {
            assert_eq!(a[c], b[c], "history {name} at step {}", b[0]);
        }
    }
    if let (Some(a), Some(b)) = (&one.temperatures, &two.temperatures) {
        let (_, rows) = &one.history;
        let (c, t) = (
            col(&one.history.0, "broken_joints"),
            col(&one.history.0, "time"),
        );
        let first = rows.iter().find(|r| r[c] > 0.0).expect("a joint broke")[t];
        assert!(
            a.times.iter().any(|&t| t > first),
            "no output after the first joint broke (t = {first})"
        );
        assert_same_temperatures(a, b, 1e-8, "hot jointed drop: 1 vs 2 ranks");
    }
    eprintln!(
        "{} joints broken; {done} repartitions moved {moved} blocks; {changed} elements changed rank",
        want.len()
    );
}

/// The jointed blocks checkpointed on 2 ranks at step 50, just after their
/// first joints broke, and restarted on 1 rank: every later output is
/// bitwise the uninterrupted one-rank run's (the restart detects afresh,
/// and the run re-detects as soon as crack faces appear, so both have
/// every pair at a crack face among their candidates).
#[test]
fn jointed_blocks_restarted_after_breaking_continue_bitwise() {
    let dir = out_dir("joint-rebalance-restart");
    let scen = dir.join("drop.toml");
    std::fs::write(&scen, scenario()).unwrap();
    let full = dir.join("full");
    run_ok(1, &scen, &full, &["--set", "output.every=2"]);
    let first = dir.join("first");
    run_ok(
        2,
        &scen,
        &first,
        &[
            "--set",
            "output.every=2",
            "--set",
            "time.steps=50",
            "--set",
            "output.checkpoint=true",
        ],
    );
    let (h, rows) = history(&first, "drop");
    let broke = rows.last().unwrap()[col(&h, "broken_joints")];
    assert!(broke > 0.0, "no joint broke before the checkpoint");
    let rest = dir.join("rest");
    let ck = first.join("drop_checkpoint.h5");
    run_ok(
        1,
        &scen,
        &rest,
        &["--set", "output.every=2", "--restart", ck.to_str().unwrap()],
    );
    let (a, b) = (read_mech(&full, "drop"), read_mech(&rest, "drop"));
    assert!(b.times.len() > 1, "the restart wrote no outputs");
    for k in 0..b.times.len() {
        let at = a
            .times
            .iter()
            .position(|&t| t == b.times[k])
            .unwrap_or_else(|| panic!("time {} not in the full run", b.times[k]));
        assert!(
            a.disp[at] == b.disp[k],
            "t = {}: displacements differ",
            b.times[k]
        );
    }
    let (ja, jb) = (joint_fields(&full, "drop"), joint_fields(&rest, "drop"));
    let (x, y) = (ja.last().unwrap(), jb.last().unwrap());
    for (f, name) in ["damage", "mode", "broke_at", "opening"].iter().enumerate() {
        assert!(x[f] == y[f], "last joint output: {name} differs");
    }
    eprintln!(
        "{broke} joints broken at the checkpoint; {} outputs after it bitwise",
        b.times.len()
    );
}
