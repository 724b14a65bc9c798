//! The free spheres' part of a checkpoint (issue 21, beyond the papers):
//! every sphere's motion by its global number, the tangential springs of
//! the touching pairs and of the sphere–face contacts as rows sorted by
//! key, and each rank's share of the energy the spheres' loads and
//! damping have done, so a checkpoint of P ranks restarts on Q. Four
//! datasets in the group `spheres` (seven with heat):
//!
//! - `spheres/state`: per sphere its set, reference centre, centre,
//!   velocity and angular velocity ([`SAVED_SPHERE`] columns);
//! - `spheres/pairs`: per touching pair (lower, higher number) its
//!   spring ξ ([`SAVED_SPHERE_PAIR`]), written by the lower end's owner;
//! - `spheres/faces`: per sphere–face contact (sphere, its order, body,
//!   normal, ξ) ([`SAVED_SPHERE_FACE`]), written by the sphere's owner;
//! - `spheres/accounts`: per rank its gravity work and damped energy
//!   ([`SAVED_SPHERE_ACCOUNT`]);
//! - with heat (a thermal run): `spheres/temperature`, per sphere its
//!   temperature; `spheres/heat_accounts`, per rank the heat its owned
//!   spheres took from the faces so far and its largest explicit Fourier
//!   number ([`SAVED_SPHERE_HEAT`]); `spheres/fe_heat`, one row: the
//!   spheres' heat handed to the FE rows and not yet released, and that
//!   released so far (`thermal::sphere_source`; the heat itself is in
//!   `state/pending_heat` with the frictional heat, `checkpoint_heat`).
//!   Mechanical checkpoints lack them; a thermal run cannot restart from one.

use std::path::Path;

use hdf5::File;
use mpi::topology::SimpleCommunicator;

use super::checkpoint::CheckpointFile;
use super::checkpoint_particles::GlobalRows;
use super::IoError;

/// Columns of a sphere's state: set, x₀, x, v, ω.
pub const SAVED_SPHERE: usize = 13;
/// Columns of a pair's spring: a, b, ξ.
pub const SAVED_SPHERE_PAIR: usize = 5;
/// Columns of a face contact's spring: sphere, order, body, n, ξ.
pub const SAVED_SPHERE_FACE: usize = 9;
/// Columns of a rank's account: gravity work, damped energy (J).
pub const SAVED_SPHERE_ACCOUNT: usize = 2;
/// Columns of a rank's heat account: heat from the faces (J), Fourier number.
pub const SAVED_SPHERE_HEAT: usize = 2;

const STATE: &str = "spheres/state";
const PAIRS: &str = "spheres/pairs";
const FACES: &str = "spheres/faces";
const ACCOUNTS: &str = "spheres/accounts";
const TEMPERATURE: &str = "spheres/temperature";
const HEAT_ACCOUNTS: &str = "spheres/heat_accounts";
const FE_HEAT: &str = "spheres/fe_heat";

/// What a rank saves of its free spheres: rows by global number (the
/// state, and the sorted spring lists' row numbers) and its account.
#[derive(Debug, Clone, Default)]
pub struct SphereCheckpoint {
    pub state: GlobalRows,
    pub pairs: GlobalRows,
    pub faces: GlobalRows,
    pub account: [f64; SAVED_SPHERE_ACCOUNT],
    /// With heat: the owned spheres' temperatures (by number), the heat
    /// account, and the FE's side, pending and released (J, the same on
    /// every rank).
    pub heat: Option<(GlobalRows, [f64; SAVED_SPHERE_HEAT], [f64; 2])>,
}

/// What a rank reads back: the state of its block of sphere numbers, its
/// block of each spring list, and every rank's account.
#[derive(Debug, Clone, Default)]
pub struct SavedSpheres {
    /// Global numbers of the state rows.
    pub ids: Vec<u32>,
    pub state: Vec<[f64; SAVED_SPHERE]>,
    pub pairs: Vec<[f64; SAVED_SPHERE_PAIR]>,
    pub faces: Vec<[f64; SAVED_SPHERE_FACE]>,
    pub accounts: Vec<[f64; SAVED_SPHERE_ACCOUNT]>,
    /// With heat: the temperatures of the state rows and every rank's
    /// heat account.
    pub heat: Option<SavedSphereHeat>,
}

/// The free spheres' heat as read back ([`SavedSpheres::heat`]; the FE's
/// side is [`CheckpointFile::sphere_fe_heat`]).
#[derive(Debug, Clone, Default)]
pub struct SavedSphereHeat {
    pub temperature: Vec<f64>,
    pub accounts: Vec<[f64; SAVED_SPHERE_HEAT]>,
}

/// Collective. Write `s`'s datasets into the open checkpoint `file`.
pub(super) fn write(
    comm: &SimpleCommunicator,
    file: &File,
    path: &Path,
    xfer: &super::ffi::CollectiveXfer,
    s: &SphereCheckpoint,
) -> Result<(), IoError> {
    file.create_group("spheres")
        .map_err(|e| IoError::hdf5(path, "creating group spheres", e))?;
    use mpi::traits::Communicator;
    let account = GlobalRows {
        gid: vec![comm.rank() as u32],
        values: s.account.to_vec(),
        total: comm.size() as u64,
    };
    let sets = [
        (STATE, SAVED_SPHERE, &s.state),
        (PAIRS, SAVED_SPHERE_PAIR, &s.pairs),
        (FACES, SAVED_SPHERE_FACE, &s.faces),
        (ACCOUNTS, SAVED_SPHERE_ACCOUNT, &account),
    ];
    super::checkpoint_particles::write_sets(comm, file, path, xfer, &sets)?;
    let Some((t, heat, fe)) = &s.heat else {
        return Ok(());
    };
    let per_rank = |values: &[f64]| GlobalRows {
        values: values.to_vec(),
        ..account.clone()
    };
    // The FE's side is the same on every rank: rank 0 writes it.
    let root = comm.rank() == 0;
    let fe = GlobalRows {
        gid: if root { vec![0] } else { Vec::new() },
        values: if root { fe.to_vec() } else { Vec::new() },
        total: 1,
    };
    let sets = [
        (TEMPERATURE, 1, t),
        (HEAT_ACCOUNTS, SAVED_SPHERE_HEAT, &per_rank(heat)),
        (FE_HEAT, 2, &fe),
    ];
    super::checkpoint_particles::write_sets(comm, file, path, xfer, &sets)
}

impl CheckpointFile {
    /// Whether the checkpoint holds free spheres.
    pub fn has_spheres(&self) -> bool {
        [STATE, PAIRS, FACES, ACCOUNTS]
            .iter()
            .all(|n| self.file.link_exists(n))
    }

    /// Rows of dataset `name`.
    fn row_count(&self, name: &str) -> Result<u64, IoError> {
        Ok(self
            .file
            .dataset(name)
            .map_err(|e| IoError::hdf5(self.path(), format!("opening {name}"), e))?
            .shape()
            .first()
            .copied()
            .unwrap_or(0) as u64)
    }

    /// Rank `rank`'s block (of `size`) of every rows of `name`.
    fn block_rows<const C: usize>(
        &self,
        name: &str,
        rank: usize,
        size: usize,
        total: u64,
    ) -> Result<(Vec<u32>, Vec<[f64; C]>), IoError> {
        let (lo, hi) = crate::parallel::exchange::block(total, size, rank);
        let ids: Vec<u32> = (lo as u32..hi as u32).collect();
        let rows = self.rows_of::<f64, C>(name, &ids, total)?;
        if let Some((k, r)) = rows
            .iter()
            .enumerate()
            .find(|(_, r)| !r.iter().all(|v| v.is_finite()))
        {
            return Err(IoError::invalid(
                self.path(),
                format!("{name} row {}: not finite: {r:?}", ids[k]),
            ));
        }
        Ok((ids, rows))
    }

    /// Rank `rank`'s blocks (of `size`) of the spheres' state (of the
    /// scenario's `total` spheres in `sets` sets) and of the spring lists,
    /// and every rank's account; with `heat`, the temperatures of the
    /// block and the heat accounts. Errors name the dataset and row.
    pub fn sphere_rows(
        &self,
        rank: usize,
        size: usize,
        total: u64,
        sets: usize,
        heat: bool,
    ) -> Result<SavedSpheres, IoError> {
        let n = self.row_count(STATE)?;
        if n != total {
            return Err(IoError::invalid(
                self.path(),
                format!(
                    "{STATE} has {n} spheres, the scenario's [[spheres]] {total} \
                     (another count or set?)"
                ),
            ));
        }
        let (ids, state) = self.block_rows::<SAVED_SPHERE>(STATE, rank, size, total)?;
        let whole = |v: f64, below: u64| v >= 0.0 && v.fract() == 0.0 && (v as u64) < below;
        if let Some((k, _)) = state
            .iter()
            .enumerate()
            .find(|(_, r)| !whole(r[0], sets as u64))
        {
            return Err(IoError::invalid(
                self.path(),
                format!(
                    "{STATE} row {}: set {} is not one of the scenario's {sets} [[spheres]] sets",
                    ids[k], state[k][0]
                ),
            ));
        }
        let keyed = |name: &str, first: &[f64], second: &[f64], id: u32| {
            if whole(first[0], total) && whole(second[0], u64::from(u32::MAX)) {
                Ok(())
            } else {
                Err(IoError::invalid(
                    self.path(),
                    format!("{name} row {id}: not a sphere number and a whole key"),
                ))
            }
        };
        let np = self.row_count(PAIRS)?;
        let (pid, pairs) = self.block_rows::<SAVED_SPHERE_PAIR>(PAIRS, rank, size, np)?;
        for (r, &id) in pairs.iter().zip(&pid) {
            keyed(PAIRS, &r[0..1], &r[1..2], id)?;
            keyed(PAIRS, &r[1..2], &r[0..1], id)?;
        }
        let nf = self.row_count(FACES)?;
        let (fid, faces) = self.block_rows::<SAVED_SPHERE_FACE>(FACES, rank, size, nf)?;
        for (r, &id) in faces.iter().zip(&fid) {
            keyed(FACES, &r[0..1], &r[1..2], id)?;
            keyed(FACES, &r[0..1], &r[2..3], id)?;
        }
        let na = self.row_count(ACCOUNTS)?;
        let ids_a: Vec<u32> = (0..na as u32).collect();
        let accounts = self.rows_of::<f64, SAVED_SPHERE_ACCOUNT>(ACCOUNTS, &ids_a, na)?;
        let heat = if heat {
            Some(self.sphere_heat_rows(&ids, total, na)?)
        } else {
            None
        };
        Ok(SavedSpheres {
            ids,
            state,
            pairs,
            faces,
            accounts,
            heat,
        })
    }

    /// The temperatures of spheres `ids` (of `total`) and the `ranks` heat
    /// accounts: a thermal run's restart needs them (and the FE's side).
    fn sphere_heat_rows(
        &self,
        ids: &[u32],
        total: u64,
        ranks: u64,
    ) -> Result<SavedSphereHeat, IoError> {
        if let Some(name) = [TEMPERATURE, HEAT_ACCOUNTS, FE_HEAT]
            .into_iter()
            .find(|n| !self.file.link_exists(n))
        {
            return Err(IoError::invalid(
                self.path(),
                format!(
                    "{name} is missing: the checkpoint holds the free spheres' motion, not \
                     their heat (a run without [thermal], or from before it was saved), \
                     and this run has [[spheres]] with [thermal]"
                ),
            ));
        }
        for (name, rows) in [(TEMPERATURE, total), (HEAT_ACCOUNTS, ranks)] {
            let n = self.row_count(name)?;
            if n != rows {
                return Err(IoError::invalid(
                    self.path(),
                    format!("{name} has {n} rows, expected {rows}"),
                ));
            }
        }
        let temperature: Vec<f64> = self
            .rows_of::<f64, 1>(TEMPERATURE, ids, total)?
            .into_iter()
            .map(|[t]| t)
            .collect();
        if let Some(k) = temperature.iter().position(|t| !t.is_finite()) {
            return Err(IoError::invalid(
                self.path(),
                format!("{TEMPERATURE} row {}: not finite", ids[k]),
            ));
        }
        let all: Vec<u32> = (0..ranks as u32).collect();
        let accounts = self.rows_of::<f64, SAVED_SPHERE_HEAT>(HEAT_ACCOUNTS, &all, ranks)?;
        if !accounts.iter().flatten().all(|v| v.is_finite()) {
            return Err(IoError::invalid(
                self.path(),
                format!("{HEAT_ACCOUNTS}: not finite"),
            ));
        }
        Ok(SavedSphereHeat {
            temperature,
            accounts,
        })
    }

    /// The free spheres' heat on the FE's side: handed over and not yet
    /// released, and released so far (J); None in a checkpoint without it.
    pub fn sphere_fe_heat(&self) -> Result<Option<[f64; 2]>, IoError> {
        if !self.file.link_exists(FE_HEAT) {
            return Ok(None);
        }
        if self.row_count(FE_HEAT)? != 1 {
            return Err(IoError::invalid(
                self.path(),
                format!("{FE_HEAT}: not one row"),
            ));
        }
        let fe = self.rows_of::<f64, 2>(FE_HEAT, &[0], 1)?[0];
        if !fe.iter().all(|v| v.is_finite()) {
            return Err(IoError::invalid(
                self.path(),
                format!("{FE_HEAT}: not finite"),
            ));
        }
        Ok(Some(fe))
    }
}
