//! Contact conductance that follows the contact pressure (issue 20; seed
//! 000 sec 8 names the link, seed 001 sec 7.1.4 lists the models): the
//! Cooper–Mikic–Yovanovich correlation for plastically deformed rough
//! surfaces. Pure: no MPI or PETSc.

use serde::{Deserialize, Serialize};

/// The Cooper–Mikic–Yovanovich model's surface constants.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cmy {
    /// Combined RMS roughness σ = √(σ_a² + σ_b²) (m).
    pub roughness: f64,
    /// Combined RMS asperity slope m = √(m_a² + m_b²).
    pub slope: f64,
    /// Micro-hardness H_c of the softer surface (Pa).
    pub hardness: f64,
    /// Prescribed contact pressure P (Pa). Thermal runs need it; a run
    /// with mechanics takes each pair's from the penalty contact unless
    /// it is given.
    #[serde(default)]
    pub pressure: Option<f64>,
}

impl Cmy {
    /// The constants' errors, naming the key under `key`.
    pub fn check(&self, key: &str) -> Result<(), String> {
        for (name, v) in [
            ("roughness", self.roughness),
            ("slope", self.slope),
            ("hardness", self.hardness),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key}.{name}: must be positive, got {v}"));
            }
        }
        match self.pressure {
            Some(p) if !(p.is_finite() && p >= 0.0) => Err(format!(
                "{key}.pressure: must be non-negative (Pa), got {p}"
            )),
            _ => Ok(()),
        }
    }
}

/// Cooper–Mikic–Yovanovich: h = 1.25 k_s (m/σ) (P/H_c)^0.95 (W/m²/K),
/// with k_s = 2 k_a k_b / (k_a + k_b) the harmonic mean of the two
/// conductivities, at contact pressure `pressure` (Pa).
pub fn cmy_conductance(k_a: f64, k_b: f64, c: &Cmy, pressure: f64) -> f64 {
    let ks = 2.0 * k_a * k_b / (k_a + k_b);
    1.25 * ks * (c.slope / c.roughness) * (pressure.max(0.0) / c.hardness).powf(0.95)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_conductance_grows_almost_linearly_with_pressure() {
        let c = Cmy {
            roughness: 1e-6,
            slope: 0.1,
            hardness: 1e9,
            pressure: None,
        };
        // Steel on steel (k = 50): 1.25 × 50 × 1e5 × (1e7/1e9)^0.95.
        let h = cmy_conductance(50.0, 50.0, &c, 1e7);
        let want = 1.25 * 50.0 * 1e5 * 0.01f64.powf(0.95);
        assert!((h - want).abs() < 1e-9 * want);
        assert!((cmy_conductance(50.0, 50.0, &c, 2e7) / h - 2f64.powf(0.95)).abs() < 1e-12);
        assert_eq!(cmy_conductance(50.0, 50.0, &c, 0.0), 0.0);
        // The harmonic mean: a poor conductor dominates.
        let hm = cmy_conductance(1.0, 1e6, &c, 1e7) / cmy_conductance(1.0, 1.0, &c, 1e7);
        assert!((hm - 2.0 * 1e6 / (1e6 + 1.0)).abs() < 1e-9);
        assert!(c.check("contact.cmy").is_ok());
        let bad = Cmy {
            hardness: -1.0,
            ..c
        };
        assert!(bad
            .check("contact.cmy")
            .unwrap_err()
            .contains("contact.cmy.hardness"));
    }
}
