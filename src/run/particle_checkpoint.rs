//! The bonded particles in checkpoints (issue 21): what a rank saves of
//! its particles (`io::checkpoint_particles`: the spheres' motion, the
//! bonds' and links' incremental states, the spheres' thermal rows) and
//! how a restart puts them back, by global number, so a checkpoint of P
//! ranks restarts on Q; a repartition holds the same rows in memory
//! ([`ParticleSnapshot`]). The spheres' temperatures reach the bonds'
//! expansion afresh from the restored thermal rows
//! (`particle_output::couple_particle_temperatures`).

use mpi::topology::SimpleCommunicator;

use crate::error::Result;
use crate::io::checkpoint_particles::{
    GlobalRows, ParticleCheckpoint, SAVED_BOND, SAVED_PARTICLE, SAVED_PARTICLE_HEAT,
};
use crate::model::Model;
use crate::parallel::exchange::{from_blocks, to_blocks};
use crate::parallel::{agree, Part};
use crate::thermal::particles::ParticleHeat;
use crate::thermal::ThermalSystem;

use super::checkpoint::{missing, unreadable, Restart};
use super::Mechanics;

/// This rank's particles for a checkpoint (None without particles).
pub(super) fn capture(
    model: &Model,
    part: &Part,
    sys: Option<&ThermalSystem>,
    mech: Option<&Mechanics>,
) -> Result<Option<ParticleCheckpoint>> {
    if !model.has_particles() {
        return Ok(None);
    }
    let motion = mech.map(|m| m.domain.saved_particles());
    // Rows are numbered by u32 in the exchange to the file's blocks.
    if let Some(r) = motion
        .iter()
        .flatten()
        .find(|r| r.total > u64::from(u32::MAX))
    {
        return Err(crate::error::Error::Mechanics(format!(
            "{} particles, bonds or links: a checkpoint holds at most {} of each",
            r.total,
            u32::MAX
        )));
    }
    let heat = match sys {
        Some(s) => {
            let owned = s.t.to_local_vec()?;
            let a = s.account_state()?;
            let ph = ParticleHeat::new(model, part);
            let (gid, _, t) = ph.rows(part, Some(&owned));
            let (_, _, t0) = ph.rows(part, Some(&a.t0));
            let (_, _, ts) = ph.rows(part, Some(&a.t_sum));
            let rs = if a.rad_sum.is_empty() {
                vec![0.0; t.len()]
            } else {
                ph.rows(part, Some(&a.rad_sum)).2
            };
            let mut values = Vec::with_capacity(SAVED_PARTICLE_HEAT * t.len());
            for k in 0..t.len() {
                values.extend_from_slice(&[t[k], t0[k], ts[k], rs[k]]);
            }
            Some(GlobalRows {
                gid: gid.iter().map(|&g| g as u32).collect(),
                values,
                total: model.particle_offsets().1,
            })
        }
        None => None,
    };
    Ok(Some(ParticleCheckpoint { motion, heat }))
}

/// Collective. Put the saved motion of the spheres and the states of the
/// bonds and links into the domain (a model with particles).
pub(super) fn restore_motion(
    comm: &SimpleCommunicator,
    model: &Model,
    r: &Restart,
    mech: &mut Mechanics,
) -> Result<()> {
    if !model.has_particles() {
        return Ok(());
    }
    if !r.file.has_particle_motion() {
        return Err(missing(
            r.file.path(),
            "the checkpoint has no particle state, the scenario has particles with mechanics",
        ));
    }
    let (ids, totals) = mech.domain.particle_ids();
    let rows = r.file.particle_motion([&ids[0], &ids[1], &ids[2]], totals);
    let rows = agree(comm, rows.map_err(|e| unreadable(r.file.path(), e)))?;
    mech.domain.restore_particles(&rows);
    Ok(())
}

/// The owned thermal rows of the spheres of `part`, from the checkpoint:
/// written into `t` and, when present, the account's t₀, Σ T and radiated
/// heat (owned-row order, as `ThermalSystem` takes them). Collective.
pub(super) fn restore_heat(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    r: &Restart,
    t: &mut [f64],
    account: Option<(&mut [f64], &mut [f64], &mut [f64])>,
) -> Result<()> {
    if !model.has_particles() {
        return Ok(());
    }
    if !r.file.has_particle_heat() {
        return Err(missing(
            r.file.path(),
            "the checkpoint has no particle temperatures, the scenario has particles with heat",
        ));
    }
    let ph = ParticleHeat::new(model, part);
    let (gid, _, _) = ph.rows(part, None);
    let ids: Vec<u32> = gid.iter().map(|&g| g as u32).collect();
    let rows = r.file.particle_heat(&ids, model.particle_offsets().1);
    let rows = agree(comm, rows.map_err(|e| unreadable(r.file.path(), e)))?;
    put_heat(&ph, part, &rows, t, account);
    Ok(())
}

/// Writes the spheres' saved heat rows `rows` (in the order of `ph`'s
/// rows) into the owned rows `t` and the account.
fn put_heat(
    ph: &ParticleHeat,
    part: &Part,
    rows: &[f64],
    t: &mut [f64],
    account: Option<(&mut [f64], &mut [f64], &mut [f64])>,
) {
    let lo = part.owned_range().0;
    let mut account = account;
    let mut k = 0;
    for b in &ph.bodies {
        for j in 0..b.centres.len() {
            let row = b.first_row + j - lo;
            let c = &rows[SAVED_PARTICLE_HEAT * k..SAVED_PARTICLE_HEAT * (k + 1)];
            t[row] = c[0];
            if let Some((t0, ts, rs)) = account.as_mut() {
                t0[row] = c[1];
                ts[row] = c[2];
                if !rs.is_empty() {
                    rs[row] = c[3];
                }
            }
            k += 1;
        }
    }
}

/// One set of rows by global number in blocks over the ranks.
struct Blocks {
    width: usize,
    lo: u64,
    rows: Vec<f64>,
    total: u64,
}

impl Blocks {
    /// Collective. `r`'s rows (`width` values each) moved into blocks.
    fn take(comm: &SimpleCommunicator, r: &GlobalRows, width: usize) -> Blocks {
        let (lo, rows) = to_blocks(comm, &r.gid, &r.values, width, r.total);
        Blocks {
            width,
            lo,
            rows,
            total: r.total,
        }
    }

    /// Collective. The rows of the global numbers `ids`.
    fn rows(&self, comm: &SimpleCommunicator, ids: &[u32]) -> Vec<f64> {
        from_blocks(comm, (self.lo, &self.rows), self.width, self.total, ids)
    }
}

/// The particles of a run held in memory by global number while the
/// ranks repartition (the rows a checkpoint holds): every rank's in
/// blocks, read back by the new owners.
pub(super) struct ParticleSnapshot {
    motion: Option<[Blocks; 3]>,
    heat: Option<Blocks>,
}

impl ParticleSnapshot {
    /// Collective. This rank's particles moved into blocks (None without
    /// particles).
    pub fn take(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        sys: Option<&ThermalSystem>,
        mech: Option<&Mechanics>,
    ) -> Result<Option<ParticleSnapshot>> {
        let Some(c) = capture(model, part, sys, mech)? else {
            return Ok(None);
        };
        let motion = c.motion.map(|m| {
            [
                Blocks::take(comm, &m[0], SAVED_PARTICLE),
                Blocks::take(comm, &m[1], SAVED_BOND),
                Blocks::take(comm, &m[2], SAVED_BOND),
            ]
        });
        let heat = c.heat.map(|h| Blocks::take(comm, &h, SAVED_PARTICLE_HEAT));
        Ok(Some(ParticleSnapshot { motion, heat }))
    }

    /// Collective. The spheres' motion and the bonds' and links' states
    /// into the new domain.
    pub fn restore_motion(&self, comm: &SimpleCommunicator, mech: &mut Mechanics) {
        if let Some(m) = &self.motion {
            let (ids, _) = mech.domain.particle_ids();
            let rows = [0, 1, 2].map(|k| m[k].rows(comm, &ids[k]));
            mech.domain.restore_particles(&rows);
        }
    }

    /// Collective. The spheres' owned thermal rows of the new `part`
    /// into `t` and the account, as [`restore_heat`].
    pub fn restore_heat(
        &self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        t: &mut [f64],
        account: Option<(&mut [f64], &mut [f64], &mut [f64])>,
    ) {
        if let Some(h) = &self.heat {
            let ph = ParticleHeat::new(model, part);
            let (gid, _, _) = ph.rows(part, None);
            let ids: Vec<u32> = gid.iter().map(|&g| g as u32).collect();
            let rows = h.rows(comm, &ids);
            put_heat(&ph, part, &rows, t, account);
        }
    }
}
