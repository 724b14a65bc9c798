//! Isotropic thermo-visco-elastic material of the finite-strain Tet4
//! (seed 004 sec 2.3–2.5, Table 1): Young's modulus and Poisson's ratio
//! give the Lamé constants of the neo-Hookean law (eq 34), the viscosity η
//! the dissipative stress (eq 35), the linear expansion coefficient α the
//! thermal stretch 1 + α ΔT (eq 25).

use super::MechanicsError;

/// Material constants of one body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticMaterial {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν (–), in (−1, 0.5).
    pub poisson: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Linear thermal expansion coefficient α (1/K).
    pub expansion: f64,
    /// Viscosity η of the dissipative stress 2 η D (Pa·s), >= 0.
    pub viscosity: f64,
}

impl ElasticMaterial {
    /// A purely elastic material: no thermal expansion, no viscosity.
    pub fn elastic(young: f64, poisson: f64, density: f64) -> Self {
        ElasticMaterial {
            young,
            poisson,
            density,
            expansion: 0.0,
            viscosity: 0.0,
        }
    }

    /// Lamé constants `(mu, lambda)` (Pa).
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        // Seed 004 Table 1 (μ = 8.33, λ = 5.56 GPa from E = 20 GPa, ν = 0.2): μ = E/(2(1+ν)), λ = Eν/((1+ν)(1−2ν)).
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        (mu, lambda)
    }

    /// P-wave modulus λ + 2μ (Pa), the stiffness of uniaxial strain.
    pub fn p_wave_modulus(&self) -> f64 {
        let (mu, lambda) = self.lame();
        lambda + 2.0 * mu
    }

    /// Dilatational (P) wave speed sqrt((λ + 2μ)/ρ) (m/s), which bounds the
    /// stable explicit time step.
    pub fn p_wave_speed(&self) -> f64 {
        (self.p_wave_modulus() / self.density).sqrt()
    }

    /// Checks that the constants are finite and physical: E > 0,
    /// −1 < ν < 0.5, ρ > 0, α finite, η >= 0.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        let bad = |msg: String| Err(MechanicsError::InvalidMaterial(msg));
        if !(self.young.is_finite() && self.young > 0.0) {
            return bad(format!(
                "Young's modulus must be positive, got {}",
                self.young
            ));
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return bad(format!(
                "Poisson's ratio must lie in (-1, 0.5), got {}",
                self.poisson
            ));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad(format!("density must be positive, got {}", self.density));
        }
        if !self.expansion.is_finite() {
            return bad(format!(
                "expansion coefficient must be finite, got {}",
                self.expansion
            ));
        }
        if !(self.viscosity.is_finite() && self.viscosity >= 0.0) {
            return bad(format!(
                "viscosity must be non-negative, got {}",
                self.viscosity
            ));
        }
        Ok(())
    }
}

/// Seed 004 Table 1 (concrete): E = 20 GPa, ν = 0.2, α = 1e-6 /K (per the
/// seeds README); the table gives no density, so 2400 kg/m³. For tests.
#[cfg(test)]
pub(crate) fn table1_concrete() -> ElasticMaterial {
    ElasticMaterial {
        young: 20e9,
        poisson: 0.2,
        density: 2400.0,
        expansion: 1e-6,
        viscosity: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lame_constants_match_table_1() {
        let (mu, lambda) = table1_concrete().lame();
        // Table 1 prints 8.33 and 5.56 GPa: tolerance half a unit of the last digit (0.005 GPa).
        assert!((mu - 8.33e9).abs() <= 0.005e9, "mu = {mu}");
        assert!((lambda - 5.56e9).abs() <= 0.005e9, "lambda = {lambda}");
        // λ + 2μ = E(1−ν)/((1+ν)(1−2ν)) exactly (round-off tolerance).
        let m = 20e9 * 0.8 / (1.2 * 0.6);
        assert!((table1_concrete().p_wave_modulus() / m - 1.0).abs() < 1e-14);
        let c = (m / 2400.0).sqrt();
        assert!((table1_concrete().p_wave_speed() / c - 1.0).abs() < 1e-14);
    }

    #[test]
    fn validation_rejects_unphysical_constants() {
        assert!(table1_concrete().validate().is_ok());
        let mut m = table1_concrete();
        m.poisson = 0.5;
        assert!(m.validate().is_err());
        let mut m = table1_concrete();
        m.density = 0.0;
        assert!(m.validate().is_err());
        let mut m = table1_concrete();
        m.viscosity = -1.0;
        assert!(m.validate().is_err());
        let mut m = table1_concrete();
        m.young = f64::NAN;
        assert!(m.validate().is_err());
    }
}
