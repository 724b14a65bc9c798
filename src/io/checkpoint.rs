//! Restart checkpoints: the whole state of a run in one HDF5 file, in the
//! original (rank-independent) numbering, written by one rank.
//!
//! Layout (`format = "fdem-checkpoint"`, `version = 1` attributes on `/`):
//! - `/mesh/reference` (N×3 f64), `/mesh/tets` (E×4 u32), `/mesh/body` (E u32)
//! - `/bodies/names`, `/bodies/templates` (newline-joined UTF-8 as u8),
//!   `/bodies/nodes`, `/bodies/elems` (B×2 u32 ranges)
//! - `/state/positions`, `/state/velocities` (N×3 f64, when mechanics ran),
//!   `/state/temperature` (N f64, when the thermal problem ran)
//! - `/state/scalars` (f64): step, time, substeps, heat account (5 values),
//!   dissipated energy, peak kinetic energy, thermal contacts
//!
//! The file is written to `<path>.tmp` and renamed, so a crash never
//! leaves a half-written checkpoint under the final name.

use std::path::{Path, PathBuf};

use hdf5::{File, H5Type};

use super::IoError;

const FORMAT: &str = "fdem-checkpoint";
const VERSION: u32 = 1;
const SCALARS: usize = 12;

/// The heat account's running state as saved.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SavedAccount {
    /// Base account: stored, stored change, Dirichlet in, flux in, convection in.
    pub base: [f64; 5],
    /// Steps since the last assembly.
    pub steps: u64,
    /// Temperatures at the last assembly, per node.
    pub t0: Vec<f64>,
    /// Sum of the step temperatures since then, per node.
    pub t_sum: Vec<f64>,
}

/// Everything needed to continue a run, or to start another from its state.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Checkpoint {
    /// Thermal (outer) steps done.
    pub step: u64,
    /// Time (s).
    pub time: f64,
    /// Explicit substeps done.
    pub substeps: u64,
    /// Reference node coordinates.
    pub reference: Vec<[f64; 3]>,
    /// Elements.
    pub tets: Vec<[u32; 4]>,
    /// Body of every element.
    pub elem_body: Vec<u32>,
    /// Body names.
    pub body_names: Vec<String>,
    /// The scenario entry each body came from.
    pub body_templates: Vec<String>,
    /// Node range of every body.
    pub body_nodes: Vec<[u32; 2]>,
    /// Element range of every body.
    pub body_elems: Vec<[u32; 2]>,
    /// Current positions (mechanics).
    pub positions: Option<Vec<[f64; 3]>>,
    /// Velocities v^{n−½} (mechanics).
    pub velocities: Option<Vec<[f64; 3]>>,
    /// The velocities of the substep before (mechanics), so that the
    /// kinetic energy at the checkpoint's step, (v^{n−3/2} + v^{n−½})/2,
    /// is the uninterrupted run's.
    pub velocities_prev: Option<Vec<[f64; 3]>>,
    /// Krylov iterations so far (the history's cumulative counter).
    pub ksp_iterations: u64,
    /// Nodal temperatures.
    pub temperature: Option<Vec<f64>>,
    /// Heat account: stored, stored change, Dirichlet in, flux in, convection in.
    pub heat: [f64; 5],
    /// Energy dissipated by contact damping and friction (J).
    pub dissipated: f64,
    /// Largest kinetic energy seen (J), for the settling test.
    pub peak_kinetic: f64,
    /// Thermal contact pairs at the checkpoint (information).
    pub thermal_contacts: u64,
    /// Each rank's share of `dissipated` (same-rank-count restarts
    /// continue the sum bitwise).
    pub dissipated_per_rank: Option<Vec<f64>>,
    /// The heat account's running state (see
    /// [`crate::thermal::system::AccountState`]), node vectors in the
    /// original numbering; older checkpoints lack it (then the account
    /// continues to round-off only).
    pub account: Option<SavedAccount>,
    /// The kinetic energy (J) at which the run settled, when this is the
    /// checkpoint of a settled run: a restart from it takes no more steps.
    pub settled: Option<f64>,
}

fn tmp_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".tmp");
    PathBuf::from(s)
}

fn put<T: H5Type + Copy>(
    file: &File,
    path: &Path,
    name: &str,
    data: &[T],
    cols: usize,
) -> Result<(), IoError> {
    let rows = data.len() / cols.max(1);
    let shape: Vec<usize> = if cols == 1 {
        vec![rows]
    } else {
        vec![rows, cols]
    };
    file.new_dataset::<T>()
        .shape(shape)
        .create(name)
        .and_then(|d| d.write_raw(data))
        .map_err(|e| IoError::hdf5(path, format!("writing {name}"), e))
}

fn get<T: H5Type + Copy>(
    file: &File,
    path: &Path,
    name: &str,
    cols: usize,
) -> Result<Vec<T>, IoError> {
    let d = file
        .dataset(name)
        .map_err(|e| IoError::hdf5(path, format!("opening {name}"), e))?;
    let shape = d.shape();
    let ok = match cols {
        1 => shape.len() == 1,
        c => shape.len() == 2 && shape[1] == c,
    };
    if !ok {
        return Err(IoError::invalid(
            path,
            format!("{name} has shape {shape:?}, expected {cols} column(s)"),
        ));
    }
    d.read_raw::<T>()
        .map_err(|e| IoError::hdf5(path, format!("reading {name}"), e))
}

fn flat3<T: Copy>(v: &[[T; 3]]) -> Vec<T> {
    v.iter().flatten().copied().collect()
}

fn rows<T: Copy + Default, const C: usize>(v: Vec<T>) -> Vec<[T; C]> {
    v.chunks_exact(C)
        .map(|c| {
            let mut a = [T::default(); C];
            a.copy_from_slice(c);
            a
        })
        .collect()
}

impl Checkpoint {
    /// Write the checkpoint (serial: call on one rank).
    pub fn write(&self, path: &Path) -> Result<(), IoError> {
        let tmp = tmp_path(path);
        let result = self.write_to(&tmp);
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, "renaming the checkpoint", e))
    }

    fn write_to(&self, path: &Path) -> Result<(), IoError> {
        let file = File::create(path).map_err(|e| IoError::hdf5(path, "creating", e))?;
        let attr = |name: &str, v: &[u8]| -> Result<(), IoError> {
            file.new_attr::<u8>()
                .shape([v.len()])
                .create(name)
                .and_then(|a| a.write_raw(v))
                .map_err(|e| IoError::hdf5(path, format!("writing attribute {name}"), e))
        };
        attr("format", FORMAT.as_bytes())?;
        attr("version", &VERSION.to_le_bytes())?;
        for g in ["mesh", "bodies", "state"] {
            file.create_group(g)
                .map_err(|e| IoError::hdf5(path, format!("creating group {g}"), e))?;
        }
        put(&file, path, "mesh/reference", &flat3(&self.reference), 3)?;
        let tets: Vec<u32> = self.tets.iter().flatten().copied().collect();
        put(&file, path, "mesh/tets", &tets, 4)?;
        put(&file, path, "mesh/body", &self.elem_body, 1)?;
        put(
            &file,
            path,
            "bodies/names",
            self.body_names.join("\n").as_bytes(),
            1,
        )?;
        put(
            &file,
            path,
            "bodies/templates",
            self.body_templates.join("\n").as_bytes(),
            1,
        )?;
        let bn: Vec<u32> = self.body_nodes.iter().flatten().copied().collect();
        let be: Vec<u32> = self.body_elems.iter().flatten().copied().collect();
        put(&file, path, "bodies/nodes", &bn, 2)?;
        put(&file, path, "bodies/elems", &be, 2)?;
        if let Some(x) = &self.positions {
            put(&file, path, "state/positions", &flat3(x), 3)?;
        }
        if let Some(v) = &self.velocities {
            put(&file, path, "state/velocities", &flat3(v), 3)?;
        }
        if let Some(v) = &self.velocities_prev {
            put(&file, path, "state/velocities_prev", &flat3(v), 3)?;
        }
        put(&file, path, "state/counters", &[self.ksp_iterations], 1)?;
        if let Some(d) = &self.dissipated_per_rank {
            put(&file, path, "state/dissipated_per_rank", d, 1)?;
        }
        if let Some(a) = &self.account {
            put(&file, path, "state/account_base", &a.base, 1)?;
            put(&file, path, "state/account_steps", &[a.steps], 1)?;
            put(&file, path, "state/account_t0", &a.t0, 1)?;
            put(&file, path, "state/account_t_sum", &a.t_sum, 1)?;
        }
        if let Some(ke) = self.settled {
            put(&file, path, "state/settled", &[ke], 1)?;
        }
        if let Some(t) = &self.temperature {
            put(&file, path, "state/temperature", t, 1)?;
        }
        let mut sc = [0.0; SCALARS];
        sc[0] = self.step as f64;
        sc[1] = self.time;
        sc[2] = self.substeps as f64;
        sc[3..8].copy_from_slice(&self.heat);
        sc[8] = self.dissipated;
        sc[9] = self.peak_kinetic;
        sc[10] = self.thermal_contacts as f64;
        put(&file, path, "state/scalars", &sc, 1)?;
        file.flush()
            .map_err(|e| IoError::hdf5(path, "flushing the checkpoint", e))
    }

    /// Read a checkpoint (serial).
    pub fn read(path: &Path) -> Result<Checkpoint, IoError> {
        if !path.is_file() {
            return Err(IoError::invalid(path, "checkpoint file not found"));
        }
        let file = File::open(path).map_err(|e| IoError::hdf5(path, "opening", e))?;
        let format = file
            .attr("format")
            .and_then(|a| a.read_raw::<u8>())
            .map_err(|_| {
                IoError::invalid(path, "not an fdem checkpoint (no `format` attribute)")
            })?;
        if format != FORMAT.as_bytes() {
            return Err(IoError::invalid(path, "not an fdem checkpoint"));
        }
        let version = file
            .attr("version")
            .and_then(|a| a.read_raw::<u8>())
            .map_err(|e| IoError::hdf5(path, "reading the version", e))?;
        if version != VERSION.to_le_bytes() {
            return Err(IoError::invalid(
                path,
                format!("checkpoint version {version:?}, this fdem reads version {VERSION}"),
            ));
        }
        let text = |name: &str| -> Result<Vec<String>, IoError> {
            let b = get::<u8>(&file, path, name, 1)?;
            let s = String::from_utf8(b)
                .map_err(|_| IoError::invalid(path, format!("{name} is not UTF-8")))?;
            Ok(s.split('\n').map(str::to_string).collect())
        };
        let opt3 = |name: &str| -> Result<Option<Vec<[f64; 3]>>, IoError> {
            if file.link_exists(name) {
                Ok(Some(rows::<f64, 3>(get(&file, path, name, 3)?)))
            } else {
                Ok(None)
            }
        };
        let sc = get::<f64>(&file, path, "state/scalars", 1)?;
        if sc.len() != SCALARS {
            return Err(IoError::invalid(path, "state/scalars has the wrong length"));
        }
        let c = Checkpoint {
            step: sc[0] as u64,
            time: sc[1],
            substeps: sc[2] as u64,
            reference: rows::<f64, 3>(get(&file, path, "mesh/reference", 3)?),
            tets: rows::<u32, 4>(get(&file, path, "mesh/tets", 4)?),
            elem_body: get(&file, path, "mesh/body", 1)?,
            body_names: text("bodies/names")?,
            body_templates: text("bodies/templates")?,
            body_nodes: rows::<u32, 2>(get(&file, path, "bodies/nodes", 2)?),
            body_elems: rows::<u32, 2>(get(&file, path, "bodies/elems", 2)?),
            positions: opt3("state/positions")?,
            velocities: opt3("state/velocities")?,
            velocities_prev: opt3("state/velocities_prev")?,
            ksp_iterations: if file.link_exists("state/counters") {
                get::<u64>(&file, path, "state/counters", 1)?
                    .first()
                    .copied()
                    .unwrap_or(0)
            } else {
                0
            },
            temperature: if file.link_exists("state/temperature") {
                Some(get(&file, path, "state/temperature", 1)?)
            } else {
                None
            },
            heat: [sc[3], sc[4], sc[5], sc[6], sc[7]],
            dissipated: sc[8],
            peak_kinetic: sc[9],
            thermal_contacts: sc[10] as u64,
            dissipated_per_rank: if file.link_exists("state/dissipated_per_rank") {
                Some(get(&file, path, "state/dissipated_per_rank", 1)?)
            } else {
                None
            },
            account: if file.link_exists("state/account_base") {
                let base = get::<f64>(&file, path, "state/account_base", 1)?;
                let steps = get::<u64>(&file, path, "state/account_steps", 1)?;
                let (Ok(base), Some(&steps)) = (<[f64; 5]>::try_from(base), steps.first()) else {
                    return Err(IoError::invalid(
                        path,
                        "state/account_base or state/account_steps has the wrong length",
                    ));
                };
                Some(SavedAccount {
                    base,
                    steps,
                    t0: get(&file, path, "state/account_t0", 1)?,
                    t_sum: get(&file, path, "state/account_t_sum", 1)?,
                })
            } else {
                None
            },
            settled: if file.link_exists("state/settled") {
                get::<f64>(&file, path, "state/settled", 1)?
                    .first()
                    .copied()
            } else {
                None
            },
        };
        c.check(path)?;
        Ok(c)
    }

    /// Internal consistency (sizes and ranges), naming what is wrong.
    fn check(&self, path: &Path) -> Result<(), IoError> {
        let nn = self.reference.len();
        let nb = self.body_names.len();
        let bad = |m: String| Err(IoError::invalid(path, m));
        if self.elem_body.len() != self.tets.len() {
            return bad("mesh/body and mesh/tets differ in length".into());
        }
        if self.body_templates.len() != nb
            || self.body_nodes.len() != nb
            || self.body_elems.len() != nb
        {
            return bad("the /bodies datasets differ in length".into());
        }
        if let Some((e, _)) = self
            .tets
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&n| n as usize >= nn))
        {
            return bad(format!(
                "element {e} refers to a node beyond the {nn} nodes"
            ));
        }
        if self.elem_body.iter().any(|&b| b as usize >= nb) {
            return bad("an element refers to a body beyond the body list".into());
        }
        for (name, len) in [
            ("state/positions", self.positions.as_ref().map(Vec::len)),
            ("state/velocities", self.velocities.as_ref().map(Vec::len)),
            ("state/temperature", self.temperature.as_ref().map(Vec::len)),
            (
                "state/account_t0",
                self.account.as_ref().map(|a| a.t0.len()),
            ),
            (
                "state/account_t_sum",
                self.account.as_ref().map(|a| a.t_sum.len()),
            ),
        ] {
            if len.is_some_and(|l| l != nn) {
                return bad(format!(
                    "{name} has {} rows for {nn} nodes",
                    len.unwrap_or(0)
                ));
            }
        }
        Ok(())
    }

    /// Indices of the bodies that came from scenario entry `template`.
    pub fn bodies_of(&self, template: &str) -> Vec<usize> {
        (0..self.body_names.len())
            .filter(|&b| self.body_templates[b] == template)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        Checkpoint {
            step: 7,
            time: 0.35,
            substeps: 7000,
            reference: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            tets: vec![[0, 1, 2, 3]],
            elem_body: vec![0],
            body_names: vec!["nut_0".into()],
            body_templates: vec!["nut".into()],
            body_nodes: vec![[0, 4]],
            body_elems: vec![[0, 1]],
            positions: Some(vec![[0.1, 0.2, 0.3]; 4]),
            velocities: Some(vec![[-1.0, 2.0, 1e-300]; 4]),
            velocities_prev: Some(vec![[-1.5, 2.5, -0.0]; 4]),
            ksp_iterations: 123_456,
            temperature: Some(vec![1.0, 2.0, 3.0, f64::MIN_POSITIVE]),
            heat: [1.0, 2.0, 3.0, 4.0, 5.0],
            dissipated: 0.5,
            peak_kinetic: 2.5,
            settled: Some(1e-3),
            dissipated_per_rank: Some(vec![0.25, 0.5]),
            account: Some(SavedAccount {
                base: [1.0, 2.0, 3.0, 4.0, 5.0],
                steps: 17,
                t0: vec![0.5; 4],
                t_sum: vec![8.5; 4],
            }),
            thermal_contacts: 3,
        }
    }

    #[test]
    fn round_trip_is_bitwise() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.h5");
        let c = sample();
        c.write(&p).unwrap();
        assert!(!tmp_path(&p).exists());
        let r = Checkpoint::read(&p).unwrap();
        assert_eq!(r, c);
        assert_eq!(r.bodies_of("nut"), vec![0]);
        let mut m = c.clone();
        m.temperature = None;
        m.positions = None;
        m.write(&p).unwrap();
        assert_eq!(Checkpoint::read(&p).unwrap(), m);
    }

    #[test]
    fn bad_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("missing.h5");
        let e = Checkpoint::read(&p).unwrap_err().to_string();
        assert!(e.contains("missing.h5") && e.contains("not found"), "{e}");
        let q = dir.path().join("text.h5");
        std::fs::write(&q, "not hdf5").unwrap();
        let e = Checkpoint::read(&q).unwrap_err().to_string();
        assert!(e.contains("text.h5"), "{e}");
        let mut c = sample();
        c.tets[0][3] = 9;
        let r = dir.path().join("bad.h5");
        c.write(&r).unwrap();
        let e = Checkpoint::read(&r).unwrap_err().to_string();
        assert!(e.contains("element 0"), "{e}");
    }
}
