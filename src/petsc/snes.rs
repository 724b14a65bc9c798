//! Newton solves (`SNES`, line search) of a problem that gives its residual
//! and assembled Jacobian. A diverged solve is an error naming its reason.

use std::ffi::{CStr, CString};
use std::marker::PhantomData;
use std::os::raw::c_void;

use petsc_sys as ffi;

use super::{Matrix, Petsc, PetscError, PetscInt, Result, Vector, PETSC_DEFAULT};
use crate::petsc_call;

/// A nonlinear problem F(x) = 0 with its Jacobian.
pub trait Nonlinear {
    /// Collective. f = F(x).
    fn residual(&mut self, x: &Vector, f: &mut Vector) -> Result<()>;
    /// Collective. j = ∂F/∂x at x (in j's preallocated pattern).
    fn jacobian(&mut self, x: &Vector, j: &mut Matrix) -> Result<()>;
}

/// What one Newton solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NonlinearStats {
    /// Newton iterations.
    pub newton: i32,
    /// Linear (Krylov) iterations over them.
    pub linear: i32,
}

/// A Newton solver owning its problem, residual and Jacobian storage.
pub struct Snes<'p, P: Nonlinear> {
    raw: ffi::SNES,
    /// Boxed so the context pointer PETSc holds stays put.
    problem: Box<P>,
    _f: Vector<'p>,
    _j: Matrix<'p>,
    _petsc: PhantomData<&'p Petsc>,
}

/// A callback's failure as a PETSc error code (PETSC_ERR_LIB).
const CALLBACK_FAILED: ffi::PetscErrorCode = 76;

unsafe extern "C" fn residual_callback<P: Nonlinear>(
    _snes: ffi::SNES,
    x: ffi::Vec,
    f: ffi::Vec,
    ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    // SAFETY: ctx is the boxed problem of the Snes being solved; x and f
    // are PETSc's vectors for the duration of the call.
    let problem = unsafe { &mut *(ctx as *mut P) };
    let (x, mut f) = unsafe { (Vector::borrowed(x), Vector::borrowed(f)) };
    match problem.residual(&x, &mut f) {
        Ok(()) => 0,
        Err(_) => CALLBACK_FAILED,
    }
}

unsafe extern "C" fn jacobian_callback<P: Nonlinear>(
    _snes: ffi::SNES,
    x: ffi::Vec,
    j: ffi::Mat,
    _p: ffi::Mat,
    ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    // SAFETY: as in residual_callback; j is the Jacobian matrix given at set-up.
    let problem = unsafe { &mut *(ctx as *mut P) };
    let (x, mut j) = unsafe { (Vector::borrowed(x), Matrix::borrowed(j)) };
    match problem.jacobian(&x, &mut j) {
        Ok(()) => 0,
        Err(_) => CALLBACK_FAILED,
    }
}

impl<'p, P: Nonlinear> Snes<'p, P> {
    /// Collective. A Newton solver (PETSc's default `newtonls`, backtracking
    /// line search) for `problem`, with `f` and `j` of the unknowns' layout
    /// as residual and Jacobian storage.
    pub fn new(petsc: &'p Petsc, problem: P, f: Vector<'p>, j: Matrix<'p>) -> Result<Self> {
        let mut raw: ffi::SNES = std::ptr::null_mut();
        petsc_call!(SNESCreate(petsc.comm(), &mut raw))?;
        let mut s = Snes {
            raw,
            problem: Box::new(problem),
            _f: f,
            _j: j,
            _petsc: PhantomData,
        };
        let ctx = &mut *s.problem as *mut P as *mut c_void;
        petsc_call!(SNESSetFunction(
            s.raw,
            s._f.as_raw(),
            Some(residual_callback::<P>),
            ctx
        ))?;
        petsc_call!(SNESSetJacobian(
            s.raw,
            s._j.as_raw(),
            s._j.as_raw(),
            Some(jacobian_callback::<P>),
            ctx
        ))?;
        Ok(s)
    }

    /// The problem (to change its data between solves).
    pub fn problem_mut(&mut self) -> &mut P {
        &mut self.problem
    }

    /// The problem.
    pub fn problem(&self) -> &P {
        &self.problem
    }

    /// The linear solver of each Newton step: types and tolerances (the
    /// options database wins after [`Snes::set_from_options`]).
    pub fn set_linear(
        &mut self,
        ksp_type: &str,
        pc_type: &str,
        rtol: f64,
        atol: f64,
    ) -> Result<()> {
        let kt = CString::new(ksp_type).map_err(|_| PetscError::Usage("NUL".into()))?;
        let pt = CString::new(pc_type).map_err(|_| PetscError::Usage("NUL".into()))?;
        let mut ksp: ffi::KSP = std::ptr::null_mut();
        petsc_call!(SNESGetKSP(self.raw, &mut ksp))?;
        petsc_call!(KSPSetType(ksp, kt.as_ptr()))?;
        let mut pc: ffi::PC = std::ptr::null_mut();
        petsc_call!(KSPGetPC(ksp, &mut pc))?;
        petsc_call!(PCSetType(pc, pt.as_ptr()))?;
        petsc_call!(KSPSetTolerances(ksp, rtol, atol, PETSC_DEFAULT, 10_000))
    }

    /// Rebuild the preconditioner (a factorisation, an AMG hierarchy) only
    /// every `lag` Jacobians, across solves: between rebuilds the Krylov
    /// solver works with the last one.
    pub fn set_lag_preconditioner(&mut self, lag: i32) -> Result<()> {
        petsc_call!(SNESSetLagPreconditioner(self.raw, lag as PetscInt))?;
        petsc_call!(SNESSetLagPreconditionerPersists(
            self.raw,
            super::to_bool(true)
        ))
    }

    /// Newton tolerances: absolute and relative residual, step, iteration cap.
    pub fn set_tolerances(&mut self, atol: f64, rtol: f64, stol: f64, max_it: i32) -> Result<()> {
        petsc_call!(SNESSetTolerances(
            self.raw,
            atol,
            rtol,
            stol,
            max_it as PetscInt,
            -1
        ))
    }

    /// Collective. Read `-snes_*` (and the linear solver's) options.
    pub fn set_from_options(&mut self) -> Result<()> {
        petsc_call!(SNESSetFromOptions(self.raw))
    }

    /// The SNES and its KSP and PC types, e.g. "newtonls: cg/gamg".
    pub fn types(&self) -> Result<String> {
        let name = |p: *const std::os::raw::c_char| {
            if p.is_null() {
                "?".to_string()
            } else {
                // SAFETY: PETSc returns NUL-terminated type names.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let (mut st, mut kt, mut pt) = (std::ptr::null(), std::ptr::null(), std::ptr::null());
        let mut ksp: ffi::KSP = std::ptr::null_mut();
        let mut pc: ffi::PC = std::ptr::null_mut();
        petsc_call!(SNESGetType(self.raw, &mut st))?;
        petsc_call!(SNESGetKSP(self.raw, &mut ksp))?;
        petsc_call!(KSPGetType(ksp, &mut kt))?;
        petsc_call!(KSPGetPC(ksp, &mut pc))?;
        petsc_call!(PCGetType(pc, &mut pt))?;
        Ok(format!("{}: {}/{}", name(st), name(kt), name(pt)))
    }

    /// Collective. Solve F(x) = 0 from the guess in `x`. A negative
    /// converged reason is [`PetscError::NonlinearDiverged`].
    pub fn solve(&mut self, x: &mut Vector) -> Result<NonlinearStats> {
        petsc_call!(SNESSolve(self.raw, std::ptr::null_mut(), x.as_raw()))?;
        let mut reason = ffi::SNESConvergedReason::SNES_CONVERGED_ITERATING;
        petsc_call!(SNESGetConvergedReason(self.raw, &mut reason))?;
        let (mut newton, mut linear): (PetscInt, PetscInt) = (0, 0);
        petsc_call!(SNESGetIterationNumber(self.raw, &mut newton))?;
        petsc_call!(SNESGetLinearSolveIterations(self.raw, &mut linear))?;
        let code = reason as i32;
        if code < 0 {
            let mut name: *const std::os::raw::c_char = std::ptr::null();
            petsc_call!(SNESGetConvergedReasonString(self.raw, &mut name))?;
            return Err(PetscError::NonlinearDiverged {
                reason: super::reason_name(name, code),
                code,
                iterations: newton,
            });
        }
        Ok(NonlinearStats { newton, linear })
    }
}

impl<P: Nonlinear> Drop for Snes<'_, P> {
    fn drop(&mut self) {
        // SAFETY: raw is a valid SNES owned by self.
        unsafe {
            ffi::SNESDestroy(&mut self.raw);
        }
    }
}
