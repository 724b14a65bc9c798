//! Distributed PETSc vectors (`VECMPI`) with borrowed array views.

use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};

use petsc_sys as ffi;

use super::{Petsc, PetscError, PetscInt, Result, PETSC_DECIDE};
use crate::petsc_call;

/// A distributed vector; move-only owner of a PETSc `Vec`.
pub struct Vector<'p> {
    raw: ffi::Vec,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Vector<'p> {
    /// Collective. A vector with `owned` entries on this rank (global size summed).
    pub fn new(petsc: &'p Petsc, owned: usize) -> Result<Self> {
        Self::on(petsc.comm(), owned)
    }

    fn on(comm: ffi::MPI_Comm, owned: usize) -> Result<Self> {
        let mut raw: ffi::Vec = std::ptr::null_mut();
        petsc_call!(VecCreateMPI(
            comm,
            owned as PetscInt,
            PETSC_DECIDE,
            &mut raw
        ))?;
        Ok(Vector {
            raw,
            _petsc: PhantomData,
        })
    }

    /// Collective over `like`'s communicator. A vector with `owned` entries
    /// on this rank.
    pub fn new_like(like: &Vector<'p>, owned: usize) -> Result<Self> {
        // SAFETY: a handle (a pointer) that PetscObjectGetComm overwrites.
        let mut comm: ffi::MPI_Comm = unsafe { std::mem::zeroed() };
        petsc_call!(PetscObjectGetComm(like.raw as ffi::PetscObject, &mut comm))?;
        Self::on(comm, owned)
    }

    /// Collective. A new vector with the same layout (values not copied).
    pub fn duplicate(&self) -> Result<Self> {
        let mut raw: ffi::Vec = std::ptr::null_mut();
        petsc_call!(VecDuplicate(self.raw, &mut raw))?;
        Ok(Vector {
            raw,
            _petsc: PhantomData,
        })
    }

    /// Collective. A copy (layout and values).
    pub fn duplicate_from(&self) -> Result<Self> {
        let mut v = self.duplicate()?;
        v.copy_from(self)?;
        Ok(v)
    }

    /// A vector PETSc owns (a callback's argument), wrapped for the safe
    /// methods and never destroyed by us.
    ///
    /// # Safety
    /// `raw` must be a valid `Vec` that outlives the wrapper.
    pub(super) unsafe fn borrowed(raw: ffi::Vec) -> std::mem::ManuallyDrop<Self> {
        std::mem::ManuallyDrop::new(Vector {
            raw,
            _petsc: PhantomData,
        })
    }

    /// The raw handle (for calls the safe layer does not wrap).
    pub fn as_raw(&self) -> ffi::Vec {
        self.raw
    }

    /// Number of entries owned by this rank.
    pub fn local_size(&self) -> usize {
        let mut n: PetscInt = 0;
        // VecGetLocalSize cannot fail on a valid vector.
        let _ = petsc_call!(VecGetLocalSize(self.raw, &mut n));
        n as usize
    }

    /// Global size.
    pub fn global_size(&self) -> usize {
        let mut n: PetscInt = 0;
        let _ = petsc_call!(VecGetSize(self.raw, &mut n));
        n as usize
    }

    /// The global index range `[start, end)` owned by this rank.
    pub fn ownership_range(&self) -> (usize, usize) {
        let (mut lo, mut hi): (PetscInt, PetscInt) = (0, 0);
        let _ = petsc_call!(VecGetOwnershipRange(self.raw, &mut lo, &mut hi));
        (lo as usize, hi as usize)
    }

    /// Set every entry to `a`.
    pub fn set(&mut self, a: f64) -> Result<()> {
        petsc_call!(VecSet(self.raw, a))
    }

    /// `self = x` (same layout).
    pub fn copy_from(&mut self, x: &Vector) -> Result<()> {
        petsc_call!(VecCopy(x.raw, self.raw))
    }

    /// `self += a x`.
    pub fn axpy(&mut self, a: f64, x: &Vector) -> Result<()> {
        petsc_call!(VecAXPY(self.raw, a, x.raw))
    }

    /// `self = a self + x`.
    pub fn aypx(&mut self, a: f64, x: &Vector) -> Result<()> {
        petsc_call!(VecAYPX(self.raw, a, x.raw))
    }

    /// `self = x .* y` (entry-wise).
    pub fn pointwise_mult(&mut self, x: &Vector, y: &Vector) -> Result<()> {
        petsc_call!(VecPointwiseMult(self.raw, x.raw, y.raw))
    }

    /// Scale by `a`.
    pub fn scale(&mut self, a: f64) -> Result<()> {
        petsc_call!(VecScale(self.raw, a))
    }

    /// Collective. Sum of all entries.
    pub fn sum(&self) -> Result<f64> {
        let mut s = 0.0;
        petsc_call!(VecSum(self.raw, &mut s))?;
        Ok(s)
    }

    /// Collective. Dot product.
    pub fn dot(&self, y: &Vector) -> Result<f64> {
        let mut s = 0.0;
        petsc_call!(VecDot(self.raw, y.raw, &mut s))?;
        Ok(s)
    }

    /// Collective. Euclidean norm.
    pub fn norm2(&self) -> Result<f64> {
        let mut s = 0.0;
        petsc_call!(VecNorm(self.raw, ffi::NormType::NORM_2, &mut s))?;
        Ok(s)
    }

    /// Collective. The smallest entry.
    pub fn min(&self) -> Result<f64> {
        let mut v = 0.0;
        petsc_call!(VecMin(self.raw, std::ptr::null_mut(), &mut v))?;
        Ok(v)
    }

    /// Collective. Max-abs norm.
    pub fn norm_inf(&self) -> Result<f64> {
        let mut s = 0.0;
        petsc_call!(VecNorm(self.raw, ffi::NormType::NORM_INFINITY, &mut s))?;
        Ok(s)
    }

    /// Add (or insert) values at global indices; call [`Vector::assemble`] after.
    pub fn set_values(&mut self, idx: &[PetscInt], vals: &[f64], add: bool) -> Result<()> {
        if idx.len() != vals.len() {
            return Err(PetscError::Usage(format!(
                "VecSetValues: {} indices but {} values",
                idx.len(),
                vals.len()
            )));
        }
        let mode = if add {
            ffi::InsertMode::ADD_VALUES
        } else {
            ffi::InsertMode::INSERT_VALUES
        };
        petsc_call!(VecSetValues(
            self.raw,
            idx.len() as PetscInt,
            idx.as_ptr(),
            vals.as_ptr(),
            mode
        ))
    }

    /// Collective. Communicate off-rank entries set by [`Vector::set_values`].
    pub fn assemble(&mut self) -> Result<()> {
        petsc_call!(VecAssemblyBegin(self.raw))?;
        petsc_call!(VecAssemblyEnd(self.raw))
    }

    /// Read-only view of the owned entries.
    pub fn view(&self) -> Result<VectorView<'_>> {
        let mut ptr: *const f64 = std::ptr::null();
        petsc_call!(VecGetArrayRead(self.raw, &mut ptr))?;
        let n = self.local_size();
        Ok(VectorView {
            vec: self.raw,
            ptr,
            len: n,
            _borrow: PhantomData,
        })
    }

    /// Mutable view of the owned entries.
    pub fn view_mut(&mut self) -> Result<VectorViewMut<'_>> {
        let mut ptr: *mut f64 = std::ptr::null_mut();
        petsc_call!(VecGetArray(self.raw, &mut ptr))?;
        let n = self.local_size();
        Ok(VectorViewMut {
            vec: self.raw,
            ptr,
            len: n,
            _borrow: PhantomData,
        })
    }

    /// Copy the owned entries into a Rust vector.
    pub fn to_local_vec(&self) -> Result<Vec<f64>> {
        Ok(self.view()?.to_vec())
    }

    /// Overwrite the owned entries from a slice of the local size.
    pub fn copy_from_slice(&mut self, vals: &[f64]) -> Result<()> {
        let mut v = self.view_mut()?;
        if v.len() != vals.len() {
            return Err(PetscError::Usage(format!(
                "copy_from_slice: local size {} but {} values",
                v.len(),
                vals.len()
            )));
        }
        v.copy_from_slice(vals);
        Ok(())
    }
}

impl Drop for Vector<'_> {
    fn drop(&mut self) {
        // SAFETY: raw is a valid Vec owned by self.
        unsafe {
            ffi::VecDestroy(&mut self.raw);
        }
    }
}

/// Read-only borrowed view of a vector's owned entries; restores on drop.
pub struct VectorView<'a> {
    vec: ffi::Vec,
    ptr: *const f64,
    len: usize,
    _borrow: PhantomData<&'a ()>,
}

impl Deref for VectorView<'_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: PETSc guarantees len valid entries until restore.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl Drop for VectorView<'_> {
    fn drop(&mut self) {
        // SAFETY: ptr came from VecGetArrayRead on vec.
        unsafe {
            ffi::VecRestoreArrayRead(self.vec, &mut self.ptr);
        }
    }
}

/// Mutable borrowed view of a vector's owned entries; restores on drop.
pub struct VectorViewMut<'a> {
    vec: ffi::Vec,
    ptr: *mut f64,
    len: usize,
    _borrow: PhantomData<&'a mut ()>,
}

impl Deref for VectorViewMut<'_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        if self.len == 0 {
            return &[];
        }
        // SAFETY: as for VectorView.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl DerefMut for VectorViewMut<'_> {
    fn deref_mut(&mut self) -> &mut [f64] {
        if self.len == 0 {
            return &mut [];
        }
        // SAFETY: exclusive borrow of the vector; PETSc guarantees len entries.
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
    }
}

impl Drop for VectorViewMut<'_> {
    fn drop(&mut self) {
        // SAFETY: ptr came from VecGetArray on vec.
        unsafe {
            ffi::VecRestoreArray(self.vec, &mut self.ptr);
        }
    }
}
