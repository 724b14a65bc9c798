//! The theta step with free-surface radiation (issue 20): nonlinear in the
//! new temperatures, solved by Newton (PETSc SNES) with the assembled
//! Jacobian. With the constrained A and rhs of the linear step (seed 000
//! eq 22) and the radiated power R(T) = c ∘ ((T + offset)⁴ − T_a⁴) of the
//! free rows (seed 001 sec 7.1.4, lumped to the nodes),
//!   F(T) = A T − rhs + θ R(T),   J = A + θ diag(4 c (T + offset)³),
//! where rhs = B Tⁿ + g − (1 − θ) R(Tⁿ). Prescribed rows have c = 0 here,
//! so they keep T = T_d.

use crate::petsc::{Matrix, Nonlinear, Result, Vector};

use super::radiation::{emitted, emitted_slope};

/// out_i = c_i ((x_i + offset)⁴ − ambient4).
pub fn emission(
    coef: &Vector,
    x: &Vector,
    offset: f64,
    ambient4: f64,
    out: &mut Vector,
) -> Result<()> {
    let (c, xv) = (coef.view()?, x.view()?);
    let mut o = out.view_mut()?;
    for i in 0..o.len() {
        o[i] = emitted(c[i], xv[i], offset, ambient4);
    }
    Ok(())
}

/// One radiating theta step: the data of F and J.
pub struct RadiatingStep<'p> {
    /// The constrained A = M/Δt + θK (prescribed rows identity).
    pub a: Matrix<'p>,
    /// B Tⁿ + g − (1 − θ) R(Tⁿ), set before each solve.
    pub rhs: Vector<'p>,
    /// ε σ a_free on free rows, 0 on prescribed rows.
    pub coef_free: Vector<'p>,
    /// θ.
    pub theta: f64,
    /// Added to temperatures to make them absolute.
    pub offset: f64,
    /// The ambient's absolute temperature to the fourth.
    pub ambient4: f64,
    /// Whether J may be factorised as symmetric.
    pub symmetric: bool,
    /// Room for R or its slope.
    pub work: Vector<'p>,
}

impl Nonlinear for RadiatingStep<'_> {
    fn residual(&mut self, x: &Vector, f: &mut Vector) -> Result<()> {
        self.a.mult(x, f)?;
        f.axpy(-1.0, &self.rhs)?;
        emission(
            &self.coef_free,
            x,
            self.offset,
            self.ambient4,
            &mut self.work,
        )?;
        f.axpy(self.theta, &self.work)
    }

    fn jacobian(&mut self, x: &Vector, j: &mut Matrix) -> Result<()> {
        j.copy_values_from(&self.a)?;
        {
            let (c, xv) = (self.coef_free.view()?, x.view()?);
            let mut d = self.work.view_mut()?;
            for i in 0..d.len() {
                d[i] = self.theta * emitted_slope(c[i], xv[i], self.offset);
            }
        }
        j.add_diagonal(&self.work)?;
        if self.symmetric {
            j.set_symmetric(true)?;
        }
        Ok(())
    }
}
