//! Bad input gives a clear error naming the file, key or element, a
//! non-zero exit, and no corrupt output, on one and two ranks.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::*;

fn scenario_dir(name: &str) -> PathBuf {
    out_dir(&format!("bad-{name}"))
}

fn write(dir: &Path, file: &str, text: &str) -> PathBuf {
    let p = dir.join(file);
    std::fs::write(&p, text).unwrap();
    p
}

const BASE: &str = r#"
[time]
dt = 0.5
steps = 4

[[materials]]
name = "m"
conductivity = 1.0
specific_heat = 1.0
density = 100.0

[[bodies]]
name = "bar"
material = "m"
mesh = { kind = "box", size = [1.0, 0.1, 0.1], element_size = 0.1 }

[[thermal.bc]]
kind = "temperature"
set = "bar.xmax"
value = 1.0
"#;

fn run_bad(ranks: usize, scen: &Path, out: &Path, extra: &[&str]) -> (Output, String) {
    let mut args = vec![
        "run",
        scen.to_str().unwrap(),
        "--quiet",
        "--output",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = fdem(ranks, &args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "{scen:?} {extra:?} should fail; stderr: {err}"
    );
    (o, err)
}

fn assert_no_output(out: &Path) {
    let files: Vec<_> = std::fs::read_dir(out)
        .map(|d| d.flatten().map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert!(files.is_empty(), "output left behind: {files:?}");
}

fn h5dump_ok(h5: &Path) {
    let o = std::process::Command::new("h5dump")
        .arg("-H")
        .arg(h5)
        .output()
        .expect("h5dump");
    assert!(
        o.status.success(),
        "h5dump -H {h5:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn malformed_toml_names_file_and_line() {
    for ranks in [1, 2] {
        let d = scenario_dir(&format!("malformed-{ranks}"));
        let s = write(&d, "bad.toml", &BASE.replace("[time]", "[time"));
        let out = d.join("out");
        let (_, err) = run_bad(ranks, &s, &out, &[]);
        assert!(err.contains("bad.toml") && err.contains("line"), "{err}");
        assert_no_output(&out);
    }
}

#[test]
fn unknown_key_is_named() {
    let d = scenario_dir("unknown-key");
    let s = write(
        &d,
        "bad.toml",
        &BASE.replace("density = 100.0", "density = 100.0\nconductivty = 2.0"),
    );
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("bad.toml") && err.contains("conductivty"),
        "{err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn missing_mesh_file_is_named() {
    let d = scenario_dir("missing-mesh");
    let text = BASE.replace(
        r#"mesh = { kind = "box", size = [1.0, 0.1, 0.1], element_size = 0.1 }"#,
        r#"mesh = { kind = "gmsh", file = "nowhere.msh" }"#,
    );
    let s = write(&d, "bad.toml", &text);
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(err.contains("nowhere.msh") && err.contains("bar"), "{err}");
    assert_no_output(&d.join("out"));
    // Issue 16: named by the path the run looked for, not relative to the
    // scenario, even when the scenario is given relative to the working
    // directory and the mesh path climbs out of the scenario's directory.
    let text = text.replace("nowhere.msh", "../bad-missing-mesh/nowhere.msh");
    write(&d, "bad.toml", &text);
    let looked_for = d.canonicalize().unwrap().join("nowhere.msh");
    for ranks in [1, 2] {
        let (_, err) = run_bad(
            ranks,
            Path::new("target/test-output/bad-missing-mesh/bad.toml"),
            &d.join("out"),
            &[],
        );
        assert!(
            err.contains(&format!("'{}'", looked_for.display())),
            "{ranks} rank(s): should name {}: {err}",
            looked_for.display()
        );
        assert_no_output(&d.join("out"));
    }
}

#[test]
fn output_path_that_is_a_file_names_the_output_directory() {
    let d = scenario_dir("output-file");
    let s = write(&d, "ok.toml", BASE);
    let file = write(&d, "afile", "not a directory\n");
    for (out, says) in [
        (file.clone(), "is an existing file, not a directory"),
        (file.join("sub"), "is a file, not a directory"),
    ] {
        for ranks in [1, 2] {
            let (_, err) = run_bad(ranks, &s, &out, &[]);
            assert!(
                err.contains(&format!("output directory {}", out.display())) && err.contains(says),
                "{ranks} rank(s), {}: {err}",
                out.display()
            );
            assert_eq!(err.matches("error: ").count(), 1, "one message: {err}");
        }
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a directory\n");
}

#[test]
fn inverted_tet_is_named() {
    let d = scenario_dir("inverted");
    let mut m = fdem::mesh::generate::box_mesh([0.0; 3], [1.0, 0.1, 0.1], 0.1).unwrap();
    m.tets[5].swap(2, 3);
    fdem::mesh::gmsh::write_msh_ascii(&m, &d.join("inv.msh")).unwrap();
    let text = BASE.replace(
        r#"mesh = { kind = "box", size = [1.0, 0.1, 0.1], element_size = 0.1 }"#,
        r#"mesh = { kind = "gmsh", file = "inv.msh" }"#,
    );
    let s = write(&d, "bad.toml", &text);
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(err.contains("inverted") && err.contains("inv.msh"), "{err}");
    assert_no_output(&d.join("out"));
}

#[test]
fn negative_conductivity_is_named() {
    let d = scenario_dir("negative-k");
    let s = write(
        &d,
        "bad.toml",
        &BASE.replace("conductivity = 1.0", "conductivity = -1.0"),
    );
    let (_, err) = run_bad(2, &s, &d.join("out"), &[]);
    assert!(
        err.contains("materials[0].conductivity") && err.contains("bad.toml"),
        "{err}"
    );
    assert_eq!(
        err.matches("materials[0].conductivity").count(),
        1,
        "printed once: {err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn unknown_set_is_named() {
    let d = scenario_dir("unknown-set");
    let s = write(&d, "bad.toml", &BASE.replace("bar.xmax", "bar.top"));
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("bar.top") && err.contains("bar.xmax"),
        "lists available sets: {err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn diverging_solver_is_an_error_and_output_stays_readable() {
    for ranks in [1, 2] {
        let d = scenario_dir(&format!("diverge-{ranks}"));
        let scen = root().join("scenarios/gmsh-block.toml");
        let out = d.join("out");
        let (_, err) = run_bad(
            ranks,
            &scen,
            &out,
            &["-ksp_type", "cg", "-pc_type", "none", "-ksp_max_it", "2"],
        );
        assert!(err.contains("DIVERGED_ITS"), "{err}");
        // The initial state was written before the failure; the file is valid.
        h5dump_ok(&out.join("gmsh-block.h5"));
        let times = fdem::io::read_times(&out.join("gmsh-block.h5")).unwrap();
        assert_eq!(times, vec![0.0]);
    }
}

#[test]
fn explicit_thermal_step_above_its_stability_limit_is_refused() {
    // Issue 16: theta = 0 at dt = 0.5 s on the 0.1 m bar (alpha = 0.01
    // m^2/s) is about 3x the explicit limit; it used to run to 1e97 K and
    // exit 0. Now it is refused before any output, naming the limit, on 1
    // and 2 ranks; the same limit for theta = 0.25 is twice as long.
    let d = scenario_dir("unstable");
    let s = write(
        &d,
        "bad.toml",
        &BASE.replace("[[thermal.bc]]", "[thermal]\ntheta = 0.0\n\n[[thermal.bc]]"),
    );
    let limit = |err: &str| -> f64 {
        let at = err
            .find("use time.dt <= ")
            .unwrap_or_else(|| panic!("{err}"))
            + 15;
        err[at..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let mut limits = Vec::new();
    for ranks in [1, 2] {
        let out = d.join(format!("out{ranks}"));
        let (_, err) = run_bad(ranks, &s, &out, &[]);
        assert!(
            err.contains("stability limit") && err.contains("thermal.theta"),
            "{err}"
        );
        assert_no_output(&out);
        limits.push(limit(&err));
    }
    assert!(
        (limits[0] - limits[1]).abs() <= 1e-3 * limits[0],
        "{limits:?}"
    );
    let (_, err) = run_bad(1, &s, &d.join("out-q"), &["--set", "thermal.theta=0.25"]);
    assert!((limit(&err) / limits[0] - 2.0).abs() < 1e-2, "{err}");
    // Just below the limit the explicit run is stable and bounded.
    let ok = d.join("ok");
    let dt = format!("time.dt={}", 0.98 * limits[0]);
    run_ok(1, &s, &ok, &["--set", &dt, "--set", "time.steps=400"]);
    let r = read_results(&ok, "bad");
    assert_within_bounds(&r, 0.0, 1.0, "explicit bar just below its limit");
}

#[test]
fn bounded_scheme_refuses_a_step_above_its_positivity_limit() {
    let d = scenario_dir("positivity");
    let s = write(
        &d,
        "bad.toml",
        &BASE.replace(
            "[[thermal.bc]]",
            "[thermal]\ntheta = 0.5\nconduction = \"bounded\"\n\n[[thermal.bc]]",
        ),
    );
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(err.contains("keeps the bounded scheme bounded"), "{err}");
    // With a consistent capacity the bounded scheme is refused outright.
    let (_, err) = run_bad(
        1,
        &s,
        &d.join("out2"),
        &["--set", "thermal.capacity=\"consistent\""],
    );
    assert!(
        err.contains("thermal.conduction") && err.contains("lumped"),
        "{err}"
    );
}

#[test]
fn blow_up_to_nan_is_reported_with_node() {
    // A stable step, but an insulated bar with a source of 1e307 W/m^3
    // overflows to infinity.
    let d = scenario_dir("nan");
    let s = write(
        &d,
        "bad.toml",
        &BASE.replace("steps = 4", "steps = 5000").replace(
            "[[thermal.bc]]\nkind = \"temperature\"\nset = \"bar.xmax\"\nvalue = 1.0",
            "[[thermal.bc]]\nkind = \"source\"\nbody = \"bar\"\nvalue = 1e307",
        ),
    );
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("non-finite temperature") && err.contains("node"),
        "{err}"
    );
    h5dump_ok(&d.join("out").join("bad.h5"));
}

/// What a killed run left in `out` for the series `stem`: every file under
/// its final name reads (h5dump), the XDMF file is whole, lists at least one
/// step and no more than the step files hold, and every step it lists reads.
/// `.part` and `.tmp` files are files being written: not checked.
fn assert_series_readable(out: &Path, stem: &str, what: &str) {
    let h5 = out.join(format!("{stem}.h5"));
    h5dump_ok(&h5);
    let steps = fdem::io::steps_dir(&h5);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&steps)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.retain(|f| f.extension().is_some_and(|x| x == "h5"));
    for f in &files {
        h5dump_ok(f);
    }
    let xdmf = std::fs::read_to_string(out.join(format!("{stem}.xdmf"))).unwrap();
    assert!(xdmf.ends_with("</Xdmf>\n"), "{what}: XDMF file not whole");
    let listed = xdmf.matches("<Time ").count();
    let times = fdem::io::read_times(&h5).unwrap();
    assert!(
        listed >= 1 && listed <= times.len() && times.len() == files.len(),
        "{what}: xdmf lists {listed}, the series holds {} steps in {} step files",
        times.len(),
        files.len()
    );
    for (k, t) in times.iter().enumerate().take(listed) {
        assert!(
            xdmf.contains(&format!("<Time Value=\"{t:e}\"/>")),
            "{what}: step {k} at t = {t} is not in the XDMF file"
        );
        let t = fdem::io::read_node_field_step(&h5, "temperature", k).unwrap();
        assert!(t.iter().all(|v| v.is_finite()), "{what}: step {k}");
    }
}

#[test]
fn killed_run_leaves_readable_output() {
    // Five kills, one in each fifth of 50..600 ms after the first output
    // appeared, at a random moment within it; FDEM_KILL_SEED repeats them.
    use rand::{Rng, SeedableRng};
    let seed: u64 = std::env::var("FDEM_KILL_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| {
            let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH);
            now.map_or(0, |d| d.as_nanos() as u64)
        });
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let d = scenario_dir("killed");
    for i in 0..5 {
        let delay = 50 + 110 * i + rng.gen_range(0..110);
        let what = format!("kill {i} at {delay} ms (FDEM_KILL_SEED={seed})");
        let out = d.join(format!("out{i}"));
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_fdem"))
            .args([
                "run",
                root().join("scenarios/slab-1d.toml").to_str().unwrap(),
                "--quiet",
                "--output",
            ])
            .arg(&out)
            .args([
                "--set",
                "output.every=20",
                "--set",
                "bodies.bar.mesh.element_size=0.05",
            ])
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap();
        // Wait until the run has written its first output (at most 20 s),
        // then let it write more and kill it mid-run.
        let xdmf_path = out.join("slab-1d.xdmf");
        let start = std::time::Instant::now();
        while !xdmf_path.exists() && start.elapsed().as_secs() < 20 {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        std::thread::sleep(std::time::Duration::from_millis(delay));
        assert!(
            child.try_wait().unwrap().is_none(),
            "{what}: the run ended before it could be killed"
        );
        child.kill().unwrap(); // SIGKILL
        let _ = child.wait();
        assert_series_readable(&out, "slab-1d", &what);
    }
}

const MECH: &str = r#"
[time]
dt = 1e-3
steps = 2

[[materials]]
name = "m"
density = 1000.0
young = 1e8
poisson = 0.3

[[bodies]]
name = "a"
material = "m"
mesh = { kind = "box", size = [0.1, 0.1, 0.1], element_size = 0.05 }

[mechanics]
"#;

#[test]
fn mechanics_step_above_the_critical_one_is_refused() {
    for ranks in [1, 2] {
        let d = scenario_dir(&format!("mech-dt-{ranks}"));
        let s = write(
            &d,
            "bad.toml",
            &MECH.replace("[mechanics]", "[mechanics]\ndt = 1e-3"),
        );
        let out = d.join("out");
        let (_, err) = run_bad(ranks, &s, &out, &[]);
        assert!(
            err.contains("mechanics.dt") && err.contains("critical"),
            "{err}"
        );
        assert_no_output(&out);
    }
}

#[test]
fn mechanics_without_elastic_constants_is_named() {
    let d = scenario_dir("mech-no-young");
    let s = write(&d, "bad.toml", &MECH.replace("young = 1e8\n", ""));
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("bad.toml") && err.contains("young") && err.contains("`m`"),
        "{err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn unknown_region_set_is_named() {
    let d = scenario_dir("mech-region");
    let s = write(
        &d,
        "bad.toml",
        &MECH.replace(
            "material = \"m\"\n",
            "material = \"m\"\nregions = { core = \"m\" }\n",
        ),
    );
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("bad.toml") && err.contains("core") && err.contains("`a`"),
        "{err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn an_element_set_box_holding_no_element_is_named() {
    let d = scenario_dir("mech-box-set");
    let s = write(
        &d,
        "bad.toml",
        &MECH.replace(
            "material = \"m\"\n",
            "material = \"m\"\nelement_sets = { far = { min = [5.0, 5.0, 5.0], max = [6.0, 6.0, 6.0] } }\n",
        ),
    );
    let (_, err) = run_bad(1, &s, &d.join("out"), &[]);
    assert!(
        err.contains("bad.toml")
            && err.contains("element_sets.`far`")
            && err.contains("no element centroid"),
        "{err}"
    );
    assert_no_output(&d.join("out"));
}

#[test]
fn mechanics_blow_up_is_an_error_not_a_corrupt_file() {
    // A step right at the critical one with a stiff contact: the run must
    // stop with an error naming an element or node, and leave a readable file.
    let d = scenario_dir("mech-blowup");
    let text = format!(
        "{}{}",
        MECH.replace("steps = 2", "steps = 200"),
        "safety = 1.0\ngravity = [0.0, 0.0, -1e9]\n[[mechanics.bc]]\nkind = \"fixed\"\nset = \"a.zmin\"\n"
    );
    let s = write(&d, "bad.toml", &text);
    let out = d.join("out");
    let (_, err) = run_bad(1, &s, &out, &[]);
    assert!(
        err.contains("mechanics") && (err.contains("element") || err.contains("node")),
        "{err}"
    );
    if out.join("bad.h5").exists() {
        h5dump_ok(&out.join("bad.h5"));
    }
}

/// A packing scenario: nuts into a container, with `pack_extra` appended
/// to the nut's `pack` table and `nut_mesh` as its mesh.
fn packing(dir: &Path, nut_mesh: &str, pack_extra: &str, height: f64) -> PathBuf {
    write(
        dir,
        "pack.toml",
        &format!(
            r#"
[time]
dt = 0.01
steps = 2

[[materials]]
name = "m"
density = 1000.0
young = 1e6
poisson = 0.22

[[bodies]]
name = "container"
material = "m"
fixed = true
mesh = {{ kind = "container", inner_radius = 0.1, wall = 0.02, height = {height}, element_size = 0.03 }}

[[bodies]]
name = "nut"
material = "m"
mesh = {nut_mesh}
pack = {{ count = 20, into = "container"{pack_extra} }}

[mechanics]
gravity = [0.0, 0.0, -9.81]

[mechanics.contact]
penalty = 1e6
"#
        ),
    )
}

#[test]
fn overlapping_initial_placement_is_refused_before_any_work() {
    let dir = scenario_dir("pack-overlap");
    let mut lines = String::new();
    for i in 0..20 {
        // Nuts 0 and 1 only 1 cm apart (they are 4 cm across); the rest stacked apart.
        let x = if i == 1 { 0.01 } else { 0.0 };
        let z = if i <= 1 { 0.05 } else { 0.05 + 0.05 * i as f64 };
        lines.push_str(&format!("{x}, 0.0, {z}, 0, 0, 0\n"));
    }
    write(&dir, "pos.csv", &lines);
    let scen = packing(
        &dir,
        r#"{ kind = "nut" }"#,
        r#", positions = "pos.csv""#,
        2.0,
    );
    for ranks in [1, 2] {
        let out = dir.join(format!("out{ranks}"));
        let (_, err) = run_bad(ranks, &scen, &out, &[]);
        assert!(
            err.contains("pack.toml") && err.contains("`nut_0` and `nut_1` overlap"),
            "{err}"
        );
        assert_no_output(&out);
    }
}

#[test]
fn particle_template_that_is_not_closed_is_refused() {
    // Two boxes sharing no node (two pieces) as one particle template.
    let dir = scenario_dir("pack-open");
    let mut a = fdem::mesh::generate::box_mesh([0.0; 3], [0.02, 0.02, 0.01], 0.01).unwrap();
    let b = fdem::mesh::generate::box_mesh([0.0, 0.0, 0.01], [0.02, 0.02, 0.01], 0.01).unwrap();
    a.append(b, 0);
    fdem::mesh::gmsh::write_msh_ascii(&a, &dir.join("split.msh")).unwrap();
    let scen = packing(&dir, r#"{ kind = "gmsh", file = "split.msh" }"#, "", 2.0);
    let out = dir.join("out");
    let (_, err) = run_bad(2, &scen, &out, &[]);
    assert!(
        err.contains("pack.toml") && err.contains("not a closed volume"),
        "{err}"
    );
    assert_no_output(&out);
}

#[test]
fn container_too_small_for_the_particles_is_refused() {
    let dir = scenario_dir("pack-small");
    let scen = packing(&dir, r#"{ kind = "nut" }"#, "", 0.01);
    let out = dir.join("out");
    let (_, err) = run_bad(1, &scen, &out, &[]);
    assert!(
        err.contains("pack.toml") && err.contains("too small for 20 particles"),
        "{err}"
    );
    assert_no_output(&out);
}

/// A mesh beyond `fdem::mesh::MAX_ELEMENTS` is refused before it is built,
/// whether one body asks for it or its copies on a lattice do.
#[test]
fn gigantic_meshes_are_refused_before_they_are_built() {
    let d = scenario_dir("gigantic");
    for (tag, edit) in [
        ("element_size = 0.1", "element_size = 0.001"),
        (
            "element_size = 0.1 }",
            "element_size = 0.1 }\nlattice = { count = [1000, 1000, 1], spacing = [1.0, 1.0, 1.0] }",
        ),
    ] {
        let s = write(&d, "bad.toml", &BASE.replace(tag, edit));
        let out = d.join("out");
        let start = std::time::Instant::now();
        let (_, err) = run_bad(1, &s, &out, &[]);
        assert!(
            err.contains("bad.toml") && err.contains("limit of 20000000"),
            "{edit}: {err}"
        );
        assert!(start.elapsed().as_secs() < 20, "{edit}: refused only after {:?}", start.elapsed());
        assert_no_output(&out);
    }
    // A model's limit is per rank (each keeps its part): 60 M Tet4 of copies
    // on 2 ranks is refused at 40 M.
    let s = d.join("bad.toml");
    let (_, err) = run_bad(2, &s, &d.join("out"), &[]);
    assert!(
        err.contains("60000000 Tet4")
            && err.contains("limit of 40000000 (20000000 per rank on 2 ranks)"),
        "{err}"
    );
}

/// Found by tests/fuzz.rs: `time.dt = 5e-324` with `end_time = 4` makes
/// u64::MAX steps, and `output.every = 10` then listed u64::MAX / 10
/// output steps (a capacity overflow panic).
#[test]
fn too_many_output_steps_are_refused() {
    let d = scenario_dir("output-steps");
    let text = BASE.replace("dt = 0.5\nsteps = 4", "dt = 5e-324\nend_time = 4.0")
        + "\n[output]\nevery = 10\n";
    let s = write(&d, "bad.toml", &text);
    let out = d.join("out");
    let (_, err) = run_bad(1, &s, &out, &[]);
    assert!(
        err.contains("output.every") && err.contains("field steps"),
        "{err}"
    );
    assert_no_output(&out);
}

/// Found by tests/fuzz.rs: a missing checkpoint was reported by every rank.
#[test]
fn missing_checkpoint_is_reported_once_on_two_ranks() {
    let d = scenario_dir("missing-checkpoint");
    let text = BASE.replace(
        r#"mesh = { kind = "box", size = [1.0, 0.1, 0.1], element_size = 0.1 }"#,
        r#"mesh = { kind = "checkpoint", file = "none_checkpoint.h5", template = "bar" }"#,
    );
    let s = write(&d, "bad.toml", &text);
    let out = d.join("out");
    let (_, err) = run_bad(2, &s, &out, &[]);
    assert!(
        err.contains("none_checkpoint.h5") && err.contains("checkpoint file not found"),
        "{err}"
    );
    assert_eq!(err.matches("error: ").count(), 1, "printed once: {err}");
    assert_no_output(&out);
}

#[test]
fn unknown_petsc_options_are_named_on_one_and_two_ranks() {
    // Issue 16: a typo and an option no object reads, both used to exit 0.
    let d = scenario_dir("petsc-options");
    let s = write(&d, "bad.toml", BASE);
    for ranks in [1, 2] {
        for (opts, named) in [
            (vec!["-ksp_monitr"], "-ksp_monitr"),
            (vec!["-foo_bar", "3"], "-foo_bar 3"),
        ] {
            let out = d.join(format!("out{ranks}"));
            let (_, err) = run_bad(ranks, &s, &out, &opts);
            assert!(
                err.contains("not used by any PETSc object") && err.contains(named),
                "{ranks} rank(s), {opts:?}: {err}"
            );
            assert_eq!(err.matches("error:").count(), 1, "one message: {err}");
            assert_no_output(&out);
        }
    }
    // Options PETSc objects do read, solve-time viewers included, and the
    // flag that accepts unused ones on purpose.
    let ok = d.join("ok");
    run_ok(
        1,
        &s,
        &ok,
        &[
            "-ksp_type",
            "cg",
            "-pc_type",
            "jacobi",
            "-ksp_converged_reason",
            "-ksp_view",
        ],
    );
    run_ok(1, &s, &ok, &["-ksp_monitr", "--allow-unused-petsc-options"]);
}

/// Issue 20: emissivity outside (0, 1], a negative film coefficient, a
/// radiating body without an emissivity, and radiation with temperatures
/// below absolute zero for want of a temperature offset: each error names
/// its key, and nothing is written.
#[test]
fn bad_ambient_keys_are_named() {
    let ambient = "\n[thermal.ambient]\ntemperature = 20.0\nradiation = true\n";
    let cases: [(&str, String, &str); 4] = [
        (
            "emissivity",
            BASE.replace("density = 100.0", "density = 100.0\nemissivity = 1.5") + ambient,
            "materials[0].emissivity",
        ),
        (
            "negative-h",
            BASE.replace("density = 100.0", "density = 100.0\nemissivity = 0.5")
                + &ambient.replace("radiation = true", "h = -5.0"),
            "thermal.ambient.h",
        ),
        (
            "no-emissivity",
            BASE.to_string() + ambient,
            "materials[0].emissivity",
        ),
        (
            "offset",
            BASE.replace("density = 100.0", "density = 100.0\nemissivity = 0.5")
                .replace("value = 1.0", "value = -300.0")
                + ambient,
            "thermal.temperature_offset",
        ),
    ];
    let gap = "\n[contact]\nresistance = 1.0\ngap = { view_factor = 1.5 }\n";
    let gap_cases = [
        (
            "gap-view",
            BASE.to_string() + gap,
            "contact.gap.view_factor",
        ),
        (
            "gap-k",
            BASE.to_string() + &gap.replace("view_factor = 1.5", "conductivity = -1.0"),
            "contact.gap.conductivity",
        ),
        (
            "cmy-pressure",
            BASE.to_string() + "\n[contact]\ncmy = { roughness = 1e-6, slope = 0.1, hardness = 1e9 }\n",
            "contact.cmy.pressure",
        ),
        (
            "cmy-hardness",
            BASE.to_string()
                + "\n[contact]\ncmy = { roughness = 1e-6, slope = 0.1, hardness = -1.0, pressure = 1.0 }\n",
            "contact.cmy.hardness",
        ),
        (
            "friction-heating",
            BASE.to_string() + "\n[contact]\nfriction_heating = { fraction = 1.5 }\n",
            "contact.friction_heating.fraction",
        ),
        (
            "friction-heating-no-mechanics",
            BASE.to_string() + "\n[contact]\nfriction_heating = { fraction = 1.0 }\n",
            "contact.friction_heating",
        ),
    ];
    let table = |t: &str| BASE.to_string() + "\n[contact]\ntable = " + t + "\n";
    let table_cases = [
        (
            "table-count",
            table("{ temperature = [0.0, 1.0], h = [1.0, 2.0, 3.0] }"),
            "contact.table.h",
        ),
        (
            "table-order",
            table("{ gap = [1.0, 0.0], h = [1.0, 2.0] }"),
            "contact.table.gap",
        ),
        (
            "table-pressure",
            table("{ pressure = [0.0, 1e6], h = [1.0, 2.0] }"),
            "contact.table.prescribed_pressure",
        ),
        ("table-negative", table("{ h = [-1.0] }"), "contact.table.h"),
        (
            "gap-k-table",
            BASE.to_string()
                + "\n[contact]\ngap = { conductivity_table = { temperature = [0.0], k = [] } }\n",
            "contact.gap.conductivity_table",
        ),
        (
            "sliding-speed",
            BASE.to_string() + "\n[contact]\nsliding_speed = -1.0\n",
            "contact.sliding_speed",
        ),
    ];
    for (name, text, key) in cases.into_iter().chain(gap_cases).chain(table_cases) {
        let d = scenario_dir(&format!("ambient-{name}"));
        let s = write(&d, "bad.toml", &text);
        for ranks in [1, 2] {
            let (_, err) = run_bad(ranks, &s, &d.join("out"), &[]);
            assert!(
                err.contains("bad.toml") && err.contains(key),
                "{name}: {err}"
            );
            assert_no_output(&d.join("out"));
        }
    }
}

/// Issue 19: bodies from a checkpoint are jointed whole; a `fracture.set`
/// or an `initial_crack` on them is refused, naming the key, before the
/// checkpoint is read (it does not exist here).
#[test]
fn jointed_checkpoint_bodies_refuse_sets_and_initial_cracks() {
    let scen = root().join("scenarios/deposited-thermal-shock.toml");
    let cases: [(&str, &str, &str); 2] = [
        ("set", "bodies.nut.fracture.set=\"core\"", "fracture.set"),
        (
            "crack",
            "bodies.nut.fracture.initial_crack={ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }",
            "fracture.initial_crack",
        ),
    ];
    for (tag, set, key) in cases {
        let out = scenario_dir(&format!("jointed-checkpoint-{tag}")).join("out");
        let (_, err) = run_bad(1, &scen, &out, &["--set", set]);
        assert!(
            err.contains(key)
                && err.contains("checkpoint")
                && err.contains("deposited-thermal-shock.toml"),
            "{tag}: {err}"
        );
        assert!(!err.contains("checkpoint file not found"), "{tag}: {err}");
        assert_no_output(&out);
    }
}

/// Issue 21: a `particles` key naming a set the body lacks, a radius no
/// sphere of which fits the set, a radius that is not positive, a body
/// kind that cannot have particles are refused, naming the key, on one
/// and two ranks.
#[test]
fn bad_particles_are_named() {
    let scen = root().join("scenarios/fede-bar.toml");
    let cases: [(&str, &[&str], &[&str]); 5] = [
        (
            "unknown-set",
            &["--set", "bodies.bar.particles.set=\"nowhere\""],
            &["particles.set", "nowhere", "middle"],
        ),
        (
            "too-large",
            &["--set", "bodies.bar.particles.radius=2e-3"],
            &["particles", "`middle`", "radius too large"],
        ),
        (
            "not-positive",
            &["--set", "bodies.bar.particles.radius=-1.0"],
            &["particles.radius", "positive"],
        ),
        (
            "fixed",
            &["--set", "bodies.bar.fixed=true"],
            &["particles", "held body"],
        ),
        (
            "whole-body",
            &["--set", "bodies.bar.particles.set=\"all\""],
            &["particles.set", "every element"],
        ),
    ];
    for (tag, extra, words) in cases {
        for ranks in [1, 2] {
            let out = scenario_dir(&format!("particles-{tag}-{ranks}")).join("out");
            let (_, err) = run_bad(ranks, &scen, &out, extra);
            for w in words {
                assert!(
                    err.contains(w) && err.contains("fede-bar.toml"),
                    "{tag}: `{w}` in {err}"
                );
            }
            assert_no_output(&out);
        }
    }
}
