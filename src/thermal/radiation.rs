//! Radiation kernels (issue 20, seed 001 sec 7.1.6): the grey-body
//! emission of a surface node to an ambient, lumped to the nodes, and the
//! exchange factor of two grey surfaces. Pure: no MPI or PETSc.

/// The Stefan–Boltzmann constant σ (W/m²/K⁴, CODATA 2018).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;

/// Seed 001 sec 7.1.6: the net radiated power of a node whose free area
/// times emissivity times σ is `coef` (W/K⁴), at temperature `t` (scenario
/// unit) with `offset` making it absolute, to an ambient of absolute
/// temperature⁴ `ambient4`: q = coef ((t + offset)⁴ − T_env⁴).
#[inline]
pub fn emitted(coef: f64, t: f64, offset: f64, ambient4: f64) -> f64 {
    let a = t + offset;
    coef * ((a * a) * (a * a) - ambient4)
}

/// dq/dt of [`emitted`]: 4 coef (t + offset)³.
#[inline]
pub fn emitted_slope(coef: f64, t: f64, offset: f64) -> f64 {
    let a = t + offset;
    4.0 * coef * a * a * a
}

/// The exchange factor of two parallel grey surfaces of emissivities
/// `e1` and `e2` (seed 001 sec 7.1.6): 1 / (1/ε₁ + 1/ε₂ − 1).
pub fn grey_exchange(e1: f64, e2: f64) -> f64 {
    1.0 / (1.0 / e1 + 1.0 / e2 - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emission_vanishes_at_the_ambient_and_its_slope_is_the_derivative() {
        let (coef, off) = (0.8 * STEFAN_BOLTZMANN * 0.06, 273.15);
        let amb = (20.0_f64 + off).powi(4);
        assert!(emitted(coef, 20.0, off, amb).abs() < 1e-12);
        let t = 500.0;
        let h = 1e-3;
        let fd = (emitted(coef, t + h, off, amb) - emitted(coef, t - h, off, amb)) / (2.0 * h);
        assert!((emitted_slope(coef, t, off) - fd).abs() < 1e-7 * fd.abs());
    }

    #[test]
    fn black_plates_exchange_fully_and_grey_ones_less() {
        assert_eq!(grey_exchange(1.0, 1.0), 1.0);
        // ε = 0.8 both: 1/(1.25 + 1.25 − 1) = 2/3.
        assert!((grey_exchange(0.8, 0.8) - 2.0 / 3.0).abs() < 1e-15);
    }
}
