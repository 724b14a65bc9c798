//! Distributed sparse matrices (`MATAIJ`: SeqAIJ on one rank, MPIAIJ on
//! several), preallocated exactly from the mesh graph.

use std::ffi::CStr;
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

    /// Collective. A square AIJ matrix with `owned` rows on this rank whose
    /// pattern is the union of the dense blocks `fill` names through
    /// [`Pattern::add`] (global indices; a rank may name rows it does not
    /// own), preallocated exactly by PETSc's `MATPREALLOCATOR` and holding
    /// explicit zeros at every place of the pattern. Inserting outside it
    /// is an error.
    pub fn with_pattern(
        petsc: &'p Petsc,
        owned: usize,
        fill: impl FnOnce(&mut Pattern) -> Result<()>,
    ) -> Result<Self> {
        let n = owned as PetscInt;
        let sized = |type_name: &CStr| -> Result<ffi::Mat> {
            let mut raw: ffi::Mat = std::ptr::null_mut();
            petsc_call!(MatCreate(petsc.comm(), &mut raw))?;
            petsc_call!(MatSetSizes(
                raw,
                n,
                n,
                super::PETSC_DECIDE,
                super::PETSC_DECIDE
            ))?;
            petsc_call!(MatSetType(raw, type_name.as_ptr()))?;
            Ok(raw)
        };
        let mut pre = Matrix {
            raw: sized(c"preallocator")?,
            _petsc: PhantomData,
        };
        petsc_call!(MatSetUp(pre.raw))?;
        let mut pattern = Pattern {
            raw: pre.raw,
            zeros: Vec::new(),
        };
        fill(&mut pattern)?;
        pre.assemble()?;
        let m = Matrix {
            raw: sized(c"aij")?,
            _petsc: PhantomData,
        };
        petsc_call!(MatPreallocatorPreallocate(pre.raw, to_bool(true), m.raw))?;
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

    /// One rank's matrix only. The nonzeros of the Cholesky factor that
    /// PETSc's own solver makes of this symmetric matrix with the fill-
    /// reducing ordering `ordering` (`c"nd"`, `c"rcm"`, ...): the symbolic
    /// factorisation alone, which costs little beside the numeric one.
    pub fn cholesky_fill(&self, ordering: &CStr) -> Result<f64> {
        let (mut row, mut col): (ffi::IS, ffi::IS) = (std::ptr::null_mut(), std::ptr::null_mut());
        petsc_call!(MatGetOrdering(
            self.raw,
            ordering.as_ptr(),
            &mut row,
            &mut col
        ))?;
        let mut factor: ffi::Mat = std::ptr::null_mut();
        let fill = (|| {
            petsc_call!(MatGetFactor(
                self.raw,
                c"petsc".as_ptr(),
                ffi::MatFactorType::MAT_FACTOR_CHOLESKY,
                &mut factor
            ))?;
            // SAFETY: plain C structs of numbers, filled in by PETSc below.
            let mut info: ffi::MatFactorInfo = unsafe { std::mem::zeroed() };
            petsc_call!(MatFactorInfoInitialize(&mut info))?;
            petsc_call!(MatCholeskyFactorSymbolic(factor, self.raw, row, &info))?;
            let mut got: ffi::MatInfo = unsafe { std::mem::zeroed() };
            petsc_call!(MatGetInfo(factor, ffi::MatInfoType::MAT_LOCAL, &mut got))?;
            Ok(got.nz_allocated)
        })();
        let _ = petsc_call!(MatDestroy(&mut factor));
        let _ = petsc_call!(ISDestroy(&mut row));
        let _ = petsc_call!(ISDestroy(&mut col));
        fill
    }

    /// A matrix PETSc owns (a callback's argument), wrapped for the safe
    /// methods and never destroyed by us.
    ///
    /// # Safety
    /// `raw` must be a valid `Mat` that outlives the wrapper.
    pub(super) unsafe fn borrowed(raw: ffi::Mat) -> std::mem::ManuallyDrop<Self> {
        std::mem::ManuallyDrop::new(Matrix {
            raw,
            _petsc: PhantomData,
        })
    }

    /// Collective. Copy the values of `x`, which has this matrix's pattern.
    pub fn copy_values_from(&mut self, x: &Matrix) -> Result<()> {
        petsc_call!(MatCopy(
            x.raw,
            self.raw,
            ffi::MatStructure::SAME_NONZERO_PATTERN
        ))
    }

    /// Zero every stored entry, keeping the pattern.
    pub fn zero_entries(&mut self) -> Result<()> {
        petsc_call!(MatZeroEntries(self.raw))
    }

    /// Collective. Add `d` to the diagonal (its entries are in the pattern).
    pub fn add_diagonal(&mut self, d: &Vector) -> Result<()> {
        petsc_call!(MatDiagonalSet(
            self.raw,
            d.as_raw(),
            ffi::InsertMode::ADD_VALUES
        ))
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

    /// Global rows `[start, end)` owned by this rank.
    pub fn ownership_range(&self) -> Result<(PetscInt, PetscInt)> {
        let (mut lo, mut hi) = (0, 0);
        petsc_call!(MatGetOwnershipRange(self.raw, &mut lo, &mut hi))?;
        Ok((lo, hi))
    }

    /// Collective. The diagonal into `v`.
    pub fn diagonal(&self, v: &mut Vector) -> Result<()> {
        petsc_call!(MatGetDiagonal(self.raw, v.as_raw()))
    }

    /// Collective. The transpose, as a new matrix.
    pub fn transpose(&self) -> Result<Self> {
        let mut raw: ffi::Mat = std::ptr::null_mut();
        petsc_call!(MatTranspose(
            self.raw,
            ffi::MatReuse::MAT_INITIAL_MATRIX,
            &mut raw
        ))?;
        Ok(Matrix {
            raw,
            _petsc: PhantomData,
        })
    }

    /// The stored columns (global) and values of owned row `r`, copied out.
    fn row(&self, r: PetscInt) -> Result<(Vec<PetscInt>, Vec<f64>)> {
        let mut n: PetscInt = 0;
        let mut cols: *const PetscInt = std::ptr::null();
        let mut vals: *const f64 = std::ptr::null();
        petsc_call!(MatGetRow(self.raw, r, &mut n, &mut cols, &mut vals))?;
        // SAFETY: MatGetRow returned n valid entries in both arrays,
        // readable until MatRestoreRow; they are copied out before that.
        let out = unsafe {
            (
                std::slice::from_raw_parts(cols, n as usize).to_vec(),
                std::slice::from_raw_parts(vals, n as usize).to_vec(),
            )
        };
        petsc_call!(MatRestoreRow(self.raw, r, &mut n, &mut cols, &mut vals))?;
        Ok(out)
    }

    /// Collective. Rewrite the stored entries of every owned row: `f(row,
    /// cols, vals, other)` sees the row's stored columns (global, ascending)
    /// and values, and `other`'s values of the same row at those columns
    /// (0 where `other` stores none), and may change `vals` in place; the
    /// pattern stays. The matrix is reassembled afterwards.
    pub fn update_owned_rows(
        &mut self,
        other: &Matrix,
        mut f: impl FnMut(PetscInt, &[PetscInt], &mut [f64], &[f64]),
    ) -> Result<()> {
        let (lo, hi) = self.ownership_range()?;
        let mut changed: Vec<(PetscInt, Vec<PetscInt>, Vec<f64>)> = Vec::new();
        for r in lo..hi {
            let (c, v) = self.row(r)?;
            let (oc, ov) = other.row(r)?;
            let aligned: Vec<f64> = c
                .iter()
                .map(|col| oc.binary_search(col).map_or(0.0, |k| ov[k]))
                .collect();
            let mut v2 = v.clone();
            f(r, &c, &mut v2, &aligned);
            if v2 != v {
                changed.push((r, c, v2));
            }
        }
        for (r, c, v) in &changed {
            petsc_call!(MatSetValues(
                self.raw,
                1,
                r,
                c.len() as PetscInt,
                c.as_ptr(),
                v.as_ptr(),
                ffi::InsertMode::INSERT_VALUES
            ))?;
        }
        self.assemble()
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

/// The pattern of a matrix under construction ([`Matrix::with_pattern`]).
pub struct Pattern {
    raw: ffi::Mat,
    zeros: Vec<f64>,
}

impl Pattern {
    /// Every (row, column) of `rows` × `cols` (global indices) is in the pattern.
    pub fn add(&mut self, rows: &[PetscInt], cols: &[PetscInt]) -> Result<()> {
        let n = rows.len() * cols.len();
        if self.zeros.len() < n {
            self.zeros.resize(n, 0.0);
        }
        petsc_call!(MatSetValues(
            self.raw,
            rows.len() as PetscInt,
            rows.as_ptr(),
            cols.len() as PetscInt,
            cols.as_ptr(),
            self.zeros.as_ptr(),
            ffi::InsertMode::INSERT_VALUES
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
