//! Tet4 heat-conduction element kernels: pure functions over coordinates
//! and material constants, free of MPI and PETSc.
//!
//! Seed 000 eqs 14–20 (their extraction garbles the signs; re-derived from
//! the weak form of eq 3): M Ṫ + (K + H) T = f with
//! M = ρc ∫ NᵀN dV, K = k ∫ BᵀB dV, H = h ∫_Γcv NᵀN dΓ,
//! f = ∫ Q N dV + ∫_Γh q N dΓ + ∫_Γcv h T_env N dΓ (q > 0 heats the body).

use crate::geometry::Tet4Geometry;

/// Seed 000 eq 16: conductivity matrix K_e = k V Bᵀ B (row-major 4×4).
pub fn conductivity(g: &Tet4Geometry, k: f64) -> [f64; 16] {
    let mut m = [0.0; 16];
    for i in 0..4 {
        for j in 0..4 {
            let gi = g.grad[i];
            let gj = g.grad[j];
            m[4 * i + j] = k * g.volume * (gi[0] * gj[0] + gi[1] * gj[1] + gi[2] * gj[2]);
        }
    }
    m
}

/// Seed 000 eq 15: consistent capacity M_e = ρcV/20 (1 + δ_ij).
pub fn capacity_consistent(g: &Tet4Geometry, rho_c: f64) -> [f64; 16] {
    let s = rho_c * g.volume / 20.0;
    let mut m = [s; 16];
    for i in 0..4 {
        m[5 * i] = 2.0 * s;
    }
    m
}

/// Row-sum lumped capacity: ρcV/4 on the diagonal (off-diagonals are
/// explicit zeros, kept so every capacity matrix shares K's pattern).
pub fn capacity_lumped(g: &Tet4Geometry, rho_c: f64) -> [f64; 16] {
    let mut m = [0.0; 16];
    for i in 0..4 {
        m[5 * i] = rho_c * g.volume / 4.0;
    }
    m
}

/// Seed 000 eq 17: uniform volumetric source Q (W/m³) → Q V / 4 per node.
pub fn source_load(g: &Tet4Geometry, q: f64) -> [f64; 4] {
    [q * g.volume / 4.0; 4]
}

/// Area and unit normal (right-hand rule) of a triangle.
pub fn triangle_area_normal(x: &[[f64; 3]; 3]) -> (f64, [f64; 3]) {
    let u = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
    let v = [x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len == 0.0 {
        return (0.0, [0.0; 3]);
    }
    (0.5 * len, [n[0] / len, n[1] / len, n[2] / len])
}

/// Seed 000 eq 18: uniform inward flux q (W/m²) on a Tri3 face → q A / 3 per node.
pub fn face_flux_load(area: f64, q: f64) -> [f64; 3] {
    [q * area / 3.0; 3]
}

/// Seed 000 eq 20: convection h (T − T_env) on a Tri3 face. Returns the
/// face matrix H_f = hA/12 (1 + δ_ij) (row-major 3×3) and the load h T_env A / 3.
pub fn face_convection(area: f64, h: f64, t_env: f64) -> ([f64; 9], [f64; 3]) {
    let s = h * area / 12.0;
    let mut m = [s; 9];
    for i in 0..3 {
        m[4 * i] = 2.0 * s;
    }
    (m, [h * t_env * area / 3.0; 3])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::tet4_geometry;

    fn unit_tet() -> [[f64; 3]; 4] {
        [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]]
    }

    #[test]
    fn unit_tet_volume_and_matrices() {
        let g = tet4_geometry(&unit_tet());
        assert!((g.volume - 1.0 / 6.0).abs() < 1e-15);
        let k = conductivity(&g, 2.0);
        // Rows of K sum to zero (constants are in the null space).
        for i in 0..4 {
            let s: f64 = (0..4).map(|j| k[4 * i + j]).sum();
            assert!(s.abs() < 1e-14);
        }
        // K_00 = k V |grad N0|^2 = 2 * 1/6 * 3.
        assert!((k[0] - 1.0).abs() < 1e-14);
        let m = capacity_consistent(&g, 6.0);
        let total: f64 = m.iter().sum();
        assert!((total - 1.0).abs() < 1e-14, "ρcV = 1");
        let ml = capacity_lumped(&g, 6.0);
        assert!((ml.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn face_loads_integrate_exactly() {
        let (a, n) = triangle_area_normal(&[[0., 0., 0.], [2., 0., 0.], [0., 1., 0.]]);
        assert!((a - 1.0).abs() < 1e-15);
        assert_eq!(n, [0.0, 0.0, 1.0]);
        let f = face_flux_load(a, 3.0);
        assert!((f.iter().sum::<f64>() - 3.0).abs() < 1e-15);
        let (h, l) = face_convection(a, 4.0, 10.0);
        // Σ H_ij = h A; Σ load = h T_env A.
        assert!((h.iter().sum::<f64>() - 4.0).abs() < 1e-14);
        assert!((l.iter().sum::<f64>() - 40.0).abs() < 1e-13);
    }
}
