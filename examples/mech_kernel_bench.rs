//! Throughput of the explicit internal-force kernel (issue 4 benchmark):
//! tet updates per second on one core, on a 1M-tet box slightly deformed
//! and moving, with a temperature field (thermal split active).
//! Run: cargo run --release --example mech_kernel_bench [cells_per_side] [repetitions]

#[path = "common/timing.rs"]
mod timing;

use fdem::mechanics::explicit::{internal_forces, mesh_elements, ThermalLoad};
use fdem::mechanics::ElasticMaterial;
use nalgebra::{Matrix3, Vector3};

fn main() {
    let n: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(56.0);
    let mesh = fdem::mesh::generate::box_mesh([0.0; 3], [1.0; 3], 1.0 / n).expect("mesh");
    let elems = mesh_elements(&mesh, 1).expect("elements");
    let mat = ElasticMaterial {
        young: 20e9,
        poisson: 0.2,
        density: 2400.0,
        expansion: 1e-5,
        viscosity: 1e3,
    };
    // A small smooth deformation and velocity field.
    let x: Vec<Vector3<f64>> = mesh
        .nodes
        .iter()
        .map(|p| Vector3::new(p[0] * 1.001 + 1e-4 * p[1], p[1] - 2e-4 * p[2], p[2] * 0.999))
        .collect();
    let v: Vec<Vector3<f64>> = mesh
        .nodes
        .iter()
        .map(|p| Vector3::new(p[1], -p[0], 0.1 * p[2]))
        .collect();
    let dt: Vec<f64> = (0..elems.len()).map(|e| 50.0 + (e % 100) as f64).collect();
    let mut f = vec![Vector3::zeros(); x.len()];
    let reps: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(10);
    let thermal = ThermalLoad {
        delta_t: Some(&dt),
        rate: None,
    };
    // Headline figure: viscous material, no stress output.
    let (best, cpu) = timing::time_best(reps, || {
        f.iter_mut().for_each(|x| *x = Vector3::zeros());
        internal_forces(&elems, &[mat], &x, &v, thermal, &mut f, None).expect("forces");
    });
    report("internal forces", elems.len(), reps, best, cpu);
    // Variants: inviscid material (no velocity gradient), and with the stresses recorded.
    let elastic = ElasticMaterial {
        viscosity: 0.0,
        ..mat
    };
    let (best, cpu) = timing::time_best(reps, || {
        f.iter_mut().for_each(|x| *x = Vector3::zeros());
        internal_forces(&elems, &[elastic], &x, &v, thermal, &mut f, None).expect("forces");
    });
    report("  viscosity 0", elems.len(), reps, best, cpu);
    let mut stress = vec![Matrix3::zeros(); elems.len()];
    let (best, cpu) = timing::time_best(reps, || {
        f.iter_mut().for_each(|x| *x = Vector3::zeros());
        internal_forces(&elems, &[mat], &x, &v, thermal, &mut f, Some(&mut stress))
            .expect("forces");
    });
    report("  with stresses", elems.len(), reps, best, cpu);
}

fn report(what: &str, tets: usize, reps: usize, best: f64, cpu: Option<f64>) {
    let rate = tets as f64 / best;
    print!(
        "{what}: {tets} tets, best of {reps}: {best:.4} s per evaluation, {:.2} million tet updates/s on one core",
        rate / 1e6
    );
    match cpu {
        // On a loaded machine the on-CPU time excludes time the thread was descheduled.
        Some(c) => println!(" (on-CPU: {:.2} M/s)", tets as f64 / c / 1e6),
        None => println!(),
    }
}
