//! The average-temperature (DEM-like) reference for a packing: every
//! particle is one temperature with capacity C_i = ρ c V_i; particles
//! exchange heat through their contacts with conductance G_ij = S_ij / Rc
//! (S_ij the total contact area between bodies i and j); bodies held at a
//! prescribed temperature (the container) are sources. This is the
//! pipe-network idea of seed 000 sec 5 (eqs 33–36) without the particles'
//! internal resistance, valid when conduction inside a particle is much
//! faster than through its contacts (high conductivity).

use nalgebra::{DMatrix, DVector};

/// A lumped network of bodies.
#[derive(Debug, Clone)]
pub struct LumpedNetwork {
    /// Capacity of every free body (J/K).
    pub capacity: Vec<f64>,
    /// Conductances (i, j, G) between free bodies i and j (W/K).
    pub links: Vec<(usize, usize, f64)>,
    /// Conductances (i, G, T) from free body i to a held temperature T.
    pub held: Vec<(usize, f64, f64)>,
}

impl LumpedNetwork {
    /// Temperatures after each of `steps` theta-method steps of `dt` from `t0`
    /// (row k is after k steps; row 0 is `t0`).
    pub fn run(&self, t0: &[f64], dt: f64, theta: f64, steps: usize) -> Vec<Vec<f64>> {
        let n = self.capacity.len();
        // Not numbered in the seeds: C dT/dt = −L T + g, the network's conductance Laplacian L.
        let mut l = DMatrix::<f64>::zeros(n, n);
        let mut g = DVector::<f64>::zeros(n);
        for &(i, j, c) in &self.links {
            l[(i, i)] += c;
            l[(j, j)] += c;
            l[(i, j)] -= c;
            l[(j, i)] -= c;
        }
        for &(i, c, t) in &self.held {
            l[(i, i)] += c;
            g[i] += c * t;
        }
        let cap = DMatrix::from_diagonal(&DVector::from_column_slice(&self.capacity));
        // Seed 000 eq 22 applied to the network: (C/Δt + θL) Tⁿ⁺¹ = (C/Δt − (1−θ)L) Tⁿ + g.
        let a = &cap / dt + &l * theta;
        let b = &cap / dt - &l * (1.0 - theta);
        let lu = a.lu();
        let mut t = DVector::from_column_slice(t0);
        let mut out = vec![t0.to_vec()];
        for _ in 0..steps {
            let rhs = &b * &t + &g;
            t = lu.solve(&rhs).expect("the network matrix is non-singular");
            out.push(t.as_slice().to_vec());
        }
        out
    }

    /// Capacity-weighted mean of a temperature vector.
    pub fn mean(&self, t: &[f64]) -> f64 {
        let c: f64 = self.capacity.iter().sum();
        self.capacity.iter().zip(t).map(|(c, t)| c * t).sum::<f64>() / c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_body_relaxes_exponentially() {
        // C dT/dt = G (T_w − T): T = T_w (1 − e^{−t G/C}); backward Euler: (1 + Δt G/C)^{−k}.
        let net = LumpedNetwork {
            capacity: vec![2.0],
            links: vec![],
            held: vec![(0, 0.5, 300.0)],
        };
        let r = net.run(&[0.0], 1.0, 1.0, 10);
        for (k, t) in r.iter().enumerate() {
            let exact = 300.0 * (1.0 - (1.0f64 + 0.25).powi(-(k as i32)));
            assert!(
                (t[0] - exact).abs() < 1e-10,
                "step {k}: {} vs {exact}",
                t[0]
            );
        }
    }

    #[test]
    fn insulated_pair_conserves_heat_and_equalises() {
        let net = LumpedNetwork {
            capacity: vec![1.0, 3.0],
            links: vec![(0, 1, 0.7)],
            held: vec![],
        };
        for theta in [0.0, 0.5, 1.0] {
            let r = net.run(&[10.0, 2.0], 0.1, theta, 400);
            for t in &r {
                assert!((net.mean(t) - 4.0).abs() < 1e-12);
            }
            let last = r.last().unwrap();
            assert!((last[0] - 4.0).abs() < 1e-6 && (last[1] - 4.0).abs() < 1e-6);
        }
    }
}
