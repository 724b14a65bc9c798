//! CSV histories (time, energies, probe values, ...) written by world rank 0.

use std::fs::File;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use mpi::traits::Communicator as _;

use super::IoError;

/// A CSV history file. World rank 0 writes it; on other ranks every call is a no-op
/// that succeeds (argument checks included, so that all ranks agree).
///
/// Each row is written with a single `write(2)` call and no user-space buffering, so
/// a killed run leaves a valid CSV with every row that was appended. Values are
/// printed in the shortest form that parses back to the identical `f64`
/// (`0.1`, `1.5e-7`, `NaN`, `inf`).
#[derive(Debug)]
pub struct HistoryWriter {
    path: PathBuf,
    columns: usize,
    file: Option<File>,
}

/// World rank, or 0 when MPI is not initialised (serial use).
fn world_rank() -> i32 {
    if mpi::environment::is_initialized() && !mpi::environment::is_finalized() {
        mpi::topology::SimpleCommunicator::world().rank()
    } else {
        0
    }
}

/// Quotes a CSV header cell when needed (RFC 4180).
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Shortest round-trip representation; plain notation for moderate magnitudes.
fn format_value(out: &mut String, v: f64) {
    use std::fmt::Write as _;
    let a = v.abs();
    let _ = if v == 0.0 || (1e-4..1e15).contains(&a) || !v.is_finite() {
        write!(out, "{v}")
    } else {
        write!(out, "{v:e}")
    };
}

impl HistoryWriter {
    /// Creates (truncates) the CSV file at `path` and writes the header row.
    /// Not collective; only world rank 0 touches the file.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, IoError> {
        if header.is_empty() {
            return Err(IoError::invalid(path, "history header has no columns"));
        }
        let file = if world_rank() == 0 {
            let mut file =
                File::create(path).map_err(|e| IoError::io(path, "creating history file", e))?;
            let mut line = header
                .iter()
                .map(|h| csv_cell(h))
                .collect::<Vec<_>>()
                .join(",");
            line.push('\n');
            file.write_all(line.as_bytes())
                .map_err(|e| IoError::io(path, "writing history header", e))?;
            Some(file)
        } else {
            None
        };
        Ok(Self {
            path: path.to_path_buf(),
            columns: header.len(),
            file,
        })
    }

    /// Continues the CSV file at `path` written by an earlier run with the
    /// same `header`: keeps its rows whose time (the column `time_column`)
    /// is at most `keep_until`, drops the later ones (the file is rewritten
    /// atomically), and appends after them. A different header is an error.
    /// Not collective; only world rank 0 touches the file.
    pub fn reopen(
        path: &Path,
        header: &[&str],
        time_column: usize,
        keep_until: f64,
    ) -> Result<Self, IoError> {
        let line: String = header
            .iter()
            .map(|h| csv_cell(h))
            .collect::<Vec<_>>()
            .join(",");
        let file = if world_rank() == 0 {
            let text = std::fs::read_to_string(path)
                .map_err(|e| IoError::io(path, "reading the history to continue it", e))?;
            let mut lines = text.lines();
            if lines.next() != Some(line.as_str()) {
                return Err(IoError::invalid(
                    path,
                    "cannot continue this history: its columns differ from this run's",
                ));
            }
            let tol = 1e-9 * keep_until.abs().max(1.0);
            let mut kept = format!("{line}\n");
            for row in lines {
                let cells: Vec<&str> = row.split(',').collect();
                let whole =
                    cells.len() == header.len() && cells.iter().all(|c| c.parse::<f64>().is_ok());
                let t: Option<f64> = cells
                    .get(time_column)
                    .filter(|_| whole)
                    .and_then(|v| v.parse().ok());
                match t {
                    Some(t) if t <= keep_until + tol => {
                        kept.push_str(row);
                        kept.push('\n');
                    }
                    // A later row, or a row cut short by a kill: dropped.
                    _ => {}
                }
            }
            let mut tmp = path.as_os_str().to_owned();
            tmp.push(".tmp");
            let tmp = PathBuf::from(tmp);
            std::fs::write(&tmp, kept)
                .and_then(|()| std::fs::rename(&tmp, path))
                .map_err(|e| IoError::io(path, "rewriting the history up to the checkpoint", e))?;
            Some(
                std::fs::OpenOptions::new()
                    .append(true)
                    .open(path)
                    .map_err(|e| IoError::io(path, "opening the history to append", e))?,
            )
        } else {
            None
        };
        Ok(Self {
            path: path.to_path_buf(),
            columns: header.len(),
            file,
        })
    }

    /// Appends one row; `values.len()` must equal the number of header columns.
    pub fn append(&mut self, values: &[f64]) -> Result<(), IoError> {
        if values.len() != self.columns {
            return Err(IoError::invalid(
                &self.path,
                format!(
                    "history row has {} values, header has {} columns",
                    values.len(),
                    self.columns
                ),
            ));
        }
        let Some(file) = self.file.as_mut() else {
            return Ok(());
        };
        let mut line = String::with_capacity(values.len() * 24);
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                line.push(',');
            }
            format_value(&mut line, v);
        }
        line.push('\n');
        file.write_all(line.as_bytes())
            .map_err(|e| IoError::io(&self.path, "appending history row", e))
    }

    /// Path of the CSV file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip() {
        for v in [
            0.0,
            -0.0,
            0.1,
            1.0 / 3.0,
            1e-300,
            -2.5e-7,
            1e300,
            123456.789,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let mut s = String::new();
            format_value(&mut s, v);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
        }
        let mut s = String::new();
        format_value(&mut s, f64::NAN);
        assert!(s.parse::<f64>().unwrap().is_nan());
    }
}
