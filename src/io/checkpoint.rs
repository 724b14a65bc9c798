//! Restart checkpoints: the whole state of a run in one HDF5 file, in the
//! original (rank-independent) numbering, written by one rank.
//!
//! Layout (`format = "fdem-checkpoint"`, `version = 1` attributes on `/`):
//! - `/mesh/reference` (N×3 f64), `/mesh/tets` (E×4 u32), `/mesh/body` (E u32)
//! - `/bodies/names`, `/bodies/templates` (newline-joined UTF-8 as u8),
//!   `/bodies/nodes`, `/bodies/elems` (B×2 u32 ranges)
//! - `/mesh/hex_corner`, `/bodies/hex8` when a body is Hex8 (`checkpoint_hexes`)
//! - `/state/positions`, `/state/velocities` (N×3 f64, when mechanics ran),
//!   `/state/temperature` (N f64, when the thermal problem ran),
//!   `/state/pending_heat` (N f64, heat handed over, not yet released)
//! - `/state/scalars` (f64): step, time, substeps, heat account (5 values),
//!   dissipated energy, peak kinetic energy, thermal contacts, radiated heat,
//!   frictional heat
//!
//! The file is written to `<path>.tmp` and renamed, so a crash never
//! leaves a half-written checkpoint under the final name.

use std::path::{Path, PathBuf};

use hdf5::{File, H5Type};
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::checkpoint_heat::{account_base, heat_of};
use super::IoError;

const FORMAT: &str = "fdem-checkpoint";
const VERSION: u32 = 1;
const SCALARS: usize = 14;

/// The heat account's running state as saved.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SavedAccount {
    /// Base account: stored, stored change, Dirichlet in, flux in,
    /// convection in, radiation in.
    pub base: [f64; 7],
    /// Steps since the last assembly.
    pub steps: u64,
    /// Temperatures at the last assembly, per node.
    pub t0: Vec<f64>,
    /// Sum of the step temperatures since then, per node.
    pub t_sum: Vec<f64>,
    /// The radiated heat since then, per node (radiating runs).
    pub rad_sum: Option<Vec<f64>>,
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
    /// Heat account: stored, stored change, Dirichlet in, flux in,
    /// convection in, radiation in.
    pub heat: [f64; 7],
    /// Energy dissipated by contact damping and friction (J).
    pub dissipated: f64,
    /// The friction's share of it (J; issue 20's frictional heating).
    pub friction_work: f64,
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
    /// Read a checkpoint (serial).
    pub fn read(path: &Path) -> Result<Checkpoint, IoError> {
        let file = open_checked(path)?;
        let text = |name: &str| text_lines(&file, path, name);
        let opt3 = |name: &str| -> Result<Option<Vec<[f64; 3]>>, IoError> {
            if file.link_exists(name) {
                Ok(Some(rows::<f64, 3>(get(&file, path, name, 3)?)))
            } else {
                Ok(None)
            }
        };
        let sc = get::<f64>(&file, path, "state/scalars", 1)?;
        if !(SCALARS - 2..=SCALARS).contains(&sc.len()) {
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
            heat: heat_of(&sc),
            dissipated: sc[8],
            friction_work: sc.get(13).copied().unwrap_or(0.0),
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
                let (Some(base), Some(&steps)) = (account_base(&base), steps.first()) else {
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
                    rad_sum: if file.link_exists("state/account_rad_sum") {
                        Some(get(&file, path, "state/account_rad_sum", 1)?)
                    } else {
                        None
                    },
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
            (
                "state/account_rad_sum",
                self.account
                    .as_ref()
                    .and_then(|a| a.rad_sum.as_ref().map(Vec::len)),
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

/// The part of a checkpoint every rank reads whole: scalars, counters and
/// the body table (O(bodies)).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckpointHead {
    /// Thermal (outer) steps done.
    pub step: u64,
    /// Time (s).
    pub time: f64,
    /// Explicit substeps done.
    pub substeps: u64,
    /// Nodes and elements of the whole mesh.
    pub nodes: u64,
    /// Elements.
    pub elems: u64,
    /// Body names.
    pub body_names: Vec<String>,
    /// The scenario entry each body came from.
    pub body_templates: Vec<String>,
    /// Node range of every body.
    pub body_nodes: Vec<[u32; 2]>,
    /// Element range of every body.
    pub body_elems: Vec<[u32; 2]>,
    /// Whether each body is Hex8 (`checkpoint_hexes`).
    pub body_hex8: Vec<bool>,
    /// Krylov iterations so far.
    pub ksp_iterations: u64,
    /// Heat account: stored, stored change, Dirichlet in, flux in,
    /// convection in, radiation in.
    pub heat: [f64; 7],
    /// Energy dissipated by contact damping and friction (J).
    pub dissipated: f64,
    /// The friction's share of it (J; issue 20's frictional heating).
    pub friction_work: f64,
    /// Largest kinetic energy seen (J).
    pub peak_kinetic: f64,
    /// Thermal contact pairs at the checkpoint (information).
    pub thermal_contacts: u64,
    /// Each rank's share of `dissipated`.
    pub dissipated_per_rank: Option<Vec<f64>>,
    /// Each rank's share of the loads' work so far (J), when saved.
    pub external_work_per_rank: Option<Vec<f64>>,
    /// The heat account's base and steps since the last assembly, when saved.
    pub account: Option<([f64; 7], u64)>,
    /// The kinetic energy at which the run settled, for a settled run.
    pub settled: Option<f64>,
    /// Which node fields the file holds.
    pub has_positions: bool,
    /// Velocities v^{n−½}.
    pub has_velocities: bool,
    /// Velocities of the substep before.
    pub has_velocities_prev: bool,
    /// Temperatures.
    pub has_temperature: bool,
    /// The radiated heat per node since the last assembly (radiating runs).
    pub has_rad_sum: bool,
    /// Whether it holds the cohesive joints' histories.
    pub has_joints: bool,
    /// The number of ranks of the run that wrote the file, when it saved
    /// each element's rank (`partition/rank`): a restart on as many ranks
    /// continues on the same parts.
    pub partition_ranks: Option<u64>,
}

impl CheckpointHead {
    /// Indices of the bodies that came from scenario entry `template`.
    pub fn bodies_of(&self, template: &str) -> Vec<usize> {
        (0..self.body_names.len())
            .filter(|&b| self.body_templates[b] == template)
            .collect()
    }
}

/// One rank's rows of a checkpoint, by global id: the nodes it owns and
/// the elements it owns (every id on exactly one rank).
#[derive(Debug, Clone, Copy, Default)]
pub struct CheckpointRows<'a> {
    /// Global ids of the nodes.
    pub node_gid: &'a [u32],
    /// Their reference coordinates.
    pub reference: &'a [[f64; 3]],
    /// Global ids of the elements.
    pub elem_gid: &'a [u32],
    /// Their nodes (global ids).
    pub tets: &'a [[u32; 4]],
    /// Their bodies.
    pub elem_body: &'a [u32],
    /// The rank of every element (with `head.partition_ranks`), when saved.
    pub elem_rank: Option<&'a [u32]>,
    /// Node fields, when saved (the same on every rank).
    pub positions: Option<&'a [[f64; 3]]>,
    /// Velocities.
    pub velocities: Option<&'a [[f64; 3]]>,
    /// Velocities of the substep before.
    pub velocities_prev: Option<&'a [[f64; 3]]>,
    /// Temperatures.
    pub temperature: Option<&'a [f64]>,
    /// Heat account: temperatures at the last assembly.
    pub account_t0: Option<&'a [f64]>,
    /// Heat account: sum of the step temperatures since.
    pub account_t_sum: Option<&'a [f64]>,
    /// Heat account: the radiated heat since, per node (radiating runs).
    pub account_rad_sum: Option<&'a [f64]>,
    /// Cohesive joints: global joint numbers, their saved values
    /// ([`crate::fracture::set::SAVED_JOINT`] each) and the total.
    pub joints: Option<(&'a [u32], &'a [f64], u64)>,
    /// Bonded particles (issue 21), by global numbers.
    pub particles: Option<&'a super::checkpoint_particles::ParticleCheckpoint>,
    /// Tangential springs: `checkpoint_springs::sorted_rows`.
    pub springs: Option<(&'a [u32], &'a [f64], u64)>,
    /// Free spheres (issue 21).
    pub spheres: Option<&'a super::checkpoint_spheres::SphereCheckpoint>,
    /// Heat handed over and not yet released, per node (`checkpoint_heat`).
    pub pending_heat: Option<&'a [f64]>,
    /// Hex corners, 4 per element (`checkpoint_hexes`), when a body is Hex8.
    pub hex_corner: Option<&'a [u32]>,
}

/// Collective. Write a checkpoint: every rank its rows (moved to
/// contiguous blocks by global id first), rank 0 the head, through MPI-IO
/// into `<path>.tmp`, renamed once complete; no rank holds the whole mesh.
/// The layout is that of [`Checkpoint::read`].
pub fn write_parallel(
    comm: &SimpleCommunicator,
    path: &Path,
    head: &CheckpointHead,
    rows: &CheckpointRows,
) -> Result<(), IoError> {
    let tmp = tmp_path(path);
    let result = write_parallel_to(comm, &tmp, head, rows);
    // Agree before renaming: one rank's failure fails every rank.
    let mine = i32::from(result.is_err());
    let mut any = 0;
    comm.all_reduce_into(&mine, &mut any, SystemOperation::max());
    if any != 0 {
        if comm.rank() == 0 {
            let _ = std::fs::remove_file(&tmp);
        }
        return result.and(Err(IoError::invalid(path, "another rank failed writing")));
    }
    let renamed = if comm.rank() == 0 {
        std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, "renaming the checkpoint", e))
    } else {
        Ok(())
    };
    let mine = i32::from(renamed.is_err());
    comm.all_reduce_into(&mine, &mut any, SystemOperation::max());
    renamed?;
    if any != 0 {
        return Err(IoError::invalid(
            path,
            "rank 0 failed renaming the checkpoint",
        ));
    }
    // A killed earlier writer's MPI-IO locks beside the `.tmp`.
    match comm.rank() {
        0 => super::remove_mpi_io_locks(&tmp),
        _ => Ok(()),
    }
}

fn write_parallel_to(
    comm: &SimpleCommunicator,
    path: &Path,
    head: &CheckpointHead,
    rows: &CheckpointRows,
) -> Result<(), IoError> {
    let h5err = |what: &str| {
        let what = what.to_string();
        move |e| IoError::hdf5(path, what, e)
    };
    let call = |what: &str| {
        let what = what.to_string();
        move |call| IoError::Hdf5Call {
            path: path.to_path_buf(),
            call,
            what,
        }
    };
    let hints = super::ffi::IoHints::new();
    let file = File::with_options()
        .with_fapl(|p| p.mpio(comm.as_raw(), Some(hints.info())))
        .create(path)
        .map_err(h5err("creating with the MPI-IO driver"))?;
    let xfer = super::ffi::CollectiveXfer::new().map_err(call("a transfer property list"))?;
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
            .map_err(h5err(&format!("creating group {g}")))?;
    }
    let root = comm.rank() == 0;
    // A dataset of `rows` × `cols`, written by rank 0 alone (small ones).
    let small = |name: &str, data: &[f64], cols: usize| -> Result<(), IoError> {
        dataset_f64(
            &file,
            path,
            name,
            data.len() / cols.max(1),
            cols,
            &xfer,
            0,
            root.then_some(data),
        )
    };
    let small_u = |name: &str, data: &[u64]| -> Result<(), IoError> {
        let ds = file
            .new_dataset::<u64>()
            .shape([data.len()])
            .create(name)
            .map_err(h5err(&format!("creating {name}")))?;
        let n = if root { data.len() as u64 } else { 0 };
        super::ffi::write_block(&ds, &xfer, &[0], &[n], if root { data } else { &[] })
            .map_err(call(&format!("writing {name}")))
    };
    let small_u32 = |name: &str, data: &[u32], cols: usize| -> Result<(), IoError> {
        let r = (data.len() / cols) as u64;
        let ds = file
            .new_dataset::<u32>()
            .shape([r as usize, cols])
            .create(name)
            .map_err(h5err(&format!("creating {name}")))?;
        let n = if root { r } else { 0 };
        super::ffi::write_block(
            &ds,
            &xfer,
            &[0, 0],
            &[n, cols as u64],
            if root { data } else { &[] },
        )
        .map_err(call(&format!("writing {name}")))
    };
    let text = |name: &str, v: &[String]| -> Result<(), IoError> {
        let b = v.join("\n").into_bytes();
        let ds = file
            .new_dataset::<u8>()
            .shape([b.len()])
            .create(name)
            .map_err(h5err(&format!("creating {name}")))?;
        let n = if root { b.len() as u64 } else { 0 };
        super::ffi::write_block(&ds, &xfer, &[0], &[n], if root { &b[..] } else { &[] })
            .map_err(call(&format!("writing {name}")))
    };
    // Node and element rows by global id, in blocks.
    let nodes = |name: &str, v: &[f64], cols: usize| -> Result<(), IoError> {
        let (lo, block) =
            crate::parallel::exchange::to_blocks(comm, rows.node_gid, v, cols, head.nodes);
        dataset_f64(
            &file,
            path,
            name,
            head.nodes as usize,
            cols,
            &xfer,
            lo,
            Some(&block),
        )
    };
    let elems_u32 = |name: &str, v: &[u32], cols: usize| -> Result<(), IoError> {
        let vf: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
        let (lo, block) =
            crate::parallel::exchange::to_blocks(comm, rows.elem_gid, &vf, cols, head.elems);
        let block: Vec<u32> = block.iter().map(|&x| x as u32).collect();
        let ds = file
            .new_dataset::<u32>()
            .shape(if cols == 1 {
                vec![head.elems as usize]
            } else {
                vec![head.elems as usize, cols]
            })
            .create(name)
            .map_err(h5err(&format!("creating {name}")))?;
        let n = (block.len() / cols) as u64;
        let (start, count) = if cols == 1 {
            (vec![lo], vec![n])
        } else {
            (vec![lo, 0], vec![n, cols as u64])
        };
        super::ffi::write_block(&ds, &xfer, &start, &count, &block)
            .map_err(call(&format!("writing {name}")))
    };
    let flat = |v: &[[f64; 3]]| -> Vec<f64> { v.iter().flatten().copied().collect() };
    nodes("mesh/reference", &flat(rows.reference), 3)?;
    let tets: Vec<u32> = rows.tets.iter().flatten().copied().collect();
    elems_u32("mesh/tets", &tets, 4)?;
    elems_u32("mesh/body", rows.elem_body, 1)?;
    text("bodies/names", &head.body_names)?;
    text("bodies/templates", &head.body_templates)?;
    let bn: Vec<u32> = head.body_nodes.iter().flatten().copied().collect();
    let be: Vec<u32> = head.body_elems.iter().flatten().copied().collect();
    small_u32("bodies/nodes", &bn, 2)?;
    small_u32("bodies/elems", &be, 2)?;
    if let Some(c) = rows.hex_corner {
        elems_u32(super::checkpoint_hexes::HEX_CORNER, c, 4)?;
        let flags: Vec<u64> = head.body_hex8.iter().map(|&h| u64::from(h)).collect();
        small_u(super::checkpoint_hexes::BODY_HEX8, &flags)?;
    }
    if let Some(x) = rows.positions {
        nodes("state/positions", &flat(x), 3)?;
    }
    if let Some(v) = rows.velocities {
        nodes("state/velocities", &flat(v), 3)?;
    }
    if let Some(v) = rows.velocities_prev {
        nodes("state/velocities_prev", &flat(v), 3)?;
    }
    small_u("state/counters", &[head.ksp_iterations])?;
    if let (Some(r), Some(n)) = (rows.elem_rank, head.partition_ranks) {
        elems_u32("partition/rank", r, 1)?;
        small_u("partition/ranks", &[n])?;
    }
    if let Some(d) = &head.dissipated_per_rank {
        small("state/dissipated_per_rank", d, 1)?;
    }
    if let Some(w) = &head.external_work_per_rank {
        small("state/external_work_per_rank", w, 1)?;
    }
    if let (Some((base, steps)), Some(t0), Some(ts)) =
        (head.account, rows.account_t0, rows.account_t_sum)
    {
        small("state/account_base", &base, 1)?;
        small_u("state/account_steps", &[steps])?;
        nodes("state/account_t0", t0, 1)?;
        nodes("state/account_t_sum", ts, 1)?;
        if let Some(r) = rows.account_rad_sum {
            nodes("state/account_rad_sum", r, 1)?;
        }
    }
    if let Some(ke) = head.settled {
        small("state/settled", &[ke], 1)?;
    }
    if let Some(t) = rows.temperature {
        nodes("state/temperature", t, 1)?;
    }
    if let Some(q) = rows.pending_heat {
        nodes(super::checkpoint_heat::PENDING_HEAT, q, 1)?;
    }
    if let Some((ids, v, total)) = rows.joints {
        let cols = crate::fracture::set::SAVED_JOINT;
        let (lo, block) = crate::parallel::exchange::to_blocks(comm, ids, v, cols, total);
        dataset_f64(
            &file,
            path,
            "state/joints",
            total as usize,
            cols,
            &xfer,
            lo,
            Some(&block),
        )?;
    }
    if let Some(p) = rows.particles {
        super::checkpoint_particles::write(comm, &file, path, &xfer, p)?;
    }
    if let Some(r) = rows.springs {
        super::checkpoint_springs::write(comm, &file, path, &xfer, r)?;
    }
    if let Some(s) = rows.spheres {
        super::checkpoint_spheres::write(comm, &file, path, &xfer, s)?;
    }
    let mut sc = [0.0; SCALARS];
    sc[0] = head.step as f64;
    sc[1] = head.time;
    sc[2] = head.substeps as f64;
    sc[3..8].copy_from_slice(&head.heat[..5]);
    sc[8] = head.dissipated;
    sc[9] = head.peak_kinetic;
    sc[10] = head.thermal_contacts as f64;
    sc[11] = head.heat[5];
    sc[12] = head.heat[6];
    sc[13] = head.friction_work;
    small("state/scalars", &sc, 1)?;
    super::ffi::flush_global(&file).map_err(call("flushing the checkpoint"))
}

/// Create `name` (`rows` × `cols` f64, 1-D when `cols` is 1) and write
/// this rank's block of rows from `lo` (none when `data` is None).
/// Collective.
#[allow(clippy::too_many_arguments)]
pub(super) fn dataset_f64(
    file: &File,
    path: &Path,
    name: &str,
    rows: usize,
    cols: usize,
    xfer: &super::ffi::CollectiveXfer,
    lo: u64,
    data: Option<&[f64]>,
) -> Result<(), IoError> {
    let shape = if cols == 1 {
        vec![rows]
    } else {
        vec![rows, cols]
    };
    let ds = file
        .new_dataset::<f64>()
        .shape(shape)
        .create(name)
        .map_err(|e| IoError::hdf5(path, format!("creating {name}"), e))?;
    let data = data.unwrap_or(&[]);
    let n = (data.len() / cols) as u64;
    let (start, count) = if cols == 1 {
        (vec![lo], vec![n])
    } else {
        (vec![lo, 0], vec![n, cols as u64])
    };
    super::ffi::write_block(&ds, xfer, &start, &count, data).map_err(|call| IoError::Hdf5Call {
        path: path.to_path_buf(),
        call,
        what: format!("writing {name}"),
    })
}

/// A checkpoint opened for reading in pieces: its head, and the rows of
/// any nodes or elements by global id. Every rank opens it (read-only,
/// serial driver) and reads only what it holds.
pub struct CheckpointFile {
    pub(super) file: File,
    path: PathBuf,
    /// Scalars and the body table.
    pub head: CheckpointHead,
}

impl CheckpointFile {
    /// Open and read the head, checking the format, the version and the
    /// sizes of the body table and of every node dataset.
    pub fn open(path: &Path) -> Result<CheckpointFile, IoError> {
        let file = open_checked(path)?;
        let text = |name: &str| text_lines(&file, path, name);
        let sc = get::<f64>(&file, path, "state/scalars", 1)?;
        if !(SCALARS - 2..=SCALARS).contains(&sc.len()) {
            return Err(IoError::invalid(path, "state/scalars has the wrong length"));
        }
        let rows_of = |name: &str| -> Result<u64, IoError> {
            let d = file
                .dataset(name)
                .map_err(|e| IoError::hdf5(path, format!("opening {name}"), e))?;
            Ok(d.shape().first().copied().unwrap_or(0) as u64)
        };
        let nodes = rows_of("mesh/reference")?;
        let elems = rows_of("mesh/tets")?;
        let first = |name: &str| -> Result<Option<u64>, IoError> {
            if file.link_exists(name) {
                Ok(get::<u64>(&file, path, name, 1)?.first().copied())
            } else {
                Ok(None)
            }
        };
        let account = if file.link_exists("state/account_base") {
            let base = get::<f64>(&file, path, "state/account_base", 1)?;
            let steps = first("state/account_steps")?;
            match (account_base(&base), steps) {
                (Some(b), Some(s)) => Some((b, s)),
                _ => {
                    return Err(IoError::invalid(
                        path,
                        "state/account_base or state/account_steps has the wrong length",
                    ))
                }
            }
        } else {
            None
        };
        let mut head = CheckpointHead {
            step: sc[0] as u64,
            time: sc[1],
            substeps: sc[2] as u64,
            nodes,
            elems,
            body_names: text("bodies/names")?,
            body_templates: text("bodies/templates")?,
            body_nodes: rows::<u32, 2>(get(&file, path, "bodies/nodes", 2)?),
            body_elems: rows::<u32, 2>(get(&file, path, "bodies/elems", 2)?),
            body_hex8: Vec::new(),
            ksp_iterations: first("state/counters")?.unwrap_or(0),
            heat: heat_of(&sc),
            dissipated: sc[8],
            friction_work: sc.get(13).copied().unwrap_or(0.0),
            peak_kinetic: sc[9],
            thermal_contacts: sc[10] as u64,
            dissipated_per_rank: if file.link_exists("state/dissipated_per_rank") {
                Some(get(&file, path, "state/dissipated_per_rank", 1)?)
            } else {
                None
            },
            external_work_per_rank: if file.link_exists("state/external_work_per_rank") {
                Some(get(&file, path, "state/external_work_per_rank", 1)?)
            } else {
                None
            },
            account,
            settled: if file.link_exists("state/settled") {
                get::<f64>(&file, path, "state/settled", 1)?
                    .first()
                    .copied()
            } else {
                None
            },
            has_positions: file.link_exists("state/positions"),
            has_velocities: file.link_exists("state/velocities"),
            has_velocities_prev: file.link_exists("state/velocities_prev"),
            has_temperature: file.link_exists("state/temperature"),
            has_rad_sum: file.link_exists("state/account_rad_sum"),
            has_joints: file.link_exists("state/joints"),
            partition_ranks: if file.link_exists("partition/rank") {
                first("partition/ranks")?
            } else {
                None
            },
        };
        let bad = |m: String| Err(IoError::invalid(path, m));
        let nb = head.body_names.len();
        head.body_hex8 = super::checkpoint_hexes::read_body_hex8(&file, path, nb)?;
        if head.body_templates.len() != nb
            || head.body_nodes.len() != nb
            || head.body_elems.len() != nb
        {
            return bad("the /bodies datasets differ in length".into());
        }
        if rows_of("mesh/body")? != elems {
            return bad("mesh/body and mesh/tets differ in length".into());
        }
        for name in [
            "state/positions",
            "state/velocities",
            "state/velocities_prev",
            "state/temperature",
            "state/account_t0",
            "state/account_t_sum",
            "state/account_rad_sum",
            super::checkpoint_heat::PENDING_HEAT,
        ] {
            if file.link_exists(name) && rows_of(name)? != nodes {
                return bad(format!(
                    "{name} has {} rows for {nodes} nodes",
                    rows_of(name)?
                ));
            }
        }
        if let Some((b, r)) = head
            .body_nodes
            .iter()
            .chain(&head.body_elems)
            .enumerate()
            .find(|(_, r)| r[0] > r[1])
        {
            return bad(format!("body range {b} is reversed: {r:?}"));
        }
        Ok(CheckpointFile {
            file,
            path: path.to_path_buf(),
            head,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows `ids` (any order) of the 2-D dataset `name` of `C` columns.
    pub(super) fn rows_of<T: H5Type + Copy + Default, const C: usize>(
        &self,
        name: &str,
        ids: &[u32],
        total: u64,
    ) -> Result<Vec<[T; C]>, IoError> {
        let d = self
            .file
            .dataset(name)
            .map_err(|e| IoError::hdf5(&self.path, format!("opening {name}"), e))?;
        let mut out = vec![[T::default(); C]; ids.len()];
        for (start, run) in runs(ids) {
            let end = start + run.len() as u64;
            if end > total {
                return Err(IoError::invalid(
                    &self.path,
                    format!("{name}: row {} beyond its {total} rows", end - 1),
                ));
            }
            let block: Vec<T> = if C == 1 {
                d.read_slice_1d::<T, _>(start as usize..end as usize)
                    .map(|a| a.into_raw_vec_and_offset().0)
            } else {
                d.read_slice_2d::<T, _>((start as usize..end as usize, ..))
                    .map(|a| a.into_raw_vec_and_offset().0)
            }
            .map_err(|e| IoError::hdf5(&self.path, format!("reading rows of {name}"), e))?;
            for (k, &i) in run.iter().enumerate() {
                out[i].copy_from_slice(&block[C * k..C * (k + 1)]);
            }
        }
        Ok(out)
    }

    /// Node rows of a 3-column node dataset (`mesh/reference`,
    /// `state/positions`, ...), for the nodes `ids`.
    pub fn node_rows3(&self, name: &str, ids: &[u32]) -> Result<Vec<[f64; 3]>, IoError> {
        self.rows_of::<f64, 3>(name, ids, self.head.nodes)
    }

    /// Rows `ids` (global joint numbers) of the joints' histories, of
    /// `total` joints.
    pub fn joint_rows(
        &self,
        ids: &[u32],
        total: u64,
    ) -> Result<Vec<[f64; crate::fracture::set::SAVED_JOINT]>, IoError> {
        self.rows_of::<f64, { crate::fracture::set::SAVED_JOINT }>("state/joints", ids, total)
    }

    /// Node rows of a 1-column node dataset (`state/temperature`, ...).
    pub fn node_rows1(&self, name: &str, ids: &[u32]) -> Result<Vec<f64>, IoError> {
        Ok(self
            .rows_of::<f64, 1>(name, ids, self.head.nodes)?
            .into_iter()
            .map(|[x]| x)
            .collect())
    }

    /// The nodes (global ids) of elements `ids`.
    pub fn elem_tets(&self, ids: &[u32]) -> Result<Vec<[u32; 4]>, IoError> {
        self.rows_of::<u32, 4>("mesh/tets", ids, self.head.elems)
    }

    /// The saved rank of elements `ids` (when `head.partition_ranks`).
    pub fn elem_ranks(&self, ids: &[u32]) -> Result<Vec<u32>, IoError> {
        Ok(self
            .rows_of::<u32, 1>("partition/rank", ids, self.head.elems)?
            .into_iter()
            .map(|[r]| r)
            .collect())
    }
}

/// Runs of consecutive ids: (first id, positions in `ids` of the run's
/// ids in ascending order).
fn runs(ids: &[u32]) -> Vec<(u64, Vec<usize>)> {
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_by_key(|&i| ids[i]);
    let mut out: Vec<(u64, Vec<usize>)> = Vec::new();
    for i in order {
        let id = u64::from(ids[i]);
        match out.last_mut() {
            Some((start, run)) if *start + run.len() as u64 == id => run.push(i),
            _ => out.push((id, vec![i])),
        }
    }
    out
}

/// Open an existing checkpoint and check its format and version.
fn open_checked(path: &Path) -> Result<File, IoError> {
    if !path.is_file() {
        return Err(IoError::invalid(path, "checkpoint file not found"));
    }
    let file = File::open(path).map_err(|e| IoError::hdf5(path, "opening", e))?;
    check_format(&file, path)?;
    Ok(file)
}

/// A newline-separated text dataset (UTF-8 bytes), as lines.
fn text_lines(file: &File, path: &Path, name: &str) -> Result<Vec<String>, IoError> {
    let b = get::<u8>(file, path, name, 1)?;
    let s =
        String::from_utf8(b).map_err(|_| IoError::invalid(path, format!("{name} is not UTF-8")))?;
    Ok(s.split('\n').map(str::to_string).collect())
}

fn check_format(file: &File, path: &Path) -> Result<(), IoError> {
    let format = file
        .attr("format")
        .and_then(|a| a.read_raw::<u8>())
        .map_err(|_| IoError::invalid(path, "not an fdem checkpoint (no `format` attribute)"))?;
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
    Ok(())
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
            heat: [1.0, 2.0, 3.0, 4.0, 5.0, -6.0, 7.0],
            dissipated: 0.5,
            friction_work: 0.125,
            peak_kinetic: 2.5,
            settled: Some(1e-3),
            dissipated_per_rank: Some(vec![0.25, 0.5]),
            account: Some(SavedAccount {
                base: [1.0, 2.0, 3.0, 4.0, 5.0, -6.5, 7.5],
                steps: 17,
                t0: vec![0.5; 4],
                t_sum: vec![8.5; 4],
                rad_sum: Some(vec![0.25; 4]),
            }),
            thermal_contacts: 3,
        }
    }

    /// Write `c` as a run on one rank would.
    fn write(c: &Checkpoint, p: &Path) -> Result<(), IoError> {
        let head = CheckpointHead {
            step: c.step,
            time: c.time,
            substeps: c.substeps,
            nodes: c.reference.len() as u64,
            elems: c.tets.len() as u64,
            body_names: c.body_names.clone(),
            body_templates: c.body_templates.clone(),
            body_nodes: c.body_nodes.clone(),
            body_elems: c.body_elems.clone(),
            ksp_iterations: c.ksp_iterations,
            heat: c.heat,
            dissipated: c.dissipated,
            friction_work: c.friction_work,
            peak_kinetic: c.peak_kinetic,
            thermal_contacts: c.thermal_contacts,
            dissipated_per_rank: c.dissipated_per_rank.clone(),
            account: c.account.as_ref().map(|a| (a.base, a.steps)),
            settled: c.settled,
            ..Default::default()
        };
        let node_gid: Vec<u32> = (0..c.reference.len() as u32).collect();
        let elem_gid: Vec<u32> = (0..c.tets.len() as u32).collect();
        let rows = CheckpointRows {
            node_gid: &node_gid,
            reference: &c.reference,
            elem_gid: &elem_gid,
            tets: &c.tets,
            elem_body: &c.elem_body,
            elem_rank: None,
            positions: c.positions.as_deref(),
            velocities: c.velocities.as_deref(),
            velocities_prev: c.velocities_prev.as_deref(),
            temperature: c.temperature.as_deref(),
            account_t0: c.account.as_ref().map(|a| &a.t0[..]),
            account_t_sum: c.account.as_ref().map(|a| &a.t_sum[..]),
            account_rad_sum: c.account.as_ref().and_then(|a| a.rad_sum.as_deref()),
            joints: None,
            particles: None,
            springs: None,
            spheres: None,
            pending_heat: None,
            hex_corner: None,
        };
        crate::testutil::on_one_rank(|comm| write_parallel(comm, p, &head, &rows))
    }

    #[test]
    fn partial_reads_are_the_rows() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.h5");
        let c = sample();
        write(&c, &p).unwrap();
        let f = CheckpointFile::open(&p).unwrap();
        assert_eq!(f.head.nodes, 4);
        assert_eq!(f.head.bodies_of("nut"), vec![0]);
        let ids = [3u32, 0, 1];
        let x = f.node_rows3("mesh/reference", &ids).unwrap();
        assert_eq!(x, ids.map(|i| c.reference[i as usize]).to_vec());
        let t = f.node_rows1("state/temperature", &ids).unwrap();
        let ct = c.temperature.as_ref().unwrap();
        assert_eq!(t, ids.map(|i| ct[i as usize]).to_vec());
        assert_eq!(f.elem_tets(&[0]).unwrap(), c.tets);
        assert!(f.node_rows3("mesh/reference", &[4]).is_err());
    }

    #[test]
    fn round_trip_is_bitwise() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.h5");
        let c = sample();
        write(&c, &p).unwrap();
        assert!(!tmp_path(&p).exists());
        let r = Checkpoint::read(&p).unwrap();
        assert_eq!(r, c);
        assert_eq!(r.bodies_of("nut"), vec![0]);
        let mut m = c.clone();
        m.temperature = None;
        m.positions = None;
        write(&m, &p).unwrap();
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
        write(&c, &r).unwrap();
        let e = Checkpoint::read(&r).unwrap_err().to_string();
        assert!(e.contains("element 0"), "{e}");
    }
}
