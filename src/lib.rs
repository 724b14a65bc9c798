//! fdem: combined finite–discrete element solver for heat transfer and
//! thermo-mechanics of 3D particle systems.
//!
//! Module map (see README "Architecture"):
//! - [`geometry`]: convex clipping (triangle ∩ tet), polygon area, tet overlap.
//! - [`contact`]: contact detection (BVH broad phase, clipping narrow phase), contact surfaces and conductances.
//! - [`mesh`]: Tet4 meshes, boundary faces, quality checks, Gmsh import, generators.
//! - [`mechanics`]: finite-strain Tet4 stress/forces with thermal expansion (seed 004 eqs 1–38), explicit kernels.
//! - [`fracture`]: cohesive-zone joints (seed 004 sec 2.7): insertion, the damage law, the 6-node joint's forces.
//! - [`dynamics`]: the per-rank explicit dynamics (subdomain, substeps, contact candidates, ordered force sums).
//! - [`thermal`]: element matrices and loads (seed 000 eqs 14–20), theta integrator (eq 22).
//! - [`parallel`]: METIS partition, owned/ghost numbering matching PETSc ownership, halos, collectives.
//! - [`petsc`]: safe RAII layer over `petsc-sys`.
//! - [`io`]: HDF5 + XDMF output, CSV histories.
//! - [`scenario`]: TOML schema with validation and clear errors.
//! - [`validation`]: analytic reference solutions.
//! - [`model`]: the data model every stage shares.
//! - [`run`]: the time loop that ties the stages together.

// `petsc_call!` evaluates its arguments inside its unsafe block; it is used
// only by the safe PETSc layer, whose types own the handles it passes.
#![allow(clippy::macro_metavars_in_unsafe)]

pub mod contact;
pub mod dynamics;
pub mod error;
pub mod fracture;
pub mod geometry;
pub mod io;
pub mod mechanics;
pub mod mesh;
pub mod model;
pub mod pack;
pub mod parallel;
pub mod petsc;
pub mod run;
pub mod scenario;
#[cfg(test)]
mod testutil;
pub mod thermal;
pub mod validation;
