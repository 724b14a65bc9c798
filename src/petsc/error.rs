//! PETSc error codes as Rust errors.
//!
//! A custom PETSc error handler records the innermost error message (the
//! function, file, line and text PETSc reports) in a thread-local; the
//! `petsc_call!` macro turns a non-zero return code into a [`PetscError`]
//! that names the PETSc function called and carries that message.

use std::cell::RefCell;
use std::ffi::CStr;
use std::os::raw::{c_char, c_int, c_void};

use petsc_sys as ffi;

/// An error returned by a PETSc call, or a diverged solve.
#[derive(Debug, Clone, thiserror::Error)]
pub enum PetscError {
    /// A PETSc function returned a non-zero error code.
    #[error("PETSc error {code} in {func}: {message}")]
    Call {
        /// The PETSc function that was called.
        func: &'static str,
        /// PETSc's error code.
        code: i32,
        /// PETSc's message (innermost routine, file:line, text).
        message: String,
    },
    /// A Krylov solve ended with a negative `KSPConvergedReason`.
    #[error("linear solver diverged: {reason} (KSPConvergedReason {code}) after {iterations} iterations; try other -ksp_type/-pc_type options or a smaller time step")]
    Diverged {
        /// PETSc's name of the reason, e.g. `DIVERGED_ITS`.
        reason: String,
        /// The numeric reason.
        code: i32,
        /// Iterations done.
        iterations: i32,
    },
    /// A Newton solve ended with a negative `SNESConvergedReason`.
    #[error("nonlinear solver diverged: {reason} (SNESConvergedReason {code}) after {iterations} Newton iterations; try a smaller time step, other -snes_linesearch_type or -snes_max_it")]
    NonlinearDiverged {
        /// PETSc's name of the reason, e.g. `DIVERGED_LINE_SEARCH`.
        reason: String,
        /// The numeric reason.
        code: i32,
        /// Newton iterations done.
        iterations: i32,
    },
    /// Misuse detected on the Rust side (bad sizes, options with NUL bytes...).
    #[error("{0}")]
    Usage(String),
}

thread_local! {
    static LAST_ERROR: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// PETSc error handler: remember the first (innermost) message of an error
/// chain and return the code unchanged, printing nothing.
///
/// # Safety
/// Called by PETSc with valid (possibly null) C strings.
pub(crate) unsafe extern "C" fn record_error_handler(
    _comm: ffi::MPI_Comm,
    line: c_int,
    func: *const c_char,
    file: *const c_char,
    code: ffi::PetscErrorCode,
    kind: ffi::PetscErrorType,
    mess: *const c_char,
    _ctx: *mut c_void,
) -> ffi::PetscErrorCode {
    let s = |p: *const c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: PETSc passes NUL-terminated strings.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    if matches!(kind, ffi::PetscErrorType::PETSC_ERROR_INITIAL) {
        let mut text = s(mess);
        if text.is_empty() {
            let mut generic: *const c_char = std::ptr::null();
            // SAFETY: PetscErrorMessage only writes the pointer.
            unsafe { ffi::PetscErrorMessage(code, &mut generic, std::ptr::null_mut()) };
            text = s(generic);
        }
        let msg = format!("{} (in {} at {}:{})", text.trim(), s(func), s(file), line);
        LAST_ERROR.with(|e| *e.borrow_mut() = Some(msg));
    }
    code
}

/// Build the error for a failed call, consuming the recorded message.
pub fn error_from_code(func: &'static str, code: i32) -> PetscError {
    let message = LAST_ERROR
        .with(|e| e.borrow_mut().take())
        .unwrap_or_else(|| {
            let mut generic: *const c_char = std::ptr::null();
            // SAFETY: PetscErrorMessage only writes the pointer.
            unsafe { ffi::PetscErrorMessage(code, &mut generic, std::ptr::null_mut()) };
            if generic.is_null() {
                "unknown error".to_string()
            } else {
                // SAFETY: PETSc returns a static NUL-terminated string.
                unsafe { CStr::from_ptr(generic) }
                    .to_string_lossy()
                    .into_owned()
            }
        });
    PetscError::Call {
        func,
        code,
        message,
    }
}

/// Call a PETSc function and turn its error code into `Result<(), PetscError>`.
///
/// `petsc_call!(VecAXPY(y, a, x))` calls `petsc_sys::VecAXPY` in an unsafe
/// block; the caller guarantees the arguments are valid handles (the macro
/// is used only inside the safe layer, whose types own those handles).
#[macro_export]
macro_rules! petsc_call {
    ($func:ident ( $($arg:expr),* $(,)? )) => {{
        #[allow(unused_unsafe)]
        let code = unsafe { petsc_sys::$func($($arg),*) };
        if code == 0 {
            Ok(())
        } else {
            Err($crate::petsc::error::error_from_code(stringify!($func), code))
        }
    }};
}
