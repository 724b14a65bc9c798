//! The command line: every shipped scenario passes `fdem check`; `fdem info`
//! reports the libraries in use; `fdem mesh` writes a Gmsh file that runs.

use crate::common::*;

#[test]
fn every_shipped_scenario_checks() {
    let mut n = 0;
    for entry in std::fs::read_dir(root().join("scenarios")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&p).unwrap();
            assert!(
                text.starts_with('#'),
                "{p:?} must open with a comment (purpose, expectation, run line)"
            );
            assert!(text.contains("Run:"), "{p:?} must show a run line");
            let o = fdem(1, &["check", p.to_str().unwrap()]);
            // A later stage (bodies from an earlier run's checkpoint) checks
            // up to the missing checkpoint on a clean checkout.
            let err = String::from_utf8_lossy(&o.stderr);
            if text.contains("kind = \"checkpoint\"") && err.contains("checkpoint file not found") {
                n += 1;
                continue;
            }
            assert!(
                o.status.success(),
                "{p:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            n += 1;
        }
    }
    assert!(n >= 6, "found only {n} scenarios");
}

#[test]
fn info_reports_versions() {
    let o = fdem(1, &["info"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(s.contains("Release Version 3.18"), "{s}");
    assert!(s.contains("Open MPI"), "{s}");
    assert!(s.contains("HDF5:  1.10"), "{s}");
    assert!(!s.contains('\0'), "no NUL bytes in the output");
}

#[test]
fn generated_gmsh_mesh_runs() {
    let d = out_dir("cli-mesh");
    let msh = d.join("m.msh");
    let o = fdem(
        1,
        &[
            "mesh",
            "--size",
            "0.2",
            "0.1",
            "0.1",
            "--h",
            "0.05",
            "--jitter",
            "0.1",
            "--out",
            msh.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let scen = d.join("s.toml");
    std::fs::write(
        &scen,
        r#"
[time]
dt = 1.0
steps = 2
[[materials]]
name = "m"
conductivity = 1.0
specific_heat = 1.0
density = 1.0
[[bodies]]
name = "b"
material = "m"
mesh = { kind = "gmsh", file = "m.msh" }
[[thermal.bc]]
kind = "temperature"
set = "xmax"
value = 1.0
"#,
    )
    .unwrap();
    run_ok(1, &scen, &d.join("out"), &[]);
}

/// Issue 16: a mechanics-only run (no heat conduction) neither shows a theta
/// in `fdem check` nor a heat balance in its summary; a thermal run shows both.
#[test]
fn mechanics_only_runs_do_not_report_heat() {
    let mech = root().join("scenarios/collision.toml");
    let o = fdem(1, &["check", mech.to_str().unwrap()]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        s.contains("mechanics only")
            && !s.contains("theta")
            && !s.contains("prescribed-temperature"),
        "{s}"
    );
    let out = out_dir("cli-mech-only");
    let stdout = run_ok(1, &mech, &out, &["--set", "time.steps=8"]);
    assert!(summary_line(&stdout, "heat").is_none(), "{stdout}");
    assert!(summary_line(&stdout, "mechanics").is_some(), "{stdout}");

    let heat = root().join("scenarios/slab-1d.toml");
    let o = fdem(1, &["check", heat.to_str().unwrap()]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("theta = ") && !s.contains("mechanics only"),
        "{s}"
    );
    let out = out_dir("cli-heat");
    let stdout = run_ok(1, &heat, &out, &[]);
    assert!(summary_line(&stdout, "heat").is_some(), "{stdout}");
}

/// Issue 16: `--set KEY=none` removes a key, so a step count can replace a
/// file's end time (both together are an error).
#[test]
fn set_none_unsets_a_key() {
    let p = root().join("scenarios/slab-1d.toml");
    let p = p.to_str().unwrap();
    let both = fdem(1, &["check", p, "--set", "time.steps=10"]);
    assert!(
        !both.status.success(),
        "steps and end_time together must be refused"
    );
    let o = fdem(
        1,
        &[
            "check",
            p,
            "--set",
            "time.end_time=none",
            "--set",
            "time.steps=10",
            "--set",
            "output.times=none",
        ],
    );
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(s.contains(" 10 steps of "), "{s}");
    let o = fdem(1, &["check", p, "--set", "time.nothing=none"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("`time.nothing` is not set"),
        "{e}"
    );
}

/// Issue 16: `--from DIR` makes a later stage read its checkpoint bodies
/// from an earlier stage's output directory (the packing tests run the
/// heat-up this way); the path it looked for is named when it is missing.
#[test]
fn from_names_the_earlier_stage_output() {
    let heat = root().join("scenarios/nut-packing-heatup.toml");
    let d = out_dir("cli-from");
    let o = fdem(
        1,
        &[
            "check",
            heat.to_str().unwrap(),
            "--from",
            d.to_str().unwrap(),
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    let want = d.join("nut-packing-deposit_checkpoint.h5");
    assert!(
        !o.status.success()
            && e.contains(&format!("{}", want.display()))
            && e.contains("checkpoint file not found"),
        "{e}"
    );
    let slab = root().join("scenarios/slab-1d.toml");
    let o = fdem(
        1,
        &[
            "check",
            slab.to_str().unwrap(),
            "--from",
            d.to_str().unwrap(),
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("no body with mesh kind"),
        "{e}"
    );
}
