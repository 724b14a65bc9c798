//! Krylov solvers. A diverged solve is an error naming its converged reason.

use std::ffi::{CStr, CString};
use std::marker::PhantomData;

use petsc_sys as ffi;

use super::{to_bool, Matrix, Petsc, PetscError, PetscInt, Result, Vector, PETSC_DEFAULT};
use crate::petsc_call;

/// What one solve did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveStats {
    /// Krylov iterations (0 for a direct `preonly` solve counts as 1 in PETSc).
    pub iterations: i32,
    /// The positive `KSPConvergedReason`.
    pub reason: i32,
}

/// A linear solver (`KSP` with its `PC`); move-only owner.
pub struct Ksp<'p> {
    raw: ffi::KSP,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Ksp<'p> {
    /// Collective. A new solver on PETSc's communicator.
    pub fn new(petsc: &'p Petsc) -> Result<Self> {
        let mut raw: ffi::KSP = std::ptr::null_mut();
        petsc_call!(KSPCreate(petsc.comm(), &mut raw))?;
        Ok(Ksp {
            raw,
            _petsc: PhantomData,
        })
    }

    /// The raw handle.
    pub fn as_raw(&self) -> ffi::KSP {
        self.raw
    }

    /// Set the operator (and preconditioning matrix). While it is not set
    /// again, the preconditioner or factorisation is reused across solves.
    pub fn set_operator(&mut self, a: &Matrix) -> Result<()> {
        petsc_call!(KSPSetOperators(self.raw, a.as_raw(), a.as_raw()))
    }

    /// Set the KSP and PC types (before [`Ksp::set_from_options`], so the
    /// options database can override them).
    pub fn set_types(&mut self, ksp_type: &str, pc_type: &str) -> Result<()> {
        let kt = CString::new(ksp_type).map_err(|_| PetscError::Usage("NUL".into()))?;
        let pt = CString::new(pc_type).map_err(|_| PetscError::Usage("NUL".into()))?;
        petsc_call!(KSPSetType(self.raw, kt.as_ptr()))?;
        let mut pc: ffi::PC = std::ptr::null_mut();
        petsc_call!(KSPGetPC(self.raw, &mut pc))?;
        petsc_call!(PCSetType(pc, pt.as_ptr()))
    }

    /// Relative and absolute residual tolerances and iteration cap.
    pub fn set_tolerances(&mut self, rtol: f64, atol: f64, max_it: i32) -> Result<()> {
        petsc_call!(KSPSetTolerances(
            self.raw,
            rtol,
            atol,
            PETSC_DEFAULT,
            max_it as PetscInt
        ))
    }

    /// Use the previous solution as the initial guess.
    pub fn set_initial_guess_nonzero(&mut self, yes: bool) -> Result<()> {
        petsc_call!(KSPSetInitialGuessNonzero(self.raw, to_bool(yes)))
    }

    /// Start each solve from Fischer's projection of the right-hand side
    /// onto the last `size` solutions (PETSc `KSPSetUseFischerGuess`, model
    /// 1); PETSc empties the space when the operator changes.
    pub fn set_fischer_guess(&mut self, size: usize) -> Result<()> {
        petsc_call!(KSPSetUseFischerGuess(self.raw, 1, size as PetscInt))
    }

    /// Collective. Put `x` into the space of [`Ksp::set_fischer_guess`]
    /// (empty until a solve, whose start would be zero): the next solve
    /// then starts from the multiple of `x` that best fits its right-hand
    /// side. After [`Ksp::set_up`], with the operator that will be solved.
    pub fn seed_fischer_guess(&mut self, x: &Vector) -> Result<()> {
        let mut g: ffi::KSPGuess = std::ptr::null_mut();
        petsc_call!(KSPGetGuess(self.raw, &mut g))?;
        petsc_call!(KSPGuessSetUp(g))?;
        petsc_call!(KSPGuessUpdate(g, x.as_raw(), x.as_raw()))
    }

    /// Stop on the natural norm (for CG: sqrt(rᵀ z), which it computes
    /// anyway, so an iteration needs one reduction less).
    pub fn set_natural_norm(&mut self) -> Result<()> {
        petsc_call!(KSPSetNormType(self.raw, ffi::KSPNormType::KSP_NORM_NATURAL))
    }

    /// Read `-ksp_*` / `-pc_*` options from the database (command line wins).
    pub fn set_from_options(&mut self) -> Result<()> {
        petsc_call!(KSPSetFromOptions(self.raw))
    }

    /// Collective. Build the preconditioner / factorisation now.
    pub fn set_up(&mut self) -> Result<()> {
        petsc_call!(KSPSetUp(self.raw))
    }

    /// Names of the KSP and PC types in use.
    pub fn types(&self) -> Result<(String, String)> {
        let mut kt: *const std::os::raw::c_char = std::ptr::null();
        petsc_call!(KSPGetType(self.raw, &mut kt))?;
        let mut pc: ffi::PC = std::ptr::null_mut();
        petsc_call!(KSPGetPC(self.raw, &mut pc))?;
        let mut pt: *const std::os::raw::c_char = std::ptr::null();
        petsc_call!(PCGetType(pc, &mut pt))?;
        let s = |p: *const std::os::raw::c_char| {
            if p.is_null() {
                "(unset)".to_string()
            } else {
                // SAFETY: PETSc type names are static NUL-terminated strings.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        Ok((s(kt), s(pt)))
    }

    /// Collective. Solve `A x = b`. A negative converged reason (divergence,
    /// breakdown, iteration cap, NaN) is returned as [`PetscError::Diverged`].
    pub fn solve(&mut self, b: &Vector, x: &mut Vector) -> Result<SolveStats> {
        petsc_call!(KSPSolve(self.raw, b.as_raw(), x.as_raw()))?;
        let mut reason = ffi::KSPConvergedReason::KSP_CONVERGED_ITERATING;
        petsc_call!(KSPGetConvergedReason(self.raw, &mut reason))?;
        let mut its: PetscInt = 0;
        petsc_call!(KSPGetIterationNumber(self.raw, &mut its))?;
        let code = reason as i32;
        if code < 0 {
            let mut name: *const std::os::raw::c_char = std::ptr::null();
            petsc_call!(KSPGetConvergedReasonString(self.raw, &mut name))?;
            return Err(PetscError::Diverged {
                reason: super::reason_name(name, code),
                code,
                iterations: its,
            });
        }
        Ok(SolveStats {
            iterations: its,
            reason: code,
        })
    }
}

impl Drop for Ksp<'_> {
    fn drop(&mut self) {
        // SAFETY: raw is a valid KSP owned by self.
        unsafe {
            ffi::KSPDestroy(&mut self.raw);
        }
    }
}
