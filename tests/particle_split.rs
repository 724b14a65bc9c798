//! A body with bonded particles cut over the ranks (issue 21, item 6):
//! a long FE | DE | FE bar (`scenarios/fede-bar.toml` made 6 mm long and
//! 2 mm × 2 mm across, its middle 5 mm particles) is large enough to be
//! split, and its lattice lies across the bisection's cuts, so on two and
//! three ranks every rank owns spheres (the `particles` debug line of
//! each rank) and bonds and links cross the cuts. The trajectories
//! (particle and node output, the spheres' full state and every bond's
//! and link's state in the checkpoint) are bitwise those of one rank; a
//! checkpoint of two ranks continues on one, two and three, bitwise; the
//! same bar conducting heat gives the temperatures of one rank to the
//! solver's round-off.

use std::path::{Path, PathBuf};

use crate::common::*;

/// Spheres of the long bar: its 5 mm × 2 mm × 2 mm set in cells of 2r = 0.25 mm.
const SPHERES: usize = 20 * 8 * 8;

/// The long bar from the scenario `file`'s bar: 6 mm × 2 mm × 2 mm, the
/// middle x in [0.5, 5.5] mm particles.
fn long_bar(file: &str) -> String {
    let text = std::fs::read_to_string(root().join("scenarios").join(file)).unwrap();
    let size = text
        .lines()
        .find(|l| l.starts_with("mesh = "))
        .unwrap()
        .to_string();
    let sets = text
        .lines()
        .find(|l| l.starts_with("element_sets = "))
        .unwrap()
        .to_string();
    text.replace(
        &size,
        "mesh = { kind = \"box\", size = [6e-3, 2e-3, 2e-3], element_size = 2.5e-4 }",
    )
    .replace(
        &sets,
        "element_sets = { middle = { min = [0.5e-3, -1.0, -1.0], max = [5.5e-3, 1.0, 1.0] } }",
    )
}

/// Writes `text` as `<dir>/long.toml`.
fn write(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("long.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `scen` on `ranks` ranks into `out` with the `particles` debug
/// log; returns the spheres each rank owns (by rank).
fn run_counting(ranks: usize, scen: &Path, out: &Path, extra: &[&str]) -> Vec<usize> {
    let bin = env!("CARGO_BIN_EXE_fdem");
    let mut cmd = std::process::Command::new("mpirun");
    cmd.args(["-n", &ranks.to_string(), "--oversubscribe", bin])
        .args(["run", scen.to_str().unwrap(), "--quiet", "--output"])
        .arg(out)
        .args(extra)
        .env("FDEM_LOG", "particles=debug")
        .envs(MPI_ENV);
    let o = cmd.output().expect("cannot start fdem");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success(),
        "fdem on {ranks} rank(s) failed:\n{stderr}"
    );
    // The log line's fields, colours removed: `rank=R owned=N`.
    let mut plain = String::new();
    let mut chars = stderr.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            for d in chars.by_ref() {
                if d == 'm' {
                    break;
                }
            }
        } else {
            plain.push(c);
        }
    }
    let field = |line: &str, key: &str| -> usize {
        let at = line.find(key).unwrap() + key.len();
        line[at..]
            .split(|c: char| !c.is_ascii_digit())
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let mut owned = vec![usize::MAX; ranks];
    for line in plain.lines().filter(|l| l.contains("spheres here")) {
        owned[field(line, "rank=")] = field(line, "owned=");
    }
    assert!(
        owned.iter().all(|&n| n != usize::MAX),
        "a rank did not log its spheres:\n{plain}"
    );
    owned
}

/// Every output of the particle series: per field (displacement,
/// velocity, temperature when written) per output the values by global
/// particle number.
fn particle_series(dir: &Path) -> (Vec<f64>, Vec<Vec<Vec<f64>>>) {
    let (times, fields) = particle_fields(dir, "long");
    // Every sphere in every field (vectors or temperatures) of every output.
    assert!(!fields.is_empty());
    for v in fields.iter().flatten() {
        assert!(
            v.len() == SPHERES || v.len() == 3 * SPHERES,
            "{} values",
            v.len()
        );
    }
    (times, fields)
}

/// The checkpoint's spheres (x, v, ω), bonds and links (d, n), by global number.
fn checkpoint_particles(dir: &Path) -> [Vec<f64>; 3] {
    let f = hdf5::File::open(dir.join("long_checkpoint.h5")).unwrap();
    ["particles/state", "particles/bonds", "particles/links"]
        .map(|name| f.dataset(name).unwrap().read_raw::<f64>().unwrap())
}

/// The long bar pulled at 1 MPa (mechanics): on 1, 2 and 3 ranks the
/// spheres are owned by every rank (two and three), and the particle
/// series, the node displacements and the checkpoint's sphere, bond and
/// link states at the end are bitwise the same.
#[test]
fn a_bar_cut_through_its_particles_moves_bitwise_on_one_two_three_ranks() {
    let dir = out_dir("particle-split-mech");
    let scen = long_bar("fede-bar.toml")
        .replace("end_time = 5e-5", "end_time = 2e-5")
        .replace("every = 1", "every = 1\ncheckpoint = true");
    let path = write(&dir, &scen);
    let mut want = None;
    for ranks in [1, 2, 3] {
        let out = dir.join(format!("ranks-{ranks}"));
        let start = std::time::Instant::now();
        let owned = run_counting(ranks, &path, &out, &[]);
        eprintln!(
            "{ranks} rank(s): spheres owned {owned:?}, {:.2} s",
            start.elapsed().as_secs_f64()
        );
        assert_eq!(owned.iter().sum::<usize>(), SPHERES, "{ranks} ranks");
        assert!(
            owned.iter().all(|&n| n > 0),
            "{ranks} ranks: a rank holds no sphere: {owned:?}"
        );
        let (times, fields) = particle_series(&out);
        let nodes = read_mech(&out, "long").disp;
        let ck = checkpoint_particles(&out);
        assert_eq!(ck[0].len(), 9 * SPHERES);
        let got = (times, fields, nodes, ck);
        match &want {
            None => {
                // Something moves: the comparison is not of a state at rest.
                let v = &got.1[1][got.0.len() - 1];
                assert!(v.iter().any(|x| x.abs() > 1e-3), "the bar is at rest");
                assert_eq!(got.0.len(), 5);
                want = Some(got);
            }
            Some(w) => {
                assert_eq!(got.0, w.0, "{ranks} ranks: output times");
                assert!(got.1 == w.1, "{ranks} ranks: the particle series differs");
                assert!(got.2 == w.2, "{ranks} ranks: node displacements differ");
                for (k, what) in ["spheres", "bonds", "links"].iter().enumerate() {
                    assert!(
                        got.3[k] == w.3[k],
                        "{ranks} ranks: checkpoint {what} differ"
                    );
                }
            }
        }
        let xdmf = std::fs::read_to_string(out.join("long_particles.xdmf")).unwrap();
        let first = std::fs::read_to_string(dir.join("ranks-1/long_particles.xdmf")).unwrap();
        assert_eq!(xdmf, first, "{ranks} ranks: the particle XDMF differs");
    }
}

/// The long bar stopped at 1e-5 s on two ranks while it moves, continued
/// to 2e-5 s on one, two and three ranks: the particle and node state at
/// the end is bitwise that of one uninterrupted run on one rank.
#[test]
fn a_checkpoint_of_two_ranks_continues_bitwise_on_one_two_three() {
    let dir = out_dir("particle-split-restart");
    let path = write(
        &dir,
        &long_bar("fede-bar.toml").replace("end_time = 5e-5", "end_time = 2e-5"),
    );
    let last = |out: &Path| {
        let (times, fields) = particle_series(out);
        let k = times.len() - 1;
        let m = read_mech(out, "long");
        let f: Vec<Vec<f64>> = fields.iter().map(|f| f[k].clone()).collect();
        (times[k], f, m.disp[m.times.len() - 1].clone())
    };
    let full = dir.join("full");
    run_ok(1, &path, &full, &[]);
    let want = last(&full);
    let first = dir.join("first");
    let owned = run_counting(
        2,
        &path,
        &first,
        &[
            "--set",
            "output.checkpoint=true",
            "--set",
            "time.end_time=1e-5",
        ],
    );
    assert!(owned.iter().all(|&n| n > 0), "{owned:?}");
    let ck = first.join("long_checkpoint.h5");
    for ranks in [1, 2, 3] {
        let out = dir.join(format!("rest-{ranks}"));
        let owned = run_counting(ranks, &path, &out, &["--restart", ck.to_str().unwrap()]);
        assert_eq!(owned.iter().sum::<usize>(), SPHERES);
        let got = last(&out);
        assert_eq!(got.0, want.0, "{ranks} ranks: end time");
        assert!(got.1 == want.1, "{ranks} ranks: particles differ");
        assert!(got.2 == want.2, "{ranks} ranks: node displacements differ");
    }
}

/// The long bar conducting heat (`scenarios/fede-heat-bar.toml`'s
/// material and ends at 0 and 100 °C; a thermal run splits it on any
/// rank count above one): on 2 and 3 ranks, with spheres on every rank,
/// the spheres' and nodes' temperatures at every output are those of one
/// rank to 1e-10 relative, and the heat has reached the spheres.
#[test]
fn a_bar_cut_through_its_particles_conducts_the_same_on_one_two_three_ranks() {
    let dir = out_dir("particle-split-heat");
    let scen = long_bar("fede-heat-bar.toml")
        .replace("end_time = 1.0", "end_time = 0.1")
        .replace("every = 20", "every = 4");
    let path = write(&dir, &scen);
    let one = dir.join("ranks-1");
    run_ok(1, &path, &one, &[]);
    let (t1, p1) = particle_series(&one);
    let r1 = read_results(&one, "long");
    assert_eq!(t1.len(), 6);
    let t = &p1[0];
    let k = t.len() - 1;
    let (lo, hi) = t[k]
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        hi > 1.0 && lo >= 0.0 && hi < 100.0,
        "spheres between {lo} and {hi}"
    );
    for ranks in [2, 3] {
        let out = dir.join(format!("ranks-{ranks}"));
        let owned = run_counting(ranks, &path, &out, &[]);
        assert_eq!(owned.iter().sum::<usize>(), SPHERES);
        assert!(owned.iter().all(|&n| n > 0), "{ranks} ranks: {owned:?}");
        let (tn, pn) = particle_series(&out);
        assert_eq!(tn, t1);
        let mut worst = 0.0f64;
        for s in 0..t.len() {
            let d = rel_diff(&t[s], &pn[0][s]);
            worst = worst.max(d);
            assert!(d < 1e-10, "{ranks} ranks, output {s}: spheres off by {d:e}");
        }
        eprintln!("{ranks} ranks: spheres' temperatures within {worst:.2e} of one rank's");
        assert_same_temperatures(&r1, &read_results(&out, "long"), 1e-10, "long heat bar");
    }
}

/// The long bar heated and expanding (`scenarios/fede-expansion-bar.toml`,
/// heat and mechanics; a conductivity of 1e3 W/(m K) and its xmin end held
/// at 20 °C, so a gradient crosses the lattice within the run and the
/// bonds across the cuts expand with their ghost spheres' temperatures):
/// on 2 and 3 ranks the spheres' temperatures and displacements at every
/// output are those of one rank to 1e-9 of their largest value (the
/// thermal solve's round-off differs with the partition).
#[test]
fn a_cut_bar_expands_with_its_temperatures_on_one_two_three_ranks() {
    let dir = out_dir("particle-split-expansion");
    let scen = long_bar("fede-expansion-bar.toml")
        .replace("conductivity = 1.0", "conductivity = 1e3")
        .replace("end_time = 1e-4", "end_time = 4e-5")
        .replace("every = 4", "every = 2")
        .replace(
            "[thermal]\ntheta = 1.0\n",
            "[thermal]\ntheta = 1.0\n\n[[thermal.bc]]\nkind = \"temperature\"\nset = \"bar.xmin\"\nvalue = 20.0\n",
        );
    assert!(scen.contains("bar.xmin") && scen.contains("1e3"));
    let path = write(&dir, &scen);
    let one = dir.join("ranks-1");
    run_ok(1, &path, &one, &[]);
    let (t1, p1) = particle_series(&one);
    assert_eq!(t1.len(), 5);
    let (disp, temp) = (&p1[0], &p1[2]);
    let k = t1.len() - 1;
    let (lo, hi) = temp[k]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    assert!(
        hi - lo > 10.0,
        "no gradient across the spheres: {lo} to {hi}"
    );
    let largest = |v: &[Vec<f64>]| v.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
    let (u_max, t_max) = (largest(disp), largest(temp));
    assert!(u_max > 0.0);
    for ranks in [2, 3] {
        let out = dir.join(format!("ranks-{ranks}"));
        let owned = run_counting(ranks, &path, &out, &[]);
        assert!(owned.iter().all(|&n| n > 0), "{ranks} ranks: {owned:?}");
        let (tn, pn) = particle_series(&out);
        assert_eq!(tn, t1);
        let off = |a: &[Vec<f64>], b: &[Vec<f64>]| {
            a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        };
        let (du, dt) = (off(disp, &pn[0]) / u_max, off(temp, &pn[2]) / t_max);
        eprintln!("{ranks} ranks: displacements within {du:.2e}, temperatures {dt:.2e}");
        assert!(du < 1e-9 && dt < 1e-9, "{ranks} ranks: {du:e} {dt:e}");
    }
}

/// The scenario `file` with its bar repeated three times: `bar`, `bar2`
/// 3 mm beside it, `bar3` 6 mm on the other side shot across both at
/// 200 m/s and pulled at 1 MPa; no damping, repartitions every 2 steps at
/// any imbalance, outputs every 2 steps.
fn three_bars(file: &str, after_body: &str) -> String {
    let text = std::fs::read_to_string(root().join("scenarios").join(file)).unwrap();
    let body_at = text.find("[[bodies]]").unwrap();
    let end_at = text.find(after_body).unwrap();
    let body = &text[body_at..end_at];
    let copy = |name: &str, extra: &str| {
        body.replace("name = \"bar\"", &format!("name = \"{name}\""))
            .replace("particles =", &format!("{extra}\nparticles ="))
    };
    let out = format!(
        "{}{body}{}{}{}\n[[mechanics.bc]]\nkind = \"traction\"\nset = \"bar3.xmax\"\n\
         value = [1e6, 0.0, 0.0]\n",
        &text[..body_at],
        copy("bar2", "translate = [0.0, 3e-3, 0.0]"),
        copy(
            "bar3",
            "translate = [0.0, -6e-3, 0.0]\ninitial_velocity = [0.0, 200.0, 0.0]"
        ),
        &text[end_at..],
    );
    let damping = out
        .lines()
        .find(|l| l.starts_with("damping = "))
        .unwrap()
        .to_string();
    let every = out
        .lines()
        .find(|l| l.starts_with("every = "))
        .unwrap()
        .to_string();
    out.replace(
        &damping,
        "damping = 0.0\n\n[mechanics.rebalance]\nevery = 2\nthreshold = 1.0\n",
    )
    .replace(&every, "every = 2")
}

/// Runs `scen` as `<dir>/bars.toml` on one and two ranks; asserts that two
/// ranks repartitioned and moved bodies. Returns the output directories.
fn one_and_two_rebalanced(dir: &Path, scen: &str) -> (PathBuf, PathBuf) {
    let path = dir.join("bars.toml");
    std::fs::write(&path, scen).unwrap();
    let (o1, o2) = (dir.join("one"), dir.join("two"));
    run_ok(1, &path, &o1, &[]);
    let summary = run_ok(2, &path, &o2, &[]);
    let (done, moved) = repartitions(&summary);
    eprintln!("2 ranks: {done} repartition(s), {moved} bodies moved");
    assert!(done >= 1 && moved > 0, "{summary}");
    (o1, o2)
}

/// The particle series' fields `names`, each output's rows in turn.
fn bar_series(dir: &Path, names: &[&str]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let h5 = dir.join("bars_particles.h5");
    let times = fdem::io::read_times(&h5).unwrap();
    let f = names
        .iter()
        .flat_map(|name| {
            (0..times.len()).map(|k| fdem::io::read_node_field_step(&h5, name, k).unwrap())
        })
        .collect();
    (times, f)
}

/// Three FE | DE | FE bars (`scenarios/fede-bar.toml`'s, small, so each
/// held whole; [`three_bars`]): on two ranks bodies change owner, their
/// spheres, bonds and links travel with them, and the particle series and
/// the nodes' displacements are bitwise those of one rank.
#[test]
fn particles_travel_with_their_bodies_in_a_repartition() {
    let dir = out_dir("particle-split-rebalance");
    let scen =
        three_bars("fede-bar.toml", "[mechanics]").replace("end_time = 5e-5", "end_time = 1e-4");
    let (o1, o2) = one_and_two_rebalanced(&dir, &scen);
    let names = ["displacement", "velocity"];
    let (a, b) = (bar_series(&o1, &names), bar_series(&o2, &names));
    assert_eq!(a.0.len(), 11);
    assert!(a == b, "the particle series differs on two ranks");
    // The shot bar moved 20 mm (its spheres too: their mean y displacement).
    let k = a.0.len() - 1;
    let uy: f64 = a.1[k].chunks_exact(3).skip(128).map(|u| u[1]).sum::<f64>() / 64.0;
    assert!((uy - 200.0 * 1e-4).abs() < 1e-3 * 200.0 * 1e-4, "{uy}");
    assert!(read_mech(&o1, "bars").disp == read_mech(&o2, "bars").disp);
}

/// The same with heat (`scenarios/fede-expansion-bar.toml`'s bars, 1e3
/// W/(m K), each bar's xmin end held at 20 °C from 120 °C, the bonds
/// expanding): the spheres' temperatures travel with them in the
/// repartitions, and on two ranks their temperatures and displacements
/// are those of one rank to 1e-9 of the largest (the thermal solve's
/// round-off differs with the partition).
#[test]
fn particle_temperatures_travel_with_their_bodies_in_a_repartition() {
    let dir = out_dir("particle-split-rebalance-heat");
    let mut scen = three_bars("fede-expansion-bar.toml", "[thermal]")
        .replace("conductivity = 1.0", "conductivity = 1e3");
    for bar in ["bar", "bar2", "bar3"] {
        scen.push_str(&format!(
            "\n[[thermal.bc]]\nkind = \"temperature\"\nset = \"{bar}.xmin\"\nvalue = 20.0\n"
        ));
    }
    let (o1, o2) = one_and_two_rebalanced(&dir, &scen);
    let names = ["displacement", "temperature"];
    let (a, b) = (bar_series(&o1, &names), bar_series(&o2, &names));
    assert_eq!(a.0, b.0);
    let n = a.0.len();
    assert_eq!(n, 11);
    let largest = |v: &[Vec<f64>]| v.iter().flatten().fold(0.0f64, |m, &x| m.max(x.abs()));
    let off = |x: &[Vec<f64>], y: &[Vec<f64>]| {
        x.iter()
            .flatten()
            .zip(y.iter().flatten())
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()))
    };
    let (du, dt) = (
        off(&a.1[..n], &b.1[..n]) / largest(&a.1[..n]),
        off(&a.1[n..], &b.1[n..]) / largest(&a.1[n..]),
    );
    eprintln!("2 ranks: displacements within {du:.2e}, temperatures {dt:.2e}");
    assert!(du < 1e-9 && dt < 1e-9, "{du:e} {dt:e}");
    // The spheres cooled from 120 °C: their temperatures moved with them.
    let t = &a.1[2 * n - 1];
    let lo = t.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(lo < 110.0, "the spheres did not cool: {lo}");
}
