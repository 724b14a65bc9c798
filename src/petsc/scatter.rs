//! Gathering entries of a distributed vector on the ranks that need them
//! (a PETSc `VecScatter` into a vector laid out by the requests).

use std::marker::PhantomData;

use petsc_sys as ffi;

use super::{Petsc, PetscInt, Result, Vector, VectorView};
use crate::petsc_call;

/// The entries `rows` (global indices, any rank's) of vectors laid out like
/// `from`, gathered in the order asked. Each distinct row is moved once:
/// contact pairs ask for the same node many times (8 rows a pair), and a
/// scatter over the repeats cost 10 MiB a rank at the N = 2000 heat-up's
/// first output on 8 ranks.
pub struct Gather<'p> {
    ctx: ffi::VecScatter,
    out: Vector<'p>,
    /// For each request, its row's place among the distinct rows.
    slot: Vec<u32>,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Gather<'p> {
    /// Collective. Set up the gathering of `rows` from vectors like `from`.
    pub fn new(from: &Vector<'p>, requests: &[PetscInt]) -> Result<Self> {
        let (rows, slot) = distinct(requests);
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
            slot,
            _petsc: PhantomData,
        })
    }

    /// Collective. Gather the requested entries of `from`; returns them in
    /// the order asked.
    pub fn gather(&mut self, from: &Vector) -> Result<Vec<f64>> {
        let mode = ffi::ScatterMode::SCATTER_FORWARD;
        let ins = ffi::InsertMode::INSERT_VALUES;
        let (x, y) = (from.as_raw(), self.out.as_raw());
        petsc_call!(VecScatterBegin(self.ctx, x, y, ins, mode))?;
        petsc_call!(VecScatterEnd(self.ctx, x, y, ins, mode))?;
        let got: VectorView<'_> = self.out.view()?;
        Ok(self.slot.iter().map(|&k| got[k as usize]).collect())
    }
}

/// The distinct rows of `requests`, sorted, and each request's place among them.
fn distinct(requests: &[PetscInt]) -> (Vec<PetscInt>, Vec<u32>) {
    let mut rows = requests.to_vec();
    rows.sort_unstable();
    rows.dedup();
    let slot = requests
        .iter()
        .map(|r| rows.partition_point(|x| x < r) as u32)
        .collect();
    (rows, slot)
}

impl Drop for Gather<'_> {
    fn drop(&mut self) {
        // SAFETY: ctx is a valid VecScatter owned by self.
        unsafe {
            ffi::VecScatterDestroy(&mut self.ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::distinct;

    #[test]
    fn repeated_rows_are_moved_once_and_returned_in_the_order_asked() {
        let (rows, slot) = distinct(&[7, 3, 7, 9, 3, 3]);
        assert_eq!(rows, vec![3, 7, 9]);
        assert_eq!(slot, vec![1, 0, 1, 2, 0, 0]);
        let back: Vec<i32> = slot.iter().map(|&k| rows[k as usize]).collect();
        assert_eq!(back, vec![7, 3, 7, 9, 3, 3]);
    }
}
