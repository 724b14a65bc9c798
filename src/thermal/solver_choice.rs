//! The default linear solver of the thermal step (issue 22): CG with
//! Jacobi where the capacity dominates the step's matrix, a factorisation
//! or algebraic multigrid elsewhere, by size and by the largest cell
//! Fourier number. The options database always wins.

use super::assembly::Operators;
use crate::petsc::{Ksp, Matrix, Petsc, Result, Vector};
use crate::scenario::GuessKind;

/// Linear solver defaults by problem size (the options database wins).
#[derive(Debug, Clone, PartialEq)]
pub struct SolverChoice {
    /// KSP type.
    pub ksp_type: String,
    /// PC type.
    pub pc_type: String,
    /// Extra defaults (name, value) put into the options database unless set.
    pub defaults: Vec<(String, String)>,
}

impl SolverChoice {
    /// CG with Jacobi when the step's matrix is close enough to its
    /// capacity part: the largest cell Fourier number `fourier` (θΔt K_ii /
    /// C_ii) at most 1 up to 10,000 unknowns, 30 up to 50,000, 100 above,
    /// and more than 1,500 unknowns on one rank (600 on several). CG stops
    /// on its natural norm (rᵀ z, which it computes anyway): one reduction
    /// an iteration less, 10 % of the step, the same error. Measured on
    /// this machine (per step): the seed's slab at 6,561 unknowns, Fourier
    /// 0.26, 404 us against 724 us for Cholesky on 1 rank (at 2.6, 917
    /// against 715); at 46,529 unknowns, Fourier 10, 17 ms against 28 ms
    /// for MUMPS and 33 ms for GAMG (at 102, 40 ms against 28 and 48); the
    /// 1 M-tet cube, Fourier 19, 116 ms against 202 ms for GAMG; the N =
    /// 2000 heat-up, Fourier 73 (the contacts' rows), 226 ms against
    /// 430 ms. Below that a factorisation is as fast or faster: 1,025
    /// unknowns, 44 us either way on 1 rank, but 32 us against 49 us for
    /// the redundant one on 2; 189 unknowns, 5.1 us against 11.7 us on 2.
    ///
    /// Otherwise, sparse direct solves, factorised once, up to 50,000 unknowns:
    /// - up to 10,000: PETSc's own Cholesky on one rank (1–6 us per step on
    ///   the seed's bars); on several ranks the `redundant` PC (every rank
    ///   factorises the whole matrix once, a solve costs one gather: 7 us
    ///   per step on 2 ranks against 178 us for a distributed solve);
    /// - 10,000 to 50,000: MUMPS, whose factorisation stays fast when
    ///   contacts couple many nodes (0.7 s where PETSc's own took 24 s on
    ///   the 512-cube contact lattice), at a higher cost per solve.
    ///
    /// Above that, CG with algebraic multigrid (GAMG), which also handles
    /// the steady limit (large dt) where the capacity no longer dominates.
    ///
    /// A non-symmetric operator (average-dT contact) uses LU instead of
    /// Cholesky, and GMRES instead of CG.
    pub fn auto(global_rows: usize, ranks: usize, symmetric: bool, fourier: f64) -> SolverChoice {
        let opt = |k: &str, v: &str| (k.to_string(), v.to_string());
        let factor = if symmetric { "cholesky" } else { "lu" };
        let smallest = if ranks == 1 { 1_500 } else { 600 };
        let jacobi_limit = match global_rows {
            n if n <= smallest => -1.0,
            0..=10_000 => 1.0,
            10_001..=50_000 => 30.0,
            _ => 100.0,
        };
        if symmetric && fourier <= jacobi_limit {
            SolverChoice {
                ksp_type: "cg".into(),
                pc_type: "jacobi".into(),
                defaults: Vec::new(),
            }
        } else if global_rows <= 10_000 && ranks == 1 {
            SolverChoice {
                ksp_type: "preonly".into(),
                pc_type: factor.into(),
                defaults: vec![opt("pc_factor_mat_ordering_type", "nd")],
            }
        } else if global_rows <= 10_000 {
            SolverChoice {
                ksp_type: "preonly".into(),
                pc_type: "redundant".into(),
                defaults: vec![
                    opt("redundant_pc_type", factor),
                    opt("redundant_pc_factor_mat_ordering_type", "nd"),
                ],
            }
        } else if global_rows <= 50_000 {
            SolverChoice {
                ksp_type: "preonly".into(),
                pc_type: factor.into(),
                // MUMPS's default 20 % workspace margin fails (DIVERGED_PC_FAILED)
                // on contact-coupled packings: the 500-nut lattice on 2 ranks.
                defaults: vec![
                    opt("pc_factor_mat_solver_type", "mumps"),
                    opt("mat_mumps_icntl_14", "200"),
                ],
            }
        } else {
            SolverChoice {
                ksp_type: if symmetric { "cg" } else { "gmres" }.into(),
                pc_type: "gamg".into(),
                defaults: Vec::new(),
            }
        }
    }
}

impl SolverChoice {
    /// Put this choice into the options database below the command line
    /// and the scenario's `[solver]` options `scenario` (each is set only
    /// where unset: the command line wins, then the scenario, then fdem's
    /// defaults), its Cholesky ordering picked by fill for the step's
    /// matrix `a` unless one of those chose it; returns the choice and
    /// that ordering.
    pub fn configure(
        mut self,
        petsc: &Petsc,
        scenario: &std::collections::BTreeMap<String, String>,
        a: &Matrix,
    ) -> Result<(SolverChoice, Option<&'static str>)> {
        for (k, v) in scenario {
            petsc.set_default_option(k, if v.is_empty() { None } else { Some(v) })?;
        }
        let ordering = match petsc.has_option("pc_factor_mat_ordering_type")? {
            true => None,
            false => self.order_by_fill(a)?,
        };
        for (k, v) in &self.defaults {
            petsc.set_own_default_option(k, Some(v))?;
        }
        Ok((self, ordering))
    }

    /// With PETSc's own Cholesky (one rank), the fill-reducing ordering
    /// whose factor of the step's matrix `a` has fewer nonzeros: nested
    /// dissection for compact bodies, reverse Cuthill–McKee for long thin
    /// ones, where its banded factor is smaller and solves faster (the
    /// seed's slab at h = 0.025 m, 1,025 unknowns: 33.7 against 41.4 us per
    /// step, measured 2026-12-05). Two symbolic factorisations, once.
    /// Returns the ordering's name; the options database still wins.
    pub fn order_by_fill(&mut self, a: &Matrix) -> Result<Option<&'static str>> {
        let key = "pc_factor_mat_ordering_type";
        let Some(at) = (self.pc_type == "cholesky")
            .then(|| self.defaults.iter().position(|(k, _)| k == key))
            .flatten()
        else {
            return Ok(None);
        };
        let (nd, rcm) = (a.cholesky_fill(c"nd")?, a.cholesky_fill(c"rcm")?);
        let best = if rcm < nd { "rcm" } else { "nd" };
        tracing::debug!(target: "solver", nd, rcm, best, "Cholesky factor nonzeros by ordering");
        self.defaults[at].1 = best.to_string();
        Ok(Some(best))
    }
}

/// Solutions Fischer's projection keeps (PETSc's default).
const FISCHER_VECTORS: usize = 10;

/// Collective. Where each iterative solve of `ksp` (type `kt`) starts,
/// with the cell Fourier number `fourier` and the scenario's `wanted`.
/// Fischer's projection of the right-hand side onto the last solutions
/// (PETSc's model 1; a least-squares fit, so any Krylov type) where CG
/// needs many iterations (Fourier number above 1: the N = 2000 heat-up,
/// Fourier 73, 32 → 19 CG iterations a step, measured 2026-12-05); else
/// the line through the last two steps, which costs nothing where CG needs
/// few (the seed's slab, 2.7 a step). A guess from the options database
/// (`-ksp_guess_type`, `-ksp_fischer_guess`) wins. Returns whether the step
/// puts its own start into the solution vector (false: a direct solve,
/// which ignores it, or a PETSc guess, which replaces it), whether
/// Fischer's space is to be seeded with Tⁿ before the first solve (else
/// that solve, and the first after every rebuild, would start from zero:
/// [`Ksp::seed_fischer_guess`]), and the label for the run summary.
pub(super) fn initial_guess(
    petsc: &Petsc,
    ksp: &mut Ksp,
    kt: &str,
    fourier: f64,
    wanted: GuessKind,
) -> Result<(bool, bool, &'static str)> {
    if kt == "preonly" {
        return Ok((false, false, ""));
    }
    ksp.set_initial_guess_nonzero(true)?;
    if petsc.has_option("ksp_guess_type")? || petsc.has_option("ksp_fischer_guess")? {
        return Ok((false, false, "; guess from the options"));
    }
    let fischer = match wanted {
        GuessKind::Auto => kt == "cg" && fourier > 1.0,
        GuessKind::Fischer => true,
        GuessKind::Line => false,
    };
    if fischer {
        ksp.set_fischer_guess(FISCHER_VECTORS)?;
        return Ok((false, true, "; Fischer guess"));
    }
    Ok((true, false, ""))
}

/// Collective. The largest cell Fourier number θΔt K_ii / C_ii over the
/// free rows: how far the step's matrix C/Δt + θK is from its capacity
/// part, which Jacobi preconditions exactly.
pub(super) fn cell_fourier(ops: &Operators, free: &Vector, theta_dt: f64) -> Result<f64> {
    let mut k = free.duplicate()?;
    ops.stiffness.diagonal(&mut k)?;
    let mut c = free.duplicate()?;
    ops.capacity.diagonal(&mut c)?;
    {
        let (cv, fv) = (c.view()?, free.view()?);
        let mut v = k.view_mut()?;
        for i in 0..v.len() {
            v[i] = if fv[i] > 0.0 && cv[i] > 0.0 {
                theta_dt * v[i] / cv[i]
            } else {
                0.0
            };
        }
    }
    k.norm_inf()
}

#[cfg(test)]
mod tests {
    use super::SolverChoice;

    fn pick(rows: usize, ranks: usize, symmetric: bool, fourier: f64) -> String {
        let c = SolverChoice::auto(rows, ranks, symmetric, fourier);
        format!("{}/{}", c.ksp_type, c.pc_type)
    }

    #[test]
    fn jacobi_where_the_capacity_dominates_a_factorisation_or_amg_elsewhere() {
        // Tiny systems factorise whatever the Fourier number.
        assert_eq!(pick(189, 1, true, 0.01), "preonly/cholesky");
        assert_eq!(pick(189, 2, true, 0.01), "preonly/redundant");
        // Between the two smallest sizes, several ranks already prefer CG.
        assert_eq!(pick(1_025, 1, true, 0.06), "preonly/cholesky");
        assert_eq!(pick(1_025, 2, true, 0.06), "cg/jacobi");
        // The limit grows with the size of the factorisation it replaces.
        assert_eq!(pick(6_561, 1, true, 0.26), "cg/jacobi");
        assert_eq!(pick(6_561, 1, true, 2.6), "preonly/cholesky");
        assert_eq!(pick(46_529, 1, true, 10.0), "cg/jacobi");
        assert_eq!(pick(46_529, 1, true, 102.0), "preonly/cholesky");
        assert_eq!(pick(185_193, 2, true, 19.0), "cg/jacobi");
        assert_eq!(pick(185_193, 2, true, 250.0), "cg/gamg");
        // A non-symmetric operator never gets CG.
        assert_eq!(pick(6_561, 1, false, 0.26), "preonly/lu");
        assert_eq!(pick(185_193, 1, false, 250.0), "gmres/gamg");
    }
}
