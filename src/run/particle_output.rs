//! The particle output (issue 21): `<stem>_particles.h5` and
//! `<stem>_particles.xdmf`, a point-set series beside the bodies' grid
//! (one XDMF Polyvertex cell per sphere, at its reference centre), so
//! ParaView shows the spheres over the finite elements: per output each
//! sphere's `displacement` (warp by it) and `velocity` in a run with
//! mechanics, its `temperature` in a run with heat. Rows are the
//! global particle numbers (body by body, each body's spheres in its
//! lattice's order), so the files do not depend on the number of ranks.
//! The history's `particles_min_T`, `particles_mean_T` and
//! `particles_max_T` are over all spheres (equal cells: the mean is the
//! volume mean).

use std::path::{Path, PathBuf};

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::CommunicatorCollectives;

use crate::error::{Error, Result};
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::model::Model;
use crate::parallel::exchange::to_blocks;
use crate::parallel::Part;
use crate::thermal::particles::ParticleHeat;
use crate::thermal::ThermalSystem;

use super::Mechanics;

/// The open particle series.
pub(super) struct ParticleOutput {
    writer: TimeSeriesWriter,
    /// Particles over all ranks.
    total: u64,
    /// The path of the series.
    pub xdmf: PathBuf,
}

fn ids(gid: &[u64]) -> Vec<u32> {
    gid.iter().map(|&g| g as u32).collect()
}

impl ParticleOutput {
    /// Collective. Create `<dir>/<stem>_particles.h5` with the spheres at
    /// their reference centres, or with `continue_after = Some(t)` reopen
    /// it to continue after the checkpoint at `t` (a restart in place);
    /// None when the model has no particles. The spheres come from the
    /// mechanics when there is one, else from the thermal rows of `part`.
    pub fn open(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        dir: &Path,
        stem: &str,
        mech: Option<&Mechanics>,
        continue_after: Option<f64>,
    ) -> Result<Option<ParticleOutput>> {
        let (_, total) = model.particle_offsets();
        if total == 0 {
            return Ok(None);
        }
        if total > u64::from(u32::MAX) {
            return Err(Error::Mechanics(format!(
                "{total} particles: the particle output holds at most {} particles",
                u32::MAX
            )));
        }
        let (gid, reference) = match mech {
            Some(m) => {
                let rows = m.domain.particle_rows();
                (rows.gid, rows.reference)
            }
            None => {
                let (gid, reference, _) = ParticleHeat::new(model, part).rows(part, None);
                (gid, reference)
            }
        };
        let point_ids = ids(&gid);
        let (p0, coords) = to_blocks(comm, &point_ids, &reference, 3, total);
        let coords: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        // One point cell per sphere, the cells in the points' blocks.
        let cells: Vec<u32> = (p0..p0 + coords.len() as u64).map(|g| g as u32).collect();
        let mesh = MeshPart {
            global_nodes: total,
            node_offset: p0,
            coords: &coords,
            global_cells: total,
            cell_offset: p0,
            cells: &cells,
            nodes_per_cell: 1,
            hexes: None,
        };
        let name = format!("{stem}_particles");
        let point_row: Vec<i32> = cells.iter().map(|&g| g as i32).collect();
        let writer = match continue_after {
            Some(t) => TimeSeriesWriter::reopen(comm, dir, &name, &mesh, &point_row, t)?,
            None => {
                let mut w = TimeSeriesWriter::create(comm, dir, &name, &mesh)?;
                w.write_static_node_field_i32("particle_id", &point_row)?;
                // The rows' check of a restart in place reads `node_id`.
                w.write_static_node_field_i32("node_id", &point_row)?;
                w
            }
        };
        let xdmf = writer.xdmf_path().to_path_buf();
        Ok(Some(ParticleOutput {
            writer,
            total,
            xdmf,
        }))
    }

    /// Collective. Write the particles' state at `time`: their motion
    /// from `mech`, their temperatures from `sys`'s rows of `part`.
    pub fn write(
        &mut self,
        comm: &SimpleCommunicator,
        time: f64,
        model: &Model,
        part: &Part,
        sys: Option<&ThermalSystem>,
        mech: Option<&Mechanics>,
    ) -> Result<()> {
        let mut fields: Vec<(&str, usize, Vec<f64>)> = Vec::new();
        if let Some(m) = mech {
            let rows = m.domain.particle_rows();
            let point_ids = ids(&rows.gid);
            fields.push((
                "displacement",
                3,
                to_blocks(comm, &point_ids, &rows.displacement, 3, self.total).1,
            ));
            fields.push((
                "velocity",
                3,
                to_blocks(comm, &point_ids, &rows.velocity, 3, self.total).1,
            ));
        }
        if let Some(s) = sys {
            let owned = s.t.to_local_vec()?;
            let (gid, _, t) = ParticleHeat::new(model, part).rows(part, Some(&owned));
            let t = to_blocks(comm, &ids(&gid), &t, 1, self.total).1;
            fields.push(("temperature", 1, t));
        }
        let f: Vec<(&str, usize, &[f64])> = fields
            .iter()
            .map(|(n, c, v)| (*n, *c, v.as_slice()))
            .collect();
        self.writer.write_step(time, &f, &[])?;
        Ok(())
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        Ok(())
    }
}

/// Collective. The lowest, mean and highest temperature of all spheres.
pub(super) fn temperature_range(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    sys: &ThermalSystem,
) -> Result<[f64; 3]> {
    let owned = sys.t.to_local_vec()?;
    let (_, _, t) = ParticleHeat::new(model, part).rows(part, Some(&owned));
    let mine_lo = t.iter().copied().fold(f64::INFINITY, f64::min);
    let mine_hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mine_sum = [t.iter().sum::<f64>(), t.len() as f64];
    let (mut lo, mut hi, mut sum) = (0.0f64, 0.0f64, [0.0f64; 2]);
    comm.all_reduce_into(&mine_lo, &mut lo, SystemOperation::min());
    comm.all_reduce_into(&mine_hi, &mut hi, SystemOperation::max());
    comm.all_reduce_into(&mine_sum[..], &mut sum[..], SystemOperation::sum());
    Ok([lo, sum[0] / sum[1].max(1.0), hi])
}

/// Give the mechanics' particles their temperatures (issue 21: the bonds
/// expand with them), after the nodes' ([`crate::dynamics::ExplicitDomain::set_temperatures`]):
/// the thermal system's sphere rows, or without one a prescribed heating's
/// value of the body at `time` (the nodes' rule, from the body's initial
/// temperature).
pub(super) fn couple_particle_temperatures(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    sys: Option<&ThermalSystem>,
    time: f64,
    m: &mut crate::dynamics::ExplicitDomain,
) -> Result<()> {
    if let Some(s) = sys {
        let owned = s.t.to_local_vec()?;
        let (gid, _, t) = ParticleHeat::new(model, part).rows(part, Some(&owned));
        m.set_particle_temperatures(comm, &gid, &t)?;
    } else if model.has_heating() {
        m.set_particle_body_temperatures(|b| {
            let body = &model.bodies[b as usize];
            model.prescribed_temperature(body.node_range.0, body.initial_temperature, time)
        });
    }
    Ok(())
}
