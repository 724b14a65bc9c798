//! The theta step with free-surface radiation (issue 20): nonlinear in the
//! new temperatures, solved by Newton (PETSc SNES) with the assembled
//! Jacobian. With the constrained A and rhs of the linear step (seed 000
//! eq 22) and the radiated power R(T) = c ∘ ((T + offset)⁴ − T_a⁴) of the
//! free rows (seed 001 sec 7.1.6, lumped to the nodes),
//!   F(T) = A T − rhs + θ R(T),   J = A + θ diag(4 c (T + offset)³),
//! where rhs = B Tⁿ + g − (1 − θ) R(Tⁿ). Prescribed rows have c = 0 here,
//! so they keep T = T_d. Radiation across near-field gaps adds L u(T) to
//! R, u = (T + offset)⁴, with L the Laplacian of the links' σ F A shares,
//! and P L diag(4 (T + offset)³) to J (P: the free rows); J is then not
//! symmetric. Contact and gap conductances that follow the temperature
//! (tables, k_gap(T): [`super::exchange`]) add their heat q(T) to R and
//! P ∂q/∂T to J, which is not symmetric either.

use crate::petsc::{Matrix, Nonlinear, Result, Vector};

use super::exchange::Exchange;

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

/// out = c ∘ ((x + offset)⁴ − ambient4) + L (x + offset)⁴ (no L: the first
/// term only), with `u` room for the fourth powers.
pub fn radiated(
    coef: &Vector,
    gap: Option<&Matrix>,
    x: &Vector,
    offset: f64,
    ambient4: f64,
    u: &mut Vector,
    out: &mut Vector,
) -> Result<()> {
    let Some(lap) = gap else {
        return emission(coef, x, offset, ambient4, out);
    };
    fourth_powers(x, offset, u)?;
    lap.mult(u, out)?;
    let (c, xv) = (coef.view()?, x.view()?);
    let mut o = out.view_mut()?;
    for i in 0..o.len() {
        o[i] += emitted(c[i], xv[i], offset, ambient4);
    }
    Ok(())
}

fn fourth_powers(x: &Vector, offset: f64, u: &mut Vector) -> Result<()> {
    let xv = x.view()?;
    let mut uv = u.view_mut()?;
    for i in 0..uv.len() {
        let a = xv[i] + offset;
        uv[i] = (a * a) * (a * a);
    }
    Ok(())
}

/// Radiation across gaps in a Newton step: L, the free rows' mask, and
/// room for L scaled and for the fourth powers and their product.
pub struct GapRadiation<'p> {
    /// The links' Laplacian.
    pub lap: Matrix<'p>,
    /// 1 on free rows, 0 on prescribed ones.
    pub free: Vector<'p>,
    /// Room for P L D.
    pub scaled: Matrix<'p>,
    /// Room for u.
    pub u: Vector<'p>,
    /// Room for L u.
    pub lu: Vector<'p>,
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
    /// Radiation across near-field gaps, when computed.
    pub gap: Option<GapRadiation<'p>>,
    /// Contact and gap heat with temperature-dependent conductance, and
    /// the free rows' mask.
    pub exchange: Option<(Exchange<'p>, Vector<'p>)>,
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
        f.axpy(self.theta, &self.work)?;
        if let Some(g) = self.gap.as_mut() {
            fourth_powers(x, self.offset, &mut g.u)?;
            g.lap.mult(&g.u, &mut g.lu)?;
            self.work.pointwise_mult(&g.lu, &g.free)?;
            f.axpy(self.theta, &self.work)?;
        }
        if let Some((ex, free)) = self.exchange.as_mut() {
            self.work.set(0.0)?;
            ex.add_heat(x, &mut self.work, false)?;
            self.work
                .pointwise_mult(&self.work.duplicate_from()?, free)?;
            f.axpy(self.theta, &self.work)?;
        }
        Ok(())
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
        if let Some(g) = self.gap.as_mut() {
            {
                let xv = x.view()?;
                let mut d = g.u.view_mut()?;
                for i in 0..d.len() {
                    let a = xv[i] + self.offset;
                    d[i] = 4.0 * a * a * a;
                }
            }
            g.scaled.copy_values_from(&g.lap)?;
            g.scaled.diagonal_scale(Some(&g.free), Some(&g.u))?;
            j.axpy_same_pattern(self.theta, &g.scaled)?;
        }
        if let Some((ex, free)) = self.exchange.as_mut() {
            ex.add_heat(x, &mut self.work, true)?;
            ex.jac.diagonal_scale(Some(free), None)?;
            j.axpy_same_pattern(self.theta, &ex.jac)?;
        }
        if self.symmetric {
            j.set_symmetric(true)?;
        }
        Ok(())
    }
}
