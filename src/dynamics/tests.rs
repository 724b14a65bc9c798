//! [`ExplicitDomain`] on one rank (a one-process communicator): the
//! physics the serial solver's tests checked (seed 004 sec 3.2 free
//! expansion, eq 38 fixed heated cube, free fall, momentum and energy of a
//! free vibration, velocity boundary conditions, the step limit) and the
//! three jobs of the domain: the substep, the force order, the candidates.

use std::path::Path;

use mpi::topology::SimpleCommunicator;
use nalgebra::{Matrix3, Vector3};

use super::{ExplicitDomain, SavedMotion};
use crate::mechanics::explicit::{critical_dt, internal_forces, mesh_elements, ThermalLoad};
use crate::mechanics::frequency::body_max_frequency;
use crate::mechanics::ElasticMaterial;
use crate::model::Model;
use crate::parallel::Part;
use crate::testutil::on_one_rank;

/// Seed 004 Table 1 (E, ν); density not in the table (concrete, 2400 kg/m³).
fn concrete(alpha: f64) -> ElasticMaterial {
    ElasticMaterial {
        young: 20e9,
        poisson: 0.2,
        density: 2400.0,
        expansion: alpha,
        viscosity: 0.0,
    }
}

/// The model of boxes `(origin, size)` of concrete with expansion `alpha`,
/// mesh size `h`, and `mechanics` the body of the `[mechanics]` table.
fn boxes(alpha: f64, h: f64, boxes: &[([f64; 3], [f64; 3])], mechanics: &str) -> Model {
    let mut text = format!(
        "[time]\ndt = 1e-3\nsteps = 1\n\n[[materials]]\nname = \"concrete\"\n\
         density = 2400.0\nyoung = 20e9\npoisson = 0.2\nexpansion = {alpha:e}\n"
    );
    for (i, (o, s)) in boxes.iter().enumerate() {
        text += &format!(
            "\n[[bodies]]\nname = \"b{i}\"\nmaterial = \"concrete\"\nmesh = {{ kind = \"box\", \
             origin = [{:e}, {:e}, {:e}], size = [{:e}, {:e}, {:e}], element_size = {h:e} }}\n",
            o[0], o[1], o[2], s[0], s[1], s[2]
        );
    }
    text += &format!("\n[mechanics]\n{mechanics}\n");
    let sc = crate::scenario::parse_str(&text, Path::new("dynamics-test.toml"), &[]).unwrap();
    Model::from_scenario(&sc).unwrap()
}

/// The unit cube of concrete.
fn cube(alpha: f64, h: f64, mechanics: &str) -> Model {
    boxes(alpha, h, &[([0.0; 3], [1.0; 3])], mechanics)
}

/// Every body of the model made on this process.
fn whole(model: &Model) -> crate::model::WholeMesh {
    model.whole_mesh().unwrap()
}

/// Every element on rank 0 of 1.
fn one_rank_layout(model: &Model) -> Part {
    let w = whole(model);
    Part::from_whole(&w, &vec![0; w.mesh.tets.len()], 0, 1)
}

fn domain(comm: &SimpleCommunicator, model: &Model, part: &Part) -> ExplicitDomain {
    ExplicitDomain::new(comm, model, part, model.dt).unwrap().0
}

/// Velocity boundary condition `value` on component `d` of node set `set`.
fn set_bc(model: &Model, part: &mut Part, set: &str, d: usize, value: Option<f64>) {
    for &n in &whole(model).mesh.node_sets[set] {
        let l = part.local_node(n).unwrap() as usize;
        part.bc.velocity[l][d] = value;
    }
}

/// Uniform temperature change `delta` over the reference temperature.
fn heat(comm: &SimpleCommunicator, model: &Model, dom: &mut ExplicitDomain, delta: f64) {
    let t = model.bodies[0].reference_temperature + delta;
    dom.set_temperatures(comm, &vec![t; dom.n_owned], None);
}

fn max_abs(m: &Matrix3<f64>) -> f64 {
    m.iter().fold(0.0, |a, v| a.max(v.abs()))
}

fn max_stress(dom: &ExplicitDomain) -> f64 {
    dom.stress.iter().map(max_abs).fold(0.0, f64::max)
}

/// Sum of the current element volumes (m³).
fn current_volume(dom: &ExplicitDomain) -> f64 {
    dom.elements
        .iter()
        .map(|el| {
            let x = el.nodes.map(|i| dom.x[i as usize]);
            el.reference.deformation_gradient(&x).determinant() * el.reference.volume0
        })
        .sum()
}

fn total_mass(dom: &ExplicitDomain) -> f64 {
    dom.mass[..dom.n_owned].iter().sum()
}

fn momentum(dom: &ExplicitDomain) -> Vector3<f64> {
    (0..dom.n_owned).map(|i| dom.mass[i] * dom.v[i]).sum()
}

/// Seed 004 sec 3.2: a free 1 m cube heated uniformly by 100 K with
/// α = 1e-5 (seeds README) reaches (1 + α ΔT)³ = 1.003003 m³ without
/// stress. Rigid motion is removed by the three symmetry planes x = 0,
/// y = 0, z = 0 (normal velocity fixed), which do not restrain the
/// expansion. Mass damping c = 2 ω_1 settles the dynamic response.
fn heated_free_cube(comm: &SimpleCommunicator, h: f64) -> (f64, f64, u64) {
    let mat = concrete(1e-5);
    let (mu, _) = mat.lame();
    // Lowest mode of the cube on three symmetry planes is a shear mode:
    // ω_1 ≈ π c_s / (2 L) with c_s = sqrt(μ/ρ).
    let w1 = std::f64::consts::PI * (mu / mat.density).sqrt() / 2.0;
    let model = cube(1e-5, h, &format!("damping = {:e}", 2.0 * w1));
    let mut part = one_rank_layout(&model);
    for (d, side) in ["b0.xmin", "b0.ymin", "b0.zmin"].iter().enumerate() {
        set_bc(&model, &mut part, side, d, Some(0.0));
    }
    let mut dom = domain(comm, &model, &part);
    heat(comm, &model, &mut dom, 100.0);
    // 30/ω_1 of settling: the slowest (critically damped) modes decay as exp(−ω_1 t).
    let steps = (30.0 / w1 / dom.dt).ceil() as u64;
    dom.advance(comm, steps).unwrap();
    (current_volume(&dom), max_stress(&dom), steps)
}

#[test]
fn free_heated_cube_expands_without_stress() {
    on_one_rank(|comm| {
        let alpha = 1e-5;
        let want = (1.0 + alpha * 100.0f64).powi(3);
        assert!((want - 1.003003).abs() < 1e-6);
        let e_alpha_dt = 20e9 * alpha * 100.0;
        for h in [1.0, 0.25] {
            let (vol, smax, steps) = heated_free_cube(comm, h);
            // Volume within 1e-4 relative; stress below 1e-3 of E α ΔT.
            assert!(
                (vol / want - 1.0).abs() < 1e-4,
                "h = {h}: volume {vol} vs {want} after {steps} steps"
            );
            assert!(
                smax < 1e-3 * e_alpha_dt,
                "h = {h}: max |sigma| = {smax} Pa after {steps} steps"
            );
        }
    });
}

/// A fixed, heated cube: every element carries the closed-form
/// compression of seed 004 eq 38 (see the element tests).
#[test]
fn fixed_heated_cube_matches_eq_38() {
    on_one_rank(|comm| {
        let mat = concrete(1e-6);
        let (mu, lambda) = mat.lame();
        let model = cube(1e-6, 1.0, "");
        let mut part = one_rank_layout(&model);
        part.bc
            .velocity
            .iter_mut()
            .for_each(|b| *b = [Some(0.0); 3]);
        let mut dom = domain(comm, &model, &part);
        heat(comm, &model, &mut dom, 100.0);
        dom.advance(comm, 5).unwrap();
        let u: f64 = 1.0 + 1e-6 * 100.0;
        let j_e = u.powi(-3);
        let want = mu / j_e * (u.powi(-2) - 1.0) + lambda / j_e * j_e.ln();
        assert_eq!(dom.stress.len(), 6);
        for st in &dom.stress {
            // Round-off tolerance 1e-10 relative; 3.332 MPa within 0.1 %.
            assert!(max_abs(&(st - Matrix3::identity() * want)) < 1e-10 * want.abs());
            assert!((st[(1, 1)].abs() / 3.332e6 - 1.0).abs() < 1e-3);
        }
        assert!((current_volume(&dom) - 1.0).abs() < 1e-14);
    });
}

/// The step is safety × the exact limit 2/ω_max of the small body, which
/// is at least the element bound L/c (Kuhn tets of edge 0.5: L = 0.5/√6);
/// a given step above the limit is an error, one at the limit is taken.
#[test]
fn time_step_above_the_limit_is_an_error() {
    on_one_rank(|comm| {
        let mat = concrete(1e-5);
        let mut model = cube(1e-5, 0.5, "substeps = 1");
        let part = one_rank_layout(&model);
        let safety = model.mechanics.as_ref().unwrap().safety;
        let dom = domain(comm, &model, &part);
        let crit = dom.dt / safety;
        let w = whole(&model);
        let x: Vec<Vector3<f64>> = w.mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let omega = body_max_frequency(&x, &w.mesh.tets, &vec![mat; w.mesh.tets.len()]).unwrap();
        // Round-off tolerance 1e-12 relative.
        assert!(
            (crit * omega / 2.0 - 1.0).abs() < 1e-12,
            "{crit} vs {}",
            2.0 / omega
        );
        let element = critical_dt(&w.mesh, &[mat]).unwrap().dt;
        let want = 0.5 / 6f64.sqrt() / mat.p_wave_speed();
        assert!((element / want - 1.0).abs() < 1e-12);
        assert!(
            crit >= element && crit <= 2.0 * element,
            "{crit} vs {element}"
        );
        model.mechanics.as_mut().unwrap().dt = Some(1.01 * crit);
        match ExplicitDomain::new(comm, &model, &part, model.dt) {
            Err(e) => assert!(e.to_string().contains("exceeds the critical"), "{e}"),
            Ok(_) => panic!("a step above the limit was accepted"),
        }
        model.mechanics.as_mut().unwrap().dt = Some(crit);
        let (dom, substeps) = ExplicitDomain::new(comm, &model, &part, model.dt).unwrap();
        assert_eq!((dom.dt, substeps), (crit, 1));
    });
}

/// Free fall: internal forces cancel, so the centre of mass follows
/// v = g t exactly (round-off, 1e-12 relative) and the body stays unstressed.
#[test]
fn free_fall_follows_gravity() {
    on_one_rank(|comm| {
        let model = boxes(
            0.0,
            0.25,
            &[([0.0; 3], [1.0, 0.5, 0.5])],
            "gravity = [0.0, 0.0, -9.81]",
        );
        let g = Vector3::new(0.0, 0.0, -9.81);
        let part = one_rank_layout(&model);
        let mut dom = domain(comm, &model, &part);
        assert!((total_mass(&dom) - 2400.0 * 0.25).abs() < 1e-9);
        let n = 200;
        dom.advance(comm, n).unwrap();
        let t = n as f64 * dom.dt;
        let m = total_mass(&dom);
        assert!((momentum(&dom) / m - g * t).norm() < 1e-12 * g.norm() * t);
        // Every node has the same velocity: no deformation (relative 1e-9).
        for v in &dom.v[..dom.n_owned] {
            assert!((v - g * t).norm() < 1e-9 * g.norm() * t);
        }
        let smax = max_stress(&dom);
        assert!(smax < 1e-3, "free fall stress {smax} Pa");
    });
}

/// Undamped free vibration (an initial deforming and rotating velocity
/// field, no constraints): linear momentum Σ m v and angular momentum
/// Σ m x × v (leapfrog-exact invariants) stay at their initial values
/// (round-off, 1e-12 relative) and the leapfrog energy ½ Σ m v^{n−½}·v^{n+½} + W(x^n),
/// exactly invariant for a linear system, is conserved to 1e-6 (the
/// strains, ~1e-7, make the finite-strain terms negligible).
#[test]
fn undamped_vibration_conserves_momentum_and_energy() {
    on_one_rank(|comm| {
        let model = cube(0.0, 0.5, "");
        let part = one_rank_layout(&model);
        let mut dom = domain(comm, &model, &part);
        let c = Vector3::new(0.3, 0.5, 0.4);
        let omega = Vector3::new(0.0, 0.0, 0.001);
        let w = whole(&model);
        let velocities: Vec<[f64; 3]> = w
            .mesh
            .nodes
            .iter()
            .map(|x| {
                let r = Vector3::from(*x) - c;
                (Vector3::new(0.002 * r.x, -0.001 * r.y * r.y, 0.003 * r.z * r.x) + omega.cross(&r))
                    .into()
            })
            .collect();
        let saved = SavedMotion {
            positions: &w.mesh.nodes,
            velocities: &velocities,
            velocities_prev: None,
            dissipated: 0.0,
            dissipated_per_rank: None,
            external_work_per_rank: None,
        };
        dom.restore(comm, saved).unwrap();
        let angular = |dom: &ExplicitDomain| -> Vector3<f64> {
            (0..dom.n_owned)
                .map(|i| dom.mass[i] * dom.x[i].cross(&dom.v[i]))
                .sum()
        };
        let p0 = momentum(&dom);
        let l0 = angular(&dom);
        let mut e0 = None;
        let mut worst: f64 = 0.0;
        let mut strain_max: f64 = 0.0;
        for _ in 0..2000 {
            dom.advance(comm, 1).unwrap();
            let kinetic = 0.5
                * (0..dom.n_owned)
                    .map(|i| dom.mass[i] * dom.v_prev[i].dot(&dom.v[i]))
                    .sum::<f64>();
            let strain = dom.state(comm).strain;
            let total = kinetic + strain;
            strain_max = strain_max.max(strain);
            let e0 = *e0.get_or_insert(total);
            worst = worst.max((total / e0 - 1.0).abs());
        }
        let pscale = total_mass(&dom) * 0.01;
        assert!((momentum(&dom) - p0).norm() < 1e-12 * pscale);
        // Lever arm scale 1 m.
        assert!(
            (angular(&dom) - l0).norm() < 1e-12 * pscale,
            "{} vs {l0}",
            angular(&dom)
        );
        // The vibration really exchanges energy (strain energy reaches > 10 % of the total).
        assert!(strain_max > 0.1 * e0.unwrap(), "{strain_max} vs {e0:?}");
        assert!(worst < 1e-6, "energy drift {worst}");
    });
}

#[test]
fn velocity_boundary_conditions_are_imposed() {
    on_one_rank(|comm| {
        let model = cube(0.0, 0.5, "gravity = [0.0, 0.0, -9.81]");
        let mut part = one_rank_layout(&model);
        for d in 0..3 {
            set_bc(&model, &mut part, "b0.zmin", d, Some(0.0));
        }
        set_bc(&model, &mut part, "b0.zmax", 0, Some(0.1));
        let mut dom = domain(comm, &model, &part);
        let n = 50;
        dom.advance(comm, n).unwrap();
        let t = n as f64 * dom.dt;
        let u = dom.displacement();
        let row = |node: u32| {
            let i = part.owned_gids().iter().position(|&o| o == node).unwrap();
            Vector3::new(u[3 * i], u[3 * i + 1], u[3 * i + 2])
        };
        let w = whole(&model);
        for &i in &w.mesh.node_sets["b0.zmin"] {
            assert_eq!(row(i), Vector3::zeros());
        }
        for &i in &w.mesh.node_sets["b0.zmax"] {
            // x displacement = 0.1 t (round-off of x += Δt u, 1e-9 relative).
            assert!((row(i).x - 0.1 * t).abs() < 1e-9 * (0.1 * t));
        }
    });
}

/// The substep is the central-difference rule: a free body under gravity
/// (six tets) has v^{k−½} = k Δt g and x^k − x^0 = Δt² g k(k+1)/2 after k
/// substeps (not numbered in the seeds; round-off).
#[test]
fn substep_moves_a_free_body_by_central_differences() {
    on_one_rank(|comm| {
        let model = cube(0.0, 1.0, "gravity = [0.0, 0.0, -9.81]");
        let g = Vector3::new(0.0, 0.0, -9.81);
        let part = one_rank_layout(&model);
        let mut dom = domain(comm, &model, &part);
        assert_eq!(dom.num_elements(), 6);
        let dt = dom.dt;
        let x0 = dom.x.clone();
        for k in 1..=4u32 {
            dom.advance(comm, 1).unwrap();
            let k = f64::from(k);
            let (v_want, u_want) = (k * dt * g, dt * dt * g * k * (k + 1.0) / 2.0);
            let no = dom.n_owned;
            for ((x, v), x0) in dom.x[..no].iter().zip(&dom.v[..no]).zip(&x0) {
                assert!((v - v_want).norm() < 1e-12 * v_want.norm());
                // Round-off of k additions to coordinates of order 1 m.
                assert!((x - x0 - u_want).norm() < 1e-14 * k);
            }
        }
    });
}

/// The force on every node is summed in global element order: it equals,
/// bitwise, the serial sum over the elements in id order, whatever order
/// the domain holds its elements in.
#[test]
fn force_sum_is_the_serial_sum_in_any_element_order() {
    on_one_rank(|comm| {
        let model = boxes(0.0, 0.25, &[([0.0; 3], [1.0, 0.5, 0.5])], "");
        let part = one_rank_layout(&model);
        let mut dom = domain(comm, &model, &part);
        // A deformed, moving state.
        let positions: Vec<[f64; 3]> = whole(&model)
            .mesh
            .nodes
            .iter()
            .map(|p| {
                [
                    p[0] + 0.01 * p[1] * p[2],
                    p[1] - 0.02 * p[0],
                    p[2] + 0.015 * p[0] * p[1],
                ]
            })
            .collect();
        let velocities: Vec<[f64; 3]> = positions.iter().map(|p| [p[2], 0.0, -p[0]]).collect();
        let saved = SavedMotion {
            positions: &positions,
            velocities: &velocities,
            velocities_prev: None,
            dissipated: 0.0,
            dissipated_per_rank: None,
            external_work_per_rank: None,
        };
        dom.restore(comm, saved).unwrap();
        let (x, v) = (dom.x.clone(), dom.v.clone());
        dom.substep(comm).unwrap();
        let first = dom.f[..dom.n_owned].to_vec();
        // Serial: every element, in id order, added into one nodal array.
        let elements = mesh_elements(&whole(&model).mesh, 1).unwrap();
        let xs: Vec<Vector3<f64>> = positions.iter().map(|p| Vector3::from(*p)).collect();
        let vs: Vec<Vector3<f64>> = velocities.iter().map(|p| Vector3::from(*p)).collect();
        let mut serial = vec![Vector3::zeros(); xs.len()];
        let material = model.materials[0].elastic.unwrap();
        internal_forces(
            &elements,
            &[material],
            &xs,
            &vs,
            ThermalLoad::none(),
            &mut serial,
            None,
        )
        .unwrap();
        assert!(serial.iter().any(|f| f.norm() > 0.0));
        for (l, f) in first.iter().enumerate() {
            assert_eq!(*f, serial[dom.node_gid[l] as usize], "node {l}");
        }
        // The same state with the elements held in reverse order.
        dom.elements.reverse();
        dom.elem_ids.reverse();
        dom.elem_tref.reverse();
        dom.elem_dt.reverse();
        dom.elem_rate.reverse();
        dom.build_assembly(comm);
        dom.x.copy_from_slice(&x);
        dom.v.copy_from_slice(&v);
        dom.substep(comm).unwrap();
        assert_eq!(dom.f[..dom.n_owned], first[..]);
    });
}

/// Broad phase: two bodies whose facing boundary tets are within the
/// search margin make candidate pairs (found once, from the lower body),
/// not in contact; farther apart than the margin they make none.
#[test]
fn candidates_are_the_pairs_within_the_margin() {
    on_one_rank(|comm| {
        let contact = "[mechanics.contact]\npenalty = 1e9\nmargin = 0.05";
        for (gap, near) in [(0.02, true), (0.2, false)] {
            let model = boxes(
                0.0,
                1.0,
                &[([0.0; 3], [1.0; 3]), ([1.0 + gap, 0.0, 0.0], [1.0; 3])],
                contact,
            );
            let part = one_rank_layout(&model);
            let mut dom = domain(comm, &model, &part);
            assert_eq!(dom.margin, 0.05);
            assert_eq!(dom.candidates.is_empty(), !near, "gap {gap}");
            for c in &dom.candidates {
                assert_eq!((c.body_a, c.body_b), (0, 1));
                for (e, b) in [(c.a, 0), (c.b, 1)] {
                    assert_eq!(whole(&model).mesh.body[e as usize], b);
                    assert!(dom.pair_info.iter().any(|t| t.gid == e && t.mask != 0));
                }
            }
            let mut keys: Vec<(u32, u32)> = dom.candidates.iter().map(|c| (c.a, c.b)).collect();
            keys.sort_unstable();
            keys.dedup();
            assert_eq!(keys.len(), dom.candidates.len());
            dom.advance(comm, 1).unwrap();
            let state = dom.state(comm);
            assert_eq!(state.candidate_pairs, dom.candidates.len() as u64);
            assert_eq!(state.active_pairs, 0);
        }
    });
}
