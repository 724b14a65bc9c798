//! Throughput of the Hex8 internal-force kernel (issue 21 benchmark):
//! hex updates per second on one core over a 40^3 box of Hex8, slightly
//! deformed and moving, with a temperature change (thermal split active),
//! through the kernel `fdem run` calls (`mechanics::hex8_element::hex8_forces_at`:
//! one-point integration with assumed-strain hourglass stiffness).
//! The checksum of the forces shows that a change of the kernel keeps its
//! results. Run: cargo run --release --example hex8_kernel_bench [cells_per_side] [repetitions]

#[path = "common/timing.rs"]
mod timing;

use fdem::mechanics::hex8_element::{hex8_forces_at, Hex8Material, Hex8Reference};
use fdem::mechanics::{ElasticMaterial, ThermalState};
use nalgebra::Vector3;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(40);
    let reps: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(5);
    let mesh = fdem::mesh::hex8::hex_box([0.0; 3], [1.0; 3], [n; 3]).expect("mesh");
    let refs: Vec<Hex8Reference> = (0..mesh.hexes.len())
        .map(|e| Hex8Reference::from_coords(&mesh.element_coords(e)).expect("reference"))
        .collect();
    for (what, viscosity) in [("internal forces", 1e3), ("  viscosity 0", 0.0)] {
        let mat = ElasticMaterial {
            young: 20e9,
            poisson: 0.2,
            density: 2400.0,
            expansion: 1e-5,
            viscosity,
        };
        // A small smooth deformation and velocity field, as the Tet4 bench.
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
        let kernel = Hex8Material::new(&mat);
        let mut f = vec![Vector3::zeros(); x.len()];
        let (best, cpu) = timing::time_best(reps, || {
            f.iter_mut().for_each(|x| *x = Vector3::zeros());
            for (e, (h, r)) in mesh.hexes.iter().zip(&refs).enumerate() {
                let th = ThermalState {
                    delta_t: 50.0 + (e % 100) as f64,
                    rate: 1.0,
                };
                let out = hex8_forces_at(r, &kernel, &x, &v, h, th).expect("forces");
                for (k, &i) in h.iter().enumerate() {
                    f[i as usize] += out.forces[k];
                }
            }
        });
        let checksum: f64 = f.iter().map(|g| g.norm()).sum();
        let rate = mesh.hexes.len() as f64 / best;
        print!(
            "{what}: {} Hex8, best of {reps}: {best:.4} s per evaluation, {:.2} million hex updates/s on one core",
            mesh.hexes.len(),
            rate / 1e6
        );
        if let Some(c) = cpu {
            print!(" ({:.2} M/s on-CPU)", mesh.hexes.len() as f64 / c / 1e6);
        }
        println!(", checksum {checksum:.9e}");
    }
}
