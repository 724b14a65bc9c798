//! Heat between free spheres of one uniform temperature each, and between
//! a sphere and a Tet4 body's face (issue 21, "Beyond the papers"): the
//! pipe network of seed 000 sec 5 (eqs 33–37) carried from discs to
//! spheres. Pure: no MPI or PETSc.
//!
//! Seed 000 eq 33 joins two particles by a pipe whose resistance is the
//! sum of the two particle resistances and a contact resistance, and
//! eq 35 makes the flow ΔT over it. Eq 34 is the resistance of a disc per
//! unit width entering through a contact arc; its three-dimensional
//! counterpart for a sphere entering through a small circular contact of
//! radius a is the constriction resistance R = 1/(4 k a) of a disc-shaped
//! contact on a half space (Batchelor & O'Brien 1977, Proc. R. Soc. A 355, 313–333:
//! two touching spheres conduct 2 k a), the leading term of eq 34's
//! −ln α in 2D becoming 1/a in 3D. The contact resistance is FDEM's per
//! unit area `rc` over the contact area π a² (seed 000 eq 39 without the
//! disc width); the contact radius is Hertz's a = √(R* δ) (Johnson 1985
//! sec 4.2). A Tet4 body's side of a sphere–face contact has no particle
//! resistance: its conduction is its finite elements'.

use std::f64::consts::PI;

/// 3D counterpart of seed 000 eq 34: resistance (K/W) of a sphere of
/// conductivity `k` entered through a circular contact of radius `a`.
pub fn sphere_resistance(k: f64, a: f64) -> f64 {
    // Batchelor & O'Brien 1977 (half of two spheres' 1/(2 k a)).
    1.0 / (4.0 * k * a)
}

/// Seed 000 eq 33 for spheres: R_AB = R_A + R_B + R*_c, with R_A, R_B from
/// [`sphere_resistance`] (`k_b` `None` for a Tet4 face) and R*_c =
/// `rc`/(π a²) for the contact resistance `rc` (K m²/W) per unit area.
pub fn pipe_resistance(k_a: f64, k_b: Option<f64>, a: f64, rc: f64) -> f64 {
    let r_b = k_b.map_or(0.0, |k| sphere_resistance(k, a));
    // Seed 000 eq 33: R_AB = R_A + R_B + R*_c (R*_c = rc / (π a²), cf. eq 39).
    sphere_resistance(k_a, a) + r_b + rc / (PI * a * a)
}

/// Seed 000 eq 35: the heat flow into A (W), Q_AB = (T_B − T_A)/R_AB.
pub fn pipe_flow(t_a: f64, t_b: f64, r_ab: f64) -> f64 {
    // Seed 000 eq 35: (T_B − T_A) = R_AB Q_AB.
    (t_b - t_a) / r_ab
}

/// Hertz's contact radius (m) a = √(R* δ) of an overlap `delta` between
/// partners of effective radius `r_star` (Johnson 1985 sec 4.2).
pub fn contact_radius(r_star: f64, delta: f64) -> f64 {
    // Johnson 1985 sec 4.2 (Hertz): a² = R* δ.
    (r_star * delta.max(0.0)).sqrt()
}

/// The conductance (W/K) of a pipe, 1/R_AB of [`pipe_resistance`], zero
/// when the pipe does not conduct (no overlap, or an infinite `rc`).
pub fn pipe_conductance(k_a: f64, k_b: Option<f64>, a: f64, rc: f64) -> f64 {
    if a <= 0.0 || !rc.is_finite() {
        return 0.0;
    }
    // Seed 000 eq 35: Q_AB = (T_B − T_A)/R_AB, so the conductance is 1/R_AB.
    1.0 / pipe_resistance(k_a, k_b, a, rc)
}

/// The forward-Euler (seed 000 eq 36 with θ = 0) Fourier number of a
/// body of capacity `c` (J/K) joined by conductances summing to `g` (W/K)
/// over a step `dt`: its new temperature is a convex combination of its
/// own and its partners' (the maximum principle) while this is ≤ 1.
pub fn explicit_fourier(dt: f64, g: f64, c: f64) -> f64 {
    // Seed 000 eq 36, θ = 0: Tⁿ⁺¹ = (1 − Δt Σg/C) Tⁿ + Δt Σ g T_j / C.
    dt * g / c
}

/// 3D counterpart of seed 000 eq 37: the heat capacity (J/K) of a sphere,
/// C = ρ c (4/3) π r³.
pub fn sphere_capacity(density: f64, specific_heat: f64, radius: f64) -> f64 {
    // Seed 000 eq 37 (disc: π ρ c r²), for a sphere: (4/3) π ρ c r³.
    4.0 / 3.0 * PI * density * specific_heat * radius.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validation::pipe_network::PipeNetwork;

    #[test]
    fn resistances_add_in_series() {
        let (k, a) = (2.0, 1e-3);
        assert!((sphere_resistance(k, a) - 125.0).abs() < 1e-12);
        // Perfect contact between equal spheres: Batchelor & O'Brien's 1/(2 k a).
        let r = pipe_resistance(k, Some(k), a, 0.0);
        assert!((r - 1.0 / (2.0 * k * a)).abs() < 1e-12);
        // A face adds no particle resistance; rc adds rc/(π a²).
        let r = pipe_resistance(k, None, a, 1e-4);
        assert!((r - (125.0 + 1e-4 / (PI * 1e-6))).abs() < 1e-9);
        assert!((pipe_flow(1.0, 3.0, 4.0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn conductance_and_fourier_number() {
        // a² = R* δ: R* = 2.5 mm (two 5 mm spheres), δ = 10 µm → a = 158 µm.
        let a = contact_radius(2.5e-3, 1e-5);
        assert!((a * a - 2.5e-8).abs() < 1e-20);
        assert_eq!(contact_radius(1.0, -1.0), 0.0);
        let g = pipe_conductance(50.0, Some(50.0), a, 1e-5);
        assert!((g * pipe_resistance(50.0, Some(50.0), a, 1e-5) - 1.0).abs() < 1e-14);
        assert_eq!(pipe_conductance(50.0, None, a, f64::INFINITY), 0.0);
        assert_eq!(pipe_conductance(50.0, None, 0.0, 0.0), 0.0);
        assert!((explicit_fourier(2.0, 3.0, 12.0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn explicit_exchange_follows_the_pipe_network() {
        // Two spheres joined by one pipe: seed 000 eqs 35–36 forward in
        // time against the network's exact exponential (pipe_network).
        let c = sphere_capacity(7800.0, 500.0, 0.005);
        assert!((c - 7800.0 * 500.0 * 4.0 / 3.0 * PI * 1.25e-7).abs() < 1e-12 * c);
        let r_ab = pipe_resistance(50.0, Some(50.0), 1e-4, 1e-5);
        let net = PipeNetwork {
            r_ab,
            cap_a: c,
            cap_b: 2.0 * c,
            alpha_a: 0.0,
            alpha_b: 0.0,
            res_a: 0.0,
            res_b: 0.0,
        };
        let tau = net.time_constant();
        let dt = tau / 1000.0;
        let (mut ta, mut tb) = (0.0, 1.0);
        for _ in 0..1000 {
            let q = pipe_flow(ta, tb, r_ab);
            ta += dt * q / c;
            tb -= dt * q / (2.0 * c);
        }
        let (ea, eb) = net.exact(0.0, 1.0, tau);
        // Forward Euler's error at t = τ with τ/dt = 1000: about e⁻¹/2000.
        assert!(
            (tb - ta - (eb - ea)).abs() < 3e-4,
            "{} {}",
            tb - ta,
            eb - ea
        );
        assert!((c * ta + 2.0 * c * tb - 2.0 * c).abs() < 1e-12 * c);
    }
}
