//! Bodies jointed on a set split over the ranks (issue 19, parallel): the
//! body keeps shared nodes in its continuum part (owned by the lowest rank
//! holding a tet at them, like any split large body) and a node per tet in
//! its jointed set; a joint at a continuum node is on every rank holding a
//! tet at one of its corners, so each node's owner adds every joint force
//! at it. Mechanics is bitwise that of one rank, temperatures agree to the
//! solve's tolerance, and a restart continues on another rank count.
//!
//! Each test asserts that the body is cut over all the ranks it runs on
//! (the output's `rank` field), with jointed and continuum tets on each of
//! 2 ranks; before this change such a body stayed whole on rank 0. The bar
//! jointed on its upper half is cut across the set's border, so some
//! continuum nodes are owned by a rank holding neither tet of some of
//! their joints (a joint only on its tets' ranks would miss them).

use crate::common::*;

/// Where the bar of scenarios/fracture-bar.toml (0.1 × 0.02 × 0.02 m, 240
/// Tet4, h = 10 mm) is jointed: every count above the 400 node copies a
/// mechanics run keeps whole.
#[derive(Clone, Copy, Debug)]
enum Set {
    /// Its middle two fifths, x in [0.03, 0.07] m (96 tets, 456 nodes):
    /// RCB's cuts across the bar fall in the set.
    Middle,
    /// Its upper half, y > 0.01 m (120 tets, 546 nodes): the cuts across
    /// the bar cross the set's border, so a continuum node there is owned
    /// by the lower rank while some of its joints have both tets on the
    /// higher one.
    Upper,
}

impl Set {
    /// The `element_sets` box.
    fn range(self) -> &'static str {
        match self {
            Set::Middle => "min = [0.03, -1.0, -1.0], max = [0.07, 1.0, 1.0]",
            Set::Upper => "min = [-1.0, 0.01, -1.0], max = [1.0, 1.0, 1.0]",
        }
    }

    /// Whether a tet's centroid lies in the set.
    fn holds(self, c: [f64; 3]) -> bool {
        match self {
            Set::Middle => (0.03..=0.07).contains(&c[0]),
            Set::Upper => c[1] >= 0.01,
        }
    }

    /// The pull (m/s): the fracture bar's for the middle; the upper half,
    /// the continuum below carrying the load, does not crack by 40 ms at
    /// that pull, at 5 times it cracks from 18 ms.
    fn pull(self) -> f64 {
        match self {
            Set::Middle => 0.01,
            Set::Upper => 0.05,
        }
    }
}

/// The bar jointed on `set`, pulled at x = 0.1 m (`pulled`, the fracture
/// bar's load) or, free and unloaded, heated at x = 0 from 0 to 100 °C
/// (no expansion: nothing moves, no joint breaks). `jointed`: with its
/// `fracture` entry.
fn set_bar(set: Set, pulled: bool, jointed: bool) -> String {
    let mesh = root().join("scenarios/meshes/bar-irregular-10.msh");
    let fracture = if jointed {
        "fracture = { set = \"jointed\" }"
    } else {
        ""
    };
    let physics = if pulled {
        format!(
            r#"[time]
dt = 1e-4
end_time = 0.024
[mechanics]
[[mechanics.bc]]
kind = "fixed"
set = "bar.xmin"
components = ["x"]
[[mechanics.bc]]
kind = "velocity"
set = "bar.xmax"
value = [{}, nan, nan]
[output]
every = 10
history_every = 1
"#,
            set.pull()
        )
    } else {
        r#"[time]
dt = 1e-4
steps = 20
[thermal]
theta = 1.0
bc = [{ kind = "temperature", set = "bar.xmin", value = 100.0 }]
[mechanics]
[solver]
rtol = 1e-12
[output]
every = 5
"#
        .to_string()
    };
    format!(
        r#"title = "bar jointed on a set"
[[materials]]
name = "rock"
conductivity = 1.0
specific_heat = 1e-3
density = 1000.0
young = 1e9
poisson = 0.2
tensile_strength = 1e6
cohesion = 2e6
friction_angle = 30.0
g_i = 100.0
g_ii = 200.0
fracture_penalty = 1e10
[[bodies]]
name = "bar"
material = "rock"
initial_temperature = 0.0
mesh = {{ kind = "gmsh", file = "{}" }}
element_sets = {{ jointed = {{ {} }} }}
{fracture}
{physics}"#,
        mesh.display(),
        set.range()
    )
}

/// The ranks holding the elements of the output `h5` (its `rank` field),
/// distinct and ascending.
fn ranks_of(h5: &std::path::Path) -> Vec<i32> {
    let mut r = fdem::io::read_static_cell_field_i32(h5, "rank").unwrap();
    r.sort_unstable();
    r.dedup();
    r
}

/// Per rank of the run in `dir`: how many of its tets have their centroid
/// in the jointed set (`in_set`) and how many not.
fn tets_by_rank(
    dir: &std::path::Path,
    stem: &str,
    in_set: impl Fn([f64; 3]) -> bool,
) -> Vec<[usize; 2]> {
    let m = read_mech(dir, stem);
    let ranks =
        fdem::io::read_static_cell_field_i32(&dir.join(format!("{stem}.h5")), "rank").unwrap();
    let mut by = vec![[0usize; 2]; 1 + *ranks.iter().max().unwrap() as usize];
    for (c, &r) in ranks.iter().enumerate() {
        by[r as usize][usize::from(!in_set(m.centroid(c)))] += 1;
    }
    by
}

/// What one pulled-bar run gives: per output the displacements and
/// velocities by node id and the joint grid's fields, the history, and
/// the ranks holding its tets.
struct BarRun {
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<f64>>,
    joints: Vec<[Vec<f64>; 4]>,
    history: (Vec<String>, Vec<Vec<f64>>),
    ranks: Vec<i32>,
    by_rank: Vec<[usize; 2]>,
}

fn pulled_bar(set: Set, ranks: usize) -> BarRun {
    let dir = out_dir(&format!("joint-set-split-bar-{set:?}-{ranks}"));
    let scen = dir.join("bar.toml");
    std::fs::write(&scen, set_bar(set, true, true)).unwrap();
    let out = dir.join("out");
    run_ok(ranks, &scen, &out, &[]);
    let m = read_mech(&out, "bar");
    let h5 = out.join("bar.h5");
    BarRun {
        vel: velocities_by_node_id(&h5, m.times.len()),
        disp: m.disp,
        joints: joint_fields(&out, "bar"),
        history: history(&out, "bar"),
        ranks: ranks_of(&h5),
        by_rank: tets_by_rank(&out, "bar", |c| set.holds(c)),
    }
}

#[test]
fn a_bar_jointed_on_its_middle_split_over_ranks_breaks_bitwise_alike() {
    breaks_bitwise_alike(Set::Middle);
}

#[test]
fn a_bar_jointed_on_its_upper_half_split_across_the_border_breaks_bitwise_alike() {
    breaks_bitwise_alike(Set::Upper);
}

/// The bar jointed on `set`, pulled until it cracks, on 1, 2 and 3 ranks:
/// bitwise the same trajectories and joints, the history's counts equal.
fn breaks_bitwise_alike(set: Set) {
    let one = pulled_bar(set, 1);
    let want = broken(&one.joints.last().expect("joint outputs")[1]);
    let (h, rows) = &one.history;
    let last = rows.last().expect("history rows");
    assert!(
        want.len() >= 4 && want.len() as f64 == last[col(h, "broken_joints")],
        "the bar must crack: {} broken joints in the grid, {} in the history",
        want.len(),
        last[col(h, "broken_joints")]
    );
    // Integer columns are equal; sums over the ranks' partial sums (energies,
    // momenta, forces) follow the partition in their last bits.
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
        let r = pulled_bar(set, p);
        assert_eq!(
            r.ranks,
            (0..p as i32).collect::<Vec<_>>(),
            "{p} ranks: the bar is not split over all ranks"
        );
        // The middle's cuts on 3 ranks leave the centre rank only jointed tets.
        if p == 2 || matches!(set, Set::Upper) {
            assert!(
                r.by_rank.iter().all(|&[j, c]| j > 0 && c > 0),
                "{p} ranks: each must hold jointed and continuum tets: {:?}",
                r.by_rank
            );
        }
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
        let got = broken(&r.joints.last().expect("joint outputs")[1]);
        assert_eq!(got, want, "{p} ranks: broken joints differ");
        eprintln!(
            "{p} ranks: {} joints broken, bitwise alike; tets (jointed, continuum) by rank {:?}",
            got.len(),
            r.by_rank
        );
        // The bar touches nothing: its contact force is round-off about
        // zero, on the scale of its load f_t × section.
        assert_same_history(
            &r.history,
            &one.history,
            &exact,
            1e6 * 4e-4,
            &format!("{p} ranks"),
        );
    }
}

/// The largest relative difference of two runs' temperatures over their outputs.
fn worst(a: &Results, b: &Results) -> f64 {
    a.temperature
        .iter()
        .zip(&b.temperature)
        .map(|(x, y)| rel_diff(x, y))
        .fold(0.0, f64::max)
}

/// A coupled run: the bar jointed on its middle, heated from one end,
/// split over 2 and 3 ranks, has one rank's temperatures (its tied rows
/// across the ranks: the continuum nodes' and the set's copies) and, its
/// joints intact, the continuum's at every copy.
#[test]
fn a_bar_jointed_on_a_set_heats_split_as_on_one_rank() {
    let dir = out_dir("joint-set-split-heat");
    let run = |jointed: bool, ranks: usize| {
        let scen = dir.join(format!("bar-{jointed}.toml"));
        std::fs::write(&scen, set_bar(Set::Middle, false, jointed)).unwrap();
        let out = dir.join(format!("j{jointed}-r{ranks}"));
        run_ok(ranks, &scen, &out, &[]);
        let stem = format!("bar-{jointed}");
        let h5 = out.join(format!("{stem}.h5"));
        let by_rank = tets_by_rank(&out, &stem, |c| Set::Middle.holds(c));
        (read_results(&out, &stem), ranks_of(&h5), by_rank)
    };
    let (one, _, _) = run(true, 1);
    let last = one.temperature.last().unwrap();
    let warm = last.iter().filter(|&&t| t > 1.0 && t < 99.0).count();
    assert!(
        warm > last.len() / 10,
        "the bar barely warmed: {warm} of {} copies between 1 and 99 °C",
        last.len()
    );
    for p in [2, 3] {
        let (r, held, by_rank) = run(true, p);
        assert_eq!(
            held,
            (0..p as i32).collect::<Vec<_>>(),
            "{p} ranks: the bar is not split over all ranks"
        );
        if p == 2 {
            assert!(
                by_rank.iter().all(|&[j, c]| j > 0 && c > 0),
                "2 ranks: each must hold jointed and continuum tets: {by_rank:?}"
            );
        }
        assert_same_temperatures(
            &one,
            &r,
            1e-8,
            &format!("bar on a set, 1 against {p} ranks"),
        );
        eprintln!("{p} ranks: temperatures within {:e}", worst(&one, &r));
    }
    let (cont, _, _) = run(false, 1);
    assert_copies_at_continuum(&one, &cont);
}

/// The hollow cylinder of scenarios/hollow-cylinder-cracking.toml jointed
/// only within 80 mm of its axis (|x|, |y| ≤ 0.08 m: its inner part,
/// where the hoop stress first reaches f_t), on `ranks` ranks into `out`
/// with `extra` arguments: its temperatures and the modes of its joints
/// at the last output.
fn set_cylinder(ranks: usize, out: &std::path::Path, extra: &[&str]) -> (Results, Vec<f64>) {
    std::fs::create_dir_all(out).unwrap();
    let text =
        std::fs::read_to_string(root().join("scenarios/hollow-cylinder-cracking.toml")).unwrap();
    let whole = "fracture = {}";
    assert!(text.contains(whole));
    let text = text.replace(
        whole,
        "element_sets = { near = { min = [-0.08, -0.08, -1.0], max = [0.08, 0.08, 1.0] } }\n\
         fracture = { set = \"near\" }",
    );
    let scen = out.join("cylinder.toml");
    std::fs::write(&scen, text).unwrap();
    cracking_run(ranks, &scen, out, "cylinder", extra)
}

/// The cylinder jointed on a set, split over 2 ranks (each holding jointed
/// and continuum tets), cracks as on one rank and continues from its
/// checkpoint on 3 and 1 ranks ([`cracks_and_restarts_as_on_one_rank`]).
#[test]
fn a_cylinder_jointed_on_a_set_cracks_split_and_restarts_as_on_one_rank() {
    let dir =
        cracks_and_restarts_as_on_one_rank("joint-set-split-cyl", "cylinder", set_cylinder, None);
    let by_rank = tets_by_rank(&dir, "cylinder", |c| {
        c[0].abs() <= 0.08 && c[1].abs() <= 0.08
    });
    assert!(
        by_rank.iter().all(|&[j, c]| j > 0 && c > 0),
        "2 ranks: each must hold jointed and continuum tets: {by_rank:?}"
    );
}

/// The fully jointed bar of scenarios/fracture-bar.toml on 3 ranks: each
/// rank's part holds only the joints at its own tets (the per-rank count
/// of the `FDEM_LOG=memory=debug` line), none all of them, and together
/// they hold each joint at least once and only a layer along the cuts
/// twice.
#[test]
fn no_rank_holds_all_the_joints_of_a_split_bar() {
    let out = out_dir("joint-set-split-counts");
    let bin = env!("CARGO_BIN_EXE_fdem");
    let scen = root().join("scenarios/fracture-bar.toml");
    let o = std::process::Command::new("mpirun")
        .args(["-n", "3", "--oversubscribe", bin, "run"])
        .arg(&scen)
        .args(["--quiet", "--output"])
        .arg(&out)
        .args(["--set", "time.end_time=1e-3"])
        .env("FDEM_LOG", "memory=debug")
        .envs(MPI_ENV)
        .output()
        .expect("cannot start fdem");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "fdem failed:\n{stdout}\n{stderr}");
    // The summary's "fracture  N joints, ...".
    let total: usize = stdout
        .lines()
        .find_map(|l| l.trim_start().strip_prefix("fracture"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no fracture line in\n{stdout}"));
    // Tracing's fields, colours stripped: "rank=R ... joints=N".
    let plain: String = {
        let mut s = String::new();
        let mut esc = false;
        for c in stderr.chars() {
            match (esc, c) {
                (false, '\u{1b}') => esc = true,
                (true, 'm') => esc = false,
                (true, _) => {}
                (false, c) => s.push(c),
            }
        }
        s
    };
    let field = |line: &str, name: &str| -> Option<usize> {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{name}=")))
            .and_then(|v| v.parse().ok())
    };
    let mut by_rank = [None; 3];
    for line in plain.lines().filter(|l| l.contains("whole_bodies=")) {
        if let (Some(r), Some(j)) = (field(line, "rank"), field(line, "joints")) {
            by_rank[r] = Some(j);
        }
    }
    let counts: Vec<usize> = by_rank
        .iter()
        .map(|c| c.unwrap_or_else(|| panic!("a rank logged no joint count:\n{plain}")))
        .collect();
    let sum: usize = counts.iter().sum();
    assert!(
        counts.iter().all(|&c| c > 0 && c < total),
        "each rank must hold some but not all of the {total} joints: {counts:?}"
    );
    assert!(
        sum >= total && sum < 2 * total,
        "the ranks hold {sum} joints in all for {total}: {counts:?}"
    );
    eprintln!("{total} joints; held per rank {counts:?}");
}
