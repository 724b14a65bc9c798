//! Free DE spheres (issue 21, "Beyond the papers"), the serial kernel
//! `mechanics::free_spheres` against references computed here: Hertz's
//! static overlap of a sphere resting on the top face of a Tet4 block, and
//! the pipe-network heat exchange of two touching spheres and of a sphere
//! on a Tet4 face.

use std::f64::consts::PI;

use fdem::mechanics::free_spheres::{
    Faces, FreeSpheres, NodeSide, SphereContact, SphereKind, SphereStep,
};
use fdem::mesh::generate::box_mesh;
use fdem::validation::pipe_network::PipeNetwork;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

const STEEL: SphereKind = SphereKind {
    radius: 0.01,
    density: 7800.0,
    young: 2e11,
    poisson: 0.3,
    conductivity: 50.0,
    specific_heat: 500.0,
};
/// The block: concrete-like.
const BLOCK: (f64, f64) = (3e10, 0.2);

/// The top of a 0.1 × 0.1 × 0.02 m Tet4 block (element size 0.02) as the
/// faces the spheres meet: its boundary triangles, nodes held.
fn block() -> (Faces, Vec<V3>) {
    let m = box_mesh([0.0; 3], [0.1, 0.1, 0.02], 0.02).unwrap();
    let faces = Faces {
        nodes: m.boundary_faces().iter().map(|f| f.nodes).collect(),
        body: vec![0; m.boundary_faces().len()],
        elastic: vec![BLOCK],
    };
    (faces, m.nodes.iter().map(|&p| V3::from(p)).collect())
}

/// One step of `s` against `faces`, over nodes held still at `nodes`
/// (temperatures `t`), adding to their `force` and `heat`.
fn step_held(
    s: &mut FreeSpheres,
    dt: f64,
    faces: &Faces,
    nodes: &[V3],
    t: Option<&[f64]>,
    force: &mut [V3],
    heat: &mut [f64],
) -> SphereStep {
    let still = vec![V3::zeros(); nodes.len()];
    let side = NodeSide {
        x: nodes,
        v: &still,
        temperature: t,
        force,
        heat,
    };
    s.step(dt, faces, side).unwrap()
}

/// A sphere dropped from touching the block's top at (x, y) settles; its
/// overlap and the force the block's nodes take.
fn settle(x: f64, y: f64) -> (f64, V3, usize) {
    let (faces, nodes) = block();
    let contact = SphereContact {
        damping: 0.3,
        friction: 0.5,
        resistance: 0.0,
    };
    let mut s = FreeSpheres::new(
        STEEL,
        contact,
        vec![V3::new(x, y, 0.02 + STEEL.radius)],
        vec![],
    );
    s.gravity = V3::new(0.0, 0.0, -9.81);
    s.damping = 200.0;
    let (m, _) = STEEL.mass_inertia();
    let e_star = fdem::contact::sphere::effective_modulus(2e11, 0.3, BLOCK.0, BLOCK.1);
    let delta = fdem::contact::sphere::hertz_static_overlap(m * 9.81, e_star, STEEL.radius);
    let dt = s.stable_dt(&faces, 4.0 * delta);
    let (mut force, mut heat) = (vec![V3::zeros(); nodes.len()], vec![0.0; nodes.len()]);
    let mut last = Default::default();
    for _ in 0..20_000 {
        force.iter_mut().for_each(|f| *f = V3::zeros());
        last = step_held(&mut s, dt, &faces, &nodes, None, &mut force, &mut heat);
    }
    assert!(s.v[0].norm() < 1e-9, "still moving: {:?}", s.v[0]);
    (
        0.02 + STEEL.radius - s.x[0].z,
        force.iter().sum(),
        last.faces,
    )
}

#[test]
fn a_sphere_resting_on_a_tet4_block_has_hertz_static_overlap() {
    let (m, _) = STEEL.mass_inertia();
    // Hertz: δ = (3 m g / (4 E* √R))^{2/3}, E* of steel on the block.
    let e_star = 1.0 / ((1.0 - 0.09) / 2e11 + (1.0 - 0.04) / BLOCK.0);
    let want = (3.0 * m * 9.81 / (4.0 * e_star * STEEL.radius.sqrt())).powf(2.0 / 3.0);
    // Over a triangle's inside, over an edge of the top's tessellation
    // (the diagonal x = y of a cell) and over a node, where six triangles
    // touch the sphere and one contact must count.
    for (x, y) in [(0.047, 0.031), (0.05, 0.05), (0.04, 0.06)] {
        let (delta, f, touches) = settle(x, y);
        let err = (delta - want).abs() / want;
        println!("at ({x}, {y}): δ = {delta:.6e} m, Hertz {want:.6e} m, error {err:.2e}");
        assert!(err < 0.01, "({x}, {y}): δ = {delta} against {want}");
        assert_eq!(touches, 1, "({x}, {y}): one contact on a flat face");
        // The nodes carry the sphere's weight, straight down.
        assert!((f.z + m * 9.81).abs() < 1e-6 * m * 9.81, "{f:?}");
        assert!(f.x.abs() + f.y.abs() < 1e-9 * m * 9.81, "{f:?}");
    }
}

#[test]
fn two_touching_spheres_exchange_heat_as_the_pipe_network() {
    let contact = SphereContact {
        damping: 0.0,
        friction: 0.0,
        resistance: 1e-5,
    };
    let r = STEEL.radius;
    let overlap = 1e-5;
    let x = vec![V3::zeros(), V3::new(2.0 * r - overlap, 0.0, 0.0)];
    let mut s = FreeSpheres::new(STEEL, contact, x, vec![0.0, 1.0]);
    s.fixed = vec![true, true];
    // The pipe network (seed 000 eqs 33–37) of two spheres, by hand: contact
    // radius a = √(R* δ) with R* = r/2, particle resistances 1/(4 k a)
    // each, contact resistance R_c/(π a²), capacities ρ c (4/3) π r³.
    let a = (0.5 * r * overlap).sqrt();
    let r_ab = 2.0 / (4.0 * 50.0 * a) + 1e-5 / (PI * a * a);
    let cap = 7800.0 * 500.0 * 4.0 / 3.0 * PI * r.powi(3);
    let net = PipeNetwork {
        r_ab,
        cap_a: cap,
        cap_b: cap,
        alpha_a: 0.0,
        alpha_b: 0.0,
        res_a: 0.0,
        res_b: 0.0,
    };
    let tau = net.time_constant();
    let steps = 2000;
    let dt = tau / steps as f64;
    assert!(dt < s.stable_heat_dt(1, overlap));
    let faces = Faces::default();
    for _ in 0..steps {
        step_held(&mut s, dt, &faces, &[], None, &mut [], &mut []);
    }
    let (ea, eb) = net.exact(0.0, 1.0, tau);
    let (got, want) = (s.t[1] - s.t[0], eb - ea);
    // Forward Euler (eq 36) at τ/dt = 2000 errs by about (τ/dt) (dt/τ)²/2
    // = 2.5e-4 relative: 1e-3 is that with room.
    println!("ΔT(τ) = {got:.6} against the pipe network's {want:.6}");
    assert!((got - want).abs() < 1e-3 * want, "{got} {want}");
    assert!((s.t[0] + s.t[1] - 1.0).abs() < 1e-12, "heat kept");
    assert_eq!(s.x[1].x, 2.0 * r - overlap, "held spheres stay");
}

#[test]
fn a_sphere_on_a_hot_tet4_face_heats_with_one_time_constant() {
    let (faces, nodes) = block();
    let contact = SphereContact {
        damping: 0.0,
        friction: 0.0,
        resistance: 1e-5,
    };
    let r = STEEL.radius;
    let overlap = 2e-6;
    let x = vec![V3::new(0.047, 0.031, 0.02 + r - overlap)];
    let mut s = FreeSpheres::new(STEEL, contact, x, vec![20.0]);
    s.fixed = vec![true];
    let t_nodes = vec![100.0; nodes.len()];
    // Sphere against a face: R = 1/(4 k a) + R_c/(π a²) with a = √(r δ); the
    // face's side is the block's elements. T(t) = 100 − 80 e^{−t/(R C)}.
    let a = (r * overlap).sqrt();
    let res = 1.0 / (4.0 * 50.0 * a) + 1e-5 / (PI * a * a);
    let cap = 7800.0 * 500.0 * 4.0 / 3.0 * PI * r.powi(3);
    let tau = res * cap;
    let steps = 2000;
    let dt = tau / steps as f64;
    let (mut force, mut heat) = (vec![V3::zeros(); nodes.len()], vec![0.0; nodes.len()]);
    let mut into_nodes = 0.0;
    let mut t_before = 20.0;
    for _ in 0..steps {
        heat.iter_mut().for_each(|q| *q = 0.0);
        step_held(
            &mut s,
            dt,
            &faces,
            &nodes,
            Some(&t_nodes),
            &mut force,
            &mut heat,
        );
        // What the nodes give is what the sphere takes.
        let q: f64 = heat.iter().sum();
        assert!((q * dt + cap * (s.t[0] - t_before)).abs() < 1e-9 * cap * 80.0);
        t_before = s.t[0];
        into_nodes += q * dt;
    }
    let want = 100.0 - 80.0 * (-1.0f64).exp();
    println!("T(τ) = {:.6} against {want:.6}", s.t[0]);
    assert!((s.t[0] - want).abs() < 1e-3 * 80.0, "{} {want}", s.t[0]);
    assert!((into_nodes + cap * (s.t[0] - 20.0)).abs() < 1e-9 * cap * 80.0);
}

#[test]
fn spheres_among_themselves_conserve_momentum_and_stack_in_order() {
    // A column of three spheres falling on each other with no faces: the
    // pair forces are equal and opposite, so without gravity the momentum
    // stays; a repeat of the run is bitwise the same.
    let contact = SphereContact {
        damping: 0.2,
        friction: 0.4,
        resistance: 0.0,
    };
    let r = STEEL.radius;
    let run = || {
        let x = vec![
            V3::new(0.0, 0.0, 0.0),
            V3::new(0.3 * r, 0.1 * r, 2.0 * r + 1e-4),
            V3::new(-0.2 * r, 0.0, 4.0 * r + 3e-4),
        ];
        let mut s = FreeSpheres::new(STEEL, contact, x, vec![]);
        s.v = vec![V3::new(0.0, 0.0, 1.0), V3::zeros(), V3::new(0.1, 0.0, -1.0)];
        let dt = s.stable_dt(&Faces::default(), 1e-4);
        let mut touched = 0;
        for _ in 0..5000 {
            let st = step_held(&mut s, dt, &Faces::default(), &[], None, &mut [], &mut []);
            touched = touched.max(st.pairs);
        }
        (s.x, s.v, s.w, touched)
    };
    let (x, v, w, touched) = run();
    assert!(touched >= 1, "the spheres met");
    let p: V3 = v.iter().sum();
    assert!((p - V3::new(0.1, 0.0, 0.0)).norm() < 1e-12, "{p:?}");
    assert!(w.iter().any(|w| w.norm() > 0.0), "friction spun them");
    let again = run();
    assert_eq!((x, v, w), (again.0, again.1, again.2));
}

#[test]
fn a_sphere_on_a_deformable_tet4_block_loads_its_nodes_with_its_weight() {
    use fdem::mechanics::explicit::{
        element_forces, lumped_masses, mesh_elements, update_nodes_damped, NodeUpdate,
    };
    use fdem::mechanics::{ElasticMaterial, ThermalLoad};
    // A soft block (E = 300 MPa) fixed at its bottom, a steel sphere on
    // its top: the Tet4 explicit mechanics and the sphere advanced
    // together, the contact force on the top triangles' nodes by the
    // contact point's barycentric weights. At rest the overlap is Hertz's
    // with E* of steel on the block, and the bottom holds both weights.
    let (young, nu, rho) = (3e8, 0.2, 2400.0);
    let mesh = box_mesh([0.0; 3], [0.1, 0.1, 0.02], 0.02).unwrap();
    let mat = [ElasticMaterial::elastic(young, nu, rho)];
    let elements = mesh_elements(&mesh, 1).unwrap();
    let mass = lumped_masses(&elements, &mat, mesh.nodes.len()).unwrap();
    let faces = Faces {
        nodes: mesh.boundary_faces().iter().map(|f| f.nodes).collect(),
        body: vec![0; mesh.boundary_faces().len()],
        elastic: vec![(young, nu)],
    };
    let n = mesh.nodes.len();
    let mut bc = vec![[None; 3]; n];
    for &i in &mesh.node_sets["zmin"] {
        bc[i as usize] = [Some(0.0); 3];
    }
    let mut x: Vec<V3> = mesh.nodes.iter().map(|&p| V3::from(p)).collect();
    let mut v = vec![V3::zeros(); n];
    let contact = SphereContact {
        damping: 0.3,
        friction: 0.5,
        resistance: 0.0,
    };
    let r = STEEL.radius;
    let mut s = FreeSpheres::new(
        STEEL,
        contact,
        vec![V3::new(0.047, 0.031, 0.02 + r)],
        vec![],
    );
    let g = V3::new(0.0, 0.0, -9.81);
    s.gravity = g;
    s.damping = 300.0;
    let (m, _) = STEEL.mass_inertia();
    let c_p = mat[0].p_wave_speed();
    let dt = (0.05 * 0.02 / c_p).min(s.stable_dt(&faces, 1e-5));
    let p = NodeUpdate {
        dt,
        gravity: g,
        mass_damping: 300.0,
    };
    let mut per_elem = vec![[V3::zeros(); 4]; elements.len()];
    let (mut f, mut heat) = (vec![V3::zeros(); n], vec![0.0; n]);
    for _ in 0..40_000 {
        f.iter_mut().for_each(|a| *a = V3::zeros());
        element_forces(
            &elements,
            &mat,
            &x,
            &v,
            ThermalLoad::none(),
            &mut per_elem,
            None,
        )
        .unwrap();
        for (el, fe) in elements.iter().zip(&per_elem) {
            for k in 0..4 {
                f[el.nodes[k] as usize] += fe[k];
            }
        }
        s.step(
            dt,
            &faces,
            NodeSide {
                x: &x,
                v: &v,
                temperature: None,
                force: &mut f,
                heat: &mut heat,
            },
        )
        .unwrap();
        update_nodes_damped(&p, |_| 300.0, &mass, &f, None, &bc, &mut x, &mut v).unwrap();
    }
    assert!(s.v[0].norm() < 1e-8, "still moving: {:?}", s.v[0]);
    // The overlap against the deformed top: the sphere's centre less the
    // height of the top triangle under it (the deepest face contact).
    let touch = (0..faces.nodes.len())
        .filter_map(|k| {
            let t = faces.nodes[k].map(|i| x[i as usize]);
            fdem::contact::sphere::sphere_triangle(&s.x[0], r, &t)
        })
        .map(|t| t.depth)
        .fold(0.0, f64::max);
    let e_star = 1.0 / ((1.0 - 0.09) / 2e11 + (1.0 - nu * nu) / young);
    let want = (3.0 * m * 9.81 / (4.0 * e_star * r.sqrt())).powf(2.0 / 3.0);
    let err = (touch - want).abs() / want;
    println!("deformable block: δ = {touch:.6e} m, Hertz {want:.6e} m, error {err:.2e}");
    assert!(err < 0.01, "δ = {touch} against {want}");
    // The fixed bottom nodes hold the block's and the sphere's weight:
    // their reaction is −(f + m_i g) summed.
    let reaction: f64 = mesh.node_sets["zmin"]
        .iter()
        .map(|&i| -(f[i as usize].z + mass[i as usize] * g.z))
        .sum();
    let total = (mass.iter().sum::<f64>() + m) * 9.81;
    println!("bottom reaction {reaction:.6} N, weights {total:.6} N");
    assert!(
        (reaction - total).abs() < 1e-3 * total,
        "{reaction} {total}"
    );
}

/// A steel sphere on the rigid block's top under gravity tilted by
/// `theta` about y (the block stands still; the slope is in the gravity),
/// starting at rest at its static overlap. Returns the centre's
/// displacement along x after `time` and the spin about y.
fn down_the_slope(theta: f64, friction: f64, time: f64) -> (f64, f64) {
    let (faces, nodes) = block();
    let contact = SphereContact {
        damping: 0.3,
        friction,
        resistance: 0.0,
    };
    let (m, _) = STEEL.mass_inertia();
    let g = 9.81;
    let e_star = fdem::contact::sphere::effective_modulus(2e11, 0.3, BLOCK.0, BLOCK.1);
    let delta =
        fdem::contact::sphere::hertz_static_overlap(m * g * theta.cos(), e_star, STEEL.radius);
    let x0 = V3::new(0.02, 0.05, 0.02 + STEEL.radius - delta);
    let mut s = FreeSpheres::new(STEEL, contact, vec![x0], vec![]);
    s.gravity = V3::new(g * theta.sin(), 0.0, -g * theta.cos());
    let dt = s.stable_dt(&faces, 4.0 * delta);
    let steps = (time / dt).round() as usize;
    let dt = time / steps as f64;
    let (mut force, mut heat) = (vec![V3::zeros(); nodes.len()], vec![0.0; nodes.len()]);
    for _ in 0..steps {
        step_held(&mut s, dt, &faces, &nodes, None, &mut force, &mut heat);
    }
    (s.x[0].x - x0.x, s.w[0].y)
}

#[test]
fn a_sphere_rolls_down_a_slope_at_five_sevenths_g_sin_theta_and_slides_on_a_steep_one() {
    let time = 0.2;
    let g = 9.81;
    // Rolling without slip needs μ ≥ (2/7) tan θ: at 10° and μ = 0.5 the
    // centre accelerates at (5/7) g sin θ and spins at v/r.
    let theta = 10f64.to_radians();
    let (x, w) = down_the_slope(theta, 0.5, time);
    let want = 0.5 * 5.0 / 7.0 * g * theta.sin() * time * time;
    let err = (x - want).abs() / want;
    println!("rolling: x = {x:.6e} m against {want:.6e} m ({err:.2e}), spin {w:.4} rad/s");
    assert!(err < 0.01, "rolling: {x} against {want}");
    let v = 5.0 / 7.0 * g * theta.sin() * time;
    assert!(
        (w - v / STEEL.radius).abs() < 0.01 * v / STEEL.radius,
        "spin {w}"
    );
    // At 30° with μ = 0.1 < (2/7) tan 30° it slides: a = g (sin θ − μ cos θ).
    // (0.15 s, so it stays on the block's top.)
    let (theta, time) = (30f64.to_radians(), 0.15);
    let (x, w) = down_the_slope(theta, 0.1, time);
    let want = 0.5 * g * (theta.sin() - 0.1 * theta.cos()) * time * time;
    let err = (x - want).abs() / want;
    println!("sliding: x = {x:.6e} m against {want:.6e} m ({err:.2e}), spin {w:.4} rad/s");
    assert!(err < 0.01, "sliding: {x} against {want}");
    // Friction's moment spins it at (5/2) μ g cos θ t / r, below rolling.
    let spin = 2.5 * 0.1 * g * theta.cos() * time / STEEL.radius;
    assert!((w - spin).abs() < 0.01 * spin, "spin {w} against {spin}");
}

#[test]
fn an_undamped_sphere_bounces_back_to_its_drop_height() {
    let (faces, nodes) = block();
    let contact = SphereContact {
        damping: 0.0,
        friction: 0.3,
        resistance: 0.0,
    };
    let drop = 1e-3;
    let x0 = V3::new(0.047, 0.031, 0.02 + STEEL.radius + drop);
    let mut s = FreeSpheres::new(STEEL, contact, vec![x0], vec![]);
    s.gravity = V3::new(0.0, 0.0, -9.81);
    let dt = s.stable_dt(&faces, 1e-5);
    let (mut force, mut heat) = (vec![V3::zeros(); nodes.len()], vec![0.0; nodes.len()]);
    let (mut touched, mut top) = (false, f64::NEG_INFINITY);
    // Fall (14 ms), impact, rise (14 ms): the highest point after impact.
    let steps = (0.04 / dt) as usize;
    for _ in 0..steps {
        let st = step_held(&mut s, dt, &faces, &nodes, None, &mut force, &mut heat);
        touched |= st.faces > 0;
        if touched && st.faces == 0 {
            top = top.max(s.x[0].z);
        }
    }
    assert!(touched, "it hit the block");
    let back = top - (0.02 + STEEL.radius);
    println!("bounce: back to {back:.6e} m of {drop:.1e} m");
    assert!((back - drop).abs() < 0.01 * drop, "{back}");
}

#[test]
fn a_step_far_above_the_stable_one_is_an_error_naming_the_sphere() {
    let contact = SphereContact {
        damping: 0.0,
        friction: 0.0,
        resistance: 0.0,
    };
    let r = STEEL.radius;
    // Two held spheres touching (δ = 1 µm) with their temperatures
    // stepped at 1e6 times the stable heat step: forward Euler amplifies
    // the difference about 5e5-fold a step, past the largest f64.
    let x = vec![V3::zeros(), V3::new(2.0 * r - 1e-6, 0.0, 0.0)];
    let mut s = FreeSpheres::new(STEEL, contact, x, vec![0.0, 1.0]);
    s.fixed = vec![true, true];
    let dt = 1e6 * s.stable_heat_dt(1, 1e-6);
    let mut err = None;
    for _ in 0..100 {
        let side = NodeSide {
            x: &[],
            v: &[],
            temperature: None,
            force: &mut [],
            heat: &mut [],
        };
        if let Err(e) = s.step(dt, &Faces::default(), side) {
            err = Some(e);
            break;
        }
    }
    let e = err.expect("an error");
    assert!(e.contains("free sphere") && e.contains("non-finite"), "{e}");
}
