//! Hex8 bodies in `fdem run` (issue 21): the box generator's
//! `element = "hex8"` through the distributed mechanics and heat
//! conduction. References are computed here: the seed 002 cantilever's
//! Timoshenko tip deflection, the seed 000 slab series, the free cube's
//! (1 + α ΔT)³.

use crate::common::*;
use fdem::validation::cantilever::Cantilever;

/// The tip (x = L) nodes' mean displacement along −z at output `k` (m).
fn tip_deflection(m: &Mech, k: usize, length: f64) -> f64 {
    let tip: Vec<f64> = m
        .coords
        .iter()
        .zip(&m.disp[k])
        .filter(|(c, _)| (c[0] - length).abs() < 1e-9)
        .map(|(_, u)| -u[2])
        .collect();
    assert!(!tip.is_empty());
    tip.iter().sum::<f64>() / tip.len() as f64
}

/// Seed 002 sec 4.1, FE alone, Hex8 of 0.5 mm (4 through the thickness)
/// by damped explicit dynamics: the static tip deflection within 3 % of
/// P L³/(3EI) + P L/(κ G A) = 0.403 mm (measured −1.4 %: 0.3974 mm), the
/// beam at rest, its bending stress as beam theory's within 2 %, and the
/// same bits on 1 and 2 ranks (the beam, 1845 nodes,
/// is cut over the two, its hexes whole).
#[test]
fn hex8_cantilever_deflects_as_timoshenko_on_one_and_two_ranks() {
    let beam = Cantilever::seed002();
    let expected = beam.deflection(beam.length);
    let scen = root().join("scenarios/cantilever-hex8.toml");
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("cantilever-hex8-{ranks}"));
        let stdout = run_ok(ranks, &scen, &out, &[]);
        assert!(stdout.contains("1280 Hex8 (as 7680 tets)"), "{stdout}");
        runs.push(read_mech(&out, "cantilever-hex8"));
    }
    let m = &runs[0];
    let k = m.times.len() - 1;
    let tip = tip_deflection(m, k, beam.length);
    let err = tip / expected - 1.0;
    eprintln!(
        "Hex8 cantilever: tip {:.4} mm, Timoshenko {:.4} mm ({:+.2} %)",
        tip * 1e3,
        expected * 1e3,
        100.0 * err
    );
    assert!(err.abs() < 0.03, "tip {tip:e} m vs {expected:e} m");
    // Static: the last two outputs (0.5 ms apart) agree to 1e-4.
    let before = tip_deflection(m, k - 1, beam.length);
    assert!((tip - before).abs() < 1e-4 * tip, "{before:e} -> {tip:e}");
    // Bending: σ_xx of the cells 4–6 mm from the clamp against beam
    // theory P (L − x)(z − H/2)/I at their centroids, each half of the
    // section summed (measured +0.6 % low in both; the tension half on top).
    let i = beam.width * beam.height.powi(3) / 12.0;
    let (mut sums, mut theory) = ([0.0; 2], [0.0; 2]);
    for (c, s) in m.cells.iter().zip(&m.stress[k]) {
        let x: [f64; 3] =
            std::array::from_fn(|d| c.iter().map(|&n| m.coords[n][d]).sum::<f64>() / 4.0);
        if (4e-3..6e-3).contains(&x[0]) {
            let half = usize::from(x[2] < beam.height / 2.0);
            sums[half] += s[0][0];
            theory[half] += beam.load * (beam.length - x[0]) * (x[2] - beam.height / 2.0) / i;
        }
    }
    for h in 0..2 {
        let ratio = sums[h] / theory[h];
        eprintln!("bending stress, half {h}: {ratio:.4} of beam theory");
        assert!((ratio - 1.0).abs() < 0.02, "half {h}: {ratio}");
    }
    assert!(sums[0] > 0.0 && sums[1] < 0.0);
    // 1 and 2 ranks: the same bits.
    for (a, b) in runs[0].disp.iter().zip(&runs[1].disp) {
        assert!(a == b, "displacements differ between 1 and 2 ranks");
    }
    assert!(runs[0].stress == runs[1].stress);
}

/// Seed 000 sec 4.2 with Hex8 (`thermal::hex8` matrices in the one PETSc
/// system): the slab series at h = 0.1 and 0.05 m, its error falling
/// about fourfold as h halves, within the measured errors + 10 %
/// (0.104 / 0.0112 / 0.0204 % and 0.0259 / 0.0030 / 0.0052 % at 10 / 50 /
/// 100 s; the Tet4 split of the same cells: 0.106 / 0.0163 / 0.0213 %),
/// every temperature within [0, 1]; and 2 ranks (the bar cut over them)
/// as 1 to 1e-9.
#[test]
fn hex8_slab_matches_the_series_at_second_order() {
    let measured = [[0.104, 0.0112, 0.0204], [0.0259, 0.0030, 0.0052]];
    let mut errors = Vec::new();
    for (i, h) in [0.1, 0.05].into_iter().enumerate() {
        let mut finals = Vec::new();
        for ranks in [1, 2] {
            let out = out_dir(&format!("slab-hex8-{h}-{ranks}"));
            let size = format!("bodies.bar.mesh.element_size={h}");
            let args = ["--set", "bodies.bar.mesh.element=hex8", "--set", &size];
            run_ok(ranks, &root().join("scenarios/slab-1d.toml"), &out, &args);
            let r = read_results(&out, "slab-1d");
            let e = [10.0, 50.0, 100.0].map(|t| slab_mean_error_percent(&r, step_at(&r, t)));
            eprintln!("Hex8 slab h = {h}, {ranks} rank(s): errors {e:?} %");
            for (j, &x) in e.iter().enumerate() {
                assert!(x <= 1.1 * measured[i][j], "h = {h}, output {j}: {x} %");
            }
            for t in &r.temperature {
                assert!(t.iter().all(|&v| (-1e-12..=1.0 + 1e-12).contains(&v)));
            }
            if ranks == 1 {
                errors.push(e);
            }
            finals.push(r.temperature.last().unwrap().clone());
        }
        let d = rel_diff(&finals[0], &finals[1]);
        assert!(d < 1e-9, "h = {h}: 1 vs 2 ranks differ by {d:e}");
    }
    for (j, (a, b)) in errors[0].iter().zip(&errors[1]).enumerate() {
        let ratio = a / b;
        assert!(ratio > 3.0, "output {j}: ratio {ratio}");
    }
}

/// Seed 004 sec 3.2 with Hex8: a free cube heated by 100 °C (α = 1e-5)
/// grows to (1 + αΔT)³ without stress, at h = 0.1 m on 2 ranks.
#[test]
fn hex8_free_cube_expands_without_stress() {
    let (alpha, dt, young, nu): (f64, f64, f64, f64) = (1e-5, 100.0, 20e9, 0.2);
    let expected = (1.0 + alpha * dt).powi(3);
    let constrained = young * alpha * dt / (1.0 - 2.0 * nu);
    let out = out_dir("cube-expansion-hex8");
    let args = [
        "--set",
        "bodies.cube.mesh.element=hex8",
        "--set",
        "bodies.cube.mesh.element_size=0.1",
    ];
    let stdout = run_ok(
        2,
        &root().join("scenarios/cube-expansion.toml"),
        &out,
        &args,
    );
    assert!(stdout.contains("1000 Hex8"), "{stdout}");
    let m = read_mech(&out, "cube-expansion");
    let k = m.times.len() - 1;
    let v: f64 = m
        .cells
        .iter()
        .map(|c| {
            let p = c.map(|n| [0, 1, 2].map(|d| m.coords[n][d] + m.disp[k][n][d]));
            let e = |i: usize| [0, 1, 2].map(|d| p[i][d] - p[0][d]);
            let (a, b, c) = (e(1), e(2), e(3));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum();
    assert!(
        (v / expected - 1.0).abs() < 1e-4,
        "volume {v:.7} m^3, expected {expected:.7}"
    );
    let smax = m.stress[k]
        .iter()
        .flat_map(|s| s.iter().flatten())
        .fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(smax < 0.01 * constrained, "max |stress| {smax:.3e} Pa");
}

/// A Gmsh MSH 4.1 ASCII file of the box [0, size] cut into `n` Hex8,
/// node tags shuffled (so the lowest-node split differs from the box
/// generator's), the faces x = 0 and x = size[0] as quadrangles in the
/// physical surfaces `clamp` and `tip`.
fn write_hex_box_msh(path: &std::path::Path, size: [f64; 3], n: [usize; 3]) {
    let hm = fdem::mesh::hex8::hex_box([0.0; 3], size, n).unwrap();
    let nn = hm.nodes.len();
    // Tag of node i: a stride prime to nn through 1..=nn (a permutation).
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let stride = (1..).map(|k| 7 + 2 * k).find(|&s| gcd(nn, s) == 1).unwrap();
    let tag = |i: u32| (i as usize * stride) % nn + 1;
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s += "$PhysicalNames\n3\n2 1 \"clamp\"\n2 2 \"tip\"\n3 3 \"solid\"\n$EndPhysicalNames\n";
    let [lx, ly, lz] = size;
    s += &format!(
        "$Entities\n0 0 2 1\n1 0 0 0 0 {ly} {lz} 1 1 0\n2 {lx} 0 0 {lx} {ly} {lz} 1 2 0\n"
    );
    s += &format!("1 0 0 0 {lx} {ly} {lz} 1 3 0\n$EndEntities\n");
    s += &format!("$Nodes\n1 {nn} 1 {nn}\n3 1 0 {nn}\n");
    for i in 0..nn as u32 {
        s += &format!("{}\n", tag(i));
    }
    for p in &hm.nodes {
        s += &format!("{:.17e} {:.17e} {:.17e}\n", p[0], p[1], p[2]);
    }
    s += "$EndNodes\n";
    // End faces: the hexes' faces (Table 1 nodes 0-3-7-4 at x = 0, 1-2-6-5 at x = L).
    let ends: Vec<(u32, Vec<[u32; 4]>)> = [(1, [0, 3, 7, 4], 0.0), (2, [1, 2, 6, 5], lx)]
        .into_iter()
        .map(|(entity, f, x): (u32, [usize; 4], f64)| {
            let quads = hm
                .hexes
                .iter()
                .map(|h| f.map(|k| h[k]))
                .filter(|q| {
                    q.iter()
                        .all(|&v| (hm.nodes[v as usize][0] - x).abs() < 1e-12)
                })
                .collect();
            (entity, quads)
        })
        .collect();
    let count = ends.iter().map(|e| e.1.len()).sum::<usize>() + hm.hexes.len();
    s += &format!("$Elements\n3 {count} 1 {count}\n");
    let mut next = 1;
    for (entity, quads) in &ends {
        s += &format!("2 {entity} 3 {}\n", quads.len());
        for q in quads {
            s += &format!(
                "{next} {} {} {} {}\n",
                tag(q[0]),
                tag(q[1]),
                tag(q[2]),
                tag(q[3])
            );
            next += 1;
        }
    }
    s += &format!("3 1 5 {}\n", hm.hexes.len());
    for h in &hm.hexes {
        let t: Vec<String> = h.iter().map(|&v| tag(v).to_string()).collect();
        s += &format!("{next} {}\n", t.join(" "));
        next += 1;
    }
    s += "$EndElements\n";
    std::fs::write(path, s).unwrap();
}

/// Gmsh hexahedra (`element = "hex8"` on a Gmsh mesh): the cantilever of
/// 1 mm Hex8 read from a file with shuffled node tags, whose tets (cut
/// through each face's lowest node) conform, against the box generator's
/// same hexes: the same tip deflection to 1e-5 (the kernels see the same
/// hexes; the loaded end's triangles, which spread the traction over its
/// nodes, are cut along other diagonals: measured 7e-7), and within 4 %
/// of the Timoshenko value with 2 hexes through the thickness (measured
/// −2.9 %; −1.4 % with 4, the first test).
#[test]
fn gmsh_hex8_cantilever_matches_the_box_generators() {
    let beam = Cantilever::seed002();
    let expected = beam.deflection(beam.length);
    let out = out_dir("cantilever-gmsh-hex8");
    std::fs::create_dir_all(&out).unwrap();
    let msh = out.join("beam.msh");
    write_hex_box_msh(&msh, [beam.length, beam.width, beam.height], [20, 4, 2]);
    let text = std::fs::read_to_string(root().join("scenarios/cantilever-hex8.toml"))
        .unwrap()
        .replace(
            "mesh = { kind = \"box\", size = [20e-3, 4e-3, 2e-3], element_size = 5e-4, element = \"hex8\" }",
            &format!("mesh = {{ kind = \"gmsh\", file = \"{}\", element = \"hex8\" }}", msh.display()),
        )
        .replace("beam.xmin", "beam.clamp")
        .replace("beam.xmax", "beam.tip");
    assert!(text.contains("kind = \"gmsh\""));
    let scen = out.join("cantilever-gmsh-hex8.toml");
    std::fs::write(&scen, text).unwrap();
    let stdout = run_ok(1, &scen, &out.join("run"), &[]);
    assert!(stdout.contains("160 Hex8 (as 960 tets)"), "{stdout}");
    let gmsh = read_mech(&out.join("run"), "cantilever-gmsh-hex8");
    let boxed_out = out_dir("cantilever-box-hex8-1mm");
    let args = ["--set", "bodies.beam.mesh.element_size=1e-3"];
    run_ok(
        1,
        &root().join("scenarios/cantilever-hex8.toml"),
        &boxed_out,
        &args,
    );
    let boxed = read_mech(&boxed_out, "cantilever-hex8");
    let (kg, kb) = (gmsh.times.len() - 1, boxed.times.len() - 1);
    let (tg, tb) = (
        tip_deflection(&gmsh, kg, beam.length),
        tip_deflection(&boxed, kb, beam.length),
    );
    eprintln!(
        "Hex8 cantilever, 1 mm: Gmsh {:.6} mm, box {:.6} mm, Timoshenko {:.4} mm",
        tg * 1e3,
        tb * 1e3,
        expected * 1e3
    );
    assert!((tg / tb - 1.0).abs() < 1e-5, "Gmsh {tg:e} vs box {tb:e}");
    assert!((tg / expected - 1.0).abs() < 0.04, "{tg:e} vs {expected:e}");
}

/// A Hex8 run stopped at a checkpoint (1 rank) and restarted (2 ranks)
/// ends in the same bits as the run straight through.
#[test]
fn hex8_restart_continues_bitwise() {
    let scen = root().join("scenarios/cantilever-hex8.toml");
    let h = ["--set", "bodies.beam.mesh.element_size=1e-3"];
    let straight = out_dir("cantilever-hex8-straight");
    run_ok(1, &scen, &straight, &h);
    let first = out_dir("cantilever-hex8-first");
    let stop = [
        "--set",
        "time.end_time=1.5e-3",
        "--set",
        "output.checkpoint=true",
    ];
    run_ok(1, &scen, &first, &[&h[..], &stop[..]].concat());
    let ck = first.join("cantilever-hex8_checkpoint.h5");
    let rest = out_dir("cantilever-hex8-rest");
    let restart = ["--restart", ck.to_str().unwrap()];
    run_ok(2, &scen, &rest, &[&h[..], &restart[..]].concat());
    let (a, b) = (
        read_mech(&straight, "cantilever-hex8"),
        read_mech(&rest, "cantilever-hex8"),
    );
    assert_eq!(a.times.last(), b.times.last());
    assert!(a.disp.last() == b.disp.last(), "restart differs");
    // Continued in place (the series of `first`, on 1 rank): its
    // hexahedral index lists every step, as the straight run's does.
    run_ok(1, &scen, &first, &[&h[..], &restart[..]].concat());
    let index =
        |d: &std::path::Path| std::fs::read_to_string(d.join("cantilever-hex8_hex8.xdmf")).unwrap();
    assert_eq!(index(&first), index(&straight));
    hex_index(&first, "cantilever-hex8", 20e-3 * 4e-3 * 2e-3);
}

/// Hex8 blocks on a Tet4 floor: the hexahedral index holds the blocks only,
/// its cell rows start after the floor's tets.
#[test]
fn hex8_index_of_hex8_blocks_on_a_tet4_floor() {
    let out = out_dir("drop8-hex8-on-tet4");
    let scen = root().join("scenarios/drop8.toml");
    let set = [
        "--set",
        "bodies.block.mesh.element=hex8",
        "--set",
        "time.steps=10",
    ];
    run_ok(1, &scen, &out, &set);
    let hexes = hex_index(&out, "drop8", 8.0 * 0.1f64.powi(3));
    assert_eq!(hexes.len(), 8 * 8);
}

/// Seed 002 Fig 7 in `fdem run` with Hex8 regions: a bonded lattice
/// (r = 0.125 mm) between Hex8 segments of 0.5 mm, linked by ghost
/// particles, on the L = 10 mm beam with the paper's sizes (FE [0, 3.5]
/// and [6.5, 10] mm, DE [3.5, 6.5] mm; damping scaled with ω₁ ∝ 1/L²):
/// the static tip within 5 % of Timoshenko's (measured −0.55 %; the
/// full-length scenario gives +0.01 %), and the same bits on 1 and 2 ranks.
#[test]
fn hex8_coupled_cantilever_within_5_percent_on_one_and_two_ranks() {
    let beam = Cantilever {
        length: 10e-3,
        ..Cantilever::seed002()
    };
    let expected = beam.deflection(beam.length);
    let scen = root().join("scenarios/cantilever-coupled.toml");
    let args = [
        "--set",
        "bodies.beam.mesh.size=[10e-3, 4e-3, 2e-3]",
        "--set",
        "bodies.beam.element_sets.middle.min=[3.5e-3, -1.0, -1.0]",
        "--set",
        "bodies.beam.element_sets.middle.max=[6.5e-3, 1.0, 1.0]",
        "--set",
        "mechanics.damping=4e4",
        "--set",
        "time.dt=1.25e-4",
        "--set",
        "time.end_time=6.25e-4",
    ];
    let mut runs = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("cantilever-coupled-{ranks}"));
        let stdout = run_ok(ranks, &scen, &out, &args);
        assert!(
            stdout.contains("448 Hex8 (as 2688 tets), 1536 bonded particles"),
            "{stdout}"
        );
        runs.push(read_mech(&out, "cantilever-coupled"));
    }
    let m = &runs[0];
    let k = m.times.len() - 1;
    let tip = tip_deflection(m, k, beam.length);
    let before = tip_deflection(m, k - 1, beam.length);
    eprintln!(
        "coupled Hex8 cantilever, L = 10 mm: tip {:.5} mm, Timoshenko {:.5} mm ({:+.2} %)",
        tip * 1e3,
        expected * 1e3,
        100.0 * (tip / expected - 1.0)
    );
    assert!(
        (tip / expected - 1.0).abs() < 0.05,
        "{tip:e} vs {expected:e}"
    );
    assert!(
        (tip - before).abs() < 1e-3 * tip,
        "not static: {before:e} -> {tip:e}"
    );
    assert!(
        runs[0].disp.last() == runs[1].disp.last(),
        "1 and 2 ranks differ"
    );
}

/// Heat across Hex8 | DE | Hex8 (`scenarios/fede-heat-bar.toml` with
/// `element = "hex8"`): held at 0 and 100 °C, the steady nodes and spheres
/// on the linear profile within 1 % of ΔT (measured 0.92 % at the
/// interface nodes, where the links give and take heat at points; 0.39 %
/// with Tet4), on 1 and 2 ranks alike (1e-8).
#[test]
fn hex8_bar_with_particles_conducts_the_linear_profile() {
    let scen = root().join("scenarios/fede-heat-bar.toml");
    let args = ["--set", "bodies.bar.mesh.element=hex8"];
    let mut finals = Vec::new();
    for ranks in [1, 2] {
        let out = out_dir(&format!("fede-heat-bar-hex8-{ranks}"));
        let stdout = run_ok(ranks, &scen, &out, &args);
        assert!(
            stdout.contains("128 Hex8 (as 768 tets), 64 bonded particles"),
            "{stdout}"
        );
        let r = read_results(&out, "fede-heat-bar");
        let k = r.times.len() - 1;
        let err = |x: f64, t: f64| (t - 100.0 * x / 3e-3).abs() / 100.0;
        let fe = r
            .coords
            .iter()
            .zip(&r.temperature[k])
            .map(|(c, &t)| err(c[0], t))
            .fold(0.0, f64::max);
        let h5 = out.join("fede-heat-bar_particles.h5");
        let centres = fdem::io::read_mesh(&h5).unwrap().coords;
        let steps = fdem::io::read_times(&h5).unwrap().len();
        let sphere_t = fdem::io::read_node_field_step(&h5, "temperature", steps - 1).unwrap();
        let de = centres
            .iter()
            .zip(&sphere_t)
            .map(|(c, &t)| err(c[0], t))
            .fold(0.0, f64::max);
        eprintln!("Hex8 | DE | Hex8 heat, {ranks} rank(s): nodes {fe:.2e}, spheres {de:.2e} of dT");
        assert!(fe < 0.01 && de < 0.01, "nodes {fe:e}, spheres {de:e}");
        finals.push(r.temperature[k].clone());
    }
    let d = rel_diff(&finals[0], &finals[1]);
    assert!(d < 1e-8, "1 vs 2 ranks: {d:e}");
}

/// `scenarios/drop8.toml`'s blocks and floor as Hex8.
const DROP8_HEX8: [&str; 4] = [
    "--set",
    "bodies.block.mesh.element=hex8",
    "--set",
    "bodies.floor.mesh.element=hex8",
];

/// The hexahedral index `<stem>_hex8.xdmf` of a series in `dir` against
/// its mesh file: `/mesh/hexes` are distinct hexes of eight distinct nodes,
/// positive in the XDMF/VTK order (six tets around the 0–6 diagonal), of
/// total volume `volume` (1e-12); the hexes' cell rows the index reads
/// (`/static/hex/*`, `/fields/hex/*` of every step) are those of each of
/// their six tets. Returns the hexes.
fn hex_index(dir: &std::path::Path, stem: &str, volume: f64) -> Vec<[u32; 8]> {
    let text = std::fs::read_to_string(dir.join(format!("{stem}_hex8.xdmf"))).unwrap();
    let f = hdf5::File::open(dir.join(format!("{stem}.h5"))).unwrap();
    let rows = f.dataset("mesh/hexes").unwrap().read_raw::<u32>().unwrap();
    let hexes: Vec<[u32; 8]> = rows
        .chunks_exact(8)
        .map(|r| r.try_into().unwrap())
        .collect();
    let nh = hexes.len();
    assert!(nh > 0 && text.contains(&format!("NumberOfElements=\"{nh}\" NodesPerElement=\"8\"")));
    let mesh = fdem::io::read_mesh(&dir.join(format!("{stem}.h5"))).unwrap();
    let x = |n: u32| nalgebra::Vector3::from(mesh.coords[n as usize]);
    let mut total = 0.0;
    for h in &hexes {
        let mut sorted = *h;
        sorted.sort_unstable();
        assert!(sorted.windows(2).all(|w| w[0] < w[1]), "{h:?}");
        for t in [
            [0, 1, 2, 6],
            [0, 2, 3, 6],
            [0, 3, 7, 6],
            [0, 7, 4, 6],
            [0, 4, 5, 6],
            [0, 5, 1, 6],
        ] {
            let [a, b, c, d] = t.map(|k| x(h[k]));
            let v = (b - a).cross(&(c - a)).dot(&(d - a)) / 6.0;
            assert!(v > 0.0, "hex {h:?}: a tet of volume {v:e}");
            total += v;
        }
    }
    assert!(
        (total / volume - 1.0).abs() < 1e-12,
        "hex volume {total} against {volume}"
    );
    let mut distinct: Vec<[u32; 8]> = hexes.clone();
    distinct.iter_mut().for_each(|h| h.sort_unstable());
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(distinct.len(), nh);
    // The tets of the hexes, body after body: hex k is tets[6 k .. 6 k + 6].
    let tets: Vec<usize> = (0..mesh.cells.len())
        .filter(|&e| {
            hexes
                .iter()
                .any(|h| mesh.cells[e].iter().all(|n| h.contains(n)))
        })
        .collect();
    assert_eq!(tets.len(), 6 * nh);
    for (k, h) in hexes.iter().enumerate() {
        let six = &tets[6 * k..6 * k + 6];
        assert!(
            six.iter()
                .all(|&e| mesh.cells[e].iter().all(|n| h.contains(n))),
            "hex {k}"
        );
    }
    assert!(!text.contains("HyperSlab") && !text.contains("/fields/cell/"));
    let cell_rows = |file: &hdf5::File, kind: &str| {
        for name in file
            .group(&format!("{kind}/cell"))
            .unwrap()
            .member_names()
            .unwrap()
        {
            assert!(
                text.contains(&format!("/{kind}/hex/{name}<")),
                "{kind} {name}"
            );
            let cell = file.dataset(&format!("{kind}/cell/{name}")).unwrap();
            let hex = file.dataset(&format!("{kind}/hex/{name}")).unwrap();
            let width = cell.shape().get(1).copied().unwrap_or(1);
            assert_eq!(hex.shape()[0], nh, "{kind} {name}");
            let read = |d: &hdf5::Dataset| match d.read_raw::<f64>() {
                Ok(v) => v,
                Err(_) => d
                    .read_raw::<i32>()
                    .unwrap()
                    .into_iter()
                    .map(f64::from)
                    .collect(),
            };
            let (c, x) = (read(&cell), read(&hex));
            for (k, &e) in tets.iter().enumerate() {
                let h = k / 6;
                assert_eq!(
                    c[e * width..(e + 1) * width],
                    x[h * width..(h + 1) * width],
                    "{kind} {name} hex {h}"
                );
            }
        }
    };
    cell_rows(&f, "static");
    for step in 0.. {
        let path = dir.join(format!("{stem}_steps/{step:06}.h5"));
        if !path.exists() {
            assert!(step > 0);
            break;
        }
        cell_rows(&hdf5::File::open(path).unwrap(), "fields");
    }
    hexes
}

/// Eight Hex8 blocks dropped onto a Hex8 floor (`scenarios/drop8.toml`):
/// contact between hexes' tets, and repartitions on 2 ranks that move the
/// Hex8 bodies (measured: 3, 9 bodies moved), in the same bits as 1 rank.
#[test]
fn hex8_bodies_collide_and_repartition_bitwise() {
    let scen = root().join("scenarios/drop8.toml");
    let hex = DROP8_HEX8;
    let one = out_dir("drop8-hex8-1");
    run_ok(1, &scen, &one, &hex);
    let two = out_dir("drop8-hex8-2");
    let rebalance = [
        "--set",
        "mechanics.rebalance.every=5",
        "--set",
        "mechanics.rebalance.threshold=1.0001",
    ];
    let stdout = run_ok(2, &scen, &two, &[&hex[..], &rebalance[..]].concat());
    assert!(!stdout.contains("0 repartition(s)"), "{stdout}");
    assert!(stdout.contains("repartition(s)"), "{stdout}");
    let (a, b) = (read_mech(&one, "drop8"), read_mech(&two, "drop8"));
    assert!(a.disp == b.disp, "1 and 2 ranks differ");
    // The hexahedral index: the floor and the eight blocks, the same on 1
    // and 2 ranks (the blocks moved between ranks on 2).
    let hexes = hex_index(&one, "drop8", 0.45 * 0.45 * 0.05 + 8.0 * 0.1f64.powi(3));
    assert_eq!(hexes, hex_index(&two, "drop8", 0.018125));
    let read = |d: &std::path::Path| std::fs::read_to_string(d.join("drop8_hex8.xdmf")).unwrap();
    assert_eq!(read(&one), read(&two));
    let k = a.times.len() - 1;
    // The blocks fell and landed: every block node moved down, none below the floor's top.
    let fell = a
        .coords
        .iter()
        .zip(&a.disp[k])
        .filter(|(c, _)| c[2] > 0.01)
        .all(|(c, u)| u[2] < 0.0 && c[2] + u[2] > -0.01);
    assert!(fell);
}

/// A later stage takes Hex8 bodies from a checkpoint as Hex8
/// (`mesh.kind = "checkpoint"`, the hexes carried by the file's hex
/// corners): the eight blocks of `scenarios/drop8.toml` and their floor,
/// saved on 2 ranks after one step without gravity (so at their reference
/// to round-off), then dropped from the checkpoint, land as the same drop made
/// directly from the box generator's Hex8 (to round-off; measured 1.2e-15
/// m), on 1 and 2 ranks, not as its Tet4 split (3.0e-3 m apart).
#[test]
fn hex8_bodies_from_a_checkpoint_stay_hex8() {
    let scen = root().join("scenarios/drop8.toml");
    let hex = DROP8_HEX8;
    let saved = out_dir("drop8-hex8-saved");
    let still = [
        "--set",
        "time.steps=1",
        "--set",
        "mechanics.gravity=[0.0, 0.0, 0.0]",
        "--set",
        "output.checkpoint=true",
    ];
    // Written on 2 ranks: each writes the hex corners of its elements.
    run_ok(2, &scen, &saved, &[&hex[..], &still[..]].concat());
    let ck = saved.join("drop8_checkpoint.h5");
    let text = std::fs::read_to_string(&scen).unwrap();
    let from = |template: &str| {
        format!(
            "mesh = {{ kind = \"checkpoint\", file = \"{}\", template = \"{template}\" }}",
            ck.display()
        )
    };
    let staged = text
        .replace(
            "mesh = { kind = \"box\", origin = [-0.1, -0.1, -0.05], size = [0.45, 0.45, 0.05], element_size = 0.05 }",
            &from("floor"),
        )
        .replace(
            "mesh = { kind = \"box\", origin = [0.0, 0.0, 0.0], size = [0.1, 0.1, 0.1], element_size = 0.05 }",
            &from("block"),
        )
        .replace("rotate = [3.0, 5.0, 7.0]\n", "")
        .replace("translate = [0.02, 0.02, 0.05]\n", "")
        .replace("lattice = { count = [2, 2, 2], spacing = [0.14, 0.14, 0.13] }\n", "");
    assert_eq!(
        staged.matches("kind = \"checkpoint\"").count(),
        2,
        "{staged}"
    );
    let stage = out_dir("drop8-hex8-staged");
    let staged_scen = stage.join("drop8-staged.toml");
    std::fs::write(&staged_scen, staged).unwrap();
    let direct = out_dir("drop8-hex8-direct");
    run_ok(1, &scen, &direct, &hex);
    let tets = out_dir("drop8-tet4-direct");
    run_ok(1, &scen, &tets, &[]);
    let at_end = |m: &Mech| -> Vec<[f64; 3]> {
        let k = m.times.len() - 1;
        m.coords
            .iter()
            .zip(&m.disp[k])
            .map(|(c, u)| [c[0] + u[0], c[1] + u[1], c[2] + u[2]])
            .collect()
    };
    let apart = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        a.iter()
            .zip(b)
            .flat_map(|(p, q)| (0..3).map(move |d| (p[d] - q[d]).abs()))
            .fold(0.0, f64::max)
    };
    let want = at_end(&read_mech(&direct, "drop8"));
    let as_tets = apart(&at_end(&read_mech(&tets, "drop8")), &want);
    assert!(
        as_tets > 1e-3,
        "the Tet4 split lands elsewhere: {as_tets:e}"
    );
    for ranks in [1, 2] {
        let out = out_dir(&format!("drop8-hex8-staged-{ranks}"));
        let stdout = run_ok(ranks, &staged_scen, &out, &[]);
        let mesh = summary_line(&stdout, "mesh").expect("a mesh line");
        assert!(mesh.contains("0 Tet4, 145 Hex8"), "{mesh}");
        let got = at_end(&read_mech(&out, "drop8-staged"));
        let d = apart(&got, &want);
        assert!(
            d < 1e-12,
            "{ranks} rank(s): {d:e} m from the direct Hex8 drop"
        );
    }
}
