//! The 2D pipe-network (discrete thermal element) model of Feng, used by
//! seed 000 sec 5 as the reference for two contacting thin cylinders A and B
//! (eqs 33–43, Table 3).
//!
//! Each particle is a node with a uniform temperature and heat capacity
//! (eq 37); the two are joined by a pipe whose resistance is the sum of the
//! two particle resistances and a contact resistance (eq 33). All
//! resistances and capacities are per unit width of the disc (2D): R in
//! K·m/W, C in J/(K·m).
//!
//! # How the extracted equations were read
//!
//! * Eq 34 (particle resistance, contact arc of half angle α):
//!   `R = (1/(π k)) (−ln α + 3/2 + α²/36)`.
//! * Eqs 35–36: `Q_AB = (T_B − T_A)/R_AB` and `C_A dT_A/dt = Q_AB`; by heat
//!   conservation `C_B dT_B/dt = −Q_AB`.
//! * Eq 38 (garbled to `QAB = 1/wcyl Bc`): the pipe flow per unit width
//!   equals the FDEM contact heat flow divided by the cylinder width w.
//! * Eq 39: `(T_B − T_A)/R_AB = (1/w) ΔT_c S_c / R_c`. FDEM's contact flux is
//!   `ΔT_c / R_c` over the contact surface `S_c`; with the pipe-network
//!   assumption `ΔT_c = T_B − T_A` this gives `R_AB = R_c w / S_c`.
//! * Eq 40 as extracted reads `RAB = Rc wcyl/Sc − RA − RB`, which contradicts
//!   eq 39; by eq 33 the left-hand side must be the pipe network's contact
//!   resistance: `R*_c = R_c w / S_c − R_A − R_B = R_AB − R_A − R_B`.
//! * `R_c` is FDEM's contact resistance per unit contact area. Table 3 labels
//!   its unit m·K/W; for eq 39 to balance it is K·m²/W (the value, 1, is used
//!   as given).
//! * Eqs 41–42 (overlap of two circles with centre distance
//!   `d = r_A + r_B − p`): the extracted eq 41,
//!   `sin α_A = sqrt(4 d² r_A² − (d² − r_A² + r_B²)²) / (2 d r_A)`, uses the
//!   distance from B's centre to the common chord and is only right for
//!   `r_A = r_B` (the seed's case). The chord's half length is
//!   `sqrt(4 d² r_A² − (d² + r_A² − r_B²)²) / (2 d)` (equivalently with A and
//!   B exchanged), which is what [`circle_overlap_half_angle`] uses; the two
//!   agree for equal radii.
//! * Eq 43: the FDEM contact surface is turned back into a half angle,
//!   `α = S_c / (2 w r)`, applied to each particle with its own radius.
//! * Table 3 gives the width as 1 m, but the stated theoretical contact
//!   surface 0.02 m² (r = 1 m, p = 0.01 m) needs w = 0.1 m, which is used.

use std::f64::consts::PI;

/// Seed 000 eq 34: resistance per unit width of a disc of conductivity `k`
/// whose heat enters through a contact arc of half angle `alpha` (rad),
/// `R = (1/(π k)) (−ln α + 3/2 + α²/36)`; accurate for α below 30°.
pub fn particle_resistance(k: f64, alpha: f64) -> f64 {
    // Seed 000 eq 34: R_A = (1/(π k_A)) (−ln α_A + 3/2 + α_A²/36).
    (-alpha.ln() + 1.5 + alpha * alpha / 36.0) / (PI * k)
}

/// Seed 000 eq 43: half angle (rad) of the contact arc equivalent to a
/// contact surface `s_c` on a cylinder of width `width` and radius `radius`,
/// `α = S_c / (2 w r)`.
pub fn contact_half_angle(s_c: f64, width: f64, radius: f64) -> f64 {
    // Seed 000 eq 43: α_A = S_c / (2 w_cyl r_A).
    s_c / (2.0 * width * radius)
}

/// Seed 000 eq 41 (corrected, see the module header): half angle (rad) at
/// the centre of circle A (radius `r_a`) of the chord where it overlaps
/// circle B (radius `r_b`) with penetration `penetration`, the centre
/// distance being `d = r_a + r_b − p`. NaN unless the circles cross
/// (`0 <= p <= 2 min(r_a, r_b)`).
pub fn circle_overlap_half_angle(r_a: f64, r_b: f64, penetration: f64) -> f64 {
    let d = r_a + r_b - penetration;
    let x = d * d + r_a * r_a - r_b * r_b;
    // Seed 000 eq 41: sin α_A = sqrt(4 d² r_A² − (d² + r_A² − r_B²)²) / (2 d r_A).
    let sin_alpha = (4.0 * d * d * r_a * r_a - x * x).sqrt() / (2.0 * d * r_a);
    sin_alpha.min(1.0).asin()
}

/// Seed 000 eq 42: theoretical contact surface of two overlapping cylinders
/// of width `width`, `S = 2 α_A r_A L`, with α_A from
/// [`circle_overlap_half_angle`].
pub fn circle_overlap_surface(r_a: f64, r_b: f64, penetration: f64, width: f64) -> f64 {
    // Seed 000 eq 42: S_c^th = 2 α_A^th r_A L.
    2.0 * circle_overlap_half_angle(r_a, r_b, penetration) * r_a * width
}

/// Two discs A and B joined by one pipe (seed 000 sec 5.1), quantities per
/// unit width.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PipeNetwork {
    /// Total pipe resistance R_AB (K·m/W), eq 33.
    pub r_ab: f64,
    /// Heat capacity of A per unit width, C_A = π ρ c r_A² (J/(K·m)), eq 37.
    pub cap_a: f64,
    /// Heat capacity of B per unit width (J/(K·m)), eq 37.
    pub cap_b: f64,
    /// Contact half angle α_A (rad) from eq 43.
    pub alpha_a: f64,
    /// Contact half angle α_B (rad) from eq 43.
    pub alpha_b: f64,
    /// Particle resistance R_A (K·m/W), eq 34 at α_A.
    pub res_a: f64,
    /// Particle resistance R_B (K·m/W), eq 34 at α_B.
    pub res_b: f64,
}

impl PipeNetwork {
    /// The pipe network adjusted to FDEM (seed 000 sec 5.2): capacities from
    /// eq 37, half angles from the FDEM contact surface `s_c` by eq 43,
    /// particle resistances by eq 34, and the total resistance matched to
    /// the FDEM contact resistance `rc` (per unit area) by eq 39,
    /// `R_AB = rc w / S_c`.
    ///
    /// Arguments: density `rho`, specific heat `c`, conductivities `k_a`,
    /// `k_b`, radii `r_a`, `r_b`, cylinder width `width`, contact surface
    /// `s_c`, contact resistance `rc`.
    ///
    /// # Panics
    /// If any argument is not positive and finite.
    #[allow(clippy::too_many_arguments)]
    pub fn fdem_adjusted(
        rho: f64,
        c: f64,
        k_a: f64,
        k_b: f64,
        r_a: f64,
        r_b: f64,
        width: f64,
        s_c: f64,
        rc: f64,
    ) -> PipeNetwork {
        for (name, v) in [
            ("rho", rho),
            ("c", c),
            ("k_a", k_a),
            ("k_b", k_b),
            ("r_a", r_a),
            ("r_b", r_b),
            ("width", width),
            ("s_c", s_c),
            ("rc", rc),
        ] {
            assert!(
                v.is_finite() && v > 0.0,
                "pipe network: {name} = {v} must be positive and finite"
            );
        }
        let alpha_a = contact_half_angle(s_c, width, r_a);
        let alpha_b = contact_half_angle(s_c, width, r_b);
        PipeNetwork {
            // Seed 000 eq 39: (T_B − T_A)/R_AB = (1/w) ΔT_c S_c / R_c with ΔT_c = T_B − T_A.
            r_ab: rc * width / s_c,
            // Seed 000 eq 37: C_A = π ρ c_p r_A².
            cap_a: PI * rho * c * r_a * r_a,
            cap_b: PI * rho * c * r_b * r_b,
            alpha_a,
            alpha_b,
            res_a: particle_resistance(k_a, alpha_a),
            res_b: particle_resistance(k_b, alpha_b),
        }
    }

    /// The pipe network's contact resistance R*_c (K·m/W).
    pub fn contact_resistance_star(&self) -> f64 {
        // Seed 000 eq 40 (with eq 33): R*_c = R_c w / S_c − R_A − R_B = R_AB − R_A − R_B.
        self.r_ab - self.res_a - self.res_b
    }

    /// Heat flow from B to A per unit width (W/m) at temperatures `t_a`, `t_b`.
    pub fn heat_flow(&self, t_a: f64, t_b: f64) -> f64 {
        // Seed 000 eq 35: T_B − T_A = R_AB Q_AB.
        (t_b - t_a) / self.r_ab
    }

    /// Time constant (s) of the exponential decay of `T_B − T_A`:
    /// `τ = R_AB / (1/C_A + 1/C_B)`.
    pub fn time_constant(&self) -> f64 {
        self.r_ab / (1.0 / self.cap_a + 1.0 / self.cap_b)
    }

    /// Forward-difference (explicit Euler) integration of eq 36 from
    /// `(t_a0, t_b0)` at t = 0: `steps` steps of size `dt`, returning the
    /// `steps + 1` states `(time, T_A, T_B)` including the initial one.
    /// Conserves `C_A T_A + C_B T_B` up to rounding; stable for
    /// `dt < 2 τ` ([`PipeNetwork::time_constant`]).
    pub fn explicit(&self, t_a0: f64, t_b0: f64, dt: f64, steps: usize) -> Vec<(f64, f64, f64)> {
        let mut out = Vec::with_capacity(steps + 1);
        let (mut t_a, mut t_b) = (t_a0, t_b0);
        out.push((0.0, t_a, t_b));
        for n in 1..=steps {
            let q = self.heat_flow(t_a, t_b);
            // Seed 000 eq 36: C_A (T_A^{n+1} − T_A^n)/Δt = Q_AB^n (and C_B for B with −Q_AB^n).
            t_a += dt * q / self.cap_a;
            t_b -= dt * q / self.cap_b;
            out.push((n as f64 * dt, t_a, t_b));
        }
        out
    }

    /// Exact solution of eqs 35–36 at time `t` from `(t_a0, t_b0)` at
    /// t = 0: `C_A T_A + C_B T_B` is conserved and `T_B − T_A` decays as
    /// `exp(−t/τ)` ([`PipeNetwork::time_constant`]). Returns `(T_A, T_B)`.
    pub fn exact(&self, t_a0: f64, t_b0: f64, t: f64) -> (f64, f64) {
        let c_sum = self.cap_a + self.cap_b;
        let mean = (self.cap_a * t_a0 + self.cap_b * t_b0) / c_sum;
        let diff = (t_b0 - t_a0) * (-t / self.time_constant()).exp();
        (
            mean - self.cap_b / c_sum * diff,
            mean + self.cap_a / c_sum * diff,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 000 Table 3 (width 0.1 m, see the module header) with the
    /// theoretical contact surface.
    fn table3(k: f64) -> PipeNetwork {
        let s_c = circle_overlap_surface(1.0, 1.0, 0.01, 0.1);
        PipeNetwork::fdem_adjusted(100.0, 1.0, k, k, 1.0, 1.0, 0.1, s_c, 1.0)
    }

    #[test]
    fn overlap_surface_of_table3_is_0_02() {
        let s = circle_overlap_surface(1.0, 1.0, 0.01, 0.1);
        assert!((s - 0.02).abs() < 1e-4, "{s}");
        // Width 1 m as printed in Table 3 would give 0.2 m², not 0.02 m².
        assert!((circle_overlap_surface(1.0, 1.0, 0.01, 1.0) - 0.2).abs() < 1e-3);
        // FDEM's computed 1.925e-2 m² is about 4 % below (seed 000 sec 5.3).
        assert!(((s - 0.01925) / s - 0.04).abs() < 5e-3);
    }

    #[test]
    fn overlap_half_angle_matches_law_of_cosines() {
        for (ra, rb, p) in [
            (1.0, 1.0, 0.01),
            (1.0, 2.0, 0.05),
            (0.5, 3.0, 0.2),
            (2.0, 0.7, 0.1),
        ] {
            let d: f64 = ra + rb - p;
            let cos = (d * d + ra * ra - rb * rb) / (2.0 * d * ra);
            let a = circle_overlap_half_angle(ra, rb, p);
            assert!((a - cos.acos()).abs() < 1e-9, "{ra} {rb} {p}: {a}");
            // Both circles see the same chord.
            let b = circle_overlap_half_angle(rb, ra, p);
            assert!((ra * a.sin() - rb * b.sin()).abs() < 1e-12);
        }
    }

    #[test]
    fn half_angle_round_trip_eq43_eq42() {
        for (r, p, w) in [(1.0, 0.01, 0.1), (0.5, 0.02, 0.3), (2.0, 0.001, 1.0)] {
            let alpha = circle_overlap_half_angle(r, r, p);
            let s = circle_overlap_surface(r, r, p, w);
            assert!((contact_half_angle(s, w, r) - alpha).abs() < 1e-14 * alpha.max(1.0));
        }
    }

    #[test]
    fn particle_resistance_decreases_with_contact_angle() {
        let mut prev = f64::INFINITY;
        for i in 1..=500 {
            let a = 0.001 * i as f64;
            let r = particle_resistance(1.0, a);
            assert!(r > 0.0 && r < prev, "alpha {a}: {r} >= {prev}");
            prev = r;
        }
        let r = particle_resistance(2.0, 0.1);
        let expect = (-(0.1f64).ln() + 1.5 + 0.01 / 36.0) / (2.0 * PI);
        assert!((r - expect).abs() < 1e-15);
    }

    #[test]
    fn table3_adjustment() {
        let net = table3(1.0);
        let s_c = circle_overlap_surface(1.0, 1.0, 0.01, 0.1);
        assert!((net.r_ab - 0.1 / s_c).abs() < 1e-14);
        assert!((net.cap_a - 100.0 * PI).abs() < 1e-12 && net.cap_a == net.cap_b);
        assert_eq!(net.alpha_a, net.alpha_b);
        assert!((net.alpha_a - circle_overlap_half_angle(1.0, 1.0, 0.01)).abs() < 1e-14);
        let rs = net.contact_resistance_star();
        assert!((rs + net.res_a + net.res_b - net.r_ab).abs() < 1e-14);
        assert!(rs > 0.0 && net.res_a > 1.0 && net.res_a < 1.3, "{net:?}");
        // A hundred times the conductivity leaves R_AB and shrinks R_A.
        let hot = table3(100.0);
        assert_eq!(hot.r_ab, net.r_ab);
        assert!((hot.res_a * 100.0 - net.res_a).abs() < 1e-12);
    }

    #[test]
    fn explicit_conserves_heat() {
        let net = PipeNetwork::fdem_adjusted(100.0, 1.0, 1.0, 3.0, 1.0, 0.6, 0.1, 0.02, 1.0);
        let total = |a: f64, b: f64| net.cap_a * a + net.cap_b * b;
        let e0 = total(0.0, 1.0);
        for (_, a, b) in net.explicit(0.0, 1.0, 1.0, 5000) {
            assert!((total(a, b) - e0).abs() < 1e-12 * e0);
        }
        let (a, b) = net.exact(0.0, 1.0, 1234.5);
        assert!((total(a, b) - e0).abs() < 1e-12 * e0);
    }

    #[test]
    fn explicit_converges_to_exact_first_order() {
        let net = table3(1.0);
        let t_end = 1000.0;
        let (ea, eb) = net.exact(0.0, 1.0, t_end);
        let mut prev_err = f64::NAN;
        for dt in [40.0, 20.0, 10.0, 5.0, 2.5] {
            let steps = (t_end / dt).round() as usize;
            let hist = net.explicit(0.0, 1.0, dt, steps);
            assert_eq!(hist.len(), steps + 1);
            let (t, a, b) = hist[steps];
            assert!((t - t_end).abs() < 1e-9);
            let err = (a - ea).abs().max((b - eb).abs());
            if prev_err.is_finite() {
                let ratio = prev_err / err;
                assert!((ratio - 2.0).abs() < 0.1, "dt {dt}: ratio {ratio}");
            }
            prev_err = err;
        }
        assert!(prev_err < 1e-3, "{prev_err}");
        // Exact solution: initial state, and the limit at the capacity-weighted mean.
        assert_eq!(net.exact(0.0, 1.0, 0.0), (0.0, 1.0));
        let (a, b) = net.exact(0.0, 1.0, 1e6);
        assert!((a - 0.5).abs() < 1e-12 && (b - 0.5).abs() < 1e-12);
    }
}
