//! Tet4 meshes: storage, boundary faces, orientation/quality checks, Gmsh
//! import and structured generators (box, cylinders, nut, container).
//!
//! Self-contained: depends only on std, nalgebra, mshio and thiserror (and
//! the pure Hex8 shape functions of `crate::mechanics::hex8` for the Gmsh
//! Hex8 reader), so it unit-tests without MPI or PETSc. Node and element indices are `u32`
//! and 0-based; a mesh has at most [`MAX_ELEMENTS`] elements.
//!
//! Submodules:
//! - `error`: [`MeshError`], the error type of this module.
//! - `geometry`: signed volume ([`tet_signed_volume`]), shape quality
//!   ([`tet_quality`]), bounding box, [`TetMesh::validate`],
//!   [`TetMesh::fix_orientation`], [`TetMesh::min_quality`].
//! - `boundary`: [`TetMesh::boundary_faces`] ([`BoundaryFace`], local face
//!   convention [`LOCAL_FACES`]) and [`TetMesh::face_area_normal`].
//! - `sets`: node sets from face sets ([`TetMesh::nodes_of_face_set`],
//!   [`TetMesh::set_nodes`]) and [`TetMesh::append`] for multi-body models.
//! - [`generate`]: structured generators ([`generate::box_mesh`]).
//! - [`gmsh`]: MSH 4.1 import (ASCII and binary, [`gmsh::read_msh`]; Hex8
//!   for seed 002, [`gmsh::read_msh_hex8`]) and ASCII export
//!   ([`gmsh::write_msh_ascii`]).
//! - [`nut`]: structured hexagonal-nut particle ([`nut::nut_mesh`], the
//!   144-tet default for seed 000 sec 6 [`nut::nut_mesh_default`]; template
//!   file `scenarios/meshes/nut-144.msh`).
//! - [`container`]: open-top cylindrical cup ([`container::container_mesh`]).
//! - [`hex8`]: structured Hex8 box ([`hex8::hex_box`]) for seed 002.
//! - [`lattice`]: bonded cubic lattice of spheres from a box (seed 002 Fig 2).
//! - [`particle_region`]: an element set of a body as particles, with its
//!   links to the remaining elements; [`heat_links`]: the weights of the
//!   half bonds that carry heat across the interface.
//! - `closed`: [`TetMesh::check_closed_volume`], the single closed solid
//!   check for particle templates.

use std::collections::BTreeMap;

mod boundary;
mod closed;
pub mod container;
mod error;
pub mod generate;
mod geometry;
pub mod gmsh;
pub mod heat_links;
pub mod hex8;
pub mod hex_tets;
pub mod lattice;
pub mod nut;
pub mod particle_region;
mod sets;
#[cfg(test)]
pub(crate) mod testutil;
pub mod without;

pub use boundary::{sorted_face, BoundaryFace, LOCAL_FACES};
pub use closed::CLOSED_VOLUME_REL_TOL;
pub use container::container_mesh;
pub use error::MeshError;
pub use geometry::{tet_quality, tet_signed_volume, DEGENERATE_REL_TOL};
pub use nut::{nut_mesh, nut_mesh_default};

/// The most Tet4 elements one generated or imported mesh may have, and a
/// model per rank ([`model_element_limit`]): 20 million. Every rank builds
/// each body's mesh whole at set-up (a generated box, a Gmsh file, the nut
/// template a packing copies; about 100 bytes per tet) before it keeps its
/// part, so a mistyped element size would otherwise try to allocate tens of
/// gigabytes; generators and the Gmsh reader refuse larger meshes with
/// [`MeshError::TooLarge`] before they allocate them.
pub const MAX_ELEMENTS: usize = 20_000_000;

/// The most Tet4 a whole model may have on `ranks` ranks: the
/// [`element_limit`] per rank, since after set-up each rank holds only its
/// part (a packing of copies is never built whole), and at most
/// [`MAX_MODEL_ELEMENTS`].
pub fn model_element_limit(ranks: usize) -> u128 {
    (element_limit() as u128 * ranks.max(1) as u128).min(MAX_MODEL_ELEMENTS as u128)
}

/// The most Tet4 of a model on any number of ranks: global element and
/// node ids are u32, and a model has at most four nodes per element.
pub const MAX_MODEL_ELEMENTS: u64 = u32::MAX as u64 / 4;

thread_local! {
    static ELEMENT_LIMIT: std::cell::Cell<usize> = const { std::cell::Cell::new(MAX_ELEMENTS) };
}

/// The element limit in force on this thread: [`MAX_ELEMENTS`] unless
/// [`with_element_limit`] lowered it.
pub fn element_limit() -> usize {
    ELEMENT_LIMIT.with(std::cell::Cell::get)
}

/// Runs `f` with the element limit lowered to `limit` (at most
/// [`MAX_ELEMENTS`]) on this thread, where a model is built, then restores
/// it: a program that builds many models (the input fuzz tests) turns a
/// valid but huge one into the [`MeshError::TooLarge`] error at once.
pub fn with_element_limit<R>(limit: usize, f: impl FnOnce() -> R) -> R {
    struct Restore(usize);
    impl Drop for Restore {
        fn drop(&mut self) {
            ELEMENT_LIMIT.with(|l| l.set(self.0));
        }
    }
    let _restore = Restore(ELEMENT_LIMIT.with(|l| l.replace(limit.min(MAX_ELEMENTS))));
    f()
}

/// [`MeshError::TooLarge`] if `what`, a mesh of `count` elements, exceeds
/// the [`element_limit`] ([`MAX_ELEMENTS`]).
pub(crate) fn check_element_count(what: &str, count: u128) -> Result<(), MeshError> {
    let limit = element_limit();
    if count > limit as u128 {
        return Err(MeshError::TooLarge(format!(
            "{what} would have {count} elements, more than fdem's limit of {limit} \
             (each body's mesh is built whole on every rank at set-up); increase the element size"
        )));
    }
    Ok(())
}

/// A Tet4 mesh holding one or more bodies.
///
/// Element `e` has nodes `tets[e]` and belongs to body `body[e]`. Named sets
/// come from Gmsh physical groups or from generators (e.g. `xmin`, `xmax`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TetMesh {
    /// Node coordinates (m).
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity, positively oriented (det of [x1-x0, x2-x0, x3-x0] > 0).
    pub tets: Vec<[u32; 4]>,
    /// Body id per element.
    pub body: Vec<u32>,
    /// Named node sets (sorted, unique node ids).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Named face sets: triangles on the boundary, nodes ordered so the
    /// right-hand normal points out of the body.
    pub face_sets: BTreeMap<String, Vec<[u32; 3]>>,
    /// Named element sets (e.g. Gmsh physical volumes).
    pub elem_sets: BTreeMap<String, Vec<u32>>,
}

impl TetMesh {
    /// One body (id 0) of the given nodes and elements, with the element
    /// set `all` (what the generators return before adding their face sets).
    pub fn one_body(nodes: Vec<[f64; 3]>, tets: Vec<[u32; 4]>) -> TetMesh {
        let ne = tets.len();
        let mut elem_sets = BTreeMap::new();
        elem_sets.insert("all".to_string(), (0..ne as u32).collect());
        TetMesh {
            nodes,
            tets,
            body: vec![0; ne],
            elem_sets,
            ..Default::default()
        }
    }
}
