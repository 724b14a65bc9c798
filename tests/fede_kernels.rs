//! Issue 21 kernels on the cantilever of seed 002: Hex8 and the bonded
//! lattice against Euler–Bernoulli + Timoshenko (references computed here).

use std::time::Instant;

use nalgebra::Vector3;

use fdem::mechanics::bond::{sphere_mass_inertia, BondStiffness};

use fdem::mechanics::hex8::hex8_jacobian;
use fdem::mechanics::hex8_element::Hex8Reference;
use fdem::mesh::gmsh::read_msh_hex8;
use fdem::mesh::hex8::{hex_box, HexMesh};
use fdem::validation::cantilever::{
    de_cantilever, fe_cantilever, fe_cantilever_on, Cantilever, Relaxation, StaticSolution,
};
use fdem::validation::cantilever_plot::write_fig8;
use fdem::validation::coupled_cantilever::coupled_cantilever;
use fdem::validation::fede_coupling::Coupling;
use fdem::validation::fede_heat::{fede_heat, HeatResult};
use fdem::validation::fede_patch::{fede_patch, PatchBar, PatchResult};
use fdem::validation::fede_wave::{constrained_wave_speed, fede_wave, lattice_wave_speed, WaveBar};

fn analytic(beam: &Cantilever, x: f64) -> f64 {
    let i = beam.width * beam.height.powi(3) / 12.0;
    let g = beam.young / (2.0 * (1.0 + beam.poisson));
    let a = beam.width * beam.height;
    beam.load * x * x * (3.0 * beam.length - x) / (6.0 * beam.young * i)
        + beam.load * x / (5.0 / 6.0 * g * a)
}

#[test]
fn hex8_cantilever_within_3_percent() {
    let beam = Cantilever::seed002();
    let start = Instant::now();
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let s = fe_cantilever(&beam, 0.5e-3, &relax).unwrap();
    let reference = analytic(&beam, s.tip_x);
    let err = (s.tip - reference) / reference;
    eprintln!(
        "FE tip {:.5} mm vs {:.5} mm ({:+.2} %), {} steps of {:.3e} s, {:.1} s wall",
        s.tip * 1e3,
        reference * 1e3,
        err * 100.0,
        s.steps,
        s.dt,
        start.elapsed().as_secs_f64()
    );
    assert!(err.abs() < 0.03, "{err}");
}

/// Bending without locking at the coarsest: the seed's beam with one
/// element through its thickness (H = 2 mm), at 0.5 mm and at 2 mm along
/// the beam (10 × 2 × 1 elements). A fully integrated brick locks here
/// (parasitic shear of the bending mode, no lateral strain); the assumed
/// strain field of the hourglass modes bends a rectangular element exactly.
#[test]
fn hex8_cantilever_one_element_through_the_thickness_within_3_percent() {
    let beam = Cantilever::seed002();
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    for n in [[40, 8, 1], [10, 2, 1]] {
        let mesh = hex_box([0.0; 3], [beam.length, beam.width, beam.height], n).unwrap();
        let s = fe_cantilever_on(&beam, &mesh, &relax).unwrap();
        let reference = analytic(&beam, s.tip_x);
        let err = (s.tip - reference) / reference;
        eprintln!(
            "{n:?} Hex8: tip {:.5} mm vs {:.5} mm ({:+.2} %), {} steps",
            s.tip * 1e3,
            reference * 1e3,
            err * 100.0,
            s.steps
        );
        assert!(err.abs() < 0.03, "{n:?}: {err}");
    }
}

/// The one-point Hex8 on a distorted mesh: the seed's beam (40×8×4 cubes
/// of 0.5 mm) with every node moved by up to 0.25 h along x (except on the
/// clamped and loaded faces) and the interior nodes also along y and z, so
/// no element is a parallelepiped while the outer faces stay planar. The
/// hourglass stiffness uses each element's centre half lengths and
/// co-rotated natural frame, exact only for parallelepipeds: this measures
/// what distortion costs in bending.
#[test]
fn hex8_distorted_cantilever_within_3_percent() {
    let beam = Cantilever::seed002();
    let start = Instant::now();
    let h = 0.5e-3;
    let n = [40, 8, 4];
    let mut mesh = hex_box([0.0; 3], [beam.length, beam.width, beam.height], n).unwrap();
    // A fixed pseudo-random number in [-1, 1) per node and direction.
    let noise = |i: usize, c: usize| {
        let t = ((i * 3 + c) as f64 * 12.9898).sin() * 43758.5453;
        2.0 * (t - t.floor()) - 1.0
    };
    let inside = |v: f64, hi: f64| v > 1e-9 && v < hi - 1e-9;
    let size = [beam.length, beam.width, beam.height];
    for (i, p) in mesh.nodes.iter_mut().enumerate() {
        let interior_yz = inside(p[1], size[1]) && inside(p[2], size[2]);
        if inside(p[0], size[0]) {
            p[0] += 0.25 * h * noise(i, 0);
            if interior_yz {
                p[1] += 0.25 * h * noise(i, 1);
                p[2] += 0.25 * h * noise(i, 2);
            }
        }
    }
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let s = fe_cantilever_on(&beam, &mesh, &relax).unwrap();
    let regular = fe_cantilever(&beam, h, &relax).unwrap();
    let reference = analytic(&beam, s.tip_x);
    let err = (s.tip - reference) / reference;
    eprintln!(
        "distorted FE tip {:.5} mm vs {:.5} mm ({:+.2} %; regular mesh {:+.2} %), {} steps, {:.1} s wall",
        s.tip * 1e3,
        reference * 1e3,
        err * 100.0,
        (regular.tip - reference) / reference * 100.0,
        s.steps,
        start.elapsed().as_secs_f64()
    );
    assert!(err.abs() < 0.03, "{err}");
}

#[test]
fn de_short_cantilever_within_8_percent() {
    // CI size: the seed's section and radius on half the length (L = 10 mm).
    let beam = Cantilever {
        length: 10e-3,
        ..Cantilever::seed002()
    };
    let start = Instant::now();
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let s = de_cantilever(&beam, 0.125e-3, &relax).unwrap();
    let reference = analytic(&beam, s.tip_x);
    let err = (s.tip - reference) / reference;
    eprintln!(
        "DE short tip {:.5} mm at x = {:.4} mm vs {:.5} mm ({:+.2} %), {} steps of {:.3e} s, {:.1} s wall",
        s.tip * 1e3,
        s.tip_x * 1e3,
        reference * 1e3,
        err * 100.0,
        s.steps,
        s.dt,
        start.elapsed().as_secs_f64()
    );
    assert!(err.abs() < 0.08, "{err}");
}

/// The seed's DE model at full size. Measured: 64 s wall in release on this machine.
#[test]
#[ignore = "about a minute on one core; CI runs the L = 10 mm beam at the same sizes"]
fn de_cantilever_full_resolution_within_8_percent() {
    let beam = Cantilever::seed002();
    let start = Instant::now();
    let s = de_cantilever(&beam, 0.125e-3, &Relaxation::default()).unwrap();
    let reference = analytic(&beam, s.tip_x);
    let err = (s.tip - reference) / reference;
    eprintln!(
        "DE tip {:.5} mm at x = {:.4} mm vs {:.5} mm ({:+.2} %), {} steps of {:.3e} s, {:.1} s wall",
        s.tip * 1e3,
        s.tip_x * 1e3,
        reference * 1e3,
        err * 100.0,
        s.steps,
        s.dt,
        start.elapsed().as_secs_f64()
    );
    assert!(err.abs() < 0.08, "{err}");
}

/// Coupled tip deflection and its error against the analytic value.
fn coupled_case(beam: &Cantilever, segment: [f64; 2]) -> f64 {
    coupled_case_with(beam, segment, Coupling::default())
}

/// [`coupled_case`] with the given coupling.
fn coupled_case_with(beam: &Cantilever, segment: [f64; 2], coupling: Coupling) -> f64 {
    let start = Instant::now();
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let s = coupled_cantilever(beam, 0.5e-3, 0.125e-3, segment, coupling, &relax).unwrap();
    let reference = analytic(beam, s.tip_x);
    let err = (s.tip - reference) / reference;
    eprintln!(
        "coupled L = {} mm: tip {:.5} mm vs {:.5} mm ({:+.2} %), {} steps of {:.3e} s, {:.1} s wall",
        beam.length * 1e3,
        s.tip * 1e3,
        reference * 1e3,
        err * 100.0,
        s.steps,
        s.dt,
        start.elapsed().as_secs_f64()
    );
    for (x, u) in &s.profile {
        eprintln!(
            "profile {:.4} {:.5} {:.5}",
            x * 1e3,
            u * 1e3,
            analytic(beam, *x) * 1e3
        );
    }
    err
}

#[test]
fn coupled_short_cantilever_within_5_percent() {
    // CI size: half the length, FE | DE | FE = [0, 3.5] [3.5, 6.5] [6.5, 10] mm.
    let beam = Cantilever {
        length: 10e-3,
        ..Cantilever::seed002()
    };
    let err = coupled_case(&beam, [3.5e-3, 6.5e-3]);
    assert!(err.abs() < 0.05, "{err}");
}

/// Eq 17 as written (ghost forces at the ghosts, ghosts spinning with their
/// element) on the seed's beam, for comparison with the default coupling.
#[test]
#[ignore = "about a minute on one core; a comparison, the default coupling is tested"]
fn coupled_cantilever_seed_eq17() {
    let err = coupled_case_with(&Cantilever::seed002(), [7.5e-3, 12.5e-3], Coupling::Seed);
    assert!(err.abs() < 0.05, "{err}");
}

/// Seed 002 Fig 7 at full size: FE on [0, 7.5] and [12.5, 20] mm, spheres
/// between. Measured: 46–70 s wall in release on this machine.
#[test]
#[ignore = "about a minute on one core; CI runs the L = 10 mm beam at the same sizes"]
fn coupled_cantilever_within_5_percent() {
    let err = coupled_case(&Cantilever::seed002(), [7.5e-3, 12.5e-3]);
    assert!(err.abs() < 0.05, "{err}");
}

/// What the patch test asserts, relative to σ_ref = E ε and to the force
/// σ_ref carries over a node's (h²) or a sphere's ((2r)²) area.
struct PatchFigures {
    /// Worst |σ_xx/σ_ref − 1| of any element.
    fe_element: f64,
    /// Worst over the layers of elements of the layer's mean σ_xx.
    fe_layer: f64,
    /// Worst over the DE planes of the section stress.
    de_section: f64,
    /// Worst over the DE layers of E × strain.
    de_strain: f64,
    /// Imposed exact field: largest net force on the inner nodes of the
    /// coupled elements (x = x₁ − h), / σ_ref h².
    inner: f64,
    /// Same on the interface face's nodes.
    face: f64,
    /// Same on the other FE nodes.
    fe_away: f64,
    /// Imposed exact field: largest net force on the first layer of spheres, / σ_ref (2r)².
    boundary: f64,
    /// Same on the other free spheres.
    de_away: f64,
}

/// The patch test's figures, printed.
fn patch_report(name: &str, bar: &PatchBar, p: &PatchResult) -> PatchFigures {
    // Reference: uniaxial stress E ε (the ends hold the exact field).
    let sigma = bar.young * bar.strain;
    let dev = |s: f64| (s / sigma - 1.0).abs();
    let fe_element = p.fe_stress.iter().map(|(_, s)| dev(*s)).fold(0.0, f64::max);
    // Elements per layer of x: the range and the mean of σ_xx/σ_ref.
    let mut layers: Vec<(f64, f64, f64, f64, usize)> = Vec::new();
    for (x, s) in &p.fe_stress {
        let r = s / sigma;
        match layers.iter_mut().find(|l| (l.0 - x).abs() < 1e-9) {
            Some(l) => {
                l.1 = l.1.min(r);
                l.2 = l.2.max(r);
                l.3 += r;
                l.4 += 1;
            }
            None => layers.push((*x, r, r, r, 1)),
        }
    }
    layers.sort_by(|a, b| a.0.total_cmp(&b.0));
    let fe_layer = layers
        .iter()
        .map(|l| (l.3 / l.4 as f64 - 1.0).abs())
        .fold(0.0, f64::max);
    let de_section = p
        .de_section
        .iter()
        .map(|(_, s)| dev(*s))
        .fold(0.0, f64::max);
    let de_strain = p
        .de_strain
        .iter()
        .map(|(_, e)| dev(bar.young * e))
        .fold(0.0, f64::max);
    let node = sigma * bar.size * bar.size;
    let sphere = sigma * 4.0 * bar.radius * bar.radius;
    let x1 = bar.interface;
    let at = |x: f64, a: f64| (x - a).abs() < 1e-9;
    let max_norm = |v: &[(Vector3<f64>, Vector3<f64>)], keep: &dyn Fn(f64) -> bool| {
        v.iter()
            .filter(|(x, _)| keep(x[0]))
            .map(|(_, f)| f.norm())
            .fold(0.0_f64, f64::max)
    };
    // The coupled elements are the FE region's last layer [x₁ − h, x₁].
    let f = PatchFigures {
        fe_element,
        fe_layer,
        de_section,
        de_strain,
        inner: max_norm(&p.fe_residual, &|x| at(x, x1 - bar.size)) / node,
        face: max_norm(&p.fe_residual, &|x| at(x, x1)) / node,
        fe_away: max_norm(&p.fe_residual, &|x| x < x1 - bar.size - 1e-9) / node,
        boundary: max_norm(&p.de_residual, &|x| at(x, x1 + bar.radius)) / sphere,
        de_away: max_norm(&p.de_residual, &|x| x > x1 + bar.radius + 1e-9) / sphere,
    };
    eprintln!(
        "{name}: {} steps of {:.3e} s; worst FE element {:.2} %, FE layer mean {:.2} %, DE section {:.2} %, \
         E×DE strain {:.2} %; |σ_yy|,|σ_zz| ≤ {:.1e} σ; deviation from the exact field {:.1e} εL",
        p.steps,
        p.dt,
        f.fe_element * 100.0,
        f.fe_layer * 100.0,
        f.de_section * 100.0,
        f.de_strain * 100.0,
        p.fe_lateral / sigma,
        p.max_deviation / (bar.strain * bar.length)
    );
    eprintln!(
        "{name}: imposed exact field, largest net force: inner nodes of the coupled elements {:.2e} σh², \
         interface-face nodes {:.2e} σh², other FE nodes {:.1e} σh²; first sphere layer {:.2e} σ(2r)², \
         other spheres {:.2e} σ(2r)²",
        f.inner, f.face, f.fe_away, f.boundary, f.de_away
    );
    for (x, lo, hi, sum, n) in layers {
        eprintln!(
            "{name}: FE layer x = {:.3} mm: σ/σ_ref mean {:.4} in [{lo:.4}, {hi:.4}]",
            x * 1e3,
            sum / n as f64
        );
    }
    for (x, s) in &p.de_section {
        eprintln!(
            "{name}: DE plane x = {:.3} mm: σ/σ_ref {:.4}",
            x * 1e3,
            s / sigma
        );
    }
    for (x, e) in &p.de_strain {
        eprintln!(
            "{name}: DE layers x = {:.3} mm: Eε/σ_ref {:.4}",
            x * 1e3,
            bar.young * e / sigma
        );
    }
    f
}

fn patch_relaxation() -> Relaxation {
    Relaxation {
        tolerance: 1e-10,
        ..Relaxation::default()
    }
}

/// Issue 21 patch test: uniform tension across the FE–DE interface
/// (4 × 2 × 2 mm bar, Hex8 h = 0.5 mm on [0, 2] mm, spheres r = 0.125 mm on
/// [2, 4] mm, ends held on the exact field, relaxed to static). Section
/// stresses within 2 % in both regions and no spurious force at the ghost
/// layer. Eq 17 as written is measured and printed beside it.
#[test]
fn fede_patch_uniform_tension_within_2_percent() {
    let bar = PatchBar::seed002();
    let start = Instant::now();
    let seed = patch_report(
        "seed eq 17",
        &bar,
        &fede_patch(&bar, Coupling::Seed, &patch_relaxation()).unwrap(),
    );
    // Eq 17 as written: the inner nodes of the coupled elements take r/h of their share (ghost docs).
    assert!(seed.inner > 0.2, "{}", seed.inner);
    let p = patch_report(
        "interface",
        &bar,
        &fede_patch(&bar, Coupling::Interface, &patch_relaxation()).unwrap(),
    );
    eprintln!("patch test wall {:.1} s", start.elapsed().as_secs_f64());
    assert!(p.fe_layer < 0.02, "FE layer {}", p.fe_layer);
    assert!(p.de_section < 0.02, "DE section {}", p.de_section);
    assert!(p.de_strain < 0.02, "DE strain {}", p.de_strain);
    // No spurious force: the inner nodes of the coupled elements feel nothing (round-off of the
    // finite-strain element, as everywhere in the FE region), the first layer of spheres no more
    // than the lattice's own box-edge spheres elsewhere.
    assert!(
        p.inner < 1e-3 && p.fe_away < 1e-3,
        "{} {}",
        p.inner,
        p.fe_away
    );
    assert!(
        p.boundary <= p.de_away * (1.0 + 1e-6),
        "{} {}",
        p.boundary,
        p.de_away
    );
}

/// The strict reading of the patch test: every element's σ_xx within 2 %.
/// Measured 3.03 % (2.97 % with the eight-point Hex8; elements at the interface beside the lateral faces):
/// the lattice's surface weights put the diagonal bonds' share of a surface
/// sphere's force at its inner bond midpoints, so the interface-face nodes
/// within h of a lateral face receive up to 7.9 % of σh² more or less than
/// a uniform traction gives them. No weighting of the links can move it:
/// each sphere's equilibrium of forces and moments fixes its links' force
/// and first moment on the face (docs/validation.md); the lattice's surface
/// weights would have to change.
#[test]
#[ignore = "fails: worst element 3.03 % at the interface beside the lateral faces (lattice surface weights), see docs/validation.md"]
fn fede_patch_every_element_within_2_percent() {
    let bar = PatchBar::seed002();
    let p = patch_report(
        "interface",
        &bar,
        &fede_patch(&bar, Coupling::Interface, &patch_relaxation()).unwrap(),
    );
    assert!(p.fe_element < 0.02, "{}", p.fe_element);
}

/// The three models of seed 002 Fig 8 on `beam`, with the coupled DE
/// segment `segment`: (FE, DE, coupled), each tip printed with its error.
fn fig8_models(
    beam: &Cantilever,
    segment: [f64; 2],
    relax: &Relaxation,
) -> [(StaticSolution, f64); 3] {
    let start = Instant::now();
    let err = |s: &StaticSolution| {
        let reference = analytic(beam, s.tip_x);
        (s.tip - reference) / reference
    };
    let fe = fe_cantilever(beam, 0.5e-3, relax).unwrap();
    let de = de_cantilever(beam, 0.125e-3, relax).unwrap();
    let coupled =
        coupled_cantilever(beam, 0.5e-3, 0.125e-3, segment, Coupling::default(), relax).unwrap();
    let out = [fe, de, coupled].map(|s| {
        let e = err(&s);
        (s, e)
    });
    for (name, (s, e)) in ["FE", "DE", "coupled"].iter().zip(&out) {
        eprintln!(
            "Fig 8 L = {} mm {name}: tip {:.5} mm at x = {:.4} mm ({:+.2} %), {} steps",
            beam.length * 1e3,
            s.tip * 1e3,
            s.tip_x * 1e3,
            e * 100.0,
            s.steps
        );
    }
    eprintln!("Fig 8 models: {:.1} s wall", start.elapsed().as_secs_f64());
    out
}

/// Fig 8 at CI size (L = 10 mm): the three profiles as a PNG in a
/// temporary directory; the tips within the tolerances.
#[test]
fn fig8_short_beam_png() {
    let beam = Cantilever {
        length: 10e-3,
        ..Cantilever::seed002()
    };
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let [(fe, fe_err), (de, de_err), (coupled, coupled_err)] =
        fig8_models(&beam, [3.5e-3, 6.5e-3], &relax);
    assert!(fe_err.abs() < 0.03, "FE {fe_err}");
    assert!(de_err.abs() < 0.08, "DE {de_err}");
    assert!(coupled_err.abs() < 0.05, "coupled {coupled_err}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fede-cantilever-short.png");
    write_fig8(&beam, &fe, &de, &coupled, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(
        bytes.len() > 1000 && bytes.starts_with(b"\x89PNG"),
        "{} bytes",
        bytes.len()
    );
}

/// Fig 8 at the seed's size: writes docs/fede-cantilever.png and prints the
/// profiles. Measured: about 2.5 minutes on one core.
#[test]
#[ignore = "about 2 minutes on one core; writes docs/fede-cantilever.png (fig8_short_beam_png runs in CI)"]
fn fig8_full_size_png() {
    let beam = Cantilever::seed002();
    let [(fe, fe_err), (de, de_err), (coupled, coupled_err)] =
        fig8_models(&beam, [7.5e-3, 12.5e-3], &Relaxation::default());
    for (name, s) in [("FE", &fe), ("DE", &de), ("coupled", &coupled)] {
        for (x, u) in &s.profile {
            eprintln!(
                "fig8 {name} {:.4} {:.5} {:.5}",
                x * 1e3,
                u * 1e3,
                analytic(&beam, *x) * 1e3
            );
        }
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/fede-cantilever.png");
    write_fig8(&beam, &fe, &de, &coupled, &path).unwrap();
    assert!(fe_err.abs() < 0.03, "FE {fe_err}");
    assert!(de_err.abs() < 0.08, "DE {de_err}");
    assert!(coupled_err.abs() < 0.05, "coupled {coupled_err}");
}

/// Worst deviations of the heat case: [FE temperature, DE temperature] as
/// fractions of T₁ − T₂, [FE element flux, DE section flux, inflow] as
/// fractions of k (T₁ − T₂)/L; printed.
fn heat_report(name: &str, bar: &PatchBar, k: f64, t: (f64, f64), r: &HeatResult) -> [f64; 5] {
    // Reference: the linear steady profile and its flux, computed here.
    let exact = |x: f64| t.0 + (t.1 - t.0) * x / bar.length;
    let dt = t.0 - t.1;
    let flux = k * dt / bar.length;
    let worst_t = |v: &[(Vector3<f64>, f64)]| {
        let (mut w, mut at) = (0.0, Vector3::zeros());
        for (x, temp) in v {
            let d = ((temp - exact(x[0])) / dt).abs();
            if d > w {
                (w, at) = (d, *x);
            }
        }
        eprintln!(
            "{name}: worst temperature {:.3} % at {:.3?} mm",
            w * 100.0,
            (at * 1e3).as_slice()
        );
        w
    };
    let worst_q = |v: &[(f64, f64)]| {
        v.iter()
            .map(|(_, q)| (q / flux - 1.0).abs())
            .fold(0.0, f64::max)
    };
    let out = [
        worst_t(&r.fe_temperature),
        worst_t(&r.de_temperature),
        worst_q(&r.fe_flux),
        worst_q(&r.de_flux),
        (r.inflow / flux - 1.0).abs(),
    ];
    eprintln!(
        "{name}: worst |T − T_exact|/ΔT: FE nodes {:.3e}, spheres {:.3e}; flux: worst element {:.3e}, \
         DE sections {:.3e}, inflow at X = 0 {:.3e}",
        out[0], out[1], out[2], out[3], out[4]
    );
    out
}

/// Issue 21, heat across the interface: the patch bar (Hex8 | spheres) held
/// at T₁ and T₂ at its ends; the steady profile is linear in both regions
/// and every element and DE section carries k (T₁ − T₂)/L, to round-off
/// (the links' heat lands where a uniform flux puts it on the Hex8 face,
/// `mesh::heat_links`; with the mechanical weights the FE nodes at the
/// face's corners were 1.22 % of T₁ − T₂ off). Eq 17 as written (2.5 %)
/// is printed beside it.
#[test]
fn fede_heat_steady_linear_to_round_off() {
    let bar = PatchBar::seed002();
    let (k, t) = (1.5, (100.0, 20.0));
    let start = Instant::now();
    let seed = fede_heat(&bar, k, t.0, t.1, Coupling::Seed).unwrap();
    heat_report("heat, seed eq 17", &bar, k, t, &seed);
    let r = fede_heat(&bar, k, t.0, t.1, Coupling::Interface).unwrap();
    let w = heat_report("heat, interface", &bar, k, t, &r);
    eprintln!("heat cases {:.1} s wall", start.elapsed().as_secs_f64());
    assert!(w.iter().all(|&e| e < 1e-9), "{w:?}");
}

/// Issue 21: a compression pulse of 20 particle spacings crosses
/// FE → DE → FE; reflected energy under 5 % of the incident, arrival times
/// within 3 % of each region's wave speed (references computed here).
#[test]
fn fede_wave_across_the_interface() {
    wave_case(Coupling::default());
}

/// The same pulse with eq 17 as written (`Coupling::Seed`), for comparison.
#[test]
fn fede_wave_seed_eq17() {
    wave_case(Coupling::Seed);
}

fn wave_case(coupling: Coupling) {
    let bar = WaveBar::seed002();
    assert!(bar.pulse_length > 10.0 * 2.0 * bar.radius);
    let start = Instant::now();
    let w = fede_wave(&bar, coupling).unwrap();
    let wall = start.elapsed().as_secs_f64();
    // Uniaxial strain (lateral motion restrained): the constrained modulus in FE, the
    // lattice's own axial modulus from its eq 4 springs in DE.
    let c_fe = constrained_wave_speed(&bar.material());
    let stiffness = BondStiffness::seed002(bar.young, bar.poisson, bar.radius).unwrap();
    let (mass, _) = sphere_mass_inertia(bar.density, bar.radius);
    let c_de = lattice_wave_speed(&stiffness, bar.radius, mass);
    let speeds = [c_fe, c_de, c_fe];
    let regions = bar.regions();
    // Travel time from X = 0 to x through the regions.
    let travel = |x: f64| -> f64 {
        (regions.iter().zip(&speeds))
            .map(|([a, b], c)| (x.min(*b) - a).max(0.0) / c)
            .sum()
    };
    let duration = bar.pulse_length / c_fe;
    eprintln!(
        "wave ({coupling:?}): c_FE = {c_fe:.3} m/s, c_DE = {c_de:.3} m/s, T = {duration:.4e} s, {} steps of {:.3e} s, {wall:.2} s wall",
        w.steps, w.dt
    );
    let (fe_de, all) = (w.reflected_fe_de / w.incident, w.reflected / w.incident);
    eprintln!(
        "energy: incident {:.4e} J; reflected at FE → DE {:.3} %, in all {:.3} %, transmitted {:.3} %; drift {:.2e} (at {:?} s)",
        w.incident,
        fe_de * 100.0,
        all * 100.0,
        w.transmitted / w.incident * 100.0,
        w.energy_drift,
        w.times
    );
    let mut worst: f64 = 0.0;
    for st in &w.stations {
        // The centroid of the input velocity is at T/2.
        let reference = 0.5 * duration + travel(st.x);
        let err = (st.arrival - reference) / (reference - 0.5 * duration);
        eprintln!(
            "station x = {:.4} mm (region {}): arrival {:.5e} s vs {:.5e} s ({:+.3} % of the travel time), peak {:.4} of V0",
            st.x * 1e3,
            st.region,
            st.arrival,
            reference,
            err * 100.0,
            st.peak / (bar.strain * c_fe)
        );
        worst = worst.max(err.abs());
    }
    for (k, speed) in speeds.iter().enumerate() {
        let pair: Vec<_> = w.stations.iter().filter(|s| s.region == k).collect();
        let (a, b) = (pair[0], pair[1]);
        let reference = (b.x - a.x) / speed;
        let err = (b.arrival - a.arrival) / reference - 1.0;
        eprintln!(
            "region {k}: {:.4} → {:.4} mm in {:.5e} s vs {:.5e} s ({:+.3} %)",
            a.x * 1e3,
            b.x * 1e3,
            b.arrival - a.arrival,
            reference,
            err * 100.0
        );
        assert!(err.abs() < 0.03, "region {k}: {err}");
    }
    assert!(worst < 0.03, "arrival from X = 0: {worst}");
    assert!(fe_de < 0.05 && all < 0.05, "{fe_de} {all}");
}

/// `mesh` as an ASCII MSH 4.1 file: one volume entity; node tags 1.. and
/// element tags 1.. in mesh order, but written in two node blocks and with
/// the elements in reverse, so the reader's sorting is exercised. Gmsh's
/// hexahedron node order equals seed 002 Table 1 (Gmsh reference manual,
/// "Node ordering"), so the connectivity is written as stored.
fn write_hex_msh(path: &std::path::Path, mesh: &HexMesh) {
    use std::fmt::Write as _;
    let (nn, ne) = (mesh.nodes.len(), mesh.hexes.len());
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s += "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n";
    let _ = writeln!(s, "$Nodes\n2 {nn} 1 {nn}");
    let half = nn / 2;
    for range in [half..nn, 0..half] {
        let _ = writeln!(s, "3 1 0 {}", range.len());
        for p in range.clone() {
            let _ = writeln!(s, "{}", p + 1);
        }
        for p in range {
            let x = mesh.nodes[p];
            let _ = writeln!(s, "{} {} {}", x[0], x[1], x[2]);
        }
    }
    let _ = writeln!(s, "$EndNodes\n$Elements\n1 {ne} 1 {ne}\n3 1 5 {ne}");
    for (e, h) in mesh.hexes.iter().enumerate().rev() {
        let tags: Vec<String> = h.iter().map(|&p| (p + 1).to_string()).collect();
        let _ = writeln!(s, "{} {}", e + 1, tags.join(" "));
    }
    s += "$EndElements\n";
    std::fs::write(path, s).unwrap();
}

#[test]
fn gmsh_hex8_cantilever_matches_hex_box() {
    // CI size: the seed's section on L = 10 mm, 1 mm cubes.
    let beam = Cantilever {
        length: 10e-3,
        ..Cantilever::seed002()
    };
    let mesh = hex_box([0.0; 3], [beam.length, beam.width, beam.height], [10, 4, 2]).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("beam.msh");
    write_hex_msh(&path, &mesh);
    let read = read_msh_hex8(&path).unwrap();
    assert_eq!(read.nodes, mesh.nodes);
    assert_eq!(read.hexes, mesh.hexes);
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    for e in 0..mesh.hexes.len() {
        let r0 = Hex8Reference::from_coords(&mesh.element_coords(e)).unwrap();
        let r1 = Hex8Reference::from_coords(&read.element_coords(e)).unwrap();
        let v = |m: &HexMesh| {
            let x = m.element_coords(e).map(Vector3::from);
            8.0 * hex8_jacobian(&x, &Vector3::zeros()).determinant()
        };
        assert!(rel(v(&read), v(&mesh)) < 1e-12, "element {e} volume");
        let (m0, m1) = (
            r0.lumped_masses(beam.density),
            r1.lumped_masses(beam.density),
        );
        for (a, b) in m1.iter().zip(&m0) {
            assert!(rel(*a, *b) < 1e-12, "element {e} lumped mass");
        }
    }
    let relax = Relaxation {
        tolerance: 1e-5,
        ..Relaxation::default()
    };
    let s0 = fe_cantilever(&beam, 1e-3, &relax).unwrap();
    let s1 = fe_cantilever_on(&beam, &read, &relax).unwrap();
    eprintln!(
        "Gmsh Hex8 beam: tip {:.6e} m vs hex_box {:.6e} m, {} steps",
        s1.tip, s0.tip, s1.steps
    );
    assert_eq!(s1.tip_x, s0.tip_x);
    assert!(rel(s1.tip, s0.tip) < 1e-12, "{} vs {}", s1.tip, s0.tip);
    assert_eq!(s1.profile.len(), s0.profile.len());
    for (a, b) in s1.profile.iter().zip(&s0.profile) {
        assert_eq!(a.0, b.0);
        assert!((a.1 - b.1).abs() <= 1e-12 * s0.tip, "{a:?} vs {b:?}");
    }
}
