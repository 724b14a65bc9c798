//! Serial readers for time-series files (tests, post-processing). They open the
//! file read-only with HDF5's default (POSIX) driver on the calling rank only.

use std::path::Path;

use hdf5::{Dataset, File, H5Type};

use super::xdmf::{step_name, Center};
use super::IoError;

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

fn read_field_step(
    path: &Path,
    center: Center,
    field: &str,
    step: usize,
) -> Result<Vec<f64>, IoError> {
    let file = open(path)?;
    // `/time` lists the completed steps; after a crash a later step may be partial.
    let steps = dataset(&file, path, "/time")?.size();
    if step >= steps {
        return Err(IoError::invalid(
            path,
            format!(
                "{} field {field:?}: step {step} requested, the file has {steps} steps",
                center.group()
            ),
        ));
    }
    let name = format!("/fields/{}/{field}/{}", center.group(), step_name(step));
    dataset(&file, path, &name)?
        .read_raw::<f64>()
        .map_err(|e| IoError::hdf5(path, format!("reading {name}"), e))
}

/// Reads step `step` of the node field `field` (all rows, row major: `N * components`
/// values). Serial, rank-local.
pub fn read_node_field_step(path: &Path, field: &str, step: usize) -> Result<Vec<f64>, IoError> {
    read_field_step(path, Center::Node, field, step)
}

/// Reads step `step` of the cell field `field` (all rows, row major). Serial, rank-local.
pub fn read_cell_field_step(path: &Path, field: &str, step: usize) -> Result<Vec<f64>, IoError> {
    read_field_step(path, Center::Cell, field, step)
}

/// Reads `/time`: the times of all steps stored in the file. Serial, rank-local.
pub fn read_times(path: &Path) -> Result<Vec<f64>, IoError> {
    read_all(path, "/time")
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
