use std::path::Path;

use super::*;

const GOOD: &str = r#"
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

fn p() -> &'static Path {
    Path::new("scenarios/test.toml")
}

#[test]
fn parses_good_scenario() {
    let s = parse_str(GOOD, p(), &[]).unwrap();
    assert_eq!(s.scenario.num_steps(), 4);
    assert_eq!(s.scenario.thermal_spec().theta, 1.0);
    assert_eq!(s.output_stem(), "test");
}

#[test]
fn unknown_key_names_file_key_and_line() {
    let text = GOOD.replace("density = 100.0", "density = 100.0\ndensty = 3");
    let e = parse_str(&text, p(), &[]).unwrap_err().to_string();
    assert!(e.contains("scenarios/test.toml"), "{e}");
    assert!(e.contains("densty"), "{e}");
    assert!(e.contains("line"), "{e}");
}

#[test]
fn malformed_toml_is_an_error() {
    let e = parse_str("[time\ndt = 1", p(), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scenarios/test.toml") && e.contains("line"),
        "{e}"
    );
}

#[test]
fn negative_conductivity_names_key() {
    let text = GOOD.replace("conductivity = 1.0", "conductivity = -1.0");
    let e = parse_str(&text, p(), &[]).unwrap_err().to_string();
    assert!(e.contains("materials[0].conductivity"), "{e}");
}

#[test]
fn set_overrides_by_path_index_and_name() {
    let sets = vec![
        "bodies.bar.mesh.element_size=0.05".to_string(),
        "time.dt=0.25".to_string(),
        "thermal.theta=0.5".to_string(),
        "thermal.bc.0.value=2".to_string(),
    ];
    let s = parse_str(GOOD, p(), &sets).unwrap().scenario;
    match &s.bodies[0].mesh {
        MeshSpec::Box { element_size, .. } => assert_eq!(*element_size, 0.05),
        _ => panic!("box expected"),
    }
    assert_eq!(s.time.dt, 0.25);
    assert_eq!(s.thermal_spec().theta, 0.5);
    match &s.thermal_spec().bc[0] {
        ThermalBcSpec::Temperature { value, .. } => assert_eq!(*value, 2.0),
        _ => panic!(),
    }
}

#[test]
fn set_is_validated_like_the_file() {
    let e = parse_str(GOOD, p(), &["thermal.theta=1.5".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("thermal.theta"), "{e}");
    let e = parse_str(GOOD, p(), &["time.dtt=1".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("dtt"), "{e}");
    let e = parse_str(GOOD, p(), &["bodies.nobody.name=x".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("nobody"), "{e}");
    let e = parse_str(GOOD, p(), &["time.dt".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("KEY=VALUE"), "{e}");
}

#[test]
fn free_damping_needs_contact_and_is_non_negative() {
    let mech = |extra: &str| {
        format!(
            "{}\n[mechanics]\ndamping = 3.0\nfree_damping = {extra}\n",
            GOOD.replace(
                "density = 100.0",
                "density = 100.0\nyoung = 1e6\npoisson = 0.2"
            )
        )
    };
    let e = parse_str(&mech("0.0"), p(), &[]).unwrap_err().to_string();
    assert!(
        e.contains("mechanics.free_damping") && e.contains("contact"),
        "{e}"
    );
    let with_contact = |v: &str| format!("{}\n[mechanics.contact]\npenalty = 1e6\n", mech(v));
    let e = parse_str(&with_contact("-1.0"), p(), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("mechanics.free_damping"), "{e}");
    let s = parse_str(&with_contact("0.0"), p(), &[]).unwrap().scenario;
    assert_eq!(s.mechanics.unwrap().free_damping, Some(0.0));
}

#[test]
fn linear_tolerance_and_rms_settle_are_checked() {
    let mech = |contact: &str, settle: &str| {
        format!(
            "{}\n[mechanics]\nsettle = {{ {settle} }}\n[mechanics.contact]\npenalty = 1e6\n{contact}\n",
            GOOD.replace(
                "density = 100.0",
                "density = 100.0\nyoung = 1e6\npoisson = 0.2"
            )
        )
    };
    let s = parse_str(
        &mech("linear_tolerance = 0.02", "rms_speed = 0.03"),
        p(),
        &[],
    )
    .unwrap()
    .scenario;
    let m = s.mechanics.unwrap();
    assert_eq!(m.contact.unwrap().linear_tolerance, 0.02);
    assert_eq!(m.settle.unwrap().rms_speed, Some(0.03));
    let e = parse_str(
        &mech("linear_tolerance = -0.1", "rms_speed = 0.03"),
        p(),
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("mechanics.contact.linear_tolerance"), "{e}");
    let s = parse_str(
        &mech("tangential_stiffness = 0.8", "rms_speed = 0.03"),
        p(),
        &[],
    );
    let c = s.unwrap().scenario.mechanics.unwrap().contact.unwrap();
    assert_eq!(c.tangential_stiffness, 0.8);
    for bad in ["1.5", "-0.1", "nan"] {
        let e = parse_str(
            &mech(&format!("tangential_stiffness = {bad}"), "rms_speed = 0.03"),
            p(),
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("mechanics.contact.tangential_stiffness"),
            "{bad}: {e}"
        );
    }
    let c = parse_str(&mech("", "rms_speed = 0.03"), p(), &[]).unwrap();
    assert_eq!(
        c.scenario.mechanics.unwrap().contact.unwrap().stick_limit,
        1.0
    );
    for bad in ["0.5", "nan"] {
        let e = parse_str(
            &mech(&format!("stick_limit = {bad}"), "rms_speed = 0.03"),
            p(),
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("mechanics.contact.stick_limit"), "{bad}: {e}");
    }
    let e = parse_str(&mech("", "rms_speed = -1.0"), p(), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("mechanics.settle"), "{e}");
    let e = parse_str(&mech("", "after = 0.1"), p(), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("rms_speed"), "{e}");
}

/// A scenario's `kind = "nut"` is the generator's default nut (the 144-tet
/// nut of `mesh::nut`); it was a 72-tet one (one layer) before.
#[test]
fn nut_mesh_defaults_are_the_generators() {
    let text = GOOD.replace(
        r#"mesh = { kind = "box", size = [1.0, 0.1, 0.1], element_size = 0.1 }"#,
        r#"mesh = { kind = "nut" }"#,
    );
    let sc = parse_str(&text, p(), &[]).unwrap();
    let MeshSpec::Nut {
        per_side,
        radial,
        layers,
        ..
    } = &sc.scenario.bodies[0].mesh
    else {
        panic!("not a nut")
    };
    assert_eq!(
        (*per_side, *radial, *layers),
        crate::mesh::nut::NUT_DIVISIONS
    );
}
