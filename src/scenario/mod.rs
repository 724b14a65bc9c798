//! Scenario files (TOML): the schema, `--set` overrides by dotted path, and
//! validation with errors naming the file and the key.
//!
//! Every table denies unknown keys. Parsing errors from the file carry its
//! line and column; overrides and value checks name the dotted key path.

mod overrides;
mod schema;

use std::path::{Path, PathBuf};

pub use overrides::apply_override;
pub use schema::*;

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
    pub fn resolve(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        }
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
