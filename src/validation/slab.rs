//! Transient conduction in a finite slab, insulated at x = 0 and held at
//! T_D at x = L from t = 0, initially at T_i (seed 000 sec 4.1, eq 32).
//!
//! The seed writes the diffusivity as α = c/k (eq 31); the physical
//! diffusivity is α = k/(ρc), which is what is used here (see
//! "Decisions on the seeds' inconsistencies" in `docs/guide.md`).

/// The slab of seed 000 sec 4.1.
#[derive(Debug, Clone, Copy)]
pub struct SlabProblem {
    /// Length L (m).
    pub length: f64,
    /// Conductivity k (W/m/K).
    pub conductivity: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Specific heat c (J/kg/K).
    pub specific_heat: f64,
    /// Initial temperature T_i.
    pub t_initial: f64,
    /// Temperature T_D held at x = L.
    pub t_dirichlet: f64,
}

impl SlabProblem {
    /// The seed's case (sec 4.2, Table 1): L = 1, k = 1, c = 1, ρ = 100, T_i = 0, T_D = 1.
    pub fn seed_000() -> Self {
        SlabProblem {
            length: 1.0,
            conductivity: 1.0,
            density: 100.0,
            specific_heat: 1.0,
            t_initial: 0.0,
            t_dirichlet: 1.0,
        }
    }

    /// Thermal diffusivity k/(ρc).
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / (self.density * self.specific_heat)
    }

    /// Temperature at position x (0 ≤ x ≤ L, measured from the insulated end) and time t.
    pub fn temperature(&self, x: f64, t: f64) -> f64 {
        let fo = self.diffusivity() * t / (self.length * self.length);
        let theta = slab_dirichlet_series(x / self.length, fo);
        self.t_dirichlet + (self.t_initial - self.t_dirichlet) * theta
    }
}

/// Seed 000 eq 32: θ(X, Fo) = Σ 4 sin λ_n / (2λ_n + sin 2λ_n) cos(λ_n X) exp(−λ_n² Fo),
/// λ_n = (n − 1/2)π, θ = (T − T_D)/(T_i − T_D), X = x/L, Fo = αt/L².
///
/// With sin λ_n = (−1)^{n+1} and sin 2λ_n = 0 the coefficient is 2(−1)^{n+1}/λ_n.
/// Summed until the terms fall below 1e-17 (Fo > 0) or for 200,000 terms at Fo = 0.
pub fn slab_dirichlet_series(x: f64, fo: f64) -> f64 {
    if fo <= 0.0 {
        return if x < 1.0 { 1.0 } else { 0.0 };
    }
    let mut sum = 0.0;
    for n in 1..=200_000u32 {
        let lambda = (n as f64 - 0.5) * std::f64::consts::PI;
        let decay = (-lambda * lambda * fo).exp();
        let coef = 4.0 * lambda.sin() / (2.0 * lambda + (2.0 * lambda).sin());
        sum += coef * (lambda * x).cos() * decay;
        if decay * coef.abs() < 1e-17 {
            break;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boundary_values_and_limits() {
        // θ = 0 at the Dirichlet end for any Fo > 0.
        assert!(slab_dirichlet_series(1.0, 0.05).abs() < 1e-12);
        // Long times: θ → 0 everywhere.
        assert!(slab_dirichlet_series(0.0, 10.0).abs() < 1e-10);
        // Early times: the insulated end has not felt the boundary yet.
        assert!((slab_dirichlet_series(0.0, 1e-3) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn one_term_limit_and_insulated_gradient() {
        // At large Fo the first term dominates: θ(0) ≈ (4/π) e^{−π²Fo/4}.
        let fo = 1.0;
        let one = 4.0 / std::f64::consts::PI * (-std::f64::consts::PI.powi(2) * fo / 4.0).exp();
        assert!((slab_dirichlet_series(0.0, fo) - one).abs() < 1e-8);
        // Zero gradient at the insulated end (symmetric difference).
        let e = 1e-6;
        let g = (slab_dirichlet_series(e, 0.1) - slab_dirichlet_series(-e, 0.1)) / (2.0 * e);
        assert!(g.abs() < 1e-8);
    }

    #[test]
    fn satisfies_heat_equation() {
        // ∂θ/∂Fo = ∂²θ/∂X² by finite differences at an interior point.
        let (x, fo, h, k) = (0.4, 0.2, 1e-3, 1e-5);
        let dt = (slab_dirichlet_series(x, fo + k) - slab_dirichlet_series(x, fo - k)) / (2.0 * k);
        let dxx = (slab_dirichlet_series(x + h, fo) - 2.0 * slab_dirichlet_series(x, fo)
            + slab_dirichlet_series(x - h, fo))
            / (h * h);
        assert!((dt - dxx).abs() < 1e-5, "{dt} vs {dxx}");
    }

    #[test]
    fn seed_problem_uses_k_over_rho_c() {
        let p = SlabProblem::seed_000();
        assert!((p.diffusivity() - 0.01).abs() < 1e-15);
        assert!((p.temperature(1.0, 10.0) - 1.0).abs() < 1e-12);
    }
}
