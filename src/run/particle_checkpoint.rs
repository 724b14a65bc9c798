//! The bonded particles in checkpoints (issue 21): what a rank saves of
//! its particles (`io::checkpoint_particles`: the spheres' motion, the
//! bonds' and links' incremental states, the spheres' thermal rows) and
//! how a restart puts them back, by global number, so a checkpoint of P
//! ranks restarts on Q. The spheres' temperatures reach the bonds'
//! expansion afresh from the restored thermal rows
//! (`particle_output::couple_particle_temperatures`).

use mpi::topology::SimpleCommunicator;

use crate::error::Result;
use crate::io::checkpoint_particles::{GlobalRows, ParticleCheckpoint, SAVED_PARTICLE_HEAT};
use crate::model::Model;
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
    Ok(())
}
