//! Contact and gap heat whose conductance depends on temperature (issue
//! 20): a tabular h(T, P, gap) (seed 001 sec 7.1.4) or the gap medium's
//! k(T)/gap (seed 001 sec 7.1.5). Each pair or gap link is a unit: the
//! Laplacian Λ of its node-to-node links at unit conductance, the weights
//! m of its mean temperature T̄ = mᵀT, and its law g(T̄). The heat leaving
//! the unit's rows is q = g(T̄) Λ T, with the Jacobian
//!   ∂q/∂T = g Λ + g'(T̄) (Λ T) mᵀ.
//! Rows of Λ sum to zero, so the units exchange heat and make none. The
//! kernel is pure; [`Exchange`] gathers the units' temperatures from PETSc.

use crate::contact::table::{ConductanceTable, Table1};
use crate::petsc::{Gather, Matrix, Result, Vector};

/// How a unit's conductance follows its mean temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// h(T̄, P, gap) of the table with this index.
    Table {
        /// Index into the laws' tables.
        table: usize,
        /// Contact pressure (Pa).
        pressure: f64,
        /// Penetration (> 0) or open gap (< 0) (m).
        gap: f64,
    },
    /// k(T̄)/gap + h of a near-field gap's medium.
    Medium {
        /// The gap (m, > 0).
        gap: f64,
        /// Near-field convection (W/m²/K).
        h: f64,
    },
}

/// The tables the laws refer to.
#[derive(Debug, Clone, Default)]
pub struct Laws {
    /// Conductance tables.
    pub tables: Vec<ConductanceTable>,
    /// The gap medium's k(T).
    pub medium: Option<Table1>,
}

impl Laws {
    /// Whether `law`'s conductance changes with temperature.
    pub fn depends_on_temperature(&self, law: &Law) -> bool {
        match law {
            Law::Table { table, .. } => self.tables[*table].depends_on_temperature(),
            Law::Medium { .. } => self.medium.as_ref().is_some_and(|m| m.x.len() > 1),
        }
    }

    /// g and dg/dT̄ of `law` at `t`.
    pub fn eval(&self, law: &Law, t: f64) -> (f64, f64) {
        match *law {
            Law::Table {
                table,
                pressure,
                gap,
            } => self.tables[table].eval(t, pressure, gap),
            Law::Medium { gap, h } => {
                let (k, dk) = self.medium.as_ref().map_or((0.0, 0.0), |m| m.eval(t));
                (k / gap + h, dk / gap)
            }
        }
    }
}

/// One pair or gap link: up to 8 rows, its unit Laplacian (row-major, 8
/// wide), its mean-temperature weights and its law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    /// PETSc rows (the first `n`).
    pub rows: [u32; 8],
    /// Rows used.
    pub n: usize,
    /// Λ at unit conductance, entry (i, j) at 8 i + j.
    pub lap: [f64; 64],
    /// T̄ = Σ mean_i T_i.
    pub mean: [f64; 8],
    /// g(T̄).
    pub law: Law,
}

/// Heat leaving the unit's rows at temperatures `t` (its rows' order) and
/// its Jacobian (8 wide), by the module's formulas.
pub fn unit_heat(u: &Unit, laws: &Laws, t: &[f64]) -> ([f64; 8], [f64; 64]) {
    let n = u.n;
    let tbar: f64 = (0..n).map(|i| u.mean[i] * t[i]).sum();
    let (g, dg) = laws.eval(&u.law, tbar);
    let mut lt = [0.0; 8];
    for (i, v) in lt.iter_mut().enumerate().take(n) {
        *v = (0..n).map(|j| u.lap[8 * i + j] * t[j]).sum();
    }
    let mut q = [0.0; 8];
    let mut jac = [0.0; 64];
    for i in 0..n {
        q[i] = g * lt[i];
        for j in 0..n {
            jac[8 * i + j] = g * u.lap[8 * i + j] + dg * lt[i] * u.mean[j];
        }
    }
    (q, jac)
}

/// The units of this rank and what evaluating them needs.
pub struct Exchange<'p> {
    units: Vec<Unit>,
    laws: Laws,
    gather: Gather<'p>,
    /// Room for the Jacobian's blocks (the operators' pattern).
    pub jac: Matrix<'p>,
}

impl<'p> Exchange<'p> {
    /// Collective. Units over vectors laid out like `like`, Jacobians in
    /// the pattern of `pattern` (which holds every unit's block).
    pub fn new(
        units: Vec<Unit>,
        laws: Laws,
        like: &Vector<'p>,
        pattern: &Matrix<'p>,
    ) -> Result<Self> {
        let rows: Vec<i32> = units
            .iter()
            .flat_map(|u| u.rows[..u.n].iter().map(|&r| r as i32))
            .collect();
        let gather = Gather::new(like, &rows)?;
        let mut jac = pattern.duplicate()?;
        jac.zero_entries()?;
        Ok(Exchange {
            units,
            laws,
            gather,
            jac,
        })
    }

    /// Collective. Add the units' heat at `x` to `out` (which must be
    /// assembled); with `jacobian`, also set `self.jac` to ∂q/∂T.
    pub fn add_heat(&mut self, x: &Vector, out: &mut Vector, jacobian: bool) -> Result<()> {
        if jacobian {
            self.jac.zero_entries()?;
        }
        let t = self.gather.gather(x)?;
        let mut at = 0;
        for u in &self.units {
            let (q, j) = unit_heat(u, &self.laws, &t[at..at + u.n]);
            at += u.n;
            let rows: Vec<i32> = u.rows[..u.n].iter().map(|&r| r as i32).collect();
            out.set_values(&rows, &q[..u.n], true)?;
            if jacobian {
                let mut block = Vec::with_capacity(u.n * u.n);
                for i in 0..u.n {
                    block.extend_from_slice(&j[8 * i..8 * i + u.n]);
                }
                self.jac.add_values(&rows, &rows, &block)?;
            }
        }
        out.assemble()?;
        if jacobian {
            self.jac.assemble()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two rows linked with unit conductance, k(T) = 1 + T/100 over a 0.5 m gap.
    fn pair() -> (Unit, Laws) {
        let mut lap = [0.0; 64];
        lap[0] = 1.0;
        lap[1] = -1.0;
        lap[8] = -1.0;
        lap[9] = 1.0;
        let mut mean = [0.0; 8];
        mean[0] = 0.5;
        mean[1] = 0.5;
        let u = Unit {
            rows: [0, 1, 0, 0, 0, 0, 0, 0],
            n: 2,
            lap,
            mean,
            law: Law::Medium { gap: 0.5, h: 0.0 },
        };
        let laws = Laws {
            tables: vec![],
            medium: Some(Table1 {
                x: vec![0.0, 100.0],
                y: vec![1.0, 2.0],
            }),
        };
        (u, laws)
    }

    #[test]
    fn heat_is_exchanged_at_the_mean_temperatures_conductance() {
        let (u, laws) = pair();
        let (q, _) = unit_heat(&u, &laws, &[60.0, 20.0]);
        // k(40) = 1.4, g = 2.8 W/K, ΔT = 40 K.
        assert!((q[0] - 112.0).abs() < 1e-12 && (q[0] + q[1]).abs() < 1e-12);
    }

    #[test]
    fn the_jacobian_is_the_derivative() {
        let (u, laws) = pair();
        let t = [60.0, 20.0];
        let (q, j) = unit_heat(&u, &laws, &t);
        let h = 1e-6;
        for c in 0..2 {
            let mut tp = t;
            tp[c] += h;
            let (qp, _) = unit_heat(&u, &laws, &tp);
            for r in 0..2 {
                let fd = (qp[r] - q[r]) / h;
                assert!(
                    (fd - j[8 * r + c]).abs() < 1e-5,
                    "({r},{c}) {fd} {}",
                    j[8 * r + c]
                );
            }
        }
    }
}
