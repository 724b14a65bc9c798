//! The joint output grid (issue 19): `<stem>_joints.h5` and
//! `<stem>_joints.xdmf`, a second time series beside the bodies' whose
//! cells are the joints' faces (one triangle per joint, its a side's
//! corners), so ParaView shows the cracks over the bodies: per output the
//! corners' `displacement` (warp by it) and per joint its `damage`, `mode`
//! (0 intact, 1 opening, 2 sliding, 3 mixed, 4 initial crack),
//! `broke_at` (s, −1 while intact) and `opening` (m, negative when
//! pressed). Rows are the global joint numbers (body by body, each body's
//! joints in its mesh's order), so the files do not depend on the number
//! of ranks.

use std::path::{Path, PathBuf};

use mpi::topology::{Communicator, SimpleCommunicator};

use crate::error::Result;
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::model::Model;
use crate::parallel::exchange::to_blocks;

use super::Mechanics;

/// The open joint series.
pub(super) struct JointOutput {
    writer: TimeSeriesWriter,
    /// Joints over all ranks.
    total: u64,
    /// The paths of the series.
    pub xdmf: PathBuf,
}

/// Row ids of this rank's joints (global joint numbers) and of their
/// three corners (3 × the joint's number + 0, 1, 2).
fn ids(gid: &[u64]) -> (Vec<u32>, Vec<u32>) {
    let cells: Vec<u32> = gid.iter().map(|&g| g as u32).collect();
    let points = gid
        .iter()
        .flat_map(|&g| (0..3).map(move |k| (3 * g + k) as u32))
        .collect();
    (cells, points)
}

impl JointOutput {
    /// Collective. Create `<dir>/<stem>_joints.h5` with the joints' faces
    /// at their reference positions, or with `continue_after = Some(t)`
    /// reopen it to continue after the checkpoint at `t` (a restart in
    /// place); None when the model has no joints.
    pub fn open(
        comm: &SimpleCommunicator,
        model: &Model,
        dir: &Path,
        stem: &str,
        mech: &Mechanics,
        continue_after: Option<f64>,
    ) -> Result<Option<JointOutput>> {
        let (_, total) = model.joint_offsets();
        if total == 0 {
            return Ok(None);
        }
        // Global ids fit the u32 rows of the exchange (3 per joint's corners).
        if 3 * total > u64::from(u32::MAX) {
            return Err(crate::error::Error::Mechanics(format!(
                "{total} joints: the joint output holds at most {} joints",
                u32::MAX / 3
            )));
        }
        let rows = mech.domain.joint_rows();
        let (cell_ids, point_ids) = ids(&rows.gid);
        let flat: Vec<f64> = rows.corners.iter().flatten().copied().collect();
        let (p0, coords) = to_blocks(comm, &point_ids, &flat, 3, 3 * total);
        let coords: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let corners: Vec<f64> = point_ids.iter().map(|&p| f64::from(p)).collect();
        let (c0, topo) = to_blocks(comm, &cell_ids, &corners, 3, total);
        let topo: Vec<u32> = topo.iter().map(|&v| v as u32).collect();
        let mesh = MeshPart {
            global_nodes: 3 * total,
            node_offset: p0,
            coords: &coords,
            global_cells: total,
            cell_offset: c0,
            cells: &topo,
            nodes_per_cell: 3,
        };
        let name = format!("{stem}_joints");
        // Rows are global: a point's row is its id, on any number of ranks.
        let point_row: Vec<i32> = (p0..p0 + coords.len() as u64).map(|g| g as i32).collect();
        let writer = match continue_after {
            Some(t) => TimeSeriesWriter::reopen(comm, dir, &name, &mesh, &point_row, t)?,
            None => {
                let mut w = TimeSeriesWriter::create(comm, dir, &name, &mesh)?;
                w.write_static_node_field_i32("node_id", &point_row)?;
                w
            }
        };
        let xdmf = writer.xdmf_path().to_path_buf();
        Ok(Some(JointOutput {
            writer,
            total,
            xdmf,
        }))
    }

    /// Collective. Write the joints' state at `time`.
    pub fn write(&mut self, comm: &SimpleCommunicator, time: f64, mech: &Mechanics) -> Result<()> {
        let rows = mech.domain.joint_rows();
        let (cell_ids, point_ids) = ids(&rows.gid);
        let total = self.total;
        let (_, u) = to_blocks(comm, &point_ids, &rows.displacement, 3, 3 * total);
        let cell = |v: &[f64]| to_blocks(comm, &cell_ids, v, 1, total).1;
        let (broke_at, damage, mode, opening) = (
            cell(&rows.broke_at),
            cell(&rows.damage),
            cell(&rows.mode),
            cell(&rows.opening),
        );
        // Cell fields in name order.
        self.writer.write_step(
            time,
            &[("displacement", 3, &u[..])],
            &[
                ("broke_at", 1, &broke_at[..]),
                ("damage", 1, &damage[..]),
                ("mode", 1, &mode[..]),
                ("opening", 1, &opening[..]),
            ],
        )?;
        Ok(())
    }

    /// Collective. `<dir>/<stem>_cracks.csv`: per jointed body (a particle
    /// of a packing), its joints, broken joints, crack area, fracture
    /// energy, first break and centroid, written by rank 0 from an
    /// all-gather of the bodies' rows (O(jointed bodies)).
    pub fn write_body_table(
        comm: &SimpleCommunicator,
        model: &Model,
        mech: &Mechanics,
        path: &Path,
    ) -> Result<()> {
        let mine: Vec<f64> = mech.domain.body_cracks().into_iter().flatten().collect();
        let all = crate::parallel::all_gather_f64(comm, &mine);
        let written = if comm.rank() == 0 {
            let mut rows: Vec<&[f64]> = all.chunks_exact(9).collect();
            rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
            let mut text = String::from(
                "body,name,joints,broken,crack_area,fracture_energy,first_break,x,y,z\n",
            );
            for r in rows {
                let name = &model.bodies[r[0] as usize].name;
                let first = if r[5].is_nan() {
                    String::new()
                } else {
                    format!("{:e}", r[5])
                };
                text.push_str(&format!(
                    "{},{name},{},{},{:e},{:e},{first},{:e},{:e},{:e}\n",
                    r[0], r[1], r[2], r[3], r[4], r[6], r[7], r[8]
                ));
            }
            std::fs::write(path, text).map_err(|source| crate::error::Error::File {
                path: path.display().to_string(),
                source,
            })
        } else {
            Ok(())
        };
        crate::parallel::agree(comm, written)
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        Ok(())
    }
}
