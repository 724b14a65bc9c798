//! Restarts of runs with bonded particles (issue 21): a run stopped at a
//! checkpoint and continued with `--restart` on one and on two ranks
//! ends as the run that never stopped. The checkpoint holds the spheres'
//! motion, each bond's and link's incremental state and, with heat, the
//! spheres' thermal rows, by global number. Free spheres (`[[spheres]]`)
//! restart the same way: their motion, springs and energy account, and
//! with heat their temperatures, heat account and the heat handed to the
//! bodies not yet released.

use std::path::Path;

use crate::common::*;

/// Particle displacements and velocities (and temperatures, when
/// written) of every output, with the output times.
#[derive(PartialEq, Debug)]
struct Particles {
    times: Vec<f64>,
    fields: Vec<Vec<Vec<f64>>>,
}

fn read_particles(dir: &Path, stem: &str) -> Particles {
    let (times, fields) = particle_fields(dir, stem);
    Particles { times, fields }
}

/// Two bars of `text` side by side (the body table repeated, moved by
/// 3 mm in y), so that on two ranks each holds one; `extra` is appended.
fn two_bars(text: &str, end_marker: &str, extra: &str) -> String {
    let body_at = text.find("[[bodies]]").unwrap();
    let end_at = text.find(end_marker).unwrap();
    let body = &text[body_at..end_at];
    let second = body
        .replace("name = \"bar\"", "name = \"bar2\"")
        .replace("particles =", "translate = [0.0, 3e-3, 0.0]\nparticles =");
    format!(
        "{}{body}{second}{}{extra}",
        &text[..body_at],
        &text[end_at..]
    )
}

/// The state at the end of a run in `dir`: the last output of the
/// particles and the nodes, and the time.
fn last(dir: &Path) -> (f64, Vec<Vec<f64>>, Vec<[f64; 3]>) {
    let p = read_particles(dir, "two-bars");
    let m = read_mech(dir, "two-bars");
    let k = p.times.len() - 1;
    let fields = p.fields.iter().map(|f| f[k].clone()).collect();
    (p.times[k], fields, m.disp[m.times.len() - 1].clone())
}

/// Runs `scen` whole on `ranks` ranks into a fresh directory `name`.
fn whole(name: &str, scen: &Path, ranks: usize) -> std::path::PathBuf {
    let dir = out_dir(name);
    run_ok(ranks, scen, &dir, &["--set", "output.checkpoint=true"]);
    dir
}

/// Runs `scen` on `ranks` ranks to `stop` (s) with a checkpoint there;
/// returns the checkpoint's path.
fn first_part(name: &str, scen: &Path, ranks: usize, stop: f64) -> std::path::PathBuf {
    let dir = out_dir(name);
    let end = format!("time.end_time={stop:?}");
    run_ok(
        ranks,
        scen,
        &dir,
        &["--set", "output.checkpoint=true", "--set", &end],
    );
    dir.join("two-bars_checkpoint.h5")
}

/// Continues from `ck` on `ranks` ranks into a fresh directory `name`
/// (its outputs start after the checkpoint's time).
fn rest(name: &str, scen: &Path, ranks: usize, ck: &Path) -> std::path::PathBuf {
    let dir = out_dir(name);
    run_ok(
        ranks,
        scen,
        &dir,
        &[
            "--restart",
            ck.to_str().unwrap(),
            "--set",
            "output.checkpoint=true",
        ],
    );
    let t = read_particles(&dir, "two-bars").times;
    assert!(t[0] > 1.9e-5, "{name}: the restart wrote from {}", t[0]);
    dir
}

/// Two FE | DE | FE bars pulled by 1 and 2 MPa (`scenarios/fede-bar.toml`,
/// mechanics only), stopped at 2e-5 s on two ranks while they still move
/// and continued to 5e-5 s on one and on two ranks: the particles'
/// displacements and velocities and the nodes' displacements at the end
/// are bitwise those of the run that never stopped (on one rank); continued
/// in place, the particle series holds every output of that run, bitwise.
#[test]
fn a_particle_run_restarts_bitwise_on_one_and_two_ranks() {
    let text = std::fs::read_to_string(root().join("scenarios/fede-bar.toml")).unwrap();
    let mut extra = String::new();
    for set in ["xmin", "ymin", "zmin"] {
        let axis = &set[..1];
        extra.push_str(&format!(
            "\n[[mechanics.bc]]\nkind = \"fixed\"\nset = \"bar2.{set}\"\ncomponents = [\"{axis}\"]\n"
        ));
    }
    extra.push_str(
        "\n[[mechanics.bc]]\nkind = \"traction\"\nset = \"bar2.xmax\"\nvalue = [2e6, 0.0, 0.0]\n",
    );
    let scen = two_bars(&text, "[mechanics]", &extra);
    let dir = out_dir("particle-restart-mech");
    let path = dir.join("two-bars.toml");
    std::fs::write(&path, scen).unwrap();
    let full = whole("particle-restart-mech-full", &path, 1);
    let want = last(&full);
    let ck = first_part("particle-restart-mech-first", &path, 2, 2e-5);
    // Still moving at the checkpoint: the restart has bond states to carry.
    let stopped = read_particles(ck.parent().unwrap(), "two-bars");
    let v = stopped.fields[1].last().unwrap();
    assert!(v.iter().any(|x| x.abs() > 1e-3), "the bars were at rest");
    for ranks in [1, 2] {
        let got = last(&rest(
            &format!("particle-restart-mech-{ranks}"),
            &path,
            ranks,
            &ck,
        ));
        assert_eq!(got.0, want.0, "{ranks} ranks: end time");
        assert!(got.1 == want.1, "{ranks} ranks: particles differ");
        assert!(got.2 == want.2, "{ranks} ranks: node displacements differ");
    }
    // In place (the first part's directory, as many ranks): the particle
    // series continues, every output bitwise the uninterrupted run's.
    let first = ck.parent().unwrap();
    let o = fdem(
        2,
        &[
            "run",
            path.to_str().unwrap(),
            "--quiet",
            "--output",
            first.to_str().unwrap(),
            "--restart",
            ck.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (
        read_particles(&full, "two-bars"),
        read_particles(first, "two-bars"),
    );
    assert_eq!(a.times, b.times, "the continued series' times");
    assert!(a == b, "the continued particle series differs");
}

/// The two free bars of `scenarios/fede-expansion-bar.toml` (heat and
/// mechanics, the spheres' temperatures from their thermal rows, the
/// bonds expanding) stopped at 2e-5 s while they expand and continued to
/// 1e-4 s: on as many ranks as the first part, bitwise the run that never
/// stopped on that many ranks (particles' motion and temperatures, nodes);
/// from a one-rank checkpoint on two ranks, the same to the round-off of
/// the thermal solve on another partition (1e-9 of the displacement).
#[test]
fn a_coupled_particle_run_restarts_with_its_temperatures() {
    let text = std::fs::read_to_string(root().join("scenarios/fede-expansion-bar.toml")).unwrap();
    let scen = two_bars(&text, "[thermal]", "");
    let dir = out_dir("particle-restart-heat");
    let path = dir.join("two-bars.toml");
    std::fs::write(&path, scen).unwrap();
    for ranks in [1, 2] {
        let want = last(&whole(
            &format!("particle-restart-heat-full-{ranks}"),
            &path,
            ranks,
        ));
        let ck = first_part(
            &format!("particle-restart-heat-first-{ranks}"),
            &path,
            ranks,
            2e-5,
        );
        let got = last(&rest(
            &format!("particle-restart-heat-{ranks}"),
            &path,
            ranks,
            &ck,
        ));
        assert_eq!(got.0, want.0, "{ranks} ranks: end time");
        assert_eq!(got.1.len(), 3, "temperatures written");
        assert!(got.1 == want.1, "{ranks} ranks: particles differ");
        assert!(got.2 == want.2, "{ranks} ranks: node displacements differ");
        if ranks == 1 {
            // The one-rank checkpoint on two ranks.
            let other = last(&rest("particle-restart-heat-1-on-2", &path, 2, &ck));
            let scale = 2e-6;
            let worst = other.1[0]
                .iter()
                .zip(&want.1[0])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < 1e-9 * scale,
                "1-rank checkpoint on 2 ranks: {worst:e}"
            );
        }
    }
}

/// A heat-only run with particles (`scenarios/fede-heat-bar.toml`, the
/// spheres rows of the thermal system) stopped at 10 ms, in its transient,
/// and continued to 20 ms on one and on two ranks: the spheres' and the
/// nodes' temperatures at the end are those of the run that never stopped
/// (bitwise on one rank; to 1e-12 of ΔT on two, another partition's
/// solve, measured bitwise there too).
#[test]
fn a_heat_run_with_particles_restarts_with_the_spheres_temperatures() {
    let scen = root().join("scenarios/fede-heat-bar.toml");
    let stem = "fede-heat-bar";
    let set = ["--set", "output.every=1", "--set", "output.checkpoint=true"];
    let end = |t: &'static str| [&set[..], &["--set", t]].concat();
    let full = out_dir("particle-restart-thermal-full");
    run_ok(1, &scen, &full, &end("time.end_time=0.02"));
    let first = out_dir("particle-restart-thermal-first");
    run_ok(1, &scen, &first, &end("time.end_time=0.01"));
    let ck = first.join(format!("{stem}_checkpoint.h5"));
    let temps = |dir: &Path| {
        let p = read_particles(dir, stem);
        let r = read_results(dir, stem);
        let (kp, kr) = (p.times.len() - 1, r.times.len() - 1);
        (
            p.times[kp],
            p.fields[0][kp].clone(),
            r.temperature[kr].clone(),
        )
    };
    let want = temps(&full);
    // Mid-transient: the spheres are far from the steady line.
    assert!(want.1.iter().any(|&t| t > 1.0) && want.1.iter().any(|&t| t < 99.0));
    for ranks in [1, 2] {
        let dir = out_dir(&format!("particle-restart-thermal-{ranks}"));
        let more = [
            &end("time.end_time=0.02")[..],
            &["--restart", ck.to_str().unwrap()],
        ]
        .concat();
        run_ok(ranks, &scen, &dir, &more);
        let got = temps(&dir);
        assert_eq!(got.0, want.0, "{ranks} ranks: end time");
        let worst = got
            .1
            .iter()
            .zip(&want.1)
            .chain(got.2.iter().zip(&want.2))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!("heat restart on {ranks} rank(s): worst temperature difference {worst:e}");
        if ranks == 1 {
            assert!(got.1 == want.1 && got.2 == want.2, "not bitwise: {worst:e}");
        } else {
            assert!(worst < 1e-10, "{ranks} ranks: {worst:e}");
        }
    }
}

/// The free spheres' last output (displacements and velocities by sphere
/// number), the block's last node displacements and the history's last
/// row, of a run of `scenarios/spheres-on-block.toml` in `dir`.
fn spheres_last(dir: &Path) -> (Vec<f64>, Vec<f64>, Vec<[f64; 3]>, Vec<f64>) {
    let h5 = dir.join("spheres_spheres.h5");
    let k = fdem::io::read_times(&h5).unwrap().len() - 1;
    let field = |name: &str| fdem::io::read_node_field_step(&h5, name, k).unwrap();
    let m = read_mech(dir, "spheres");
    let (_, rows) = history(dir, "spheres");
    (
        field("displacement"),
        field("velocity"),
        m.disp[m.times.len() - 1].clone(),
        rows.last().unwrap().clone(),
    )
}

/// The bed of 40 free spheres settling on a block
/// (`scenarios/spheres-on-block.toml`) stopped at 0.12 s on two ranks,
/// while the spheres still fall, bounce and roll on each other (Mindlin
/// springs on pairs and on the block's faces), and continued to 0.3 s on
/// one and on two ranks: the spheres' displacements and velocities, the
/// block's nodes and the energies of the history's last row are bitwise
/// those of the run that never stopped.
#[test]
fn free_spheres_restart_bitwise_on_one_and_two_ranks() {
    let src = root().join("scenarios/spheres-on-block.toml");
    let dir = out_dir("sphere-restart");
    let path = dir.join("spheres.toml");
    std::fs::copy(&src, &path).unwrap();
    let full = out_dir("sphere-restart-full");
    run_ok(2, &path, &full, &[]);
    let want = spheres_last(&full);
    let first = out_dir("sphere-restart-first");
    let stdout = run_ok(
        2,
        &path,
        &first,
        &["--set", "output.checkpoint=true", "--set", "time.steps=12"],
    );
    let ck = first.join("spheres_checkpoint.h5");
    // Moving and touching at the checkpoint: springs to carry.
    let (_, v, _, _) = spheres_last(&first);
    assert!(v.iter().any(|c| c.abs() > 1e-2), "the spheres were at rest");
    let line = summary_line(&stdout, "spheres").expect("a spheres line");
    let pairs = number_before(line, "touching pairs");
    let faces = number_before(line, "sphere-face contacts");
    eprintln!("at the checkpoint: {pairs} touching pairs, {faces} sphere-face contacts");
    assert!(pairs > 0.0 && faces > 0.0, "{line}");
    for ranks in [1, 2] {
        let out = out_dir(&format!("sphere-restart-{ranks}"));
        run_ok(ranks, &path, &out, &["--restart", ck.to_str().unwrap()]);
        let got = spheres_last(&out);
        assert!(
            got.0 == want.0,
            "{ranks} ranks: sphere displacements differ"
        );
        assert!(got.1 == want.1, "{ranks} ranks: sphere velocities differ");
        assert!(got.2 == want.2, "{ranks} ranks: node displacements differ");
        // The energies summed over the ranks: bitwise on as many ranks,
        // to the sum's round-off on one.
        let tol = if ranks == 2 { 0.0 } else { 1e-12 };
        for (k, (a, b)) in got.3.iter().zip(&want.3).enumerate() {
            assert!(
                (a - b).abs() <= tol * b.abs().max(1e-30),
                "{ranks} ranks: history column {k}: {a:e} against {b:e}"
            );
        }
    }
}

/// The last output of a run of `scenarios/spheres-heat.toml` in `dir`:
/// the free spheres' displacements and temperatures (by sphere number),
/// the block's node temperatures (by node id), and the history's header
/// and last row.
struct HeatLast {
    displacement: Vec<f64>,
    spheres_t: Vec<f64>,
    nodes_t: Vec<f64>,
    header: Vec<String>,
    row: Vec<f64>,
}

fn heat_last(dir: &Path) -> HeatLast {
    let stem = "spheres-heat";
    let h5 = dir.join(format!("{stem}_spheres.h5"));
    let k = fdem::io::read_times(&h5).unwrap().len() - 1;
    let field = |name: &str| fdem::io::read_node_field_step(&h5, name, k).unwrap();
    let r = read_results(dir, stem);
    let (header, rows) = history(dir, stem);
    HeatLast {
        displacement: field("displacement"),
        spheres_t: field("temperature"),
        nodes_t: r.temperature.last().unwrap().clone(),
        header,
        row: rows.last().unwrap().clone(),
    }
}

/// Free spheres carrying heat (`scenarios/spheres-heat.toml`, 40 cold
/// spheres falling onto a block heated from below, 0.2 s) stopped at
/// 0.12 s on two ranks, while the first spheres touch the block and take
/// its heat (heat pending for the next thermal step), and continued to
/// 0.2 s on one and on two ranks. The checkpoint holds the spheres'
/// temperatures and heat account and the heat handed to the block not yet
/// released: on two ranks the spheres' motion and temperatures, the
/// block's temperatures and the history's last row are bitwise those of
/// the run that never stopped; on one rank the motion is bitwise and the
/// temperatures and the history are within the direct solve's round-off
/// on another rank count.
#[test]
fn free_spheres_heat_restart_bitwise_on_one_and_two_ranks() {
    let src = root().join("scenarios/spheres-heat.toml");
    let dir = out_dir("sphere-heat-restart");
    let path = dir.join("spheres-heat.toml");
    std::fs::copy(&src, &path).unwrap();
    let end = ["--set", "time.steps=20"];
    let full = out_dir("sphere-heat-restart-full");
    run_ok(2, &path, &full, &end);
    let want = heat_last(&full);
    let first = out_dir("sphere-heat-restart-first");
    run_ok(
        2,
        &path,
        &first,
        &["--set", "output.checkpoint=true", "--set", "time.steps=12"],
    );
    let ck = first.join("spheres-heat_checkpoint.h5");
    // Heat moving at the checkpoint: taken from the faces, and pending.
    let (h, rows) = history(&first, "spheres-heat");
    let at = rows.last().unwrap();
    let (taken, pending) = (
        at[col(&h, "spheres_heat_from_faces")],
        at[col(&h, "spheres_heat_pending")],
    );
    let warm = at[col(&h, "spheres_max_T")];
    eprintln!("at the checkpoint: spheres took {taken:e} J, {pending:e} J pending, warmest {warm}");
    assert!(taken > 0.0 && pending != 0.0 && warm > 20.0, "{at:?}");
    for ranks in [1, 2] {
        let out = out_dir(&format!("sphere-heat-restart-{ranks}"));
        let mut args = vec!["--restart", ck.to_str().unwrap()];
        args.extend_from_slice(&end);
        run_ok(ranks, &path, &out, &args);
        let got = heat_last(&out);
        assert!(
            got.displacement == want.displacement,
            "{ranks} ranks: sphere displacements differ"
        );
        // Temperatures relative to the range T1 − T0 = 80 K, and the
        // history: bitwise on as many ranks; on one, the direct solve's
        // and the sums' round-off.
        let tol = if ranks == 2 { 0.0 } else { 1e-12 };
        for (what, a, b) in [
            ("sphere", &got.spheres_t, &want.spheres_t),
            ("node", &got.nodes_t, &want.nodes_t),
        ] {
            let worst = a
                .iter()
                .zip(b.iter())
                .map(|(x, y)| (x - y).abs() / 80.0)
                .fold(0.0, f64::max);
            eprintln!("{ranks} ranks: {what} temperatures {worst:.2e} of T1 - T0 apart");
            assert!(
                a.len() == b.len() && worst <= tol,
                "{ranks} ranks: {what}: {worst:e}"
            );
        }
        assert_eq!(got.header, want.header);
        // Heat columns against the boundary heat (`convection_heat_in` is
        // a round-off residue of order 1e-12 J here), the others relative.
        let heat_in = want.row[col(&want.header, "boundary_heat_in")].abs();
        let mut worst: f64 = 0.0;
        for (k, (a, b)) in got.row.iter().zip(&want.row).enumerate() {
            let scale = match got.header[k].contains("heat") {
                true => b.abs().max(heat_in),
                false => b.abs().max(1e-30),
            };
            let d = (a - b).abs() / scale;
            worst = worst.max(d);
            assert!(
                d <= tol,
                "{ranks} ranks: history column {}: {a:e} against {b:e}",
                got.header[k]
            );
        }
        eprintln!("{ranks} ranks: history's last row {worst:.2e} apart (relative)");
    }
    // A checkpoint without the spheres' temperatures (a mechanical run's,
    // or one from before they were saved): a clear error naming them.
    let old = dir.join("no-temperatures_checkpoint.h5");
    std::fs::copy(&ck, &old).unwrap();
    hdf5::File::open_rw(&old)
        .unwrap()
        .unlink("spheres/temperature")
        .unwrap();
    let out = out_dir("sphere-heat-restart-old");
    let args = [
        "run",
        path.to_str().unwrap(),
        "--quiet",
        "--output",
        out.to_str().unwrap(),
        "--restart",
        old.to_str().unwrap(),
    ];
    let o = fdem(1, &args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("spheres/temperature is missing"), "{err}");
}
