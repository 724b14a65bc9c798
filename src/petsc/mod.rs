//! Safe RAII layer over `petsc-sys`.
//!
//! Lifecycle: `mpi::initialize()` first, then [`Petsc::init`] (sets
//! `PETSC_COMM_WORLD` to the rsmpi world and calls `PetscInitialize` with the
//! real argv so `-ksp_type`, `-pc_type`, `-ksp_monitor`, `-log_view`,
//! `-malloc_dump` work), then objects ([`Vector`], [`Matrix`], [`Ksp`]) that
//! borrow the guard. Rust drops in reverse order, so every PETSc object is
//! destroyed before `PetscFinalize`, which runs before `MPI_Finalize`.
//!
//! PETSc objects are move-only owners with an `as_raw()` escape hatch; array
//! access goes through borrowed views whose `Drop` restores the array.

pub mod error;
mod ksp;
mod matrix;
mod scatter;
mod snes;
mod vector;

use std::ffi::{CStr, CString};
use std::marker::PhantomData;
use std::os::raw::{c_char, c_int};

use mpi::traits::AsRaw;
use petsc_sys as ffi;

pub use error::PetscError;
pub use ksp::{Ksp, SolveStats};
pub use matrix::{Matrix, Pattern};
pub use scatter::Gather;
pub use snes::{Nonlinear, NonlinearStats, Snes};
pub use vector::{Vector, VectorView, VectorViewMut};

use crate::petsc_call;

/// PETSc's `PetscInt` (32-bit in the build this crate requires).
pub type PetscInt = ffi::PetscInt;

/// `PETSC_DECIDE` / `PETSC_DETERMINE` (macros, not exported by bindgen).
pub const PETSC_DECIDE: PetscInt = -1;
/// `PETSC_DEFAULT` for tolerances (macro in PETSc).
pub const PETSC_DEFAULT: f64 = -2.0;

/// Result alias for PETSc calls.
pub type Result<T> = std::result::Result<T, PetscError>;

/// The PETSc library, initialised on a communicator. Dropping it calls
/// `PetscFinalize` (which prints `-log_view` and `-malloc_dump` reports).
pub struct Petsc {
    comm: ffi::MPI_Comm,
    /// Options fdem put into the database as its own defaults (not the
    /// user's): not reported by [`Petsc::unknown_options`] when unused.
    own_defaults: std::cell::RefCell<Vec<String>>,
    // Not Send/Sync: PETSc is used from the thread that initialised it.
    _not_send: PhantomData<*const ()>,
}

impl Petsc {
    /// Collective. Initialise PETSc on `world` with the program's arguments
    /// (`args[0]` is the program name). PETSc options among them are read
    /// by PETSc; the caller is expected to have removed its own arguments or
    /// to ignore PETSc's warnings about unused options.
    pub fn init<C: AsRaw<Raw = ffi::MPI_Comm>>(world: &C, args: &[String]) -> Result<Petsc> {
        let mut flag = ffi::PetscBool::PETSC_FALSE;
        petsc_call!(PetscInitialized(&mut flag))?;
        if flag == ffi::PetscBool::PETSC_TRUE {
            return Err(PetscError::Usage(
                "PETSc is already initialised in this process".into(),
            ));
        }
        // PETSc keeps pointers into argv for the life of the program: leak it.
        let cstrings: Vec<CString> = args
            .iter()
            .map(|a| CString::new(a.as_str()))
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| PetscError::Usage("argument contains a NUL byte".into()))?;
        let mut ptrs: Vec<*mut c_char> = cstrings
            .into_iter()
            .map(|c| c.into_raw())
            .chain(std::iter::once(std::ptr::null_mut()))
            .collect();
        let argc = Box::leak(Box::new((ptrs.len() - 1) as c_int));
        let argv_ptr = ptrs.as_mut_ptr();
        std::mem::forget(ptrs);
        let argv = Box::leak(Box::new(argv_ptr));
        // SAFETY: PETSC_COMM_WORLD must be set before PetscInitialize; the
        // communicator outlives PETSc because MPI finalises after us.
        unsafe {
            ffi::PETSC_COMM_WORLD = world.as_raw();
        }
        petsc_call!(PetscInitialize(
            argc,
            argv,
            std::ptr::null(),
            std::ptr::null()
        ))?;
        petsc_call!(PetscPushErrorHandler(
            Some(error::record_error_handler),
            std::ptr::null_mut()
        ))?;
        Ok(Petsc {
            comm: world.as_raw(),
            own_defaults: Default::default(),
            _not_send: PhantomData,
        })
    }

    /// The communicator PETSc was initialised on.
    pub fn comm(&self) -> ffi::MPI_Comm {
        self.comm
    }

    /// PETSc's version string, e.g. "PETSc Release Version 3.18.5, ...".
    pub fn version(&self) -> Result<String> {
        let mut buf = [0 as c_char; 256];
        petsc_call!(PetscGetVersion(buf.as_mut_ptr(), buf.len()))?;
        // SAFETY: PETSc writes a NUL-terminated string into buf.
        Ok(unsafe { CStr::from_ptr(buf.as_ptr()) }
            .to_string_lossy()
            .into_owned())
    }

    /// The options in the global database that no PETSc object has read
    /// so far (PETSc's `-options_left` list): `(name without the dash,
    /// value)`.
    pub fn unused_options(&self) -> Result<Vec<(String, Option<String>)>> {
        let mut n: PetscInt = 0;
        let mut names: *mut *mut c_char = std::ptr::null_mut();
        let mut values: *mut *mut c_char = std::ptr::null_mut();
        petsc_call!(PetscOptionsLeftGet(
            std::ptr::null_mut(),
            &mut n,
            &mut names,
            &mut values
        ))?;
        let mut out = Vec::with_capacity(n as usize);
        for i in 0..n as usize {
            // SAFETY: PetscOptionsLeftGet returned n names and n values
            // (a value may be null), valid until PetscOptionsLeftRestore.
            let (name, value) = unsafe {
                let name = CStr::from_ptr(*names.add(i)).to_string_lossy().into_owned();
                let v = *values.add(i);
                let value =
                    (!v.is_null()).then(|| CStr::from_ptr(v).to_string_lossy().into_owned());
                (name, value)
            };
            out.push((name.trim_start_matches('-').to_string(), value));
        }
        petsc_call!(PetscOptionsLeftRestore(
            std::ptr::null_mut(),
            &mut n,
            &mut names,
            &mut values
        ))?;
        Ok(out)
    }

    /// Collective. The options no PETSc object will read, by name: those
    /// [`Petsc::unused_options`] lists after set-up, less the ones a
    /// `KSPSolve` reads only when it runs (`-ksp_view*`,
    /// `-ksp_converged_*`, `-ksp_compute_*`, `-ksp_plot_*`).
    pub fn unknown_options(&self) -> Result<Vec<String>> {
        let read_by_solve = |n: &str| {
            ["ksp_view", "ksp_converged_", "ksp_compute_", "ksp_plot_"]
                .iter()
                .any(|p| n.starts_with(p))
        };
        Ok(self
            .unused_options()?
            .into_iter()
            .filter(|(n, _)| !read_by_solve(n) && !self.own_defaults.borrow().contains(n))
            .map(|(n, v)| match v {
                Some(v) => format!("-{n} {v}"),
                None => format!("-{n}"),
            })
            .collect())
    }

    /// [`Petsc::set_default_option`] for a default of fdem's own (a solver
    /// choice's), which may go unused when the user picks another solver.
    pub fn set_own_default_option(&self, name: &str, value: Option<&str>) -> Result<()> {
        self.own_defaults
            .borrow_mut()
            .push(name.trim_start_matches('-').to_string());
        self.set_default_option(name, value)
    }

    /// Set an option in the global options database unless the command line
    /// (or an earlier call) already set it, so the command line wins.
    pub fn set_default_option(&self, name: &str, value: Option<&str>) -> Result<()> {
        let key = format!("-{}", name.trim_start_matches('-'));
        let ckey = CString::new(key).map_err(|_| PetscError::Usage("NUL in option".into()))?;
        let mut set = ffi::PetscBool::PETSC_FALSE;
        petsc_call!(PetscOptionsHasName(
            std::ptr::null_mut(),
            std::ptr::null(),
            ckey.as_ptr(),
            &mut set
        ))?;
        if set == ffi::PetscBool::PETSC_TRUE {
            return Ok(());
        }
        let cval = value
            .map(CString::new)
            .transpose()
            .map_err(|_| PetscError::Usage("NUL in option value".into()))?;
        petsc_call!(PetscOptionsSetValue(
            std::ptr::null_mut(),
            ckey.as_ptr(),
            cval.as_ref().map_or(std::ptr::null(), |c| c.as_ptr())
        ))
    }

    /// Whether an option is present in the options database.
    pub fn has_option(&self, name: &str) -> Result<bool> {
        let key = format!("-{}", name.trim_start_matches('-'));
        let ckey = CString::new(key).map_err(|_| PetscError::Usage("NUL in option".into()))?;
        let mut set = ffi::PetscBool::PETSC_FALSE;
        petsc_call!(PetscOptionsHasName(
            std::ptr::null_mut(),
            std::ptr::null(),
            ckey.as_ptr(),
            &mut set
        ))?;
        Ok(set == ffi::PetscBool::PETSC_TRUE)
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        // SAFETY: all objects borrowing the guard are gone (lifetimes);
        // the handler pushed in `init` is popped so PETSc frees it.
        unsafe {
            ffi::PetscPopErrorHandler();
            ffi::PetscFinalize();
        }
    }
}

/// A converged reason's name from PETSc's string for it (`reason N` when
/// PETSc has none).
pub(crate) fn reason_name(name: *const c_char, code: i32) -> String {
    if name.is_null() {
        format!("reason {code}")
    } else {
        // SAFETY: PETSc's reason strings are static and NUL-terminated.
        unsafe { CStr::from_ptr(name) }
            .to_string_lossy()
            .into_owned()
    }
}

pub(crate) fn to_bool(b: bool) -> ffi::PetscBool {
    if b {
        ffi::PetscBool::PETSC_TRUE
    } else {
        ffi::PetscBool::PETSC_FALSE
    }
}
