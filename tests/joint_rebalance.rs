//! Repartition with joints (issue 19, `mechanics.rebalance`): eight
//! jointed blocks dropped onto a floor (scenarios/drop8.toml with weak
//! joints) crack where they land, and on 2 ranks the whole blocks change
//! rank during the run (repartitions every 2 steps at any imbalance). The
//! joints' damage travels with their tets, so trajectories, the joint
//! grid and the broken joints are bitwise those of one rank.

mod common;

use common::*;

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

/// The numbers before "repartition(s)" and "bodies moved" in a summary.
fn repartitions(summary: &str) -> (u64, u64) {
    let Some(line) = summary
        .lines()
        .find(|l| l.trim_start().starts_with("balance"))
    else {
        return (0, 0);
    };
    let words: Vec<&str> = line.split_whitespace().collect();
    let before = |w: &str| -> u64 {
        let i = words.iter().position(|x| x.starts_with(w)).unwrap();
        words[i - 1].parse().unwrap()
    };
    (before("repartition"), before("bodies"))
}

struct Drop {
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<f64>>,
    joints: Vec<[Vec<f64>; 4]>,
    history: (Vec<String>, Vec<Vec<f64>>),
    summary: String,
    owners: Vec<Vec<f64>>,
}

fn drop(ranks: usize) -> Drop {
    let dir = out_dir(&format!("joint-rebalance-{ranks}"));
    let scen = dir.join("drop.toml");
    std::fs::write(&scen, scenario()).unwrap();
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
    let jh5 = out.join("drop_joints.h5");
    let steps = fdem::io::read_times(&jh5).unwrap().len();
    Drop {
        vel: velocities_by_node_id(&h5, m.times.len()),
        // The field exists where a repartition may move elements.
        owners: (0..m.times.len())
            .filter(|_| ranks > 1)
            .map(|k| fdem::io::read_cell_field_step(&h5, "owner_rank", k).unwrap())
            .collect(),
        disp: m.disp,
        joints: (0..steps)
            .map(|k| {
                ["damage", "mode", "broke_at", "opening"]
                    .map(|f| fdem::io::read_cell_field_step(&jh5, f, k).unwrap())
            })
            .collect(),
        history: history(&out, "drop"),
        summary,
    }
}

#[test]
fn jointed_blocks_repartitioned_on_two_ranks_fall_and_crack_bitwise_as_on_one() {
    let one = drop(1);
    let want = broken(&one.joints.last().expect("joint outputs")[1]);
    assert!(
        !want.is_empty(),
        "the blocks must crack where they land: no joint broke"
    );
    let two = drop(2);
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
    let (ja, jb) = (full.join("drop_joints.h5"), rest.join("drop_joints.h5"));
    let (na, nb) = (
        fdem::io::read_times(&ja).unwrap().len(),
        fdem::io::read_times(&jb).unwrap().len(),
    );
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
    for f in ["damage", "mode", "broke_at", "opening"] {
        let x = fdem::io::read_cell_field_step(&ja, f, na - 1).unwrap();
        let y = fdem::io::read_cell_field_step(&jb, f, nb - 1).unwrap();
        assert!(x == y, "last joint output: {f} differs");
    }
    eprintln!(
        "{broke} joints broken at the checkpoint; {} outputs after it bitwise",
        b.times.len()
    );
}
