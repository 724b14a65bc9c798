//! Analytic and exact reference solutions the validation tests compare against.

pub mod ambient;
pub mod cantilever;
pub mod cantilever_plot;
pub mod coupled_cantilever;
pub mod fede_bar;
pub mod fede_coupling;
pub mod fede_heat;
pub mod fede_patch;
pub mod fede_wave;
pub mod lumped;
pub mod pipe_network;
pub mod semidiscrete;
pub mod slab;
pub mod thermoelastic;

pub use lumped::LumpedNetwork;
pub use pipe_network::{
    circle_overlap_half_angle, circle_overlap_surface, contact_half_angle, particle_resistance,
    PipeNetwork,
};
pub use semidiscrete::{dense_operators, semidiscrete_solution};
pub use slab::{slab_dirichlet_series, SlabProblem};
