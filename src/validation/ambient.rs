//! Lumped (Bi ≪ 1) bodies cooling to an ambient (issue 20): the references
//! of the free-surface convection and radiation tests.

use crate::thermal::radiation::STEFAN_BOLTZMANN;

/// A body of heat capacity `capacity` (ρ c V, J/K) with free area `area`
/// (m²) radiating with emissivity `eps` to a 0 K ambient from the absolute
/// temperature `t0`: C dT/dt = −ε σ A T⁴ integrates to
/// T(t) = (T0⁻³ + 3 ε σ A t / C)^(−1/3).
pub fn radiative_cooling(t0: f64, eps: f64, area: f64, capacity: f64, t: f64) -> f64 {
    (t0.powi(-3) + 3.0 * eps * STEFAN_BOLTZMANN * area * t / capacity).powf(-1.0 / 3.0)
}

/// The same body convecting with film coefficient `h` to an ambient at
/// `t_env`: T(t) = T_env + (T0 − T_env) exp(−h A t / C).
pub fn convective_cooling(t0: f64, t_env: f64, h: f64, area: f64, capacity: f64, t: f64) -> f64 {
    t_env + (t0 - t_env) * (-h * area * t / capacity).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radiative_solution_solves_its_equation() {
        let (t0, eps, a, c) = (1000.0, 0.8, 0.06, 1000.0);
        let t = 37.0;
        let dt = 1e-3;
        let slope = (radiative_cooling(t0, eps, a, c, t + dt)
            - radiative_cooling(t0, eps, a, c, t - dt))
            / (2.0 * dt);
        let temp = radiative_cooling(t0, eps, a, c, t);
        let rhs = -eps * STEFAN_BOLTZMANN * a * temp.powi(4) / c;
        assert!((slope - rhs).abs() < 1e-6 * rhs.abs());
        assert!((radiative_cooling(t0, eps, a, c, 0.0) - t0).abs() < 1e-9 * t0);
    }

    #[test]
    fn the_convective_solution_halves_in_its_half_life() {
        let (h, a, c) = (50.0, 0.06, 1000.0);
        let half = c * 2f64.ln() / (h * a);
        assert!((convective_cooling(300.0, 100.0, h, a, c, half) - 200.0).abs() < 1e-10);
    }
}
