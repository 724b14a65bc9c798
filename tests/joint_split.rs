//! A jointed body split over the ranks (issue 19, parallel): the fully
//! jointed bar of scenarios/fracture-bar.toml (960 node copies, above the
//! size a mechanics run keeps whole) is cut by RCB on 2 and 3 ranks, its
//! joints across the cuts advanced on both sides and owned once. It breaks
//! on every rank count with bitwise the same trajectories (displacements and
//! velocities at every output) and the same joints: the same broken set,
//! damage, mode, breaking time and opening of every joint.
//!
//! The history's integer columns (steps, broken joints by mode, closed
//! cracks) are equal too. Its energies, momenta and forces are sums over
//! the ranks of each rank's partial sums (one all-reduce per row), so
//! their last bits follow the partition whatever the body: they are held
//! to 1e-9 of their scale here, which catches a joint counted twice.

use crate::common::*;

const STEM: &str = "fracture-bar";
/// The bar's tensile strength (Pa) and cross-section (m²).
const F_T: f64 = 1e6;
const SECTION: f64 = 0.02 * 0.02;

/// What one run gives: per output step the displacements and velocities
/// (by node id) and the joint grid's fields (by global joint number), the
/// history, and the rank of every element.
struct SplitRun {
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<f64>>,
    joints: Vec<[Vec<f64>; 4]>,
    history: (Vec<String>, Vec<Vec<f64>>),
    ranks: Vec<i32>,
}

fn run(ranks: usize) -> SplitRun {
    let out = out_dir(&format!("joint-split-{ranks}"));
    run_ok(
        ranks,
        &root().join("scenarios/fracture-bar.toml"),
        &out,
        &[
            "--set",
            "output.every=10",
            "--set",
            "output.history_every=1",
        ],
    );
    let m = read_mech(&out, STEM);
    let h5 = out.join(format!("{STEM}.h5"));
    let vel = velocities_by_node_id(&h5, m.times.len());
    let joints = joint_fields(&out, STEM);
    SplitRun {
        disp: m.disp,
        vel,
        joints,
        history: history(&out, STEM),
        ranks: fdem::io::read_static_cell_field_i32(&h5, "rank").unwrap(),
    }
}

/// The global numbers of the joints broken (modes 1–3) at the last output.
fn broken_set(r: &SplitRun) -> Vec<usize> {
    broken(&r.joints.last().expect("joint outputs")[1])
}

#[test]
fn a_jointed_bar_split_over_ranks_breaks_bitwise_alike() {
    let one = run(1);
    let broken = broken_set(&one);
    let (h, rows) = &one.history;
    let last = rows.last().expect("history rows");
    assert!(
        broken.len() >= 4 && broken.len() as f64 == last[col(h, "broken_joints")],
        "the bar must break: {} broken joints in the grid, {} in the history",
        broken.len(),
        last[col(h, "broken_joints")]
    );
    let exact = [
        "step",
        "time",
        "broken_joints",
        "broken_opening",
        "broken_sliding",
        "broken_mixed",
        "closed_cracks",
    ];
    for p in [2, 3] {
        let r = run(p);
        let mut held: Vec<i32> = r.ranks.clone();
        held.sort_unstable();
        held.dedup();
        assert_eq!(
            held,
            (0..p as i32).collect::<Vec<_>>(),
            "{p} ranks: the bar is not split over all ranks"
        );
        assert_eq!(r.disp.len(), one.disp.len(), "{p} ranks: outputs");
        for k in 0..one.disp.len() {
            assert!(
                r.disp[k] == one.disp[k],
                "{p} ranks, output {k}: displacements differ"
            );
            assert!(
                r.vel[k] == one.vel[k],
                "{p} ranks, output {k}: velocities differ"
            );
        }
        assert_eq!(r.joints.len(), one.joints.len(), "{p} ranks: joint outputs");
        for (k, (a, b)) in r.joints.iter().zip(&one.joints).enumerate() {
            for (f, name) in ["damage", "mode", "broke_at", "opening"].iter().enumerate() {
                assert!(a[f] == b[f], "{p} ranks, joint output {k}: {name} differs");
            }
        }
        assert_eq!(broken_set(&r), broken, "{p} ranks: broken joints differ");
        assert_same_history(
            &r.history,
            &one.history,
            &exact,
            F_T * SECTION,
            &format!("{p} ranks"),
        );
    }
}

/// The rank of every element, its reference centroid, and per output the
/// displacements and velocities by node id, and the history.
struct CRun {
    ranks: Vec<i32>,
    centroids: Vec<[f64; 3]>,
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<f64>>,
    history: (Vec<String>, Vec<Vec<f64>>),
}

/// The jointed C of scenarios/self-contact-c.toml squeezed to 0.3 of its
/// length: its height (0.44 m) becomes its longest side, so RCB cuts it
/// at mid-height, through the slot, and the tips that swell across the
/// slot lie on two ranks.
fn squeezed_c(ranks: usize) -> CRun {
    let out = out_dir(&format!("joint-split-c-{ranks}"));
    let mut mesh =
        fdem::mesh::gmsh::read_msh(&root().join("scenarios/meshes/c-shape.msh")).unwrap();
    for p in &mut mesh.nodes {
        p[0] *= 0.3;
    }
    fdem::mesh::gmsh::write_msh_ascii(&mesh, &out.join("c.msh")).unwrap();
    let text = std::fs::read_to_string(root().join("scenarios/self-contact-c.toml")).unwrap();
    let tips = "tips = { min = [0.8, -1.0, -1.0]";
    assert!(text.contains(tips));
    let text = text
        .replace("meshes/c-shape.msh", "c.msh")
        .replace(tips, "tips = { min = [0.24, -1.0, -1.0]");
    let scen = out.join("c.toml");
    std::fs::write(&scen, text).unwrap();
    run_ok(ranks, &scen, &out, &["--set", "output.every=25"]);
    let m = read_mech(&out, "c");
    let h5 = out.join("c.h5");
    let vel = velocities_by_node_id(&h5, m.times.len());
    CRun {
        ranks: fdem::io::read_static_cell_field_i32(&h5, "rank").unwrap(),
        centroids: (0..m.cells.len()).map(|c| m.centroid(c)).collect(),
        disp: m.disp,
        vel,
        history: history(&out, "c"),
    }
}

/// Self-contact across a cut (issue 19): the squeezed C's tips, on two
/// ranks, swell into each other and press; each tet meets the other
/// rank's as a ghost copy of the same body. The contacts, and the
/// trajectories bitwise, are those of one rank.
#[test]
fn a_split_jointed_body_meets_itself_across_the_cut() {
    let one = squeezed_c(1);
    let two = squeezed_c(2);
    // Tips (reference x > 0.24 m) below and above the slot, by rank.
    let tip_ranks = |lower: bool| {
        let mut r: Vec<i32> = (0..two.ranks.len())
            .filter(|&e| {
                let c = two.centroids[e];
                c[0] > 0.24 && (c[2] < 0.22) == lower
            })
            .map(|e| two.ranks[e])
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    };
    let (low, high) = (tip_ranks(true), tip_ranks(false));
    assert!(
        low.len() == 1 && high.len() == 1 && low != high,
        "the tips are not on two ranks: {low:?} below the slot, {high:?} above"
    );
    let (h, rows) = &one.history;
    let contacts = col(h, "mech_contacts");
    assert!(
        rows.last().expect("history rows")[contacts] > 0.0,
        "the tips never touched"
    );
    let (h2, rows2) = &two.history;
    assert_eq!(h2, h);
    for name in ["mech_contacts", "mech_candidates"] {
        let c = col(h, name);
        let a: Vec<f64> = rows.iter().map(|r| r[c]).collect();
        let b: Vec<f64> = rows2.iter().map(|r| r[c]).collect();
        assert_eq!(a, b, "1 and 2 ranks: {name}");
    }
    assert_eq!(one.disp.len(), two.disp.len());
    for k in 0..one.disp.len() {
        assert!(
            one.disp[k] == two.disp[k],
            "output {k}: displacements differ"
        );
        assert!(one.vel[k] == two.vel[k], "output {k}: velocities differ");
    }
}

/// A split jointed run checkpoints each joint once and continues: the bar
/// stopped on 2 ranks after it broke (at 22 of its 24 ms) and continued
/// from its checkpoint on 2 ranks (its parts, as saved) and on 3 (a new
/// cut) ends with bitwise the uninterrupted one-rank run's displacements
/// and joint damage.
#[test]
fn a_split_jointed_run_restarts_from_its_checkpoint() {
    let scen = root().join("scenarios/fracture-bar.toml");
    let args = [
        "--set",
        "output.every=20",
        "--set",
        "output.checkpoint=true",
    ];
    let last = |dir: &std::path::Path| {
        let m = read_mech(dir, STEM);
        let k = m.times.len() - 1;
        let [d, ..] = joint_fields(dir, STEM).pop().expect("joint outputs");
        (m.times[k], m.disp[k].clone(), d)
    };
    let full = out_dir("joint-split-restart-full");
    run_ok(1, &scen, &full, &args);
    let want = last(&full);
    let first = out_dir("joint-split-restart-first");
    let stop = [&args[..], &["--set", "time.end_time=0.022"]].concat();
    run_ok(2, &scen, &first, &stop);
    let (h, rows) = history(&first, STEM);
    assert!(
        rows.last().unwrap()[col(&h, "broken_joints")] > 0.0,
        "no joint broke before the checkpoint"
    );
    let ck = first.join(format!("{STEM}_checkpoint.h5"));
    for ranks in [2, 3] {
        let rest = out_dir(&format!("joint-split-restart-{ranks}"));
        let more = [&args[..], &["--restart", ck.to_str().unwrap()]].concat();
        run_ok(ranks, &scen, &rest, &more);
        let got = last(&rest);
        assert_eq!(got.0, want.0, "{ranks} ranks: end time");
        assert!(got.1 == want.1, "{ranks} ranks: displacements differ");
        assert!(got.2 == want.2, "{ranks} ranks: joint damage differs");
    }
}
