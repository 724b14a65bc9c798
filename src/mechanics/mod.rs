//! Finite-strain explicit mechanics with thermal expansion: pure kernels,
//! free of MPI and PETSc, usable serially or as the per-rank kernel.
//!
//! Implements seed 004 (thermo-mechanical FDEM) sec 2.1–2.6:
//! - [`element`]: constant-strain Tet4 with the deformation gradient F,
//!   J and B (eqs 1–7), velocity gradient L and rate of deformation D
//!   (eqs 8–15), the thermal split F = F_T F_e with F_T = (1 + α ΔT) I
//!   (eqs 16–33), the Cauchy stress of eq 34 on the elastic part with the
//!   viscous stress of eq 35, nodal internal forces and stored energy; the
//!   fixed heated element reproduces eq 38 (sec 3.1, Table 1).
//! - [`material`]: [`ElasticMaterial`] (E, ν, ρ, α, η) and its Lamé constants.
//! - [`explicit`]: lumped mass, central-difference update with gravity,
//!   mass-proportional damping and velocity boundary conditions, stable
//!   time step; the loop over them (one rank or many) is
//!   [`crate::dynamics::ExplicitDomain`].
//! - [`frequency`]: the highest natural frequency of a whole small body
//!   (its exact explicit step limit) and congruence of template copies.
//! - [`hex8`]: trilinear Hex8 shape functions, Jacobian and the inverse
//!   isoparametric maps of Hex8 (Newton) and Tet4 (exact), seed 002 eqs 6–11.
//! - [`hex8_element`]: finite-strain Hex8 with the same law, selective
//!   reduced shear and twist-mode hourglass control; lumped mass.
//! - [`bond`]: bonded sphere lattice of seed 002 (eqs 2–4, 12–15): spring
//!   and conductance constants, incremental bond kernel with rotations,
//!   bond heat flows, damped particle update.
//! - [`free_spheres`]: free DE spheres of one kind (issue 21): Hertz
//!   contact with friction among themselves and on Tet4 faces, pipe-network
//!   heat, explicit update.
//! - [`ghost`]: ghost particles of the FE–DE interface (seed 002 eqs 5,
//!   16–17): placement, interpolation, force and heat return with N_I.
//! - `error`: [`MechanicsError`].
//!
//! Conventions: tension-positive Cauchy stress; nodal force arrays hold the
//! forces acting on the nodes (M a = f); ΔT is the element temperature
//! minus the stress-free reference temperature.

pub mod bond;
pub mod element;
mod error;
pub mod explicit;
pub mod free_spheres;
pub mod frequency;
pub mod ghost;
pub mod hex8;
pub mod hex8_element;
pub mod interface_link;
pub mod material;
pub mod sphere_contacts;

pub use element::{element_response, ElementResponse, Kinematics, Tet4Reference, ThermalState};
pub use error::MechanicsError;
pub use explicit::{critical_dt, CriticalDt, MechElement, ThermalLoad, VelocityBc};
pub use material::ElasticMaterial;
