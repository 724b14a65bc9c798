//! Self-contact of a jointed body (issue 19): a C-shaped body whose arm
//! tips swell into the slot between them meets itself. The tips (element
//! set `tips`, a material with a large expansion) are heated over a
//! ramp; each grows towards the slot by about α ΔT h / 2, so together
//! they would close it by α ΔT h = 1.5 × the slot. The arms' tets shared
//! no vertex of the continuous mesh, so only the self-contact search
//! pairs them. Asserted against references computed here: the tips pass
//! through each other without contact (the control), and with it they
//! overlap no deeper than the penalty allows under the largest stress
//! the swelling can make, yet touch; the arms bent apart store about the
//! energy of two cantilevers pushed back by the excess closure; the
//! self-contact forces sum to zero and momentum stays zero (no external
//! force); 1 and 2 ranks (the body split over both) give bitwise the
//! same trajectories. Thermal
//! variant: the two tips at different temperatures conduct only once they
//! touch, and only with a `[contact]` table.

use crate::common::*;
use fdem::mesh::TetMesh;

/// Young's modulus (Pa), Poisson's ratio, density, contact penalty (Pa).
const E: f64 = 1e7;
const NU: f64 = 0.25;
const RHO: f64 = 1000.0;
const PENALTY: f64 = 1e9;
/// Arm thickness h, slot g, element size (m) and the tips' α ΔT.
const H: f64 = 0.2;
const GAP: f64 = 0.04;
const CELL: f64 = 0.1;
const SWELL: f64 = 0.3;
/// Width of the spine, start of the tips (m).
const SPINE: f64 = 0.2;
const TIPS: f64 = 0.8;

/// The C: arms z in [0, h] and [h + g, 2h + g], x in [0, 1], joined by a
/// spine x in [0, 0.2] across the slot; 0.1 m thick in y. Kuhn tets of a
/// 10 × 1 × 5 grid whose z layers are 0, 0.1, 0.2, 0.24, 0.34, 0.44,
/// without the slot's cells.
fn c_mesh() -> TetMesh {
    let g = fdem::mesh::generate::box_mesh([0.0; 3], [10.0, 1.0, 5.0], 1.0).unwrap();
    let zs = [0.0, 0.1, H, H + GAP, H + GAP + 0.1, 2.0 * H + GAP];
    let at = |p: [f64; 3]| [p[0] * CELL, p[1] * CELL, zs[p[2].round() as usize]];
    let keep: Vec<[u32; 4]> = g
        .tets
        .iter()
        .copied()
        .filter(|t| {
            let c = t.iter().fold([0.0; 3], |s, &n| {
                let p = at(g.nodes[n as usize]);
                [s[0] + p[0] / 4.0, s[1] + p[1] / 4.0, s[2] + p[2] / 4.0]
            });
            !(c[0] > SPINE && c[2] > H && c[2] < H + GAP)
        })
        .collect();
    let mut new_id = vec![u32::MAX; g.nodes.len()];
    let mut nodes = Vec::new();
    let tets = keep
        .iter()
        .map(|t| {
            t.map(|n| {
                if new_id[n as usize] == u32::MAX {
                    new_id[n as usize] = nodes.len() as u32;
                    nodes.push(at(g.nodes[n as usize]));
                }
                new_id[n as usize]
            })
        })
        .collect();
    TetMesh::one_body(nodes, tets)
}

/// The shipped scenario `scenarios/self-contact-c.toml` (its constants
/// are this file's): jointed everywhere (joints far too strong to
/// break), the tips heated by 100 °C over 0.3 s with mass damping near
/// critical for the arms' bending, 0.45 s in all; with or without its
/// penalty contact.
fn scenario(contact: bool) -> String {
    let text = std::fs::read_to_string(root().join("scenarios/self-contact-c.toml")).unwrap();
    let text = text.replace("meshes/c-shape.msh", "c.msh");
    if contact {
        return text;
    }
    let table = "[mechanics.contact]\npenalty = 1e9\nfriction = 0.3\n";
    assert!(text.contains(table));
    text.replace(table, "")
}

/// Output of one run: times, reference coordinates, cells, and per step
/// the displacement and velocity of every node (by node id).
struct Run {
    times: Vec<f64>,
    coords: Vec<[f64; 3]>,
    cells: Vec<[usize; 4]>,
    disp: Vec<Vec<[f64; 3]>>,
    vel: Vec<Vec<[f64; 3]>>,
    /// The rank of every element.
    ranks: Vec<i32>,
}

fn run(ranks: usize, contact: bool) -> Run {
    let out = out_dir(&format!("self-contact-{contact}-{ranks}"));
    fdem::mesh::gmsh::write_msh_ascii(&c_mesh(), &out.join("c.msh")).unwrap();
    // The shipped mesh is this one.
    let shipped = std::fs::read(root().join("scenarios/meshes/c-shape.msh")).unwrap();
    assert!(shipped == std::fs::read(out.join("c.msh")).unwrap());
    let scen = out.join("c.toml");
    std::fs::write(&scen, scenario(contact)).unwrap();
    run_ok(ranks, &scen, &out, &[]);
    let m = read_mech(&out, "c");
    let h5 = out.join("c.h5");
    let (_, _, ids, _) = read_nodes(&h5);
    let vel = (0..m.times.len())
        .map(|k| {
            let v = fdem::io::read_node_field_step(&h5, "velocity", k).unwrap();
            let mut o = vec![[0.0; 3]; ids.len()];
            for (row, &id) in ids.iter().enumerate() {
                o[id as usize] = [v[3 * row], v[3 * row + 1], v[3 * row + 2]];
            }
            o
        })
        .collect();
    Run {
        times: m.times,
        coords: m.coords,
        cells: m.cells,
        disp: m.disp,
        vel,
        ranks: fdem::io::read_static_cell_field_i32(&h5, "rank").unwrap(),
    }
}

impl Run {
    /// How deep the tips overlap at step k (m, negative: apart): over the
    /// tips' slot faces, the lower arm's top (reference z = h) above the
    /// upper arm's bottom (z = h + g) at the same reference (x, y); the
    /// node copies of one point, the deepest.
    fn overlap(&self, k: usize) -> f64 {
        let key = |c: &[f64; 3]| ((c[0] / 0.05).round() as i64, (c[1] / 0.05).round() as i64);
        let mut lower: std::collections::BTreeMap<(i64, i64), f64> = Default::default();
        let mut upper: std::collections::BTreeMap<(i64, i64), f64> = Default::default();
        for (c, u) in self.coords.iter().zip(&self.disp[k]) {
            if c[0] < TIPS + 1e-9 {
                continue;
            }
            let z = c[2] + u[2];
            if (c[2] - H).abs() < 1e-9 {
                let e = lower.entry(key(c)).or_insert(f64::NEG_INFINITY);
                *e = e.max(z);
            } else if (c[2] - H - GAP).abs() < 1e-9 {
                let e = upper.entry(key(c)).or_insert(f64::INFINITY);
                *e = e.min(z);
            }
        }
        assert!(!lower.is_empty() && lower.len() == upper.len());
        lower
            .iter()
            .map(|(p, zl)| zl - upper[p])
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Lumped masses ρ V / 4 of the nodes (the run's, to round-off).
    fn masses(&self) -> Vec<f64> {
        let mut m = vec![0.0; self.coords.len()];
        for c in &self.cells {
            let x = c.map(|n| self.coords[n]);
            let d = |i: usize| [0, 1, 2].map(|j| x[i][j] - x[0][j]);
            let (a, b, e) = (d(1), d(2), d(3));
            let v = (a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0])
                + a[2] * (b[0] * e[1] - b[1] * e[0]))
                .abs()
                / 6.0;
            for &n in c {
                m[n] += RHO * v / 4.0;
            }
        }
        m
    }
}

/// Without contact the tips pass through each other, by about the
/// swelling's closure less the slot.
#[test]
fn without_contact_the_tips_pass_through_each_other() {
    let r = run(1, false);
    let k = r.times.len() - 1;
    let free = SWELL * H - GAP;
    let o = r.overlap(k);
    eprintln!("no contact: overlap {o:.4e} m (closure less slot {free:.4e})");
    assert!(o > 0.5 * free, "overlap {o} m");
}

/// With contact the tips meet and press: the overlap stays within what
/// the penalty gives at the largest stress the swelling can make, the
/// tips are in compression across the slot below that stress, momentum
/// stays zero, and 1 and 2 ranks agree bitwise.
#[test]
fn the_tips_meet_themselves_and_press() {
    let one = run(1, true);
    let k = one.times.len() - 1;
    // The largest contact stress: the excess closure taken up by both
    // tips in uniaxial strain (constrained modulus), a bound since the
    // arms also bend away.
    let m_c = E * (1.0 - NU) / ((1.0 + NU) * (1.0 - 2.0 * NU));
    let sigma_max = m_c * (SWELL * H - GAP) / (2.0 * H);
    // Flat contact: pressure ≈ p_n δ / (2ℓ) with ℓ the cell (see
    // contact::pair_stiffness), so δ ≤ 2ℓ σ / p_n; twice that for the
    // dynamics and the corners.
    let depth = 2.0 * (2.0 * CELL * sigma_max / PENALTY);
    let deepest = (0..one.times.len())
        .map(|s| one.overlap(s))
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "contact: deepest overlap {deepest:.3e} m (bound {depth:.3e}), at the end {:.3e}",
        one.overlap(k)
    );
    assert!(deepest < depth, "overlap {deepest} m above {depth} m");
    // The tips touch at the end (the swelling closes the slot and more):
    // at most a few percent of the slot apart at the nodes.
    assert!(
        one.overlap(k) > -0.05 * GAP,
        "apart at the end: {}",
        one.overlap(k)
    );
    // The force: the arms bent apart by the contact store the strain
    // energy the control run lacks. As cantilevers clamped at the spine,
    // each tip pushed back by half the excess closure δ at the tips'
    // middle (a = 0.7 m): F = 3 E I δ / a³, stored F δ / 2 per arm. The
    // spine and the joints make the real arms softer (less energy).
    let control = out_dir_of(false, 1);
    run(1, false);
    let (h, rows) = history(&out_dir_of(true, 1), "c");
    let (hc, rows_c) = history(&control, "c");
    let stored = rows.last().unwrap()[col(&h, "strain_energy")]
        - rows_c.last().unwrap()[col(&hc, "strain_energy")];
    let inertia = CELL * H.powi(3) / 12.0;
    let push = 0.5 * (SWELL * H - GAP);
    let force = 3.0 * E * inertia * push / 0.7f64.powi(3);
    let ratio = stored / (force * push);
    eprintln!("arms: bending energy {stored:.3e} J, clamped cantilevers {:.3e} J (ratio {ratio:.2}), F = {force:.1} N", force * push);
    assert!(
        (0.2..1.5).contains(&ratio),
        "bending energy {stored} J, ratio {ratio}"
    );
    // The self-contact forces are equal and opposite: the body's net
    // contact force is round-off of F.
    for r in &rows {
        let net = ["c_force_x", "c_force_y", "c_force_z"].map(|c| r[col(&h, c)].abs());
        assert!(
            net.iter().all(|&f| f < 1e-9 * force),
            "net contact force {net:?}"
        );
    }
    // Momentum: no external force, so it stays zero, to round-off of the
    // largest momentum of a node set.
    let mass = one.masses();
    for (s, v) in one.vel.iter().enumerate() {
        let mut p = [0.0; 3];
        let mut scale = 0.0;
        for (mi, vi) in mass.iter().zip(v) {
            for d in 0..3 {
                p[d] += mi * vi[d];
            }
            scale += mi * (vi[0].abs() + vi[1].abs() + vi[2].abs());
        }
        let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(
            norm <= 1e-9 * scale.max(1e-30),
            "step {s}: momentum {p:?} of {scale}"
        );
    }
    let two = run(2, true);
    // The body (1,008 node copies) is split over the two ranks: its arms
    // meet across the cut, as ghosts of each other's tets.
    assert!(
        two.ranks.contains(&0) && two.ranks.contains(&1),
        "the C body is not split over the 2 ranks"
    );
    assert_eq!(one.times, two.times);
    for s in 0..one.times.len() {
        assert!(one.disp[s] == two.disp[s], "step {s}: 1 and 2 ranks differ");
        assert!(one.vel[s] == two.vel[s], "step {s}: velocities differ");
    }
}

fn out_dir_of(contact: bool, ranks: usize) -> std::path::PathBuf {
    root()
        .join("target")
        .join("test-output")
        .join(format!("self-contact-{contact}-{ranks}"))
}

/// The thermal variant: the C of the test above with conduction; the
/// upper tip's top face (face set `hot`) held at 100 °C heats the upper
/// tip, which alone swells (α ΔT h / 2 = 2 × the slot at 100 °C) until it
/// presses on the lower tip. Diffusivity 0.1 m²/s: the upper tip warms in
/// about h² / D = 0.4 s, while heat through the arms and spine (1.4 m)
/// would take 20 s. With a `[contact]` table the pressed tips conduct
/// S / Rc; `contact` false leaves the table out (no contact conduction).
fn thermal_scenario(contact: bool) -> String {
    let table = if contact {
        "[contact]\nresistance = 1e-4\nevery = 1\n"
    } else {
        ""
    };
    format!(
        r#"
[time]
dt = 2e-3
end_time = 0.6

[[materials]]
name = "rubber"
density = {RHO}
young = {E:e}
poisson = {NU}
conductivity = 100.0
specific_heat = 1.0
tensile_strength = 1e8
cohesion = 1e8
friction_angle = 30.0
g_i = 1e8
g_ii = 1e8
fracture_penalty = 1e8

[[materials]]
name = "swelling"
density = {RHO}
young = {E:e}
poisson = {NU}
conductivity = 100.0
specific_heat = 1.0
expansion = 0.008

[[bodies]]
name = "c"
material = "rubber"
mesh = {{ kind = "gmsh", file = "c.msh" }}
initial_temperature = 0.0
element_sets = {{ tips = {{ min = [{TIPS}, -1.0, -1.0], max = [2.0, 2.0, 2.0] }} }}
regions = {{ tips = "swelling" }}
fracture = {{}}

{table}
[thermal]
theta = 1.0

[[thermal.bc]]
kind = "temperature"
set = "hot"
value = 100.0
ramp = 0.3

[mechanics]
damping = 40.0

[mechanics.contact]
penalty = {PENALTY:e}
friction = 0.3

[output]
every = 25
"#
    )
}

/// Two parts of one body at different temperatures conduct only while
/// they touch: the lower tip stays at 0 °C until the swelling upper tip
/// presses on it, then warms through the contact; without the `[contact]`
/// table it stays near 0 °C though pressed (only what creeps along the
/// arms and the spine).
#[test]
fn touching_parts_of_one_body_conduct_heat() {
    let mut mesh = c_mesh();
    let top = 2.0 * H + GAP;
    let hot: Vec<[u32; 3]> = mesh
        .boundary_faces()
        .into_iter()
        .map(|f| f.nodes)
        .filter(|f| {
            f.iter().all(|&n| {
                let p = mesh.nodes[n as usize];
                (p[2] - top).abs() < 1e-9 && p[0] > TIPS - 1e-9
            })
        })
        .collect();
    assert_eq!(hot.len(), 4);
    mesh.face_sets.insert("hot".into(), hot);
    let mut lower_warmed = Vec::new();
    for contact in [true, false] {
        let out = out_dir(&format!("self-contact-thermal-{contact}"));
        fdem::mesh::gmsh::write_msh_ascii(&mesh, &out.join("c.msh")).unwrap();
        let scen = out.join("c.toml");
        std::fs::write(&scen, thermal_scenario(contact)).unwrap();
        run_ok(1, &scen, &out, &[]);
        let m = read_mech(&out, "c");
        // Touching: the run's penalty pairs that overlap (history, every step).
        let (h, rows) = history(&out, "c");
        let first_touch = rows
            .iter()
            .find(|r| r[col(&h, "mech_contacts")] > 0.0)
            .map_or(f64::INFINITY, |r| r[col(&h, "time")]);
        // The lower tip's slot face: its warmest node copy, per output.
        let lower: Vec<usize> = (0..m.coords.len())
            .filter(|&n| (m.coords[n][2] - H).abs() < 1e-9 && m.coords[n][0] > TIPS + 1e-9)
            .collect();
        let touched = first_touch.is_finite();
        let mut warmest = 0.0f64;
        for k in 0..m.times.len() {
            let t = lower
                .iter()
                .map(|&n| m.temperature[k][n])
                .fold(f64::MIN, f64::max);
            eprintln!(
                "contact table {contact}: t = {:.3}: lower tip {t:.4e} (first touch {first_touch})",
                m.times[k]
            );
            // Before the tips touch, no heat has reached the lower tip
            // (through the arms and the spine, 1e-10 of the range).
            if m.times[k] < first_touch {
                assert!(
                    t.abs() < 1e-6,
                    "t = {}: lower tip at {t} before touching",
                    m.times[k]
                );
            }
            warmest = warmest.max(t);
        }
        assert!(touched, "the tips never met");
        lower_warmed.push(warmest);
    }
    eprintln!(
        "lower tip: {:.3e} with contact heat, {:.3e} without",
        lower_warmed[0], lower_warmed[1]
    );
    // Through the contact: degrees; without it, only what diffuses along
    // the arms and the spine in 0.6 s (below 1e-3 °C).
    assert!(lower_warmed[0] > 1.0, "no heat through the contact");
    assert!(lower_warmed[1].abs() < 1e-3, "heat without a contact table");
}
