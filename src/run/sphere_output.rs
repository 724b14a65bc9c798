//! The free spheres' output (issue 21, beyond the papers):
//! `<stem>_spheres.h5` and `<stem>_spheres.xdmf`, a point set beside the
//! bodies' grid as the bonded particles' (one XDMF Polyvertex cell per
//! sphere at its placed centre, [`super::particle_output`]), so ParaView
//! shows both: per output each sphere's `displacement` (warp by it),
//! `velocity` and `radius`. Rows are the global sphere numbers (set by
//! set, each in its placement order), so the files do not depend on the
//! number of ranks.

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::dynamics::SphereRows;
use crate::error::{Error, Result};
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::parallel::exchange::to_blocks;

/// The open sphere series.
pub(super) struct SphereOutput {
    writer: TimeSeriesWriter,
    total: u64,
    /// The path of the series.
    pub xdmf: PathBuf,
}

fn ids(rows: &SphereRows) -> Vec<u32> {
    rows.gid.iter().map(|&g| g as u32).collect()
}

impl SphereOutput {
    /// Collective. Create `<dir>/<stem>_spheres.h5` with the spheres of
    /// `rows` (this rank's) at their placed centres.
    pub fn open(
        comm: &SimpleCommunicator,
        rows: &SphereRows,
        dir: &Path,
        stem: &str,
    ) -> Result<SphereOutput> {
        let total = rows.total;
        if total > u64::from(u32::MAX) {
            return Err(Error::Mechanics(format!(
                "{total} free spheres: the sphere output holds at most {}",
                u32::MAX
            )));
        }
        let (p0, coords) = to_blocks(comm, &ids(rows), &rows.reference, 3, total);
        let coords: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
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
        let mut writer = TimeSeriesWriter::create(comm, dir, &format!("{stem}_spheres"), &mesh)?;
        let row: Vec<i32> = cells.iter().map(|&g| g as i32).collect();
        writer.write_static_node_field_i32("sphere_id", &row)?;
        let xdmf = writer.xdmf_path().to_path_buf();
        Ok(SphereOutput {
            writer,
            total,
            xdmf,
        })
    }

    /// Collective. Write the spheres of `rows` (this rank's) at `time`.
    pub fn write(&mut self, comm: &SimpleCommunicator, time: f64, rows: &SphereRows) -> Result<()> {
        let id = ids(rows);
        let block = |v: &[f64], w: usize| to_blocks(comm, &id, v, w, self.total).1;
        let fields = [
            ("displacement", 3, block(&rows.displacement, 3)),
            ("velocity", 3, block(&rows.velocity, 3)),
            ("radius", 1, block(&rows.radius, 1)),
        ];
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
