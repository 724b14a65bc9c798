//! Result output: parallel HDF5 time series with an XDMF index, CSV histories,
//! and small serial readers used by tests.
//!
//! # Time series (`<dir>/<stem>.h5`, `<dir>/<stem>_steps/`, `<dir>/<stem>.xdmf`)
//!
//! [`TimeSeriesWriter`] writes a series as several HDF5 files through the MPI-IO
//! driver: the *mesh file* `<stem>.h5` (mesh and static fields, written once) and
//! one *step file* `<stem>_steps/<k:06>.h5` per output step `k` = 0, 1, ... Every
//! rank contributes the contiguous block of rows it owns (see [`MeshPart`]); rows
//! are written with hyperslab selections and MPI-IO *collective* transfer. Ranks
//! that own no rows take part with empty selections. The run passes rows in global
//! id order, so one and two ranks write the same datasets (the static `rank`
//! field aside). The layout is:
//!
//! | file                      | path                  | shape    | type | content                               |
//! |---------------------------|-----------------------|----------|------|---------------------------------------|
//! | `<stem>.h5`               | `/mesh/coordinates`   | `[N, 3]` | f64  | node coordinates                      |
//! | `<stem>.h5`               | `/mesh/topology`      | `[E, 4]` | u32  | Tet4 connectivity, global node rows   |
//! | `<stem>.h5`               | `/static/node/<name>` | `[N]`    | i32  | static per-node fields (body id, ...) |
//! | `<stem>.h5`               | `/static/cell/<name>` | `[E]`    | i32  | static per-cell fields                |
//! | `<stem>.h5`               | `/mesh/hexes`         | `[H, 8]` | u32  | Hex8 bodies' hexes (if any)           |
//! | `<stem>.h5`               | `/static/hex/<name>`  | `[H]`    | i32  | a hex's first tet's static cell value |
//! | `<stem>_steps/<k:06>.h5`  | `/time`               | `[1]`    | f64  | the time of step `k`                  |
//! | `<stem>_steps/<k:06>.h5`  | `/fields/node/<name>` | `[N, c]` | f64  | node field (`[N]` if c = 1)           |
//! | `<stem>_steps/<k:06>.h5`  | `/fields/cell/<name>` | `[E, c]` | f64  | cell field (`[E]` if c = 1)           |
//! | `<stem>_steps/<k:06>.h5`  | `/fields/hex/<name>`  | `[H, c]` | f64  | a hex's first tet's cell field row    |
//!
//! A field of 6 components is a symmetric tensor, its rows in XDMF `Tensor6`
//! order xx, xy, xz, yy, yz, zz ([`TENSOR6_ORDER`], [`tensor6`]), which the
//! XDMF file marks `AttributeType="Tensor6"`. (A triangle grid, the joint
//! output, has `[E, 3]` topology.)
//!
//! Every dataset is contiguous and allocated when created. The static fields
//! are written before the first step; the set of time-dependent fields is fixed
//! by the first [`TimeSeriesWriter::write_step`] call. The readers ([`read_times`],
//! [`read_node_field_step`], ...) take the mesh file's path and find the step
//! files beside it ([`steps_dir`], [`step_path`]): the steps of a series are the
//! step files present from `000000.h5` on, up to the first one missing.
//!
//! The XDMF file (XDMF 3 syntax) holds a temporal collection with one uniform grid
//! per completed step; the mesh and static fields, from the mesh file, are repeated
//! in every step, the fields come from the step's file. It refers to the files by
//! names relative to itself (`<stem>.h5:/mesh/...`,
//! `<stem>_steps/000012.h5:/fields/...`), so the index, the mesh file and the step
//! directory can be moved together. It uses plain HDF `DataItem`s only (no
//! `HyperSlab`), because ParaView's default reader for `.xdmf` (Xdmf3ReaderS)
//! drops hyperslab attributes; it was checked with ParaView 5.11's "XDMF Reader",
//! Xdmf3ReaderS and Xdmf3ReaderT. So does the hexahedral index of the Hex8
//! bodies, `<stem>_hex8.xdmf`, which reads the hexes' own rows
//! (`/static/hex`, `/fields/hex`).
//!
//! ## Crash safety
//!
//! No file is ever modified under its final name. Each HDF5 file is created
//! under `<name>.part`, written, and closed by every rank (`H5Fclose`: all data
//! and metadata written); after all ranks agree, rank 0 syncs it (`fsync`) and
//! renames it to its final name. Only then does rank 0 rewrite the XDMF file, by
//! writing and syncing `<stem>.xdmf.tmp` and renaming it over `<stem>.xdmf`. The
//! order is: the mesh file (at the first step, or at the close if there is
//! none), then for each step its step file, then the index. A rename replaces a
//! name atomically, so after a kill (SIGKILL, at any moment, of any rank):
//!
//! - every `<stem>.h5` and `<stem>_steps/<k:06>.h5` is a closed, complete HDF5
//!   file (h5dump and ParaView read it); a file caught being written is only a
//!   `.part`, which no reader and no index looks at;
//! - `<stem>.xdmf` is whole, and it lists only steps whose files were in place
//!   before it was written (a step file it does not list yet may exist: a kill
//!   between the step's rename and the index's);
//! - the steps present from `000000.h5` on (what [`read_times`] returns) are a
//!   prefix of the series.
//!
//! The syncs before the renames extend this to a crash of the machine, as far
//! as the file system keeps the order of a sync and a later rename. A new series
//! removes an old one of the same stem first: its index, then its step files,
//! then its mesh file ([`remove_outputs`]), so no index names a removed file. A
//! series continued in place after a restart ([`TimeSeriesWriter::reopen`])
//! keeps its mesh file untouched, rewrites the index for the steps up to the
//! checkpoint, and only then removes the later step files and any `.part`
//! leftover, in step order. A run that fails before its first step should call
//! [`remove_outputs`] so that no half-written output is left behind;
//! [`TimeSeriesWriter::create`] removes its own files when it fails. Each step
//! costs one small file created, closed and synced, whatever the number of steps
//! before it; the index, rewritten per step, grows with the number of steps.
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
pub mod checkpoint_heat;
pub mod checkpoint_hexes;
pub mod checkpoint_particles;
pub mod checkpoint_spheres;
pub mod checkpoint_springs;
mod ffi;
mod hdf5_out;
mod history;
pub mod particles;
pub mod plot;
mod read;
mod xdmf;
mod xdmf_hex;

use std::path::{Path, PathBuf};

pub use hdf5_out::{FieldData, HexRows, MeshPart, TimeSeriesWriter};
pub use history::HistoryWriter;
pub use read::{
    read_cell_field_step, read_mesh, read_node_field_step, read_static_cell_field_i32,
    read_static_node_field_i32, read_times, read_triangles, MeshData,
};
pub use xdmf_hex::{hex_index_path, HexBlock};

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
/// The steps are in [`steps_dir`]`(<dir>/<stem>.h5)`.
pub fn output_paths(dir: &Path, stem: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{stem}.h5")),
        dir.join(format!("{stem}.xdmf")),
    )
}

/// The directory of the step files of the series whose mesh file is `h5`:
/// `<dir>/<stem>_steps` for `<dir>/<stem>.h5`.
pub fn steps_dir(h5: &Path) -> PathBuf {
    let stem = h5.file_stem().unwrap_or_default().to_string_lossy();
    h5.with_file_name(format!("{stem}_steps"))
}

/// The file of output step `step` (0, 1, ...) of the series whose mesh file
/// is `h5`: `<dir>/<stem>_steps/<step:06>.h5`.
pub fn step_path(h5: &Path, step: usize) -> PathBuf {
    steps_dir(h5).join(xdmf::step_file_name(step))
}

/// Removes the time series `<stem>` from `dir`: first the indexes
/// `<stem>.xdmf` and `<stem>_hex8.xdmf` (and leftover `.tmp` files), then the step directory
/// `<stem>_steps` with its files, then the mesh file `<stem>.h5` (and a
/// leftover `<stem>.h5.part` and its MPI-IO locks `<stem>.h5.part-*.lock`);
/// missing files are ignored. In that order no
/// index ever names a removed file.
///
/// Not collective: call it on rank 0 (calling it on several ranks is harmless).
/// Use it when a run fails before its first output step.
pub fn remove_outputs(dir: &Path, stem: &str) -> Result<(), IoError> {
    let (h5, xdmf) = output_paths(dir, stem);
    let tmp = xdmf::tmp_path(&xdmf);
    let hex = hex_index_path(&xdmf);
    let hex_tmp = xdmf::tmp_path(&hex);
    let part = hdf5_out::part_path(&h5);
    let ignore_missing = |path: &Path, r: std::io::Result<()>| match r {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(IoError::io(path, "removing output file", e))
        }
        _ => Ok(()),
    };
    for path in [&xdmf, &tmp, &hex, &hex_tmp] {
        ignore_missing(path, std::fs::remove_file(path))?;
    }
    let steps = steps_dir(&h5);
    ignore_missing(&steps, std::fs::remove_dir_all(&steps))?;
    for path in [&h5, &part] {
        ignore_missing(path, std::fs::remove_file(path))?;
    }
    remove_mpi_io_locks(&part)
}

/// Removes the `<file>-<job>-<pid>.lock` files that Open MPI's MPI-IO
/// leaves beside `file` when a rank is killed while it holds it open;
/// a missing directory is ignored.
pub(crate) fn remove_mpi_io_locks(file: &Path) -> Result<(), IoError> {
    let dir = file.parent().unwrap_or(Path::new("."));
    let prefix = format!(
        "{}-",
        file.file_name().unwrap_or_default().to_string_lossy()
    );
    let listing = |e| IoError::io(dir, "listing the output directory", e);
    let entries = match std::fs::read_dir(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        r => r.map_err(listing)?,
    };
    for entry in entries {
        let name = entry.map_err(listing)?.file_name();
        let name = name.to_string_lossy();
        if name.starts_with(&prefix) && name.ends_with(".lock") {
            let path = dir.join(&*name);
            match std::fs::remove_file(&path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(IoError::io(&path, "removing an MPI-IO lock", e))
                }
                _ => {}
            }
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

    #[test]
    fn remove_outputs_takes_the_mpi_io_locks_of_a_killed_run() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let mine = [
            "s.h5",
            "s.xdmf",
            "s_hex8.xdmf",
            "s_hex8.xdmf.tmp",
            "s.h5.part",
            "s.h5.part-349306881-30771.lock",
        ];
        let others = ["t.h5.part-1-2.lock", "s.h5.lock", "other.h5"];
        for f in mine.iter().chain(&others) {
            std::fs::write(d.join(f), "old").unwrap();
        }
        remove_outputs(d, "s").unwrap();
        let mut left: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["other.h5", "s.h5.lock", "t.h5.part-1-2.lock"]);
    }

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
