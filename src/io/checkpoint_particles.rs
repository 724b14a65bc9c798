//! The bonded particles' part of a checkpoint (issue 21): each rank's
//! spheres, bonds and interface links by global number (body by body, in
//! each body's lattice order, as the particle output numbers them), so a
//! checkpoint of P ranks restarts on Q whichever rank holds a body. Four
//! datasets, each present when the run had it:
//!
//! - `particles/state`: per sphere x, v, ω ([`SAVED_PARTICLE`] columns);
//! - `particles/bonds`: per bond its incremental state d and n
//!   ([`SAVED_BOND`], `mechanics::bond::BondState`);
//! - `particles/links`: per sphere–element link the same;
//! - `particles/heat`: per sphere its thermal row's temperature and heat
//!   account values t₀, Σ T and radiated heat ([`SAVED_PARTICLE_HEAT`]).
//!
//! Written collectively through the checkpoint's MPI-IO file
//! ([`super::checkpoint::write_parallel`]); read in pieces by each rank.

use std::path::Path;

use hdf5::File;
use mpi::topology::SimpleCommunicator;

use super::checkpoint::CheckpointFile;
use super::IoError;

/// Columns of a sphere's saved motion: position, velocity, angular velocity.
pub const SAVED_PARTICLE: usize = 9;
/// Columns of a bond's or link's saved state: d and n.
pub const SAVED_BOND: usize = 6;
/// Columns of a sphere's saved heat: T, account t₀, Σ T, radiated heat.
pub const SAVED_PARTICLE_HEAT: usize = 4;

/// One set of rows by global number: this rank's numbers, their values
/// (width columns each, flat) and the number of rows over all ranks.
#[derive(Debug, Clone, Default)]
pub struct GlobalRows {
    pub gid: Vec<u32>,
    pub values: Vec<f64>,
    pub total: u64,
}

/// What a rank saves of its particles (each part present when the run had it).
#[derive(Debug, Clone, Default)]
pub struct ParticleCheckpoint {
    /// Sphere motion, bond and link states (mechanics).
    pub motion: Option<[GlobalRows; 3]>,
    /// Sphere temperatures and heat account (heat).
    pub heat: Option<GlobalRows>,
}

const NAMES: [(&str, usize); 3] = [
    ("particles/state", SAVED_PARTICLE),
    ("particles/bonds", SAVED_BOND),
    ("particles/links", SAVED_BOND),
];
const HEAT: &str = "particles/heat";

/// Collective. Write `p`'s datasets into the open checkpoint `file`
/// (every rank calls it with the same parts present).
pub(super) fn write(
    comm: &SimpleCommunicator,
    file: &File,
    path: &Path,
    xfer: &super::ffi::CollectiveXfer,
    p: &ParticleCheckpoint,
) -> Result<(), IoError> {
    file.create_group("particles")
        .map_err(|e| IoError::hdf5(path, "creating group particles", e))?;
    let mut sets: Vec<(&str, usize, &GlobalRows)> = Vec::new();
    if let Some(m) = &p.motion {
        sets.extend(NAMES.iter().zip(m).map(|(&(n, c), r)| (n, c, r)));
    }
    if let Some(h) = &p.heat {
        sets.push((HEAT, SAVED_PARTICLE_HEAT, h));
    }
    write_sets(comm, file, path, xfer, &sets)
}

/// Collective. Write each `(name, columns, rows)` of `sets` as a dataset
/// of its rows by global number (every rank its rows, moved into blocks).
pub(super) fn write_sets(
    comm: &SimpleCommunicator,
    file: &File,
    path: &Path,
    xfer: &super::ffi::CollectiveXfer,
    sets: &[(&str, usize, &GlobalRows)],
) -> Result<(), IoError> {
    for &(name, cols, r) in sets {
        let (lo, block) =
            crate::parallel::exchange::to_blocks(comm, &r.gid, &r.values, cols, r.total);
        super::checkpoint::dataset_f64(
            file,
            path,
            name,
            r.total as usize,
            cols,
            xfer,
            lo,
            Some(&block),
        )?;
    }
    Ok(())
}

impl CheckpointFile {
    /// Whether the checkpoint holds the spheres' motion and bond states.
    pub fn has_particle_motion(&self) -> bool {
        NAMES.iter().all(|(n, _)| self.file.link_exists(n))
    }

    /// Whether the checkpoint holds the spheres' temperatures.
    pub fn has_particle_heat(&self) -> bool {
        self.file.link_exists(HEAT)
    }

    /// Checks that dataset `name` has `total` rows (the scenario's).
    fn particle_count(&self, name: &str, total: u64) -> Result<(), IoError> {
        let n = self
            .file
            .dataset(name)
            .map_err(|e| IoError::hdf5(self.path(), format!("opening {name}"), e))?
            .shape()
            .first()
            .copied()
            .unwrap_or(0) as u64;
        if n != total {
            return Err(IoError::invalid(
                self.path(),
                format!(
                    "{name} has {n} rows, the scenario's particles {total} \
                     (another particle radius or set?)"
                ),
            ));
        }
        Ok(())
    }

    /// Rows `ids` (global numbers, of `totals`) of the spheres' motion, the
    /// bonds' and the links' states, flat.
    pub fn particle_motion(
        &self,
        ids: [&[u32]; 3],
        totals: [u64; 3],
    ) -> Result<[Vec<f64>; 3], IoError> {
        for ((name, _), &total) in NAMES.iter().zip(&totals) {
            self.particle_count(name, total)?;
        }
        let s = self.rows_of::<f64, SAVED_PARTICLE>(NAMES[0].0, ids[0], totals[0])?;
        let b = self.rows_of::<f64, SAVED_BOND>(NAMES[1].0, ids[1], totals[1])?;
        let l = self.rows_of::<f64, SAVED_BOND>(NAMES[2].0, ids[2], totals[2])?;
        Ok([s.concat(), b.concat(), l.concat()])
    }

    /// Rows `ids` (global particle numbers, of `total`) of the spheres' heat, flat.
    pub fn particle_heat(&self, ids: &[u32], total: u64) -> Result<Vec<f64>, IoError> {
        self.particle_count(HEAT, total)?;
        Ok(self
            .rows_of::<f64, SAVED_PARTICLE_HEAT>(HEAT, ids, total)?
            .concat())
    }
}
