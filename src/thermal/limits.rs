//! Time-step limits of the theta method (seed 000 eqs 22–23): the limits
//! themselves (pure), and the run's checks of its step on PETSc below.
//!
//! - Stability: for θ < 1/2 the scheme (M/Δt + θK) Tⁿ⁺¹ = (M/Δt − (1−θ)K) Tⁿ
//!   amplifies the mode of the largest eigenvalue λ_max of M⁻¹K unless
//!   Δt ≤ 2 / ((1 − 2θ) λ_max). Above it the run grows without bound (an
//!   explicit slab at 100× its limit reached 1e97 K in a few hundred steps).
//! - Positivity (the bounded scheme, `thermal::monotone`): with a lumped
//!   capacity and an operator without positive couplings, the right-hand
//!   side matrix M_L/Δt − (1−θ)K has no negative entry, so the new
//!   temperatures stay within the old ones, iff every diagonal entry is ≥ 0:
//!   Δt ≤ m_i / ((1 − θ) K_ii) for every free node i.

/// The largest stable step for `theta` < 1/2, given λ_max of M⁻¹K (1/s);
/// `None` when every step is stable (θ ≥ 1/2, or no conduction at all).
pub fn stability_limit(theta: f64, lambda_max: f64) -> Option<f64> {
    (theta < 0.5 && lambda_max > 0.0).then(|| 2.0 / ((1.0 - 2.0 * theta) * lambda_max))
}

/// The largest step that keeps M_L/Δt − (1−θ)K non-negative, from the
/// lumped capacities `m` and the diagonal `k_diag` of the free rows;
/// `None` for θ = 1 (or no conduction).
pub fn positivity_limit(theta: f64, m: &[f64], k_diag: &[f64]) -> Option<f64> {
    m.iter()
        .zip(k_diag)
        .filter_map(|(&mi, &k)| node_positivity_limit(theta, mi, k))
        .reduce(f64::min)
}

/// One node's share of [`positivity_limit`]: m / ((1 − θ) K_ii).
pub fn node_positivity_limit(theta: f64, m: f64, k_ii: f64) -> Option<f64> {
    (theta < 1.0 && k_ii > 0.0).then(|| m / ((1.0 - theta) * k_ii))
}

// The distributed checks of a run's step (PETSc): the power iteration
// for λ_max and the refusal of a step above either limit.
use crate::error::Error;
use crate::model::Model;
use crate::petsc::{Ksp, Petsc, Result, Vector};
use crate::scenario::{CapacityKind, ConductionKind};

use super::assembly::Operators;

/// Collective. λ_max of M⁻¹K over the free rows, by power iteration from a
/// node-alternating start (the highest modes), as the Rayleigh quotient
/// xᵀKx / xᵀMx: it converges from below, so a step refused with it is
/// certainly unstable. Lumped M divides, a consistent M is solved (CG).
fn largest_eigenvalue(petsc: &Petsc, model: &Model, ops: &Operators, free: &Vector) -> Result<f64> {
    let mut x = free.duplicate()?;
    {
        let (lo, _) = x.ownership_range();
        let f = free.view()?;
        let mut v = x.view_mut()?;
        for i in 0..v.len() {
            let g = (lo + i) as f64;
            let sign = if (lo + i) % 2 == 0 { 1.0 } else { -1.0 };
            v[i] = f[i] * sign * (1.0 + 0.25 * (g * 0.618_033_988_75).fract());
        }
    }
    let mut kx = x.duplicate()?;
    let mut mx = x.duplicate()?;
    let mut mass = None;
    if model.thermal.capacity == CapacityKind::Consistent {
        let mut ksp = Ksp::new(petsc)?;
        ksp.set_operator(&ops.capacity)?;
        ksp.set_types("cg", "jacobi")?;
        ksp.set_tolerances(1e-10, 1e-300, 1000)?;
        mass = Some(ksp);
    }
    let mut lambda = 0.0;
    for k in 0..1000 {
        let norm = x.norm2()?;
        if norm == 0.0 {
            return Ok(0.0);
        }
        x.scale(1.0 / norm)?;
        ops.stiffness.mult(&x, &mut kx)?;
        kx.pointwise_mult(&kx.duplicate_from()?, free)?;
        ops.capacity.mult(&x, &mut mx)?;
        let rq = x.dot(&kx)? / x.dot(&mx)?;
        match mass.as_mut() {
            Some(ksp) => {
                ksp.solve(&kx, &mut x)?;
            }
            None => {
                let m = ops.capacity_rowsum.view()?;
                let y = kx.view()?;
                let mut v = x.view_mut()?;
                for i in 0..v.len() {
                    v[i] = y[i] / m[i];
                }
            }
        }
        x.pointwise_mult(&x.duplicate_from()?, free)?;
        if k > 10 && (rq - lambda).abs() <= 1e-6 * rq.abs() {
            return Ok(rq);
        }
        lambda = rq;
    }
    Ok(lambda)
}

/// Collective. Refuse a time step above the theta method's stability limit
/// (θ < 1/2) or, for the bounded scheme with θ < 1, above its positivity
/// limit (`thermal::limits`), naming the limit.
pub(super) fn check_time_step(
    petsc: &Petsc,
    model: &Model,
    ops: &Operators,
    free: &Vector,
) -> crate::error::Result<()> {
    let (theta, dt) = (model.thermal.theta, model.dt);
    if theta < 0.5 {
        let lambda = largest_eigenvalue(petsc, model, ops, free)?;
        if let Some(limit) = super::limits::stability_limit(theta, lambda) {
            if dt > limit {
                return Err(Error::TimeStep(format!(
                    "time.dt = {dt:e} s is above the stability limit of thermal.theta = {theta} \
                     (dt <= 2/((1 - 2 theta) lambda_max) = {limit:.4e} s, with lambda_max = \
                     {lambda:.4e} 1/s the largest eigenvalue of M^-1 K): use time.dt <= {limit:.3e} \
                     or thermal.theta >= 0.5"
                )));
            }
        }
    }
    if model.thermal.conduction == ConductionKind::Bounded && theta < 1.0 {
        let mut ratio = free.duplicate()?;
        ops.stiffness.diagonal(&mut ratio)?;
        {
            let (m, f) = (ops.capacity_rowsum.view()?, free.view()?);
            let mut v = ratio.view_mut()?;
            for i in 0..v.len() {
                let node = super::limits::node_positivity_limit(theta, m[i], v[i]);
                v[i] = node.filter(|_| f[i] > 0.0).unwrap_or(f64::MAX);
            }
        }
        let limit = ratio.min()?;
        if dt > limit {
            return Err(Error::TimeStep(format!(
                "time.dt = {dt:e} s is above the step that keeps the bounded scheme bounded at \
                 thermal.theta = {theta} (dt <= m_i / ((1 - theta) K_ii) = {limit:.4e} s): use \
                 time.dt <= {limit:.3e} or thermal.theta = 1"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of n nodes (1D, unit spacing, unit capacity, insulated ends):
    /// λ_max of M⁻¹K → 4 from below (4 sin²(π (n−1)/(2n))).
    #[test]
    fn explicit_limit_of_a_chain_is_half_over_the_conductance() {
        let n = 200;
        let lambda = 4.0
            * (std::f64::consts::PI * (n - 1) as f64 / (2.0 * n as f64))
                .sin()
                .powi(2);
        let dt = stability_limit(0.0, lambda).unwrap();
        assert!((dt - 0.5).abs() < 1e-3, "{dt}");
        // Crank–Nicolson and backward Euler: no limit.
        assert_eq!(stability_limit(0.5, lambda), None);
        assert_eq!(stability_limit(1.0, lambda), None);
        // θ = 0.25 doubles the limit.
        assert!((stability_limit(0.25, lambda).unwrap() - 2.0 * dt).abs() < 1e-12);
        // The forward-Euler chain really is stable below the limit and not above.
        let grow = |dt: f64| {
            let mut t: Vec<f64> = (0..n)
                .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
                .collect();
            for _ in 0..2000 {
                let old = t.clone();
                for i in 0..n {
                    let l = if i > 0 { old[i - 1] - old[i] } else { 0.0 };
                    let r = if i + 1 < n { old[i + 1] - old[i] } else { 0.0 };
                    t[i] = old[i] + dt * (l + r);
                }
            }
            t.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        };
        assert!(grow(0.99 * dt) < 1.0 && grow(1.01 * dt) > 1e3);
    }

    #[test]
    fn positivity_limit_is_the_smallest_node_ratio() {
        let m = [2.0, 1.0, 4.0];
        let k = [1.0, 2.0, 0.0];
        assert_eq!(positivity_limit(0.0, &m, &k), Some(0.5));
        assert_eq!(positivity_limit(0.5, &m, &k), Some(1.0));
        assert_eq!(positivity_limit(1.0, &m, &k), None);
    }
}
