//! Result output: parallel HDF5 time series with an XDMF index, CSV histories,
//! and small serial readers used by tests.
//!
//! # Time series (`<dir>/<stem>.h5` + `<dir>/<stem>.xdmf`)
//!
//! [`TimeSeriesWriter`] writes one HDF5 file through the MPI-IO driver. Every rank
//! contributes the contiguous block of rows it owns (see [`MeshPart`]); rows are
//! written with hyperslab selections and MPI-IO *collective* transfer. Ranks that
//! own no rows take part with empty selections. The file layout is:
//!
//! | path                          | shape    | type | content                                |
//! |-------------------------------|----------|------|----------------------------------------|
//! | `/mesh/coordinates`           | `[N, 3]` | f64  | node coordinates                       |
//! | `/mesh/topology`              | `[E, 4]` | u32  | Tet4 connectivity, global node rows    |
//! | `/static/node/<name>`         | `[N]`    | i32  | static per-node fields (body id, ...)  |
//! | `/static/cell/<name>`         | `[E]`    | i32  | static per-cell fields                 |
//! | `/time`                       | `[S]`    | f64  | output times, one per completed step   |
//! | `/fields/node/<name>/<k:06>`  | `[N, c]` | f64  | node field at step `k` (`[N]` if c = 1) |
//! | `/fields/cell/<name>/<k:06>`  | `[E, c]` | f64  | cell field at step `k` (`[E]` if c = 1) |
//!
//! A field of 6 components is a symmetric tensor, its rows in XDMF `Tensor6`
//! order xx, xy, xz, yy, yz, zz ([`TENSOR6_ORDER`], [`tensor6`]), which the
//! XDMF file marks `AttributeType="Tensor6"`.
//!
//! `/time` is chunked and unlimited; every other dataset is contiguous and
//! allocated when created. The set of time-dependent fields is fixed by the first
//! [`TimeSeriesWriter::write_step`] call.
//!
//! The XDMF file (XDMF 3 syntax) holds a temporal collection with one uniform grid
//! per completed step; static fields are repeated in every step. It refers to the
//! HDF5 file by its bare file name, so both files can be moved together. It uses
//! plain HDF `DataItem`s only (no `HyperSlab`), because ParaView's default reader
//! for `.xdmf` (Xdmf3ReaderS) drops hyperslab attributes; it was checked with
//! ParaView 5.11's "XDMF Reader", Xdmf3ReaderS and Xdmf3ReaderT.
//!
//! ## Crash safety
//!
//! After each step the HDF5 file is flushed (`H5Fflush`, global scope), all ranks
//! synchronise, and only then rank 0 rewrites the XDMF file by writing
//! `<stem>.xdmf.tmp` and renaming it over `<stem>.xdmf`. A process killed at any
//! moment therefore leaves an XDMF file that lists only steps whose data were
//! flushed. Between two flushes the HDF5 metadata changes only by in-place updates
//! (group B-tree, symbol-table and local-heap blocks, the `/time` extent) and newly
//! appended blocks; nothing is freed and reused, so the blocks of the last flushed
//! state stay intact. (Each field's step group reserves local-heap room for 16384
//! step names up front because a growing heap would be moved and its old block
//! freed; symbol-table leaves hold 512 links so that they rarely split.) The file
//! uses the default (earliest) format bounds on purpose: the 1.10
//! "latest" superblock carries open-for-write flags that make an unclosed file
//! unreadable without `h5clear`.
//!
//! The HDF5 file is built as `<stem>.h5.part` and renamed to `<stem>.h5` only once
//! the first step is flushed (or, without steps, at the closing flush), so
//! `<stem>.h5` always has a complete mesh, and the first step's metadata (its new
//! groups and their reserved heaps, the run's largest flush) never change a file of
//! that name. Later flushes are small (an object header per field, in-place symbol
//! table and heap updates), but a kill in the middle of one is not covered by the
//! scheme. A run that fails
//! before its first step should call [`remove_outputs`] so that no half-written
//! output is left behind; [`TimeSeriesWriter::create`] removes its own files when
//! it fails.
//!
//! # Histories
//!
//! [`HistoryWriter`] writes a CSV file from world rank 0 (a no-op elsewhere), one
//! `write(2)` per row, values printed so that they parse back to the same `f64`.
//!
//! # Collective calls
//!
//! Functions documented as "Collective." must be called by every rank of the
//! communicator, in the same order and with the same names, field sets and times.
//! Input is validated on every rank and the verdict is agreed upon before any
//! collective HDF5 operation, so invalid input yields an error on all ranks instead
//! of a deadlock. A [`TimeSeriesWriter`] must be dropped or closed before MPI is
//! finalised.

pub mod checkpoint;
mod ffi;
mod hdf5_out;
mod history;
pub mod particles;
pub mod plot;
mod read;
mod xdmf;

use std::path::{Path, PathBuf};

pub use hdf5_out::{FieldData, MeshPart, TimeSeriesWriter};
pub use history::HistoryWriter;
pub use read::{
    read_cell_field_step, read_mesh, read_node_field_step, read_static_cell_field_i32,
    read_static_node_field_i32, read_times, read_triangles, MeshData,
};

/// The `(row, column)` of each of the six components of a symmetric tensor in
/// XDMF `Tensor6` order: xx, xy, xz, yy, yz, zz (the upper triangle row by
/// row). The XDMF specification defines this order, and ParaView's readers
/// (the legacy "XDMF Reader" and the Xdmf3 readers) expand a `Tensor6`
/// attribute in it.
pub const TENSOR6_ORDER: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// A symmetric 3×3 tensor as the six values of an XDMF `Tensor6` attribute,
/// in [`TENSOR6_ORDER`] (xx, xy, xz, yy, yz, zz); the upper triangle is read.
pub fn tensor6(s: &nalgebra::Matrix3<f64>) -> [f64; 6] {
    TENSOR6_ORDER.map(|(i, j)| s[(i, j)])
}

/// Errors of the output module. Every message names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// An operating-system I/O operation failed.
    #[error("{}: {what}: {cause}", path.display())]
    Io {
        /// File or directory concerned.
        path: PathBuf,
        /// What was being done.
        what: String,
        /// The underlying error.
        cause: std::io::Error,
    },
    /// An HDF5 operation reported through `hdf5-metno` failed.
    #[error("{}: HDF5 error while {what}: {cause}", path.display())]
    Hdf5 {
        /// File concerned.
        path: PathBuf,
        /// What was being done.
        what: String,
        /// The underlying error.
        cause: hdf5::Error,
    },
    /// A direct HDF5 C call failed.
    #[error("{}: HDF5 call {call} failed while {what}", path.display())]
    Hdf5Call {
        /// File concerned.
        path: PathBuf,
        /// The C function that failed.
        call: &'static str,
        /// What was being done.
        what: String,
    },
    /// The caller passed inconsistent or invalid data.
    #[error("{}: invalid input: {what}", path.display())]
    Invalid {
        /// File concerned.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// A collective operation failed on another rank (that rank reports the cause).
    #[error("{}: {what} failed on another MPI rank", path.display())]
    OtherRank {
        /// File concerned.
        path: PathBuf,
        /// What was being done.
        what: String,
    },
    /// The writer was used after an earlier failed write or after it was closed.
    #[error("{}: writer is unusable after an earlier error", path.display())]
    Unusable {
        /// File concerned.
        path: PathBuf,
    },
}

impl IoError {
    pub(crate) fn io(path: &Path, what: impl Into<String>, cause: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            what: what.into(),
            cause,
        }
    }

    pub(crate) fn hdf5(path: &Path, what: impl Into<String>, cause: hdf5::Error) -> Self {
        Self::Hdf5 {
            path: path.to_path_buf(),
            what: what.into(),
            cause,
        }
    }

    pub(crate) fn invalid(path: &Path, what: impl Into<String>) -> Self {
        Self::Invalid {
            path: path.to_path_buf(),
            what: what.into(),
        }
    }
}

/// Paths of the output files of a time series: `(<dir>/<stem>.h5, <dir>/<stem>.xdmf)`.
pub fn output_paths(dir: &Path, stem: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{stem}.h5")),
        dir.join(format!("{stem}.xdmf")),
    )
}

/// Removes the time-series outputs `<stem>.h5`, `<stem>.xdmf` and leftovers
/// `<stem>.h5.part`, `<stem>.xdmf.tmp` from `dir`; missing files are ignored.
///
/// Not collective: call it on rank 0 (calling it on several ranks is harmless).
/// Use it when a run fails before its first output step.
pub fn remove_outputs(dir: &Path, stem: &str) -> Result<(), IoError> {
    let (h5, xdmf) = output_paths(dir, stem);
    let tmp = xdmf::tmp_path(&xdmf);
    let part = hdf5_out::part_path(&h5);
    for path in [&h5, &part, &xdmf, &tmp] {
        match std::fs::remove_file(path) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(IoError::io(path, "removing output file", e)),
        }
    }
    Ok(())
}

/// Checks a field name or file stem: non-empty, not `.` or `..`, and free of `/`,
/// `:`, whitespace and control characters (it ends up in HDF5 paths and in XDMF
/// `file.h5:/path` references). Returns a description of the problem.
pub(crate) fn check_name(kind: &str, name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err(format!("{kind} name is empty"));
    }
    let bad_char = |c: char| c == '/' || c == ':' || c.is_whitespace() || c.is_control();
    if name == "." || name == ".." || name.chars().any(bad_char) {
        return Err(format!(
            "{kind} name {name:?} must not be '.' or '..' nor contain '/', ':', whitespace or control characters"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// XDMF `Tensor6` is xx, xy, xz, yy, yz, zz; a symmetric tensor with a
    /// distinct value in every place must come out in exactly that order.
    #[test]
    fn tensor6_is_in_xdmf_order() {
        let s = nalgebra::Matrix3::new(11.0, 12.0, 13.0, 12.0, 22.0, 23.0, 13.0, 23.0, 33.0);
        assert_eq!(tensor6(&s), [11.0, 12.0, 13.0, 22.0, 23.0, 33.0]);
        // Uniaxial zz: the only non-zero value is the last one.
        let zz = nalgebra::Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0);
        assert_eq!(tensor6(&zz), [0.0, 0.0, 0.0, 0.0, 0.0, 5.0]);
    }
}
