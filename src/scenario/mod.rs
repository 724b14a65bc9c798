//! Scenario files (TOML): the schema, `--set` overrides by dotted path, and
//! validation with errors naming the file and the key.
//!
//! Every table denies unknown keys. Parsing errors from the file carry its
//! line and column; overrides and value checks name the dotted key path.

mod overrides;
mod schema;
mod solver;
mod spheres;
mod validate;

use std::path::{Path, PathBuf};

pub use overrides::apply_override;
pub use schema::*;
pub use solver::{GuessKind, SolverSpec};
pub use spheres::{SphereBox, SphereSpec};

/// A scenario problem: which file, which key, what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{path}: cannot read scenario: {source}")]
    Read {
        /// The scenario path.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (unknown key, wrong type), with line.
    #[error("{path}: {message}")]
    Parse {
        /// The scenario path.
        path: PathBuf,
        /// toml's message (line, column, key).
        message: String,
    },
    /// A value is out of range or inconsistent.
    #[error("{path}: {key}: {message}")]
    Invalid {
        /// The scenario path.
        path: PathBuf,
        /// Dotted key path.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A `--set KEY=VALUE` could not be applied.
    #[error("--set {assignment}: {message}")]
    Override {
        /// The assignment as given.
        assignment: String,
        /// What is wrong.
        message: String,
    },
}

/// A parsed and validated scenario, with where it came from.
#[derive(Debug, Clone)]
pub struct LoadedScenario {
    /// The scenario file.
    pub path: PathBuf,
    /// Its directory (relative mesh paths resolve against it).
    pub base_dir: PathBuf,
    /// The content.
    pub scenario: Scenario,
}

impl LoadedScenario {
    /// Resolve a path given in the scenario relative to the scenario's directory.
    /// The result is absolute, so that messages name the file the run
    /// looked for whatever the working directory: the scenario's directory
    /// is canonicalised and the path's leading `..` steps are taken on it
    /// (exact, as a canonical path has no symbolic links).
    pub fn resolve(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let mut out = std::fs::canonicalize(&self.base_dir)
            .or_else(|_| std::path::absolute(&self.base_dir))
            .unwrap_or_else(|_| self.base_dir.clone());
        let mut leading = true;
        for c in p.components() {
            match c {
                std::path::Component::CurDir => {}
                std::path::Component::ParentDir if leading && out.parent().is_some() => {
                    out.pop();
                }
                other => {
                    leading = false;
                    out.push(other);
                }
            }
        }
        out
    }

    /// `--from DIR`: bodies of `kind = "checkpoint"` are read from DIR (an
    /// earlier stage's output directory, relative to the working directory)
    /// by their file name, or from DIR itself when it names an `.h5` file.
    pub fn take_checkpoints_from(&mut self, dir: &Path) -> Result<(), ScenarioError> {
        let err = |message: String| ScenarioError::Invalid {
            path: self.path.clone(),
            key: "--from".into(),
            message,
        };
        let dir = std::path::absolute(dir).map_err(|e| err(format!("{}: {e}", dir.display())))?;
        let mut n = 0;
        for b in &mut self.scenario.bodies {
            if let schema::MeshSpec::Checkpoint { file, .. } = &mut b.mesh {
                let name = Path::new(file.as_str())
                    .file_name()
                    .map(PathBuf::from)
                    .unwrap_or_default();
                let p = if dir.extension().is_some_and(|e| e == "h5") && !dir.is_dir() {
                    dir.clone()
                } else {
                    dir.join(name)
                };
                *file = p.to_string_lossy().into_owned();
                n += 1;
            }
        }
        if n == 0 {
            return Err(err(
                "the scenario has no body with mesh kind = \"checkpoint\" to take from there"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Name of the output stem: `output.stem` or the file stem.
    pub fn output_stem(&self) -> String {
        self.scenario.output.stem.clone().unwrap_or_else(|| {
            self.path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "fdem".into())
        })
    }
}

/// Read, override (`--set` assignments `a.b.c=value`), parse and validate a scenario.
pub fn load(path: &Path, sets: &[String]) -> Result<LoadedScenario, ScenarioError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_str(&text, path, sets)
}

/// Parse scenario text as if read from `path` (used by `load` and tests).
pub fn parse_str(
    text: &str,
    path: &Path,
    sets: &[String],
) -> Result<LoadedScenario, ScenarioError> {
    let perr = |message: String| ScenarioError::Parse {
        path: path.to_path_buf(),
        message,
    };
    // First pass on the text itself: errors carry line and column.
    let mut scenario: Scenario = toml::from_str(text).map_err(|e| perr(e.to_string()))?;
    if !sets.is_empty() {
        let mut value: toml::Table = toml::from_str(text).map_err(|e| perr(e.to_string()))?;
        for s in sets {
            apply_override(&mut value, s)?;
        }
        let de = toml::Value::Table(value);
        scenario = serde_path_to_error::deserialize(de).map_err(|e| {
            perr(format!(
                "after --set overrides: {}: {}",
                e.path(),
                e.inner()
            ))
        })?;
    }
    let base_dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let loaded = LoadedScenario {
        path: path.to_path_buf(),
        base_dir,
        scenario,
    };
    loaded
        .scenario
        .validate()
        .map_err(|(key, message)| ScenarioError::Invalid {
            path: path.to_path_buf(),
            key,
            message,
        })?;
    Ok(loaded)
}

#[cfg(test)]
mod tests;
