//! Throughput of the bonded-lattice kernel (issue 21 asks at least 20 M
//! bond updates/s per core): `mechanics::bond::bond_forces` (seed 002 eqs
//! 2–4, 12–15: the incremental relative displacement carried with the
//! rotation of the centre line, the springs' force and the moments) over
//! every bond of a cubic lattice with its 26 neighbours, the spheres
//! moving and spinning with small random velocities, as in a lattice
//! under load. Also the bond heat flows (`bond_heat`). Prints M bond
//! updates/s on one core.
//! Run: cargo run --release --example bond_kernel_bench [spheres_per_side] [repetitions]

#[path = "common/timing.rs"]
mod timing;

use fdem::mechanics::bond::{bond_conductance, bond_forces, bond_heat, BondState, BondStiffness};
use fdem::mesh::lattice::cubic_lattice;
use nalgebra::Vector3;

fn main() {
    let n: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(40.0);
    let reps: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(10);
    // Seed 002's cantilever constants: E = 1000 MPa, nu = 0.23, r = 0.125 mm.
    let r = 0.125e-3;
    let side = n * 2.0 * r;
    let lattice = cubic_lattice([0.0; 3], [side; 3], r, true).expect("lattice");
    let stiffness = BondStiffness::seed002(1e9, 0.23, r).expect("stiffness");
    let ns = lattice.centres.len();
    let nb = lattice.bonds.len();
    let x0: Vec<Vector3<f64>> = lattice.centres.iter().map(|c| Vector3::from(*c)).collect();
    // A fixed pseudo-random value in [-1, 1) per (sphere, component).
    let noise = |p: usize, k: usize| {
        let v = (p as u64)
            .wrapping_mul(2_654_435_761)
            .wrapping_add(k as u64 * 40_503)
            % 1000;
        v as f64 / 500.0 - 1.0
    };
    let dt = 1e-8;
    let v: Vec<Vector3<f64>> = (0..ns)
        .map(|p| Vector3::new(noise(p, 1), noise(p, 2), noise(p, 3)) * 1e-3)
        .collect();
    let w: Vec<Vector3<f64>> = (0..ns)
        .map(|p| Vector3::new(noise(p, 4), noise(p, 5), noise(p, 6)) * 10.0)
        .collect();
    let x: Vec<Vector3<f64>> = x0.iter().zip(&v).map(|(x, v)| x + v * dt).collect();
    let mut state: Vec<BondState> = lattice
        .bonds
        .iter()
        .map(|b| BondState::new(&x0[b.i as usize], &x0[b.j as usize]))
        .collect();
    let mut force = vec![Vector3::zeros(); ns];
    let mut moment = vec![Vector3::zeros(); ns];
    let (best, cpu) = timing::time_best(reps, || {
        force.iter_mut().for_each(|f| *f = Vector3::zeros());
        moment.iter_mut().for_each(|m| *m = Vector3::zeros());
        bond_forces(
            &lattice.bonds,
            &mut state,
            &stiffness,
            &x,
            &v,
            &w,
            dt,
            None,
            &mut force,
            &mut moment,
        );
    });
    let largest = force.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let on_cpu = cpu.map_or(String::new(), |c| {
        format!(", {:.1} M/s on CPU", nb as f64 / c / 1e6)
    });
    println!(
        "bonds: {ns} spheres, {nb} bonds, {:.1} M bond updates/s per core (best of {reps}{on_cpu}); largest force {largest:.3e} N",
        nb as f64 / best / 1e6
    );
    let h = bond_conductance(1.5, r);
    let t: Vec<f64> = (0..ns).map(|p| 20.0 + noise(p, 7)).collect();
    let mut heat = vec![0.0; ns];
    let (best, cpu) = timing::time_best(reps, || {
        heat.iter_mut().for_each(|q| *q = 0.0);
        bond_heat(&lattice.bonds, &h, &t, &mut heat);
    });
    let net: f64 = heat.iter().sum();
    let on_cpu = cpu.map_or(String::new(), |c| {
        format!(", {:.1} M/s on CPU", nb as f64 / c / 1e6)
    });
    println!(
        "bond heat: {nb} bonds, {:.1} M bond flows/s per core (best of {reps}{on_cpu}); net heat {net:.1e} W",
        nb as f64 / best / 1e6
    );
}
