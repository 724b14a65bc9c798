//! Analytic and exact reference solutions the validation tests compare against.

pub mod semidiscrete;
pub mod slab;

pub use semidiscrete::{dense_operators, semidiscrete_solution};
pub use slab::{slab_dirichlet_series, SlabProblem};
