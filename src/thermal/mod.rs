//! Heat conduction: Tet4 element kernels (seed 000 eqs 14–20, pure), Hex8
//! element matrices ([`hex8`]), bonded particles' conduction blocks
//! ([`lattice_heat`], pure) and rows ([`particles`]), the
//! distributed assembly and the theta integrator (eq 22) on PETSc.

pub mod assembly;
pub mod element;
pub mod exchange;
pub mod flows;
pub mod hex8;
pub mod lattice_heat;
pub mod limits;
pub mod monotone;
pub mod node_rows;
pub mod nonlinear;
pub mod particles;
pub mod radiation;
mod row_sum;
pub mod solver_choice;
pub mod system;

pub use solver_choice::SolverChoice;
pub use system::{StepStats, ThermalSystem};
