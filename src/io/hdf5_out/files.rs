//! The files of a series: each is created under `<name>.part` with the
//! MPI-IO driver, closed, synced and only then renamed to its final name,
//! so that a final name never refers to a file being written.

use std::path::{Path, PathBuf};

use hdf5::plist::dataset_create::{AllocTime, FillTime};
use hdf5::{Dataset, File, Group, H5Type};
use mpi::raw::AsRaw as _;
use mpi::topology::SimpleCommunicator;

use super::super::xdmf::step_of_file_name;
use super::super::{steps_dir, IoError};

/// `<path>.part`: a file of the series while it is being written.
pub(crate) fn part_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".part");
    PathBuf::from(name)
}

/// Collective. Creates (truncates) `path` with the MPI-IO driver on `comm`.
/// The default (earliest) format bounds keep the files readable by older
/// HDF5 libraries, ParaView's among them.
pub(super) fn create_file(comm: &SimpleCommunicator, path: &Path) -> Result<File, IoError> {
    let hints = crate::io::ffi::IoHints::new();
    File::with_options()
        .with_fapl(|p| p.mpio(comm.as_raw(), Some(hints.info())))
        .create(path)
        .map_err(|e| IoError::hdf5(path, "creating the file with the MPI-IO driver", e))
}

/// Collective. A contiguous, early-allocated dataset of fixed shape.
pub(super) fn fixed_dataset<T: H5Type>(
    group: &Group,
    name: &str,
    shape: &[u64],
) -> hdf5::Result<Dataset> {
    let shape: Vec<usize> = shape.iter().map(|&d| d as usize).collect();
    group
        .new_dataset::<T>()
        .shape(shape)
        .alloc_time(Some(AllocTime::Early))
        .fill_time(FillTime::Never)
        .create(name)
}

/// Rank 0, after every rank has closed `part`: syncs it to disk and renames
/// it to `path` (replacing a file of that name), so that `path` names either
/// the old file or the whole new one, also after a crash of the machine.
pub(super) fn publish(part: &Path, path: &Path) -> Result<(), IoError> {
    std::fs::File::open(part)
        .and_then(|f| f.sync_all())
        .map_err(|e| IoError::io(part, "syncing the closed file", e))?;
    std::fs::rename(part, path).map_err(|e| IoError::io(path, "renaming the file into place", e))
}

/// Removes `path`, ignoring a missing file.
pub(super) fn remove_if_present(path: &Path) -> Result<(), IoError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(IoError::io(path, "removing a file", e))
        }
        _ => Ok(()),
    }
}

/// Rank 0. Removes from the step directory of mesh file `h5` the step files
/// of steps `first` and later, in step order, and any `.part` leftover of
/// an interrupted run (with the `<file>.part-<job>-<pid>.lock` file Open
/// MPI's MPI-IO leaves beside it when a rank is killed while it is open). Removing in step order keeps the steps present from
/// `000000.h5` on (what readers see) a prefix of the series at every moment.
pub(super) fn remove_steps_from(h5: &Path, first: usize) -> Result<(), IoError> {
    let dir = steps_dir(h5);
    let entries = match std::fs::read_dir(&dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(IoError::io(&dir, "listing the step files", e)),
    };
    let mut doomed: Vec<(usize, PathBuf)> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| IoError::io(&dir, "listing the step files", e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".part") || (name.contains(".part-") && name.ends_with(".lock")) {
            doomed.push((0, entry.path()));
        } else if let Some(k) = step_of_file_name(&name).filter(|&k| k >= first) {
            doomed.push((k, entry.path()));
        }
    }
    doomed.sort();
    doomed
        .iter()
        .try_for_each(|(_, path)| remove_if_present(path))
}
