//! The free spheres' output (issue 21, beyond the papers):
//! `<stem>_spheres.h5` and `<stem>_spheres.xdmf`, a point set beside the
//! bodies' grid as the bonded particles' (one XDMF Polyvertex cell per
//! sphere at its placed centre, [`super::particle_output`]), so ParaView
//! shows both: per output each sphere's `displacement` (warp by it),
//! `velocity`, `radius` and, in a thermal run, `temperature`. Rows are the global sphere numbers (set by
//! set, each in its placement order), so the files do not depend on the
//! number of ranks.

use std::path::{Path, PathBuf};

use mpi::topology::SimpleCommunicator;

use crate::dynamics::{SphereHeat, SphereRows};
use crate::error::{Error, Result};
use crate::io::{MeshPart, TimeSeriesWriter};
use crate::parallel::exchange::to_blocks;
use crate::thermal::ThermalSystem;

use super::Mechanics;

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
            hexes: None,
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
        let mut fields = vec![
            ("displacement", 3, block(&rows.displacement, 3)),
            ("velocity", 3, block(&rows.velocity, 3)),
            ("radius", 1, block(&rows.radius, 1)),
        ];
        // A thermal run's (issue 21); every rank agrees: the model decides.
        if rows.heat {
            fields.push(("temperature", 1, block(&rows.temperature, 1)));
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

/// The free spheres' heat account (issue 21) at the end or a history row:
/// the spheres' ([`SphereHeat`]) and the FE's side of it, the heat the
/// spheres gave the FE rows (released) and handed over for the next step
/// (pending). Closes as ΔE_FE + ΔE_spheres + pending = boundary heat in.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SphereHeatAccount {
    pub spheres: SphereHeat,
    pub released: f64,
    pub pending: f64,
}

impl SphereHeatAccount {
    /// Collective. The account now; None without sphere heat.
    pub(super) fn now(
        comm: &SimpleCommunicator,
        sys: Option<&ThermalSystem>,
        mech: Option<&Mechanics>,
    ) -> Option<SphereHeatAccount> {
        let spheres = mech?.domain.sphere_heat(comm)?;
        let src = sys?.sphere_source();
        Some(SphereHeatAccount {
            spheres,
            released: src.released,
            pending: src.pending,
        })
    }

    /// The spheres' stored change since the start (J).
    pub fn stored_change(&self) -> f64 {
        self.spheres.stored - self.spheres.initial
    }
}

/// The history's sphere heat columns (a thermal run with spheres).
pub(super) fn history_header(model: &crate::model::Model, heat: bool) -> Vec<String> {
    if !heat || model.spheres.is_empty() {
        return Vec::new();
    }
    [
        "spheres_stored_heat",
        "spheres_heat_from_faces",
        "fe_heat_from_spheres",
        "spheres_heat_pending",
        "spheres_min_T",
        "spheres_max_T",
        "spheres_fourier",
    ]
    .map(String::from)
    .to_vec()
}

/// Collective. The history's sphere heat values ([`history_header`]).
pub(super) fn history_values(
    comm: &SimpleCommunicator,
    sys: Option<&ThermalSystem>,
    mech: Option<&Mechanics>,
) -> Vec<f64> {
    SphereHeatAccount::now(comm, sys, mech).map_or_else(Vec::new, |a| {
        let s = a.spheres;
        vec![
            s.stored,
            s.from_faces,
            a.released,
            a.pending,
            s.min,
            s.max,
            s.fourier,
        ]
    })
}
