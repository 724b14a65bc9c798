//! Throughput of the cohesive joint kernel (issue 19 benchmark): joint
//! updates per second on one core, over every internal face of a box mesh
//! made discontinuous, in three states: every tet moved rigidly by its own
//! small offset (joints below their peak), by a larger one (most joints
//! softening), and all tets pushed towards the centre (joints pressed
//! together and sliding: the Mohr–Coulomb branch).
//! Run: cargo run --release --example joint_kernel_bench [cells_per_side] [repetitions]

#[path = "common/timing.rs"]
mod timing;

use fdem::fracture::insert::make_discontinuous;
use fdem::fracture::law::FractureMaterial;
use fdem::fracture::set::JointSet;
use nalgebra::Vector3;

fn main() {
    let n: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(24.0);
    let reps: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(10);
    let h = 0.1 / n;
    let mesh = fdem::mesh::generate::box_mesh([0.0; 3], [0.1; 3], h).expect("mesh");
    let jointed = make_discontinuous(&mesh.nodes, &mesh.tets, &vec![true; mesh.tets.len()]);
    // Seed 004 Table 2's joint constants.
    let material = FractureMaterial {
        tensile_strength: 10e6,
        cohesion: 20e6,
        friction_angle: 30f64.to_radians(),
        g_i: 50.0,
        g_ii: 100.0,
        penalty: 1e12,
        bk_exponent: 1.0,
    };
    let mut set = JointSet::new(jointed.joints.clone(), &material).expect("joints");
    let nj = set.faces.len();
    let x0: Vec<Vector3<f64>> = jointed.nodes.iter().map(|p| Vector3::from(*p)).collect();
    let mut out = vec![[Vector3::zeros(); 3]; nj];
    // Each tet is moved rigidly by its own offset, so the joints open,
    // slide and close (a smooth field would move both faces alike). The
    // opening at a joint's peak is about f_t h / p_f.
    let peak = material.tensile_strength * h / material.penalty;
    let direction = |t: u32| {
        // A fixed pseudo-random unit vector per tet.
        let r = |k: u32| {
            let v = (t
                .wrapping_mul(2_654_435_761)
                .wrapping_add(k.wrapping_mul(40_503)))
                % 1000;
            f64::from(v) / 500.0 - 1.0
        };
        Vector3::new(r(1), r(2), r(3)).normalize()
    };
    let centre = Vector3::new(0.05, 0.05, 0.05);
    let centroid = |t: usize| {
        jointed.tets[t]
            .iter()
            .map(|&k| x0[k as usize])
            .sum::<Vector3<f64>>()
            / 4.0
    };
    #[allow(clippy::type_complexity)]
    let states: [(&str, Box<dyn Fn(usize) -> Vector3<f64>>); 3] = [
        (
            "below the peak",
            Box::new(|t| 0.3 * peak * direction(t as u32)),
        ),
        ("softening", Box::new(|t| 3.0 * peak * direction(t as u32))),
        (
            "pressed together",
            Box::new(|t| -(0.5 * peak / h) * (centroid(t) - centre)),
        ),
    ];
    // What the set holds per joint (faces and area, law, history, time of
    // breaking), besides the caller's six forces.
    let per_joint = std::mem::size_of_val(&set.faces[0])
        + std::mem::size_of_val(&set.stiffness[0])
        + std::mem::size_of_val(&set.states[0])
        + std::mem::size_of_val(&set.broke_at[0]);
    println!(
        "joint set: {per_joint} B per joint held, {} B per joint of forces",
        std::mem::size_of_val(&out[0])
    );
    for (name, displacement) in &states {
        let mut x = x0.clone();
        for (t, tet) in jointed.tets.iter().enumerate() {
            let u = displacement(t);
            for &node in tet {
                x[node as usize] = x0[node as usize] + u;
            }
        }
        set = JointSet::new(jointed.joints.clone(), &material).expect("joints");
        let mut totals = Default::default();
        let (best, cpu) = timing::time_best(reps, || {
            totals = set.forces(&x, 0.0, &mut out);
        });
        let damaged = set.states.iter().filter(|s| s.damage > 0.0).count();
        let wall = nj as f64 / best / 1e6;
        let on_cpu = cpu.map_or(String::new(), |c| {
            format!(", {:.1} M/s on CPU", nj as f64 / c / 1e6)
        });
        println!(
            "joints {name}: {nj} joints, {wall:.1} M joint updates/s per core (best of {reps}{on_cpu}); \
             {damaged} damaged, {} broken, stored {:.3e} J",
            totals.broken, totals.stored
        );
    }
}
