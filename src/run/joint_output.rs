//! The joint output grid (issue 19): `<stem>_joints.h5` and
//! `<stem>_joints.xdmf`, a second time series beside the bodies' whose
//! cells are the joints' faces (one triangle per joint, its a side's
//! corners), so ParaView shows the cracks over the bodies: per output the
//! corners' `displacement` (warp by it) and per joint its `damage`, `mode`
//! (0 intact, 1 opening, 2 sliding, 3 mixed, 4 initial crack),
//! `broke_at` (s, −1 while intact), `opening` (m, negative when
//! pressed) and `status`, the contact status of a crack's faces in the
//! codes of the boundary faces' status grid (0 free, 2 closed, 3 sliding;
//! −1 while intact), so the status follows the cracks. Rows are the global joint numbers (body by body, each body's
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
            hexes: None,
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
        let (broke_at, damage, mode, opening, status) = (
            cell(&rows.broke_at),
            cell(&rows.damage),
            cell(&rows.mode),
            cell(&rows.opening),
            cell(&rows.status),
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
                ("status", 1, &status[..]),
            ],
        )?;
        Ok(())
    }

    /// Collective. `<dir>/<stem>_cracks.csv`: per jointed body (a particle
    /// of a packing), its joints, broken joints, crack area, fracture
    /// energy, first break and centroid, written by rank 0 from an
    /// all-gather of the bodies' rows (O(jointed bodies)).
    /// Also draws `<stem>_particle_cracks.png` beside `path` when there
    /// are several jointed bodies (see [`crack_fraction_curves`]); returns
    /// the files written.
    pub fn write_body_table(
        comm: &SimpleCommunicator,
        model: &Model,
        mech: &Mechanics,
        path: &Path,
    ) -> Result<Vec<PathBuf>> {
        let mine: Vec<f64> = mech.domain.body_cracks().into_iter().flatten().collect();
        let all = crate::parallel::all_gather_f64(comm, &mine);
        let merged = crate::dynamics::merge_body_cracks(all.chunks_exact(9));
        let rows: Vec<&[f64]> = merged.iter().map(|r| &r[..]).collect();
        let png = (rows.len() > 1).then(|| {
            let name = path.file_name().map_or(String::new(), |n| {
                n.to_string_lossy()
                    .replace("_cracks.csv", "_particle_cracks.png")
            });
            path.with_file_name(name)
        });
        let written = if comm.rank() == 0 {
            let mut text = String::from(
                "body,name,joints,broken,crack_area,fracture_energy,first_break,x,y,z\n",
            );
            for r in &rows {
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
            std::fs::write(path, text)
                .map_err(|source| crate::error::Error::File {
                    path: path.display().to_string(),
                    source,
                })
                .and_then(|()| match &png {
                    Some(png) => particle_crack_plot(model, &rows, png),
                    None => Ok(()),
                })
        } else {
            Ok(())
        };
        crate::parallel::agree(comm, written)?;
        Ok(std::iter::once(path.to_path_buf()).chain(png).collect())
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        Ok(())
    }
}

/// Per radial band of the bodies' centroids about the vertical axis
/// `axis` (x, y), the fraction of its bodies with at least one broken joint
/// against time, from each body's first breaking time (`rows` as in
/// `<stem>_cracks.csv`: body, joints, broken, crack area, fracture energy,
/// first break (NaN: none), x, y, z). `bins` bands of equal width out to
/// the farthest body; each curve is a step function from 0 to `t_end`.
pub(super) fn crack_fraction_curves(
    rows: &[&[f64]],
    axis: [f64; 2],
    bins: usize,
    t_end: f64,
) -> Vec<(String, Vec<(f64, f64)>)> {
    let r = |row: &[f64]| (row[6] - axis[0]).hypot(row[7] - axis[1]);
    let r_max = rows.iter().map(|row| r(row)).fold(0.0, f64::max);
    let bins = bins.max(1);
    let width = if r_max > 0.0 {
        r_max / bins as f64
    } else {
        1.0
    };
    let band = |row: &[f64]| ((r(row) / width) as usize).min(bins - 1);
    (0..bins)
        .filter_map(|b| {
            let members: Vec<&&[f64]> = rows.iter().filter(|row| band(row) == b).collect();
            if members.is_empty() {
                return None;
            }
            let n = members.len() as f64;
            let mut times: Vec<f64> = members
                .iter()
                .map(|row| row[5])
                .filter(|t| !t.is_nan())
                .collect();
            times.sort_by(f64::total_cmp);
            let mut points = vec![(0.0, 0.0)];
            for (k, &t) in times.iter().enumerate() {
                points.push((t, k as f64 / n));
                points.push((t, (k + 1) as f64 / n));
            }
            points.push((
                t_end.max(points.last().map_or(0.0, |p| p.0)),
                times.len() as f64 / n,
            ));
            let label = format!(
                "r {:.3}-{:.3} m ({} bodies)",
                b as f64 * width,
                (b + 1) as f64 * width,
                members.len()
            );
            Some((label, points))
        })
        .collect()
}

/// `<stem>_particle_cracks.png`: [`crack_fraction_curves`] about the
/// particle statistics' axis (default the z axis), in its radial bins
/// (default 4).
fn particle_crack_plot(model: &Model, rows: &[&[f64]], path: &Path) -> Result<()> {
    use crate::io::plot::{write_png, LinePlot, Series};
    let (axis, bins) = model
        .output
        .particles
        .as_ref()
        .map_or(([0.0, 0.0], 4), |p| (p.axis, p.radial_bins.min(8)));
    let t_end = model.steps as f64 * model.dt;
    let curves = crack_fraction_curves(rows, axis, bins, t_end);
    let plot = LinePlot {
        title: "Cracked particles, by distance from the axis",
        x_label: "time [s]",
        y_label: "fraction of the bodies with a broken joint",
        series: curves
            .iter()
            .map(|(label, points)| Series {
                label,
                points,
                dashed: false,
            })
            .collect(),
    };
    write_png(&plot, path, (1000, 700))
        .map_err(|e| crate::error::Error::Io(crate::io::IoError::invalid(path, e.to_string())))
}

#[cfg(test)]
mod tests {
    use super::crack_fraction_curves;

    #[test]
    fn crack_fractions_step_up_at_first_breaks_per_radial_band() {
        let nan = f64::NAN;
        // body, joints, broken, area, energy, first break, x, y, z
        let rows: Vec<[f64; 9]> = vec![
            [0.0, 10.0, 1.0, 1e-4, 1e-3, 0.5, 0.1, 0.0, 0.0],
            [1.0, 10.0, 0.0, 0.0, 0.0, nan, 0.0, 0.2, 0.0],
            [2.0, 10.0, 2.0, 2e-4, 2e-3, 0.25, 0.0, 1.0, 0.0],
            [3.0, 10.0, 0.0, 0.0, 0.0, nan, -1.0, 0.0, 0.0],
        ];
        let refs: Vec<&[f64]> = rows.iter().map(|r| &r[..]).collect();
        let c = crack_fraction_curves(&refs, [0.0, 0.0], 2, 1.0);
        assert_eq!(c.len(), 2);
        // Inner band (r < 0.5): bodies 0 and 1, one cracked at 0.5 s.
        assert_eq!(c[0].1, vec![(0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (1.0, 0.5)]);
        assert!(c[0].0.contains("2 bodies"));
        // Outer band: bodies 2 and 3, one cracked at 0.25 s.
        assert_eq!(
            c[1].1,
            vec![(0.0, 0.0), (0.25, 0.0), (0.25, 0.5), (1.0, 0.5)]
        );
    }
}
