//! Time-step limits of the theta method (seed 000 eqs 22–23), pure.
//!
//! - Stability: for θ < 1/2 the scheme (M/Δt + θK) Tⁿ⁺¹ = (M/Δt − (1−θ)K) Tⁿ
//!   amplifies the mode of the largest eigenvalue λ_max of M⁻¹K unless
//!   Δt ≤ 2 / ((1 − 2θ) λ_max). Above it the run grows without bound (an
//!   explicit slab at 100× its limit reached 1e97 K in a few hundred steps).
//! - Positivity (the bounded scheme, `thermal::monotone`): with a lumped
//!   capacity and an operator without positive couplings, the right-hand
//!   side matrix M_L/Δt − (1−θ)K has no negative entry, so the new
//!   temperatures stay within the old ones, iff every diagonal entry is ≥ 0:
//!   Δt ≤ m_i / ((1 − θ) K_ii) for every free node i.

/// The largest stable step for `theta` < 1/2, given λ_max of M⁻¹K (1/s);
/// `None` when every step is stable (θ ≥ 1/2, or no conduction at all).
pub fn stability_limit(theta: f64, lambda_max: f64) -> Option<f64> {
    (theta < 0.5 && lambda_max > 0.0).then(|| 2.0 / ((1.0 - 2.0 * theta) * lambda_max))
}

/// The largest step that keeps M_L/Δt − (1−θ)K non-negative, from the
/// lumped capacities `m` and the diagonal `k_diag` of the free rows;
/// `None` for θ = 1 (or no conduction).
pub fn positivity_limit(theta: f64, m: &[f64], k_diag: &[f64]) -> Option<f64> {
    m.iter()
        .zip(k_diag)
        .filter_map(|(&mi, &k)| node_positivity_limit(theta, mi, k))
        .reduce(f64::min)
}

/// One node's share of [`positivity_limit`]: m / ((1 − θ) K_ii).
pub fn node_positivity_limit(theta: f64, m: f64, k_ii: f64) -> Option<f64> {
    (theta < 1.0 && k_ii > 0.0).then(|| m / ((1.0 - theta) * k_ii))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of n nodes (1D, unit spacing, unit capacity, insulated ends):
    /// λ_max of M⁻¹K → 4 from below (4 sin²(π (n−1)/(2n))).
    #[test]
    fn explicit_limit_of_a_chain_is_half_over_the_conductance() {
        let n = 200;
        let lambda = 4.0
            * (std::f64::consts::PI * (n - 1) as f64 / (2.0 * n as f64))
                .sin()
                .powi(2);
        let dt = stability_limit(0.0, lambda).unwrap();
        assert!((dt - 0.5).abs() < 1e-3, "{dt}");
        // Crank–Nicolson and backward Euler: no limit.
        assert_eq!(stability_limit(0.5, lambda), None);
        assert_eq!(stability_limit(1.0, lambda), None);
        // θ = 0.25 doubles the limit.
        assert!((stability_limit(0.25, lambda).unwrap() - 2.0 * dt).abs() < 1e-12);
        // The forward-Euler chain really is stable below the limit and not above.
        let grow = |dt: f64| {
            let mut t: Vec<f64> = (0..n)
                .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
                .collect();
            for _ in 0..2000 {
                let old = t.clone();
                for i in 0..n {
                    let l = if i > 0 { old[i - 1] - old[i] } else { 0.0 };
                    let r = if i + 1 < n { old[i + 1] - old[i] } else { 0.0 };
                    t[i] = old[i] + dt * (l + r);
                }
            }
            t.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        };
        assert!(grow(0.99 * dt) < 1.0 && grow(1.01 * dt) > 1e3);
    }

    #[test]
    fn positivity_limit_is_the_smallest_node_ratio() {
        let m = [2.0, 1.0, 4.0];
        let k = [1.0, 2.0, 0.0];
        assert_eq!(positivity_limit(0.0, &m, &k), Some(0.5));
        assert_eq!(positivity_limit(0.5, &m, &k), Some(1.0));
        assert_eq!(positivity_limit(1.0, &m, &k), None);
    }
}
