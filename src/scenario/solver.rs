//! The `[solver]` table: the thermal step's linear solver, whose defaults
//! `thermal::solver_choice` picks; the command line's PETSc options win.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Linear solver settings. Anything here can also be given on the command
/// line as a PETSc option, which wins.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// KSP type (`-ksp_type`); default chosen by problem size (see README).
    #[serde(default)]
    pub ksp_type: Option<String>,
    /// PC type (`-pc_type`).
    #[serde(default)]
    pub pc_type: Option<String>,
    /// Relative tolerance (`-ksp_rtol`), default 1e-10.
    #[serde(default)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (`-ksp_atol`), default 1e-50.
    #[serde(default)]
    pub atol: Option<f64>,
    /// Iteration cap (`-ksp_max_it`), default 10000.
    #[serde(default)]
    pub max_it: Option<u32>,
    /// Any other PETSc options, without the leading dash: `{ ksp_monitor = "" }`.
    #[serde(default)]
    pub options: BTreeMap<String, String>,
    /// Where an iterative step starts (default: chosen by the cell Fourier number).
    #[serde(default)]
    pub guess: GuessKind,
}

/// Where an iterative thermal step starts its Krylov iterations.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GuessKind {
    /// Fischer's projection for CG where the cell Fourier number exceeds 1,
    /// else the line through the last two steps.
    #[default]
    Auto,
    /// The line through the last two steps, 2Tⁿ − Tⁿ⁻¹.
    Line,
    /// Fischer's projection onto the last solutions (PETSc `KSPGUESSFISCHER`,
    /// model 1, 10 vectors; a least-squares fit, so any Krylov type).
    Fischer,
}
