//! Hex8 heat-conduction element matrices (2×2×2 Gauss): conductivity
//! K = k ∫ ∇N_I·∇N_J dV and capacity M = ρc ∫ N_I N_J dV (consistent) or
//! its row sums (lumped), the Hex8 counterparts of the Tet4 matrices of
//! seed 000 eqs 15–16 in [`super::element`]. Pure, free of MPI and PETSc;
//! row-major 8×8 arrays in the node order of seed 002 Table 1.

use nalgebra::Vector3;

use crate::mechanics::hex8::hex8_shape;
use crate::mechanics::hex8_element::{hex8_gauss_points, Hex8Gauss};

/// Seed 000 eq 16 on a Hex8: K_IJ = k Σ_g ∇N_I·∇N_J dV_g (2×2×2 Gauss, exact
/// for a parallelepiped).
pub fn hex8_conductivity(r: &Hex8Gauss, k: f64) -> [f64; 64] {
    let mut m = [0.0; 64];
    for g in 0..8 {
        let grad: &[Vector3<f64>; 8] = &r.grad[g];
        for i in 0..8 {
            for j in 0..8 {
                // seed 000 eq 16: K = k ∫ Bᵀ B dV, Gauss point g.
                m[8 * i + j] += k * grad[i].dot(&grad[j]) * r.dv[g];
            }
        }
    }
    m
}

/// Seed 000 eq 15 on a Hex8: M_IJ = ρc Σ_g N_I N_J dV_g (consistent).
pub fn hex8_capacity_consistent(r: &Hex8Gauss, rho_c: f64) -> [f64; 64] {
    let mut m = [0.0; 64];
    for (g, xi) in hex8_gauss_points().iter().enumerate() {
        let n = hex8_shape(xi);
        for i in 0..8 {
            for j in 0..8 {
                // seed 000 eq 15: M = ρc ∫ Nᵀ N dV, Gauss point g.
                m[8 * i + j] += rho_c * n[i] * n[j] * r.dv[g];
            }
        }
    }
    m
}

/// Row-sum lumped capacity ρc ∫ N_I dV on the diagonal (zeros elsewhere, so
/// it shares K's pattern as the Tet4 lumped matrix does).
pub fn hex8_capacity_lumped(r: &Hex8Gauss, rho_c: f64) -> [f64; 64] {
    let mut m = [0.0; 64];
    for (i, mi) in r.lumped_masses(rho_c).iter().enumerate() {
        m[9 * i] = *mi;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::hex8::HEX8_NATURAL;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn distorted() -> Hex8Gauss {
        let mut rng = Pcg64::seed_from_u64(1);
        let x0 = HEX8_NATURAL.map(|c| {
            Vector3::new(
                0.5 * (c[0] + 1.0) + rng.gen_range(-0.1..0.1),
                0.3 * (c[1] + 1.0) + rng.gen_range(-0.1..0.1),
                0.8 * (c[2] + 1.0) + rng.gen_range(-0.1..0.1),
            )
        });
        Hex8Gauss::new(&x0).unwrap()
    }

    #[test]
    fn conductivity_rows_sum_to_zero_and_linear_fields_give_k_grad_t() {
        let r = distorted();
        let k = 3.5;
        let m = hex8_conductivity(&r, k);
        let scale = k * r.volume().cbrt();
        for i in 0..8 {
            let s: f64 = (0..8).map(|j| m[8 * i + j]).sum();
            assert!(s.abs() < 1e-13 * scale, "row {i}: {s}");
            // Symmetric.
            for j in 0..8 {
                assert!((m[8 * i + j] - m[8 * j + i]).abs() < 1e-14 * scale);
            }
        }
        // Energy of a linear field T = g·X is k |g|² V (exact with 2×2×2 Gauss).
        let g = Vector3::new(2.0, -1.0, 0.5);
        let xb = HEX8_NATURAL.map(|c| Vector3::new(c[0] * 0.5, c[1] * 1.5, c[2] * 0.25));
        let rb = Hex8Gauss::new(&xb).unwrap();
        let mb = hex8_conductivity(&rb, k);
        let t: Vec<f64> = xb.iter().map(|p| g.dot(p)).collect();
        let mut energy = 0.0;
        for i in 0..8 {
            for j in 0..8 {
                energy += t[i] * mb[8 * i + j] * t[j];
            }
        }
        let expect = k * g.norm_squared() * rb.volume();
        assert!((energy - expect).abs() < 1e-12 * expect);
    }

    #[test]
    fn capacities_sum_to_rho_c_v() {
        let r = distorted();
        let rho_c = 2.0e6;
        let c = hex8_capacity_consistent(&r, rho_c);
        let l = hex8_capacity_lumped(&r, rho_c);
        let total = rho_c * r.volume();
        assert!((c.iter().sum::<f64>() - total).abs() < 1e-12 * total);
        assert!((l.iter().sum::<f64>() - total).abs() < 1e-12 * total);
        // The lumped diagonal is the consistent row sum.
        for i in 0..8 {
            let row: f64 = (0..8).map(|j| c[8 * i + j]).sum();
            assert!((row - l[9 * i]).abs() < 1e-12 * total);
        }
    }
}
