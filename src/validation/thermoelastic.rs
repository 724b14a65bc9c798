//! Analytic thermoelastic references for thin discs (plane stress, free
//! flat faces): the hollow cylinder of seed 004 sec 3.3 (steady logarithmic
//! temperature, eq 39) and the steel core bonded in a concrete ring of seed
//! 004 sec 4 (uniform heating, eq 40).
//!
//! # How the extracted equations were read
//!
//! * Eq 39 lost its structure in extraction (its temperature reads
//!   `Ta + (Tb − Ta) ln a / ln b`, and `a²/b²` appears where `a²/r²`
//!   belongs). We use the textbook plane-stress solution for a thin annular
//!   disc with free edges (Timoshenko & Goodier, Theory of Elasticity, thin
//!   disc with axisymmetric temperature), [`annulus_stress_from_integrals`],
//!   which for the logarithmic field reduces to
//!   `σ_r = αEΔ/2 [−ln(r/a)/ln(b/a) + (1 − a²/r²) b²/(b² − a²)]`,
//!   `σ_θ = αEΔ/2 [−(1 + ln(r/a))/ln(b/a) + (1 + a²/r²) b²/(b² − a²)]`,
//!   `Δ = T_b − T_a`: the seed's eq 39 with `a²/r²` restored.
//! * Eq 40 is garbled too; it is re-derived here from the compatibility of
//!   the radial displacement at the interface (see [`BondedDisc`]). In the
//!   seed's notation (`a` the steel core, `b` the concrete ring)
//!   `p = (α_a − α_b) ΔT E_a / [E_a/E_b (β + ν_b) + (1 − ν_a)]`, which is
//!   the same expression divided through by `E_a`.
//! * Sec 4 gives the "ten times smaller" expansion coefficients as
//!   `α = 7.2e-7` (concrete) and `2.2e-6` /°C (steel), while Table 3 lists
//!   `7.0e-6` for concrete; [`BondedDisc::seed_004_sec4`] uses the text's
//!   values.
//!
//! Stresses are in Pa (tension positive), temperatures in °C measured from
//! the stress-free temperature, lengths in m. In plane stress the thermal
//! stresses of a free disc do not depend on Poisson's ratio.

/// Seed 004 sec 3.3: steady temperature in a hollow cylinder with
/// `T(a) = t_a`, `T(b) = t_b` (adiabatic flat faces).
pub fn hollow_cylinder_temperature(r: f64, a: f64, b: f64, t_a: f64, t_b: f64) -> f64 {
    // Seed 004 eq 39, first line (garbled to "Ta + (Tb − Ta) ln a / ln b"): T = Ta + (Tb − Ta) ln(r/a)/ln(b/a).
    t_a + (t_b - t_a) * (r / a).ln() / (b / a).ln()
}

/// `∫_a^r ln(s/a) s ds = r²/2 ln(r/a) − r²/4 + a²/4`.
pub fn log_moment(r: f64, a: f64) -> f64 {
    0.5 * r * r * (r / a).ln() - 0.25 * r * r + 0.25 * a * a
}

/// Plane-stress thermal stresses `(σ_r, σ_θ)` at radius `r` of a thin
/// annular disc `a ≤ r ≤ b` with free edges and an axisymmetric
/// temperature `T(r)` (Timoshenko & Goodier):
/// `σ_r = αE/r² [(r² − a²)/(b² − a²) I_b − I_r]`,
/// `σ_θ = αE/r² [(r² + a²)/(b² − a²) I_b + I_r − T r²]`,
/// given `alpha_e = αE`, `t_r = T(r)`, `i_r = ∫_a^r T s ds` and
/// `i_b = ∫_a^b T s ds`, with `T` measured from the stress-free temperature.
pub fn annulus_stress_from_integrals(
    r: f64,
    a: f64,
    b: f64,
    alpha_e: f64,
    t_r: f64,
    i_r: f64,
    i_b: f64,
) -> (f64, f64) {
    let d = b * b - a * a;
    let r2 = r * r;
    // Seed 004 eq 39 (garbled in the text; textbook plane-stress thin disc): σ_r = αE/r² [(r²−a²)/(b²−a²) ∫_a^b T r dr − ∫_a^r T r dr].
    let s_r = alpha_e / r2 * ((r2 - a * a) / d * i_b - i_r);
    // Seed 004 eq 39 (garbled in the text; textbook plane-stress thin disc): σ_θ = αE/r² [(r²+a²)/(b²−a²) ∫_a^b T r dr + ∫_a^r T r dr − T r²].
    let s_t = alpha_e / r2 * ((r2 + a * a) / d * i_b + i_r - t_r * r2);
    (s_r, s_t)
}

/// The thin hollow cylinder of seed 004 sec 3.3: steady conduction between
/// `T(a) = t_a` and `T(b) = t_b`, free edges and faces (plane stress).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HollowCylinder {
    /// Inner radius a (m).
    pub inner_radius: f64,
    /// Outer radius b (m).
    pub outer_radius: f64,
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν (does not enter the plane-stress stresses).
    pub poisson: f64,
    /// Linear thermal expansion coefficient α (1/°C).
    pub alpha: f64,
    /// Inner temperature T_a (°C).
    pub t_inner: f64,
    /// Outer temperature T_b (°C).
    pub t_outer: f64,
    /// Stress-free (initial) temperature (°C).
    pub t_ref: f64,
}

impl HollowCylinder {
    /// Seed 004 sec 3.3, Table 2: a = 0.03 m, b = 0.15 m, E = 20 GPa,
    /// ν = 0.2, α = 5e-6 /°C, T_a = 0, T_b = 100, initial temperature 0.
    pub fn seed_004() -> Self {
        HollowCylinder {
            inner_radius: 0.03,
            outer_radius: 0.15,
            young: 20e9,
            poisson: 0.2,
            alpha: 5e-6,
            t_inner: 0.0,
            t_outer: 100.0,
            t_ref: 0.0,
        }
    }

    /// Steady temperature at radius r.
    pub fn temperature(&self, r: f64) -> f64 {
        hollow_cylinder_temperature(
            r,
            self.inner_radius,
            self.outer_radius,
            self.t_inner,
            self.t_outer,
        )
    }

    /// Plane-stress `(σ_r, σ_θ)` at radius r (Pa): [`annulus_stress_from_integrals`]
    /// with the closed-form integrals of the logarithmic field.
    pub fn stress(&self, r: f64) -> (f64, f64) {
        let (a, b) = (self.inner_radius, self.outer_radius);
        let l = (b / a).ln();
        let dt = self.t_outer - self.t_inner;
        let t0 = self.t_inner - self.t_ref;
        // T − T_ref = t0 + dt ln(r/a)/l, so ∫_a^r (T − T_ref) s ds = t0 (r² − a²)/2 + dt/l log_moment(r).
        let moment = |x: f64| 0.5 * t0 * (x * x - a * a) + dt / l * log_moment(x, a);
        annulus_stress_from_integrals(
            r,
            a,
            b,
            self.alpha * self.young,
            self.temperature(r) - self.t_ref,
            moment(r),
            moment(b),
        )
    }

    /// The same stresses in the simplified closed form (seed 004 eq 39 with
    /// `a²/r²` restored): `σ_r = αEΔ/2 [−ln(r/a)/L + (1 − a²/r²) b²/(b² − a²)]`,
    /// `σ_θ = αEΔ/2 [−(1 + ln(r/a))/L + (1 + a²/r²) b²/(b² − a²)]`,
    /// `Δ = T_b − T_a`, `L = ln(b/a)`. A uniform offset of the temperature
    /// causes no stress in a free disc.
    pub fn stress_closed_form(&self, r: f64) -> (f64, f64) {
        let (a, b) = (self.inner_radius, self.outer_radius);
        let l = (b / a).ln();
        let k = 0.5 * self.alpha * self.young * (self.t_outer - self.t_inner);
        let g = b * b / (b * b - a * a);
        let q = a * a / (r * r);
        let lr = (r / a).ln();
        // Seed 004 eq 39 (garbled in the text: a²/b² read for a²/r²): σ_rr = αE(Tb−Ta)/2 [−ln(r/a)/ln(b/a) + (1 − a²/r²) b²/(b²−a²)].
        let s_r = k * (-lr / l + (1.0 - q) * g);
        // Seed 004 eq 39 (garbled in the text: a²/b² read for a²/r²): σ_θθ = αE(Tb−Ta)/2 [−(1 + ln(r/a))/ln(b/a) + (1 + a²/r²) b²/(b²−a²)].
        let s_t = k * (-(1.0 + lr) / l + (1.0 + q) * g);
        (s_r, s_t)
    }
}

/// Elastic and thermal properties of one material of [`BondedDisc`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscMaterial {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Linear thermal expansion coefficient α (1/°C).
    pub alpha: f64,
}

/// A thin disc (plane stress, free faces): a solid core `r ≤ a` perfectly
/// bonded inside a ring `a ≤ r ≤ b` with a free outer edge, both heated
/// uniformly by `ΔT` (seed 004 sec 4, eq 40).
///
/// Compatibility of the radial displacement at `r = a`:
/// core (solid disc under uniform external pressure p, σ_r = σ_θ = −p):
/// `u = α_s ΔT a − p a (1 − ν_s)/E_s`; ring (Lamé, internal pressure p,
/// free at b): `u = α_c ΔT a + p a/E_c (β + ν_c)`, `β = (b² + a²)/(b² − a²)`;
/// so `p = (α_s − α_c) ΔT / [(1 − ν_s)/E_s + (β + ν_c)/E_c]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondedDisc {
    /// Core radius a (m).
    pub core_radius: f64,
    /// Outer radius b of the ring (m).
    pub outer_radius: f64,
    /// Core material (steel in the seed).
    pub core: DiscMaterial,
    /// Ring material (concrete in the seed).
    pub ring: DiscMaterial,
    /// Uniform temperature rise from the stress-free state (°C).
    pub delta_t: f64,
}

impl BondedDisc {
    /// Seed 004 sec 4 (Table 3, with the text's expansion coefficients ten
    /// times below the experiment's): steel core a = 0.03 m (E = 40 GPa,
    /// ν = 0.3, α = 2.2e-6 /°C) in a concrete ring b = 0.15 m (E = 20 GPa,
    /// ν = 0.2, α = 7.2e-7 /°C), ΔT = 100 °C.
    pub fn seed_004_sec4() -> Self {
        BondedDisc {
            core_radius: 0.03,
            outer_radius: 0.15,
            core: DiscMaterial {
                young: 40e9,
                poisson: 0.3,
                alpha: 2.2e-6,
            },
            ring: DiscMaterial {
                young: 20e9,
                poisson: 0.2,
                alpha: 7.2e-7,
            },
            delta_t: 100.0,
        }
    }

    /// Seed 004 sec 4 with the experiment's expansion coefficients (Table 3,
    /// ten times [`Self::seed_004_sec4`]'s: 2.2e-5 /°C for the steel, 7.2e-6
    /// /°C for the concrete as the text gives it; Table 3 prints 7.0e-6):
    /// the case that cracks.
    pub fn seed_004_experiment() -> Self {
        let mut d = Self::seed_004_sec4();
        d.core.alpha = 2.2e-5;
        d.ring.alpha = 7.2e-6;
        d
    }

    /// `β = (b² + a²)/(b² − a²)`.
    pub fn beta(&self) -> f64 {
        let (a2, b2) = (self.core_radius.powi(2), self.outer_radius.powi(2));
        (b2 + a2) / (b2 - a2)
    }

    /// Interface pressure p (Pa, positive when the core pushes on the ring).
    pub fn interface_pressure(&self) -> f64 {
        let (s, c) = (self.core, self.ring);
        // Seed 004 eq 40 (garbled in the text; re-derived): p = (α_s − α_c) ΔT / [(1 − ν_s)/E_s + (β + ν_c)/E_c].
        (s.alpha - c.alpha) * self.delta_t
            / ((1.0 - s.poisson) / s.young + (self.beta() + c.poisson) / c.young)
    }

    /// `(σ_r, σ_θ)` (Pa) at radius r: `(−p, −p)` in the core (`r < a`),
    /// the Lamé solution in the ring (`a ≤ r ≤ b`).
    pub fn stress(&self, r: f64) -> (f64, f64) {
        let p = self.interface_pressure();
        if r < self.core_radius {
            return (-p, -p);
        }
        let (a2, b2, r2) = (self.core_radius.powi(2), self.outer_radius.powi(2), r * r);
        // Seed 004 eq 40 (garbled in the text; re-derived): σ_r = −p a² (b² − r²) / (r² (b² − a²)).
        let s_r = -p * a2 * (b2 - r2) / (r2 * (b2 - a2));
        // Seed 004 eq 40: σ_θ = p a² (b² + r²) / (r² (b² − a²)).
        let s_t = p * a2 * (b2 + r2) / (r2 * (b2 - a2));
        (s_r, s_t)
    }

    /// Radial displacement u(r) (m) from the plane-stress strains
    /// `u/r = (σ_θ − ν σ_r)/E + α ΔT` of the material at r.
    pub fn radial_displacement(&self, r: f64) -> f64 {
        let m = if r < self.core_radius {
            self.core
        } else {
            self.ring
        };
        let (s_r, s_t) = self.stress(r);
        r * ((s_t - m.poisson * s_r) / m.young + m.alpha * self.delta_t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Composite Simpson integral of f over [lo, hi] with n (even) panels.
    fn simpson(f: impl Fn(f64) -> f64, lo: f64, hi: f64, n: usize) -> f64 {
        let dx = (hi - lo) / n as f64;
        let mut s = f(lo) + f(hi);
        for i in 1..n {
            let w = if i % 2 == 1 { 4.0 } else { 2.0 };
            s += w * f(lo + dx * i as f64);
        }
        s * dx / 3.0
    }

    #[test]
    fn temperature_boundary_values() {
        let c = HollowCylinder::seed_004();
        assert_eq!(c.temperature(0.03), 0.0);
        assert!((c.temperature(0.15) - 100.0).abs() < 1e-12);
        // Harmonic: r dT/dr constant.
        let d = |r: f64| r * (c.temperature(r * 1.0001) - c.temperature(r * 0.9999)) / (0.0002 * r);
        assert!((d(0.05) - d(0.12)).abs() < 1e-6 * d(0.05).abs());
    }

    #[test]
    fn log_moment_matches_quadrature() {
        let a = 0.03;
        for r in [0.03, 0.05, 0.1, 0.15] {
            let q = simpson(|s| (s / a).ln() * s, a, r, 2000);
            assert!((log_moment(r, a) - q).abs() < 1e-12, "r {r}");
        }
    }

    #[test]
    fn hollow_cylinder_closed_form_matches_quadrature() {
        // Also with a non-zero inner temperature and reference temperature.
        let mut shifted = HollowCylinder::seed_004();
        shifted.t_inner = 20.0;
        shifted.t_outer = -35.0;
        shifted.t_ref = 7.0;
        for c in [HollowCylinder::seed_004(), shifted] {
            let (a, b) = (c.inner_radius, c.outer_radius);
            let t = |s: f64| c.temperature(s) - c.t_ref;
            let i_b = simpson(|s| t(s) * s, a, b, 4000);
            let scale = c.alpha * c.young * (c.t_outer - c.t_inner).abs();
            for k in 0..=24 {
                let r = a + (b - a) * k as f64 / 24.0;
                let i_r = simpson(|s| t(s) * s, a, r, 4000);
                let q = annulus_stress_from_integrals(r, a, b, c.alpha * c.young, t(r), i_r, i_b);
                let s = c.stress(r);
                let f = c.stress_closed_form(r);
                for (x, y) in [(q.0, s.0), (q.1, s.1), (s.0, f.0), (s.1, f.1)] {
                    assert!((x - y).abs() < 1e-9 * scale, "r {r}: {x} vs {y}");
                }
            }
            // Free edges.
            for r in [a, b] {
                assert!(c.stress(r).0.abs() < 1e-12 * scale, "σ_r({r})");
                assert!(c.stress_closed_form(r).0.abs() < 1e-12 * scale);
            }
        }
    }

    #[test]
    fn hollow_cylinder_equilibrium_and_compatibility() {
        let c = HollowCylinder::seed_004();
        let e = 1e-6;
        for k in 1..20 {
            let r = 0.03 + 0.12 * k as f64 / 20.0;
            let (s_r, s_t) = c.stress(r);
            let ds_r = (c.stress(r + e).0 - c.stress(r - e).0) / (2.0 * e);
            // dσ_r/dr + (σ_r − σ_θ)/r = 0.
            assert!((ds_r + (s_r - s_t) / r).abs() < 1e-6 * 1e6 / r, "r {r}");
            // Compatibility: ε_r = d(r ε_θ)/dr with ε = (σ − νσ')/E + αT.
            let eps_t = |r: f64| {
                let (s_r, s_t) = c.stress(r);
                (s_t - c.poisson * s_r) / c.young + c.alpha * (c.temperature(r) - c.t_ref)
            };
            let eps_r = (s_r - c.poisson * s_t) / c.young + c.alpha * (c.temperature(r) - c.t_ref);
            let d = ((r + e) * eps_t(r + e) - (r - e) * eps_t(r - e)) / (2.0 * e);
            assert!((d - eps_r).abs() < 1e-9, "r {r}: {d} vs {eps_r}");
        }
    }

    #[test]
    fn hollow_cylinder_seed_004_values() {
        let c = HollowCylinder::seed_004();
        let (a, b) = (c.inner_radius, c.outer_radius);
        let (_, st_a) = c.stress(a);
        let (_, st_b) = c.stress(b);
        let r_max = (0..=1200)
            .map(|k| a + (b - a) * k as f64 / 1200.0)
            .max_by(|x, y| c.stress(*x).0.total_cmp(&c.stress(*y).0))
            .unwrap();
        println!(
            "seed 004 hollow cylinder: σ_θ(a) = {:.4} MPa, σ_θ(b) = {:.4} MPa, \
             max σ_r = {:.4} MPa at r = {:.4} m",
            st_a / 1e6,
            st_b / 1e6,
            c.stress(r_max).0 / 1e6,
            r_max
        );
        assert!(c.stress(r_max).0 > 0.0);
        // αEΔ/2 = 5 MPa; σ_θ(a) = 5 MPa (2b²/(b²−a²) − 1/ln 5).
        let l = 5f64.ln();
        let expect_a = 5e6 * (2.0 * 0.0225 / 0.0216 - 1.0 / l);
        let expect_b = 5e6 * (0.0234 / 0.0216 - (1.0 + l) / l);
        assert!((st_a - expect_a).abs() < 1e-6);
        assert!((st_b - expect_b).abs() < 1e-6);
        assert!((st_a / 1e6 - 7.3100).abs() < 1e-3, "{st_a}");
        assert!((st_b / 1e6 + 2.6900).abs() < 1e-3, "{st_b}");
        // Hoop stress resultant vanishes: ∫_a^b σ_θ dr = 0 (free edges).
        let n = simpson(|r| c.stress(r).1, a, b, 4000);
        assert!(n.abs() < 1e-6 * 1e6 * (b - a));
    }

    #[test]
    fn bonded_disc_seed_004_values() {
        let d = BondedDisc::seed_004_sec4();
        let p = d.interface_pressure();
        let beta = d.beta();
        let (s_r_a, s_t_a) = d.stress(d.core_radius);
        println!(
            "seed 004 steel in concrete: β = {beta:.6}, p = {:.4} MPa, σ_θ(a) = {:.4} MPa, \
             σ_θ(b) = {:.4} MPa",
            p / 1e6,
            s_t_a / 1e6,
            d.stress(d.outer_radius).1 / 1e6
        );
        assert!((beta - 0.0234 / 0.0216).abs() < 1e-12);
        let expect = 1.48e-4 / (0.7 / 40e9 + (beta + 0.2) / 20e9);
        assert!((p - expect).abs() < 1e-6 * expect);
        assert!((p / 1e6 - 1.8122).abs() < 1e-4, "{p}");
        assert!((s_t_a - p * beta).abs() < 1e-9 * p);
        assert!((s_t_a / 1e6 - 1.9633).abs() < 1e-4, "{s_t_a}");
        // Radial stress continuous at the interface, zero at the free edge.
        assert!((s_r_a + p).abs() < 1e-9 * p);
        assert_eq!(d.stress(0.5 * d.core_radius), (-p, -p));
        assert!(d.stress(d.outer_radius).0.abs() < 1e-9 * p);
        // Seed's form: p = (α_a − α_b) ΔT E_a / [E_a/E_b (β + ν_b) + (1 − ν_a)].
        let (s, c) = (d.core, d.ring);
        let seed = (s.alpha - c.alpha) * d.delta_t * s.young
            / (s.young / c.young * (beta + c.poisson) + (1.0 - s.poisson));
        assert!((seed - p).abs() < 1e-12 * p);
    }

    #[test]
    fn bonded_disc_compatibility_and_equilibrium() {
        let mut hot = BondedDisc::seed_004_sec4();
        hot.core.alpha = 2.2e-5;
        hot.ring.alpha = 7.0e-6;
        for d in [BondedDisc::seed_004_sec4(), hot] {
            let (a, b) = (d.core_radius, d.outer_radius);
            let p = d.interface_pressure();
            // Interface displacement continuous.
            let u_core = d.radial_displacement(a * (1.0 - 1e-15));
            let u_ring = d.radial_displacement(a);
            assert!(
                (u_core - u_ring).abs() < 1e-12 * u_ring.abs(),
                "{u_core} vs {u_ring}"
            );
            let u_core_formula =
                d.core.alpha * d.delta_t * a - p * a * (1.0 - d.core.poisson) / d.core.young;
            assert!((u_core - u_core_formula).abs() < 1e-12 * u_core.abs());
            let u_ring_formula =
                d.ring.alpha * d.delta_t * a + p * a / d.ring.young * (d.beta() + d.ring.poisson);
            assert!((u_ring - u_ring_formula).abs() < 1e-12 * u_ring.abs());
            // Equilibrium in the ring and compatibility ε_r = du/dr.
            let e = 1e-7;
            for k in 1..20 {
                let r = a + (b - a) * k as f64 / 20.0;
                let (s_r, s_t) = d.stress(r);
                let ds_r = (d.stress(r + e).0 - d.stress(r - e).0) / (2.0 * e);
                assert!((ds_r + (s_r - s_t) / r).abs() < 1e-6 * p / r, "r {r}");
                let du = (d.radial_displacement(r + e) - d.radial_displacement(r - e)) / (2.0 * e);
                let m = d.ring;
                let eps_r = (s_r - m.poisson * s_t) / m.young + m.alpha * d.delta_t;
                assert!(
                    (du - eps_r).abs() < 1e-7 * eps_r.abs(),
                    "r {r}: {du} vs {eps_r}"
                );
            }
        }
        println!(
            "with the experiment's α (2.2e-5, 7.0e-6): p = {:.3} MPa, σ_θ(a) = {:.3} MPa",
            hot.interface_pressure() / 1e6,
            hot.stress(hot.core_radius).1 / 1e6
        );
    }
}
