//! Conduction blocks of a bonded sphere lattice and of its half bonds to
//! the finite elements (issue 21, seed 002), for the one thermal system.
//!
//! A bond of conductance g between spheres i and j carries
//! Q_{j→i} = g (T_j − T_i) (`mechanics::bond` docs: g = h w, with
//! h₁ = h₂ = 2kr/5, h₃ = 0 from the flux equivalence on the cubic cell,
//! derived there as eq 4 derives the stiffnesses), so its block of K
//! (flows = −K T) is g [1 −1; −1 1].
//!
//! A link is a sphere's half of a sphere–ghost bond (conductance 2hw: the
//! weight is doubled), whose other end is the element's material point at
//! the bond's midpoint on the interface, at temperature T_o = Σ N_I T_I
//! (the ghost's interpolation, seed 002 eq 16, at that point). It carries
//! Q = g (T_o − T_s) into the sphere and returns −Q to the nodes as N_I
//! (−Q) (eq 17 for heat). With a = (1, −N_1, …, −N_4) over
//! (T_s, T_1, …, T_4) the flows are −g a aᵀ T: the block is g a aᵀ,
//! symmetric, positive semi-definite, its rows summing to zero (Σ N_I = 1),
//! so heat is conserved. For a linear field the half bond carries exactly
//! the full bond's g/2 (T_g − T_s): the interface adds no resistance and
//! counts the element's half cell once (the elements conduct it).
//! Pure: no MPI, no PETSc.

/// K block (2 × 2, row-major) of a bond of conductance `g` (W/K).
pub fn bond_block(g: f64) -> [f64; 4] {
    // seed 002 eq 4's flux analogue (mechanics::bond docs): Q_{j→i} = g (T_j − T_i).
    [g, -g, -g, g]
}

/// K block (5 × 5, row-major, over the sphere then the element's four
/// nodes) of a link of conductance `g` (W/K, the half bond's) whose FE end
/// has shape functions `shape` (N_I at the bond's midpoint).
pub fn link_block(g: f64, shape: &[f64; 4]) -> [f64; 25] {
    // seed 002 eqs 16–17 for heat: T_o = Σ N_I T_I, Q_s = g (T_o − T_s), Q_I = −N_I Q_s.
    let a = [1.0, -shape[0], -shape[1], -shape[2], -shape[3]];
    std::array::from_fn(|k| g * (a[k / 5] * a[k % 5]))
}

/// Heat flow (W) into the sphere of a link of conductance `g` at sphere
/// temperature `t_sphere` and nodal temperatures `t_nodes`.
pub fn link_flow(g: f64, shape: &[f64; 4], t_sphere: f64, t_nodes: &[f64; 4]) -> f64 {
    // seed 002 eq 16 for heat: the point's temperature Σ N_I T_I.
    let t_point: f64 = (0..4).map(|k| shape[k] * t_nodes[k]).sum();
    g * (t_point - t_sphere)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flows(block: &[f64], t: &[f64]) -> Vec<f64> {
        let n = t.len();
        (0..n)
            .map(|i| -(0..n).map(|j| block[n * i + j] * t[j]).sum::<f64>())
            .collect()
    }

    #[test]
    fn bond_block_carries_g_delta_t_and_conserves_heat() {
        let q = flows(&bond_block(3.0), &[1.0, 2.0]);
        assert_eq!(q, vec![3.0, -3.0]);
    }

    #[test]
    fn link_block_is_symmetric_conserves_heat_and_matches_its_flow() {
        let shape = [0.1, 0.2, 0.3, 0.4];
        let g = 2.5;
        let b = link_block(g, &shape);
        for i in 0..5 {
            assert!((0..5).map(|j| b[5 * i + j]).sum::<f64>().abs() < 1e-15);
            for j in 0..5 {
                assert_eq!(b[5 * i + j], b[5 * j + i]);
            }
        }
        let t = [1.0, 3.0, -2.0, 5.0, 0.5];
        let q = flows(&b, &t);
        let into_sphere = link_flow(g, &shape, t[0], &[t[1], t[2], t[3], t[4]]);
        assert!((q[0] - into_sphere).abs() < 1e-14);
        for k in 0..4 {
            assert!((q[k + 1] + shape[k] * into_sphere).abs() < 1e-14);
        }
        // A uniform temperature carries nothing.
        assert!(flows(&b, &[7.0; 5]).iter().all(|v| v.abs() < 1e-13));
    }

    /// In a linear field T = G x, a link of 2g from a sphere at x = 0 to its
    /// midpoint at x = r carries what the full bond g to the ghost at x = 2r
    /// would: g (T_g − T_s) = 2g (T_o − T_s).
    #[test]
    fn half_bond_in_a_linear_field_carries_the_full_bonds_flow() {
        let (g, grad, r) = (0.4, 30.0, 1e-3);
        // A tet with nodes at x = 0, 2r, 0, 0 (y, z elsewhere): the midpoint x = r is half-way.
        let shape = [0.5, 0.5, 0.0, 0.0];
        let nodes = [0.0, grad * 2.0 * r, 0.0, 0.0];
        let half = link_flow(2.0 * g, &shape, 0.0, &nodes);
        let full = g * (grad * 2.0 * r - 0.0);
        assert!((half - full).abs() < 1e-15 * full.abs().max(1.0));
    }
}
