//! Serial readers for time series (tests, post-processing). They open the
//! files read-only with HDF5's default (POSIX) driver on the calling rank only.
//! A series is named by its mesh file `<dir>/<stem>.h5`; its steps are the
//! step files `<dir>/<stem>_steps/000000.h5`, `000001.h5`, ... present under
//! their final names, up to the first one missing.

use std::path::Path;

use hdf5::{Dataset, File, H5Type};

use super::xdmf::Center;
use super::{step_path, IoError};

fn open(path: &Path) -> Result<File, IoError> {
    File::open(path).map_err(|e| IoError::hdf5(path, "opening read-only", e))
}

fn dataset(file: &File, path: &Path, name: &str) -> Result<Dataset, IoError> {
    file.dataset(name)
        .map_err(|e| IoError::hdf5(path, format!("opening dataset {name}"), e))
}

fn read_all<T: H5Type>(path: &Path, name: &str) -> Result<Vec<T>, IoError> {
    let file = open(path)?;
    dataset(&file, path, name)?
        .read_raw::<T>()
        .map_err(|e| IoError::hdf5(path, format!("reading {name}"), e))
}

/// The time of one step file: its `/time`, a single value.
pub(crate) fn read_step_time(step_file: &Path) -> Result<f64, IoError> {
    match read_all::<f64>(step_file, "/time")?[..] {
        [t] => Ok(t),
        ref other => Err(IoError::invalid(
            step_file,
            format!("/time holds {} values, expected 1", other.len()),
        )),
    }
}

/// Number of steps of the series of mesh file `h5`: step files present
/// from `000000.h5` on, up to the first one missing.
fn count_steps(h5: &Path) -> usize {
    (0..).take_while(|&k| step_path(h5, k).is_file()).count()
}

fn read_field_step(
    path: &Path,
    center: Center,
    field: &str,
    step: usize,
) -> Result<Vec<f64>, IoError> {
    let file = step_path(path, step);
    if !file.is_file() {
        return Err(IoError::invalid(
            path,
            format!(
                "{} field {field:?}: step {step} requested, the series has {} steps",
                center.group(),
                count_steps(path)
            ),
        ));
    }
    read_all(&file, &format!("/fields/{}/{field}", center.group()))
}

/// Reads step `step` of the node field `field` (all rows, row major: `N * components`
/// values) from the step file of the series of mesh file `path`. Serial, rank-local.
pub fn read_node_field_step(path: &Path, field: &str, step: usize) -> Result<Vec<f64>, IoError> {
    read_field_step(path, Center::Node, field, step)
}

/// Reads step `step` of the cell field `field` (all rows, row major) from the
/// step file of the series of mesh file `path`. Serial, rank-local.
pub fn read_cell_field_step(path: &Path, field: &str, step: usize) -> Result<Vec<f64>, IoError> {
    read_field_step(path, Center::Cell, field, step)
}

/// Reads the times of all steps of the series of mesh file `path` (the
/// `/time` of each step file, in step order). Serial, rank-local.
pub fn read_times(path: &Path) -> Result<Vec<f64>, IoError> {
    drop(open(path)?);
    (0..count_steps(path))
        .map(|k| read_step_time(&step_path(path, k)))
        .collect()
}

/// Reads the static node field `/static/node/<name>`. Serial, rank-local.
pub fn read_static_node_field_i32(path: &Path, name: &str) -> Result<Vec<i32>, IoError> {
    read_all(path, &format!("/static/node/{name}"))
}

/// Reads the static cell field `/static/cell/<name>`. Serial, rank-local.
pub fn read_static_cell_field_i32(path: &Path, name: &str) -> Result<Vec<i32>, IoError> {
    read_all(path, &format!("/static/cell/{name}"))
}

/// A whole mesh as stored in a time-series file.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshData {
    /// `/mesh/coordinates`.
    pub coords: Vec<[f64; 3]>,
    /// `/mesh/topology` (global node rows).
    pub cells: Vec<[u32; 4]>,
}

/// Reads the mesh: `/mesh/coordinates` and `/mesh/topology`. Serial, rank-local.
pub fn read_mesh(path: &Path) -> Result<MeshData, IoError> {
    let coords = read_all::<f64>(path, "/mesh/coordinates")?;
    let topo = read_all::<u32>(path, "/mesh/topology")?;
    Ok(MeshData {
        coords: coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        cells: topo
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
    })
}

/// Points and triangles (three point rows each).
pub type Triangles = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Reads a triangle mesh (the joint grid): `/mesh/coordinates` and the
/// three corners of each cell in `/mesh/topology`. Serial, rank-local.
pub fn read_triangles(path: &Path) -> Result<Triangles, IoError> {
    let coords = read_all::<f64>(path, "/mesh/coordinates")?;
    let topo = read_all::<u32>(path, "/mesh/topology")?;
    Ok((
        coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        topo.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    ))
}
