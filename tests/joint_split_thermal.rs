//! A fully jointed body split over the ranks in a coupled thermal run
//! (issue 19, parallel): the copies of a vertex tied by intact joints
//! share one thermal row across the ranks (numbered by a rendezvous on
//! the lowest copy), so the split body's temperatures are those of one
//! rank (to the iterative solve's tolerance) and, while its joints hold,
//! those of the same body without joints; when joints break the rows are
//! numbered again and a closed crack across the cut meets its other face
//! on the joint's owner.

use crate::common::*;

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

/// The fully jointed cracking cylinder split over ranks cracks as on one
/// rank and continues from its checkpoint on 3 and 1 ranks
/// ([`cracks_and_restarts_as_on_one_rank`]; the one-rank run is
/// [`cracking_cylinder_reference`], shared with tests/thermal_cracking.rs).
#[test]
fn a_split_jointed_cylinder_cracks_and_restarts_as_on_one_rank() {
    cracks_and_restarts_as_on_one_rank(
        "joint-split-thermal-cyl",
        "hollow-cylinder-cracking",
        cylinder,
        Some(cracking_cylinder_reference()),
    );
}
