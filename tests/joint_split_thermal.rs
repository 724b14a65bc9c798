//! A fully jointed body split over the ranks in a coupled thermal run
//! (issue 19, parallel): the copies of a vertex tied by intact joints
//! share one thermal row across the ranks (numbered by a rendezvous on
//! the lowest copy), so the split body's temperatures are those of one
//! rank (to the iterative solve's tolerance) and, while its joints hold,
//! those of the same body without joints; when joints break the rows are
//! numbered again and a closed crack across the cut meets its other face
//! on the joint's owner.

use crate::common::*;

/// The ranks holding the elements of the run in `dir` (its `rank` field).
fn ranks_held(dir: &std::path::Path, stem: &str) -> Vec<i32> {
    let h5 = dir.join(format!("{stem}.h5"));
    let mut r = fdem::io::read_static_cell_field_i32(&h5, "rank").unwrap();
    r.sort_unstable();
    r.dedup();
    r
}

/// The jointed bar of scenarios/fracture-bar.toml (960 node copies), free
/// and unloaded, heated at x = min to 100 °C from 0 °C (no expansion, so
/// nothing moves and no joint breaks): the diffusion length over the run
/// is about half the bar. `jointed`: with `fracture = {}`.
fn heated_bar(jointed: bool) -> String {
    let mesh = root().join("scenarios/meshes/bar-irregular-10.msh");
    format!(
        r#"title = "heated bar"
[time]
dt = 1e-4
steps = 20
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
{}
[thermal]
theta = 1.0
bc = [{{ kind = "temperature", set = "bar.xmin", value = 100.0 }}]
[mechanics]
[solver]
rtol = 1e-12
[output]
every = 5
"#,
        mesh.display(),
        if jointed { "fracture = {}" } else { "" }
    )
}

#[test]
fn a_split_jointed_bar_heats_as_on_one_rank_and_as_the_continuum() {
    let dir = out_dir("joint-split-thermal-bar");
    std::fs::create_dir_all(&dir).unwrap();
    let run = |jointed: bool, ranks: usize| {
        let scen = dir.join(format!("bar-{jointed}.toml"));
        std::fs::write(&scen, heated_bar(jointed)).unwrap();
        let out = dir.join(format!("j{jointed}-r{ranks}"));
        run_ok(ranks, &scen, &out, &[]);
        let stem = format!("bar-{jointed}");
        (read_results(&out, &stem), ranks_held(&out, &stem))
    };
    let (one, _) = run(true, 1);
    // Heat has spread part of the way along the bar: not all of it at
    // the end value, nor untouched.
    let last = one.temperature.last().unwrap();
    let warm = last.iter().filter(|&&t| t > 1.0 && t < 99.0).count();
    assert!(
        warm > last.len() / 10,
        "the bar barely warmed: {warm} of {} copies between 1 and 99 °C",
        last.len()
    );
    for p in [2, 3] {
        let (r, held) = run(true, p);
        assert_eq!(
            held,
            (0..p as i32).collect::<Vec<_>>(),
            "{p} ranks: the bar is not split over all ranks"
        );
        assert_same_temperatures(&one, &r, 1e-8, &format!("jointed bar, 1 against {p} ranks"));
    }
    // The same bar without joints: at every copy its vertex's temperature.
    let (cont, _) = run(false, 1);
    assert_copies_at_continuum(&one, &cont);
}

/// The hollow cylinder of scenarios/hollow-cylinder-cracking.toml (its
/// joints break from 4.5 ms), on `ranks` ranks into `out`, with `extra`
/// arguments: its temperatures and the modes of its joints at the last
/// output.
fn cylinder(ranks: usize, out: &std::path::Path, extra: &[&str]) -> (Results, Vec<f64>) {
    let scen = root().join("scenarios/hollow-cylinder-cracking.toml");
    cracking_run(ranks, &scen, out, "hollow-cylinder-cracking", extra)
}

#[test]
fn a_split_jointed_cylinder_cracks_as_on_one_rank() {
    let one_dir = out_dir("joint-split-thermal-cyl-1");
    let (one, one_mode) = cylinder(1, &one_dir, &[]);
    let want = broken(&one_mode);
    assert!(!want.is_empty(), "the cylinder must crack");
    let two_dir = out_dir("joint-split-thermal-cyl-2");
    let (two, two_mode) = cylinder(2, &two_dir, &[]);
    assert_eq!(
        ranks_held(&two_dir, "hollow-cylinder-cracking"),
        vec![0, 1],
        "the cylinder is not split over 2 ranks"
    );
    assert_eq!(broken(&two_mode), want, "2 ranks: broken joints differ");
    assert_same_temperatures(&one, &two, 1e-8, "cracking cylinder, 1 against 2 ranks");
}

/// A split cracking cylinder checkpointed on 2 ranks after its first
/// joints broke (at 7.4 ms) continues to 8 ms on 3 ranks (a new cut)
/// and on 1 to the uninterrupted one-rank run's broken joints and
/// temperatures.
#[test]
fn a_split_jointed_cylinder_restarts_on_other_rank_counts() {
    let ck_args = [
        "--set",
        "output.checkpoint=true",
        "--set",
        "time.end_time=8e-3",
    ];
    let (want, want_mode) = cylinder(1, &out_dir("joint-split-thermal-restart-full"), &ck_args);
    let first = out_dir("joint-split-thermal-restart-first");
    let stop = [&ck_args[..], &["--set", "time.end_time=7.4e-3"]].concat();
    let (_, first_mode) = cylinder(2, &first, &stop);
    assert_eq!(ranks_held(&first, "hollow-cylinder-cracking"), vec![0, 1]);
    assert!(
        !broken(&first_mode).is_empty(),
        "no joint broke before the checkpoint"
    );
    let ck = first.join("hollow-cylinder-cracking_checkpoint.h5");
    for ranks in [3, 1] {
        let rest = out_dir(&format!("joint-split-thermal-restart-{ranks}"));
        let more = [&ck_args[..], &["--restart", ck.to_str().unwrap()]].concat();
        let (got, mode) = cylinder(ranks, &rest, &more);
        assert_eq!(
            ranks_held(&rest, "hollow-cylinder-cracking"),
            (0..ranks as i32).collect::<Vec<_>>(),
            "{ranks} ranks: the restarted cylinder is not split over all ranks"
        );
        assert_eq!(
            broken(&mode),
            broken(&want_mode),
            "{ranks} ranks: broken joints differ"
        );
        let (k, kw) = (got.times.len() - 1, want.times.len() - 1);
        assert_eq!(got.times[k], want.times[kw], "{ranks} ranks: end time");
        let d = rel_diff(&got.temperature[k], &want.temperature[kw]);
        assert!(d < 1e-8, "{ranks} ranks: end temperatures differ by {d:e}");
    }
}
