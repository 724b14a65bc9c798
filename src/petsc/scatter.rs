//! Gathering entries of a distributed vector on the ranks that need them
//! (a PETSc `VecScatter` into a vector laid out by the requests).

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::{Petsc, PetscInt, Result, Vector, VectorView};
use crate::petsc_call;

/// The entries `rows` (global indices, any rank's) of vectors laid out like
/// `from`, gathered into this rank's part of `out` in the order asked.
pub struct Gather<'p> {
    ctx: ffi::VecScatter,
    out: Vector<'p>,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Gather<'p> {
    /// Collective. Set up the gathering of `rows` from vectors like `from`.
    pub fn new(from: &Vector<'p>, rows: &[PetscInt]) -> Result<Self> {
        let out = Vector::new_like(from, rows.len())?;
        // SAFETY: a handle (a pointer) that PetscObjectGetComm overwrites.
        let mut comm: ffi::MPI_Comm = unsafe { std::mem::zeroed() };
        petsc_call!(PetscObjectGetComm(
            from.as_raw() as ffi::PetscObject,
            &mut comm
        ))?;
        let mut is: ffi::IS = std::ptr::null_mut();
        petsc_call!(ISCreateGeneral(
            comm,
            rows.len() as PetscInt,
            rows.as_ptr(),
            ffi::PetscCopyMode::PETSC_COPY_VALUES,
            &mut is
        ))?;
        let mut ctx: ffi::VecScatter = std::ptr::null_mut();
        // iy NULL: the requests fill `out`'s owned entries in order.
        let made = petsc_call!(VecScatterCreate(
            from.as_raw(),
            is,
            out.as_raw(),
            std::ptr::null_mut(),
            &mut ctx
        ));
        // SAFETY: is was created above and is not used after this.
        unsafe {
            ffi::ISDestroy(&mut is);
        }
        made?;
        Ok(Gather {
            ctx,
            out,
            _petsc: PhantomData,
        })
    }

    /// Collective. Gather the requested entries of `from`; returns them in
    /// the order asked.
    pub fn gather(&mut self, from: &Vector) -> Result<VectorView<'_>> {
        let mode = ffi::ScatterMode::SCATTER_FORWARD;
        let ins = ffi::InsertMode::INSERT_VALUES;
        let (x, y) = (from.as_raw(), self.out.as_raw());
        petsc_call!(VecScatterBegin(self.ctx, x, y, ins, mode))?;
        petsc_call!(VecScatterEnd(self.ctx, x, y, ins, mode))?;
        self.out.view()
    }
}

impl Drop for Gather<'_> {
    fn drop(&mut self) {
        // SAFETY: ctx is a valid VecScatter owned by self.
        unsafe {
            ffi::VecScatterDestroy(&mut self.ctx);
        }
    }
}
