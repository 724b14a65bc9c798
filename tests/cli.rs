//! The command line: every shipped scenario passes `fdem check`; `fdem info`
//! reports the libraries in use; `fdem mesh` writes a Gmsh file that runs.

mod common;

use common::*;

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
