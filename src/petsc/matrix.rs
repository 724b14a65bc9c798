//! Distributed sparse matrices (`MATAIJ`: SeqAIJ on one rank, MPIAIJ on
//! several), preallocated exactly from the mesh graph.

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::{to_bool, Petsc, PetscError, PetscInt, Result, Vector};
use crate::petsc_call;

/// A distributed sparse matrix; move-only owner of a PETSc `Mat`.
pub struct Matrix<'p> {
    raw: ffi::Mat,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Matrix<'p> {
    /// Collective. A square AIJ matrix with `owned` rows on this rank,
    /// preallocated with `d_nnz[i]` entries of row `i` in the diagonal block
    /// (columns owned by this rank) and `o_nnz[i]` in the off-diagonal block.
    /// Inserting outside the preallocation is an error, not a slow path.
    pub fn new_aij(
        petsc: &'p Petsc,
        owned: usize,
        d_nnz: &[PetscInt],
        o_nnz: &[PetscInt],
    ) -> Result<Self> {
        if d_nnz.len() != owned || o_nnz.len() != owned {
            return Err(PetscError::Usage(format!(
                "MatCreateAIJ: {owned} owned rows but {} / {} preallocation counts",
                d_nnz.len(),
                o_nnz.len()
            )));
        }
        let mut raw: ffi::Mat = std::ptr::null_mut();
        let n = owned as PetscInt;
        petsc_call!(MatCreateAIJ(
            petsc.comm(),
            n,
            n,
            super::PETSC_DECIDE,
            super::PETSC_DECIDE,
            0,
            d_nnz.as_ptr(),
            0,
            o_nnz.as_ptr(),
            &mut raw
        ))?;
        let m = Matrix {
            raw,
            _petsc: PhantomData,
        };
        petsc_call!(MatSetOption(
            m.raw,
            ffi::MatOption::MAT_NEW_NONZERO_ALLOCATION_ERR,
            to_bool(true)
        ))?;
        Ok(m)
    }

    /// Collective. A copy with the same pattern and values.
    pub fn duplicate(&self) -> Result<Self> {
        let mut raw: ffi::Mat = std::ptr::null_mut();
        petsc_call!(MatDuplicate(
            self.raw,
            ffi::MatDuplicateOption::MAT_COPY_VALUES,
            &mut raw
        ))?;
        Ok(Matrix {
            raw,
            _petsc: PhantomData,
        })
    }

    /// The raw handle.
    pub fn as_raw(&self) -> ffi::Mat {
        self.raw
    }

    /// Add a dense block `vals` (row-major, rows.len() × cols.len()) at
    /// global indices. Call [`Matrix::assemble`] after all additions.
    pub fn add_values(&mut self, rows: &[PetscInt], cols: &[PetscInt], vals: &[f64]) -> Result<()> {
        if rows.len() * cols.len() != vals.len() {
            return Err(PetscError::Usage(format!(
                "MatSetValues: {}x{} block but {} values",
                rows.len(),
                cols.len(),
                vals.len()
            )));
        }
        petsc_call!(MatSetValues(
            self.raw,
            rows.len() as PetscInt,
            rows.as_ptr(),
            cols.len() as PetscInt,
            cols.as_ptr(),
            vals.as_ptr(),
            ffi::InsertMode::ADD_VALUES
        ))
    }

    /// Collective. Final assembly (communicates off-rank entries).
    pub fn assemble(&mut self) -> Result<()> {
        petsc_call!(MatAssemblyBegin(
            self.raw,
            ffi::MatAssemblyType::MAT_FINAL_ASSEMBLY
        ))?;
        petsc_call!(MatAssemblyEnd(
            self.raw,
            ffi::MatAssemblyType::MAT_FINAL_ASSEMBLY
        ))
    }

    /// Declare the matrix symmetric (lets PETSc pick symmetric methods).
    pub fn set_symmetric(&mut self, spd: bool) -> Result<()> {
        petsc_call!(MatSetOption(
            self.raw,
            ffi::MatOption::MAT_SYMMETRIC,
            to_bool(true)
        ))?;
        if spd {
            petsc_call!(MatSetOption(
                self.raw,
                ffi::MatOption::MAT_SPD,
                to_bool(true)
            ))?;
        }
        Ok(())
    }

    /// Collective. `y = A x`.
    pub fn mult(&self, x: &Vector, y: &mut Vector) -> Result<()> {
        petsc_call!(MatMult(self.raw, x.as_raw(), y.as_raw()))
    }

    /// Collective. `z = A x + y`.
    pub fn mult_add(&self, x: &Vector, y: &Vector, z: &mut Vector) -> Result<()> {
        petsc_call!(MatMultAdd(self.raw, x.as_raw(), y.as_raw(), z.as_raw()))
    }

    /// Collective. `self += a X` where X has the same nonzero pattern.
    pub fn axpy_same_pattern(&mut self, a: f64, x: &Matrix) -> Result<()> {
        petsc_call!(MatAXPY(
            self.raw,
            a,
            x.raw,
            ffi::MatStructure::SAME_NONZERO_PATTERN
        ))
    }

    /// Collective. `self += a I`.
    pub fn shift(&mut self, a: f64) -> Result<()> {
        petsc_call!(MatShift(self.raw, a))
    }

    /// Collective. `self *= a`.
    pub fn scale(&mut self, a: f64) -> Result<()> {
        petsc_call!(MatScale(self.raw, a))
    }

    /// Collective. `self = diag(l) self diag(r)`; `None` skips a side.
    pub fn diagonal_scale(&mut self, l: Option<&Vector>, r: Option<&Vector>) -> Result<()> {
        petsc_call!(MatDiagonalScale(
            self.raw,
            l.map_or(std::ptr::null_mut(), |v| v.as_raw()),
            r.map_or(std::ptr::null_mut(), |v| v.as_raw())
        ))
    }

    /// Collective. Row sums into `v`.
    pub fn row_sums(&self, v: &mut Vector) -> Result<()> {
        petsc_call!(MatGetRowSum(self.raw, v.as_raw()))
    }

    /// Collective. Zero the given rows (global indices owned by this rank)
    /// and put `diag` on their diagonal.
    pub fn zero_rows(&mut self, rows: &[PetscInt], diag: f64) -> Result<()> {
        petsc_call!(MatZeroRows(
            self.raw,
            rows.len() as PetscInt,
            rows.as_ptr(),
            diag,
            std::ptr::null_mut(),
            std::ptr::null_mut()
        ))
    }

    /// Collective. Zero the given rows and columns (global indices owned by
    /// this rank) and put `diag` on their diagonal; keeps symmetry.
    pub fn zero_rows_columns(&mut self, rows: &[PetscInt], diag: f64) -> Result<()> {
        petsc_call!(MatZeroRowsColumns(
            self.raw,
            rows.len() as PetscInt,
            rows.as_ptr(),
            diag,
            std::ptr::null_mut(),
            std::ptr::null_mut()
        ))
    }
}

impl Drop for Matrix<'_> {
    fn drop(&mut self) {
        // SAFETY: raw is a valid Mat owned by self.
        unsafe {
            ffi::MatDestroy(&mut self.raw);
        }
    }
}
