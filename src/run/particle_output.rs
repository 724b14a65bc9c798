//! The particle output (issue 21): `<stem>_particles.h5` and
//! `<stem>_particles.xdmf`, a point-set series beside the bodies' grid
//! (one XDMF Polyvertex cell per sphere, at its reference centre), so
//! ParaView shows the spheres over the finite elements: per output each
//! sphere's `displacement` (warp by it) and `velocity`. Rows are the
//! global particle numbers (body by body, each body's spheres in its
//! lattice's order), so the files do not depend on the number of ranks.

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::error::{Error, Result};
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::model::Model;
use crate::parallel::exchange::to_blocks;

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
    /// their reference centres; None when the model has no particles.
    pub fn open(
        comm: &SimpleCommunicator,
        model: &Model,
        dir: &Path,
        stem: &str,
        mech: &Mechanics,
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
        let rows = mech.domain.particle_rows();
        let point_ids = ids(&rows.gid);
        let (p0, coords) = to_blocks(comm, &point_ids, &rows.reference, 3, total);
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
        };
        let name = format!("{stem}_particles");
        let point_row: Vec<i32> = cells.iter().map(|&g| g as i32).collect();
        let mut writer = TimeSeriesWriter::create(comm, dir, &name, &mesh)?;
        writer.write_static_node_field_i32("particle_id", &point_row)?;
        let xdmf = writer.xdmf_path().to_path_buf();
        Ok(Some(ParticleOutput {
            writer,
            total,
            xdmf,
        }))
    }

    /// Collective. Write the particles' state at `time`.
    pub fn write(&mut self, comm: &SimpleCommunicator, time: f64, mech: &Mechanics) -> Result<()> {
        let rows = mech.domain.particle_rows();
        let point_ids = ids(&rows.gid);
        let (_, u) = to_blocks(comm, &point_ids, &rows.displacement, 3, self.total);
        let (_, v) = to_blocks(comm, &point_ids, &rows.velocity, 3, self.total);
        self.writer.write_step(
            time,
            &[("displacement", 3, &u[..]), ("velocity", 3, &v[..])],
            &[],
        )?;
        Ok(())
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        Ok(())
    }
}
