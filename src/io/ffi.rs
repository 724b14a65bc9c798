//! The few HDF5 C calls that `hdf5-metno` 0.15 does not wrap: collective data
//! transfer (`H5Pset_dxpl_mpio`), writes with explicit (possibly empty) hyperslab
//! selections and a global-scope `H5Fflush`.
//!
//! The symbols come from the libhdf5 that `hdf5-metno-sys` links; the declarations
//! follow the C API of HDF5 >= 1.10 (`hid_t` is 64 bits). Every call is made while
//! holding `hdf5-metno`'s library lock, like `hdf5-metno`'s own calls.

#![allow(non_camel_case_types, non_upper_case_globals)]

use std::os::raw::{c_int, c_void};

use hdf5::{Dataset, Datatype, H5Type};

type hid_t = i64;
type herr_t = c_int;
type hsize_t = u64;

const H5S_SELECT_SET: c_int = 0;
const H5FD_MPIO_COLLECTIVE: c_int = 1;
const H5F_SCOPE_GLOBAL: c_int = 1;

extern "C" {
    static H5P_CLS_DATASET_XFER_ID_g: hid_t;
    fn H5open() -> herr_t;
    fn H5Pcreate(cls_id: hid_t) -> hid_t;
    fn H5Pset_dxpl_mpio(dxpl_id: hid_t, xfer_mode: c_int) -> herr_t;
    fn H5Pclose(plist_id: hid_t) -> herr_t;
    fn H5Dget_space(dset_id: hid_t) -> hid_t;
    fn H5Screate_simple(rank: c_int, dims: *const hsize_t, maxdims: *const hsize_t) -> hid_t;
    fn H5Sselect_hyperslab(
        space_id: hid_t,
        op: c_int,
        start: *const hsize_t,
        stride: *const hsize_t,
        count: *const hsize_t,
        block: *const hsize_t,
    ) -> herr_t;
    fn H5Sselect_none(space_id: hid_t) -> herr_t;
    fn H5Sclose(space_id: hid_t) -> herr_t;
    fn H5Dwrite(
        dset_id: hid_t,
        mem_type_id: hid_t,
        mem_space_id: hid_t,
        file_space_id: hid_t,
        dxpl_id: hid_t,
        buf: *const c_void,
    ) -> herr_t;
    fn H5Fflush(object_id: hid_t, scope: c_int) -> herr_t;
}

/// Name of the C call that failed.
pub(crate) type CallError = &'static str;

fn check_id(id: hid_t, call: CallError) -> Result<hid_t, CallError> {
    if id < 0 {
        Err(call)
    } else {
        Ok(id)
    }
}

fn check(status: herr_t, call: CallError) -> Result<(), CallError> {
    if status < 0 {
        Err(call)
    } else {
        Ok(())
    }
}

/// An owned dataspace identifier.
struct Space(hid_t);

impl Drop for Space {
    fn drop(&mut self) {
        // SAFETY: `self.0` is a valid dataspace id owned by this value.
        unsafe {
            H5Sclose(self.0);
        }
    }
}

/// A dataset-transfer property list selecting MPI-IO collective transfer.
pub(crate) struct CollectiveXfer(hid_t);

impl CollectiveXfer {
    pub(crate) fn new() -> Result<Self, CallError> {
        hdf5::sync::sync(|| {
            // SAFETY: plain HDF5 C calls; H5open initialises the class ids read below.
            unsafe {
                check(H5open(), "H5open")?;
                let id = check_id(H5Pcreate(H5P_CLS_DATASET_XFER_ID_g), "H5Pcreate")?;
                let xfer = Self(id);
                check(
                    H5Pset_dxpl_mpio(xfer.0, H5FD_MPIO_COLLECTIVE),
                    "H5Pset_dxpl_mpio",
                )?;
                Ok(xfer)
            }
        })
    }
}

impl Drop for CollectiveXfer {
    fn drop(&mut self) {
        // SAFETY: `self.0` is a valid property-list id owned by this value.
        hdf5::sync::sync(|| unsafe {
            H5Pclose(self.0);
        });
    }
}

/// Creates the file dataspace of `ds` with the block `start .. start + count`
/// selected (nothing selected when the block is empty), and a 1-D memory
/// dataspace of the same number of elements.
fn spaces(ds: &Dataset, start: &[u64], count: &[u64]) -> Result<(Space, Space, usize), CallError> {
    let n: u64 = count.iter().product();
    // SAFETY: plain HDF5 C calls on ids owned here; arrays outlive the calls.
    unsafe {
        let file = Space(check_id(H5Dget_space(ds.id()), "H5Dget_space")?);
        let mem_dims = [n];
        let mem = Space(check_id(
            H5Screate_simple(1, mem_dims.as_ptr(), std::ptr::null()),
            "H5Screate_simple",
        )?);
        if n == 0 {
            check(H5Sselect_none(file.0), "H5Sselect_none")?;
            check(H5Sselect_none(mem.0), "H5Sselect_none")?;
        } else {
            check(
                H5Sselect_hyperslab(
                    file.0,
                    H5S_SELECT_SET,
                    start.as_ptr(),
                    std::ptr::null(),
                    count.as_ptr(),
                    std::ptr::null(),
                ),
                "H5Sselect_hyperslab",
            )?;
        }
        let n = usize::try_from(n).map_err(|_| "H5Screate_simple")?;
        Ok((file, mem, n))
    }
}

/// Writes `data` (C order) into the block `start .. start + count` of `ds` with
/// collective transfer. Collective: every rank calls it, possibly with an empty block.
pub(crate) fn write_block<T: H5Type>(
    ds: &Dataset,
    xfer: &CollectiveXfer,
    start: &[u64],
    count: &[u64],
    data: &[T],
) -> Result<(), CallError> {
    assert_eq!(start.len(), count.len());
    let mem_type = Datatype::from_type::<T>().map_err(|_| "H5Tcopy")?;
    hdf5::sync::sync(|| {
        let (file, mem, n) = spaces(ds, start, count)?;
        assert_eq!(
            n,
            data.len(),
            "write_block: data length does not match block"
        );
        // SAFETY: `data` holds exactly the selected number of elements of type T,
        // whose HDF5 memory type is `mem_type`.
        unsafe {
            check(
                H5Dwrite(
                    ds.id(),
                    mem_type.id(),
                    mem.0,
                    file.0,
                    xfer.0,
                    data.as_ptr().cast(),
                ),
                "H5Dwrite",
            )
        }
    })
}

/// `H5Fflush(file, H5F_SCOPE_GLOBAL)`. Collective for files opened with MPI-IO.
pub(crate) fn flush_global(file: &hdf5::File) -> Result<(), CallError> {
    // SAFETY: `file.id()` is a valid, open file id.
    hdf5::sync::sync(|| unsafe { check(H5Fflush(file.id(), H5F_SCOPE_GLOBAL), "H5Fflush") })
}

/// The MPI-IO hints fdem opens its parallel files with, freed on drop.
///
/// `cb_buffer_size`: the collective buffer of each aggregator rank. Open
/// MPI's OMPIO defaults to 32 MiB, allocated on the aggregators at each
/// collective write, which was the peak of an 8-rank N = 2000 heat-up
/// (two 16 MiB buffers on rank 0, about a fifth of its memory); 4 MiB
/// keeps the writes collective at a few more rounds for large fields.
pub(crate) struct IoHints(mpi_sys::MPI_Info);

/// Collective buffer per aggregator (bytes).
const CB_BUFFER_SIZE: &str = "4194304";

impl IoHints {
    pub(crate) fn new() -> IoHints {
        let mut info = std::mem::MaybeUninit::<mpi_sys::MPI_Info>::uninit();
        // SAFETY: MPI is initialised before any file is opened; the key and
        // value are NUL-terminated; MPI_Info_set copies them.
        unsafe {
            mpi_sys::MPI_Info_create(info.as_mut_ptr());
            let info = info.assume_init();
            let key = std::ffi::CString::new("cb_buffer_size").expect("no NUL");
            let value = std::ffi::CString::new(CB_BUFFER_SIZE).expect("no NUL");
            mpi_sys::MPI_Info_set(info, key.as_ptr(), value.as_ptr());
            IoHints(info)
        }
    }

    /// The info object (the MPI-IO driver duplicates it).
    pub(crate) fn info(&self) -> mpi_sys::MPI_Info {
        self.0
    }
}

impl Drop for IoHints {
    fn drop(&mut self) {
        // SAFETY: created by MPI_Info_create and freed once.
        unsafe {
            mpi_sys::MPI_Info_free(&mut self.0);
        }
    }
}
