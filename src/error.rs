//! The crate's top-level error: every failure a run can report, each
//! message naming the file, key, element or PETSc function involved.

use crate::{io::IoError, mesh::MeshError, petsc::PetscError, scenario::ScenarioError};

/// Any error of a run.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Scenario file problem.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// Mesh problem (file, element).
    #[error("{context}: {source}")]
    Mesh {
        /// Which body or file.
        context: String,
        /// The mesh error.
        source: MeshError,
    },
    /// The model is inconsistent (unknown set, empty BC...).
    #[error("{path}: {message}")]
    Model {
        /// The scenario path.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// PETSc failure or diverged solve.
    #[error(transparent)]
    Petsc(#[from] PetscError),
    /// Output failure.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A non-finite temperature appeared.
    #[error("non-finite temperature at step {step} (t = {time} s) at node {node}: the solution diverged; reduce dt or use theta >= 0.5")]
    NonFinite {
        /// Step number.
        step: u64,
        /// Time.
        time: f64,
        /// Original node id.
        node: usize,
    },
    /// PETSc options that nothing reads (a typo, or an option for an
    /// object the run does not create).
    #[error("PETSc option(s) not used by any PETSc object: {0}; check the spelling (`-help` lists the options), or pass --allow-unused-petsc-options")]
    UnusedPetscOptions(String),
    /// The thermal time step is above a limit of the scheme.
    #[error("thermal: {0}")]
    TimeStep(String),
    /// The explicit mechanics failed (inverted element, blow-up, bad step).
    #[error("mechanics: {0}")]
    Mechanics(String),
    /// Another rank failed; its error is printed by that rank.
    #[error("another MPI rank reported an error")]
    OtherRank,
    /// Partitioning failure.
    #[error("partitioning failed: {0}")]
    Partition(String),
    /// The output directory cannot be used (an existing file, no permission).
    #[error("output directory {path}: {message}")]
    OutputDir {
        /// The directory as given (`--output` or `output.directory`).
        path: String,
        /// What is wrong.
        message: String,
    },
    /// Plain I/O failure (directories, summary files).
    #[error("{path}: {source}")]
    File {
        /// The path.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// Result alias.
pub type Result<T> = std::result::Result<T, Error>;
