//! Output: the HDF5/XDMF series, the history CSV (per-body temperature
//! columns), the particle statistics and the per-body contact areas.
//!
//! Collective like the rest of the run; rank 0 alone writes the CSV and
//! PNG files, and every rank agrees on the outcome.

use std::path::{Path, PathBuf};

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::io::checkpoint::CheckpointHead;
use crate::io::particles::ParticleReport;
use crate::io::{HistoryWriter, MeshPart, TimeSeriesWriter};
use crate::model::Model;
use crate::parallel::exchange::{block, to_blocks};
use crate::parallel::{agree, Part};
use crate::scenario::ParticleOutputSpec;
use crate::thermal::ThermalSystem;

use super::{hex_output::HexOutput, Mechanics};

/// The files a run writes into, open.
pub(super) struct Output {
    /// Output directory.
    pub dir: PathBuf,
    /// File stem.
    pub stem: String,
    /// Whether this run continues the series already in `dir` (a restart in place).
    pub continues: bool,
    /// History CSV.
    pub history_path: PathBuf,
    writer: TimeSeriesWriter,
    history: HistoryWriter,
    groups: BodyGroups,
    stats: BodyStats,
    /// Particle statistics (rank 0 keeps them; every rank takes part in the reductions).
    report: Option<ParticleReport>,
    radial_steps: Vec<u64>,
    /// Whether element owners may change during the run (mechanics with
    /// repartitions enabled, on any number of ranks): then each output has
    /// an `owner_rank` cell field beside the static `rank`.
    owners_move: bool,
    /// Jointed bodies: (time, crack area, fracture energy) at each output,
    /// for the crack plot.
    cracks: Vec<(f64, f64, f64)>,
    /// Issue 20: per history row, the time and the heat in by each
    /// mechanism so far (prescribed temperatures, fluxes, convection,
    /// radiation, friction), the stored heat's change, the heat moved
    /// through contacts and across gaps so far, and those two flows now.
    heat: Vec<[f64; 11]>,
    /// The joint output grid, when the model has joints.
    pub joints: Option<super::joint_output::JointOutput>,
    /// The particle point set, when the model has particles (issue 21).
    pub particles: Option<super::particle_output::ParticleOutput>,
    /// The boundary faces' contact status, in runs with thermal contact.
    status: Option<super::status_output::StatusOutput>,
}

impl Output {
    /// Collective. Create the output directory and open the series and the
    /// history: continued after the checkpoint when a restart writes into
    /// the directory of the series it continues, else new.
    pub fn open(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        output_dir: Option<&Path>,
        heat: bool,
        mechanics: bool,
        restart: Option<&CheckpointHead>,
    ) -> Result<Output> {
        let rank = comm.rank();
        let stem = model.output.stem.clone();
        let dir = output_dir.map_or_else(|| model.output.directory.clone(), Path::to_path_buf);
        let made = if rank == 0 {
            create_output_dir(&dir)
        } else {
            Ok(())
        };
        agree(comm, made)?;
        // A restart into the directory of the series it continues keeps that
        // series up to the checkpoint and appends; anywhere else it starts one.
        let (h5_path, _) = crate::io::output_paths(&dir, &stem);
        let continues = restart.is_some() && {
            let mut exists = i32::from(rank == 0 && h5_path.is_file());
            comm.process_at_rank(0).broadcast_into(&mut exists);
            exists == 1
        };
        let keep_until = restart.map_or(0.0, |c| c.time);
        let writer = open_writer(
            comm,
            model,
            part,
            &dir,
            &stem,
            continues.then_some(keep_until),
        )?;
        let history_path = dir.join(format!("{stem}_history.csv"));
        let mut header: Vec<String> = vec!["step".into(), "time".into()];
        if heat {
            for h in [
                "stored_heat",
                "boundary_heat_in",
                "ksp_iterations",
                "contacts",
                "contact_area",
                "convection_heat_in",
                "radiation_heat_in",
                "newton_iterations",
                "gap_area",
                "contact_pressure",
                "contact_conductance",
                "friction_heat_in",
                "contact_heat_flow",
                "gap_heat_flow",
                "gap_radiation_flow",
            ] {
                header.push(h.into());
            }
        }
        // Seed 001 sec 7.1.1: the boundary faces by contact status.
        let status = if heat && model.contact.is_some() {
            for h in [
                "faces_free",
                "faces_near_field",
                "faces_closed",
                "faces_sliding",
            ] {
                header.push(h.into());
            }
            let after = continues.then_some(keep_until);
            Some(super::status_output::StatusOutput::open(
                comm, model, part, &dir, &stem, after,
            )?)
        } else {
            None
        };
        if mechanics {
            for h in [
                "mech_time",
                "kinetic_energy",
                "strain_energy",
                "contact_energy",
                "dissipated_energy",
                "momentum_x",
                "momentum_y",
                "momentum_z",
                "mech_contacts",
                "mech_candidates",
                "external_work",
            ] {
                header.push(h.into());
            }
            if model
                .contact
                .as_ref()
                .is_some_and(|c| c.friction_heating.is_some())
            {
                header.push("friction_work".into());
            }
            if model.has_joints() {
                for h in [
                    "joint_energy",
                    "fracture_energy",
                    "broken_joints",
                    "crack_area",
                    "broken_opening",
                    "broken_sliding",
                    "broken_mixed",
                    "closed_cracks",
                    "crack_friction",
                ] {
                    header.push(h.into());
                }
            }
        }
        // Per-body columns, or per scenario entry when there are many bodies.
        let moments = body_moments(comm, model, part);
        let groups = BodyGroups::new(model, &moments);
        if heat {
            for g in &groups.names {
                for s in ["min", "mean", "max"] {
                    header.push(format!("{g}_{s}_T"));
                }
            }
        }
        if heat && model.has_particles() {
            for s in ["min", "mean", "max"] {
                header.push(format!("particles_{s}_T"));
            }
        }
        if mechanics {
            for g in &groups.names {
                for d in ["x", "y", "z"] {
                    header.push(format!("{g}_force_{d}"));
                }
            }
        }
        header.extend(super::sphere_output::history_header(model, heat));
        let header_ref: Vec<&str> = header.iter().map(String::as_str).collect();
        let history = if continues {
            HistoryWriter::reopen(&history_path, &header_ref, 1, keep_until)
        } else {
            HistoryWriter::create(&history_path, &header_ref)
        };
        let history = agree(comm, history.map_err(Error::from))?;
        let stats = BodyStats::new(comm, model, part)?;
        let report = model.output.particles.as_ref().and_then(|p| {
            heat.then_some(())?;
            particle_report(model, &moments, p)
        });
        let radial_steps: Vec<u64> = match &model.output.particles {
            Some(p) if !p.radial_times.is_empty() => p
                .radial_times
                .iter()
                .map(|&t| (t / model.dt).round() as u64)
                .collect(),
            _ => (1..=4).map(|k| k * model.steps / 4).collect(),
        };
        Ok(Output {
            dir,
            stem,
            continues,
            history_path,
            writer,
            history,
            groups,
            stats,
            report,
            radial_steps,
            // On every rank count alike, so that a run restarted in place
            // on another number of ranks writes the series' field set.
            owners_move: mechanics
                && model
                    .mechanics
                    .as_ref()
                    .is_some_and(|m| m.rebalance.every > 0),
            cracks: Vec::new(),
            heat: Vec::new(),
            joints: None,
            particles: None,
            status,
        })
    }

    /// Collective. After a repartition: the per-body tables of the new part.
    pub fn repartitioned(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
    ) -> Result<()> {
        self.stats = BodyStats::new(comm, model, part)?;
        Ok(())
    }

    /// Whether the particle statistics need every step.
    pub fn every_step(&self) -> bool {
        self.report.is_some()
    }

    /// Collective. Write the fields of `step` to the series and a row to the history.
    #[allow(clippy::too_many_arguments)]
    pub fn write(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        sys: &mut Option<ThermalSystem>,
        mech: Option<&Mechanics>,
        contacts: &ContactSet,
        step: u64,
    ) -> Result<()> {
        let time = step as f64 * model.dt;
        let t = match sys.as_ref() {
            Some(s) => Some(s.node_temperatures(part)?),
            None => None,
        };
        // Each field goes to its block of global rows as soon as it is
        // made, so no rank holds its own rows and the blocks of every field
        // at once (the output was the peak of the N = 2000 runs on 8 ranks).
        let mut node_fields: Vec<(&str, usize, Vec<f64>)> = Vec::new();
        let mut cell_fields: Vec<(&str, usize, Vec<f64>)> = Vec::new();
        // After each field its transients' pages go back, before the next
        // field touches new ones (the heap's holes they reused).
        let mut node = |n, c, v: Vec<f64>| {
            node_fields.push((n, c, node_block(comm, model, part, &v, c)));
            super::summary::release_free_memory();
        };
        if let Some(t) = &t {
            node("temperature", 1, t.clone());
        }
        if let Some(Mechanics { domain: m, .. }) = mech {
            node("displacement", 3, m.displacement());
            node("velocity", 3, m.velocity());
            let mut cell = |n, c, v: Vec<f64>| {
                cell_fields.push((n, c, cell_block(comm, model, part, &v, c)));
                super::summary::release_free_memory();
            };
            // Cell fields in name order (the writer indexes fields by name anyway).
            if self.owners_move {
                let rank = f64::from(comm.rank());
                cell("owner_rank", 1, vec![rank; part.num_elements()]);
            }
            cell("stress", 6, m.stress_tensor6(&part.elem_gid));
        } else if model.has_motion() {
            // Rigid displacement of each owned node (ParaView: Warp By Vector).
            let u: Vec<f64> = part
                .owned_gids()
                .iter()
                .flat_map(|&n| {
                    model.bodies[model.body_of_node(n)]
                        .velocity
                        .map(|v| v * time)
                })
                .collect();
            node("displacement", 3, u);
        }
        let nf: Vec<(&str, usize, &[f64])> = node_fields
            .iter()
            .map(|(n, c, v)| (*n, *c, v.as_slice()))
            .collect();
        let cf: Vec<(&str, usize, &[f64])> = cell_fields
            .iter()
            .map(|(n, c, v)| (*n, *c, v.as_slice()))
            .collect();
        self.writer.write_step(time, &nf, &cf)?;
        if let (Some(j), Some(m)) = (self.joints.as_mut(), mech) {
            j.write(comm, time, m)?;
        }
        if let Some(p) = self.particles.as_mut() {
            p.write(comm, time, model, part, sys.as_ref(), mech)?;
        }
        if let Some(st) = self.status.as_mut() {
            let positions = match mech {
                Some(Mechanics { domain: m, .. }) => m.part_positions(),
                None => part
                    .node_gid
                    .iter()
                    .zip(&part.mesh.nodes)
                    .map(|(&n, x)| {
                        let v = model.bodies[model.body_of_node(n)].velocity;
                        [0, 1, 2].map(|d| x[d] + v[d] * time)
                    })
                    .collect(),
            };
            let sliding = model.contact.as_ref().map_or(0.0, |c| c.sliding_speed);
            st.write(comm, part, &positions, contacts, sliding, time)?;
        }
        self.history_row(comm, model, part, sys, mech, contacts, step)
    }

    /// Collective. Append the history row of `step` (with or without fields).
    #[allow(clippy::too_many_arguments)]
    pub fn history_row(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        sys: &mut Option<ThermalSystem>,
        mech: Option<&Mechanics>,
        contacts: &ContactSet,
        step: u64,
    ) -> Result<()> {
        let time = step as f64 * model.dt;
        let t = match sys.as_ref() {
            Some(s) => Some(s.node_temperatures(part)?),
            None => None,
        };
        let mut row = vec![step as f64, time];
        if let Some(s) = sys.as_mut() {
            let e = s.energy()?;
            row.extend_from_slice(&[
                e.stored,
                e.boundary_in(),
                s.iterations as f64,
                contacts.total_pairs as f64,
                contacts.total_area,
                e.convection_in,
                e.radiation_in,
                s.newton_iterations as f64,
                contacts.total_gap_area,
            ]);
            // Area-weighted mean pressure, Σ S/Rc of the thermal pairs at
            // the current temperatures, and the heat through contacts and
            // across gaps now.
            let f = s.contact_flows(model, contacts)?;
            let mut mine = [0.0, 0.0, f.conductance, f.contact, f.gap, f.gap_radiation];
            for (p, d) in contacts.local.iter().zip(&contacts.dofs) {
                mine[0] += p.area() * d.pressure;
                mine[1] += p.area();
            }
            let mut all = [0.0; 6];
            comm.all_reduce_into(&mine[..], &mut all[..], SystemOperation::sum());
            let pressure = if all[1] > 0.0 { all[0] / all[1] } else { 0.0 };
            row.extend_from_slice(&[pressure, all[2], e.friction_in, all[3], all[4], all[5]]);
            if let Some(st) = self.status.as_ref() {
                let sliding = model.contact.as_ref().map_or(0.0, |c| c.sliding_speed);
                row.extend(st.counts(comm, contacts, sliding).map(|c| c as f64));
            }
            if model.has_contact_physics() {
                // Heat moved between bodies: Σ|q| integrated by the
                // trapezoid rule over the history rows.
                let (through, across) = match self.heat.last() {
                    Some(p) => {
                        let dt = time - p[0];
                        (
                            p[7] + 0.5 * dt * (p[9] + all[3]),
                            p[8] + 0.5 * dt * (p[10] + all[4] + all[5]),
                        )
                    }
                    None => (0.0, 0.0),
                };
                self.heat.push([
                    time,
                    e.dirichlet_in,
                    e.flux_in,
                    e.convection_in,
                    e.radiation_in,
                    e.friction_in,
                    e.stored_change,
                    through,
                    across,
                    all[3],
                    all[4] + all[5],
                ]);
            }
        }
        if let Some(Mechanics {
            domain: m,
            substeps_per_step: n,
        }) = mech
        {
            let st = m.state(comm);
            row.extend_from_slice(&[
                step as f64 * *n as f64 * m.dt,
                st.kinetic,
                st.strain,
                st.contact,
                st.dissipated,
                st.momentum[0],
                st.momentum[1],
                st.momentum[2],
                st.active_pairs as f64,
                st.candidate_pairs as f64,
                st.external_work,
            ]);
            if model
                .contact
                .as_ref()
                .is_some_and(|c| c.friction_heating.is_some())
            {
                row.push(st.friction_work);
            }
            if model.has_joints() {
                self.cracks.push((time, st.crack_area, st.fracture));
                row.extend_from_slice(&[
                    st.joint,
                    st.fracture,
                    st.broken_joints as f64,
                    st.crack_area,
                    st.broken_by_mode[0] as f64,
                    st.broken_by_mode[1] as f64,
                    st.broken_by_mode[2] as f64,
                    st.closed_cracks as f64,
                    st.crack_friction,
                ]);
            }
        }
        if let Some(t) = &t {
            for s in self.groups.reduce(&self.stats.compute(comm, t)) {
                row.extend_from_slice(&s);
            }
        }
        if let (Some(s), true) = (sys.as_ref(), model.has_particles()) {
            row.extend(super::particle_output::temperature_range(
                comm, model, part, s,
            )?);
        }
        if let Some(m) = mech {
            let ng = self.groups.names.len();
            for f in m.domain.group_forces(comm, &self.groups.group, ng) {
                row.extend_from_slice(&f);
            }
        }
        let spheres = super::sphere_output::history_values(comm, sys.as_ref(), mech);
        row.extend(spheres);
        self.history.append(&row)?;
        Ok(())
    }

    /// Collective. Record the particle statistics of `step` (and its radial
    /// profile at the profile steps).
    pub fn record(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        sys: &Option<ThermalSystem>,
        step: u64,
    ) -> Result<()> {
        if let (Some(r), Some(s)) = (self.report.as_mut(), sys.as_ref()) {
            let t = s.node_temperatures(part)?;
            let st = self.stats.compute(comm, &t);
            let time = step as f64 * model.dt;
            r.record(time, &st);
            if self.radial_steps.contains(&step) {
                r.record_profile(time, &st);
            }
        }
        Ok(())
    }

    /// Collective. Write the particle statistics and the per-body contact
    /// areas, close the series; the files written besides the series.
    pub fn finish(
        &self,
        comm: &SimpleCommunicator,
        model: &Model,
        contacts: &ContactSet,
    ) -> Result<Vec<PathBuf>> {
        let (dir, stem) = (&self.dir, &self.stem);
        let mut particle_files = Vec::new();
        if let Some(r) = &self.report {
            let written = if comm.rank() == 0 {
                r.write(dir, stem).map_err(Error::from)
            } else {
                Ok(Vec::new())
            };
            particle_files = agree(comm, written)?;
        }
        if let Some(j) = &self.joints {
            particle_files.push(j.xdmf.clone());
        }
        if let Some(p) = &self.particles {
            particle_files.push(p.xdmf.clone());
        }
        if let Some(st) = &self.status {
            particle_files.push(st.xdmf.clone());
        }
        if model.has_joints() && !self.cracks.is_empty() {
            let path = dir.join(format!("{stem}_cracks.png"));
            let written = if comm.rank() == 0 {
                crack_plot(&self.cracks, &path)
            } else {
                Ok(())
            };
            agree(comm, written)?;
            particle_files.push(path);
        }
        if !self.heat.is_empty() {
            let path = dir.join(format!("{stem}_heat.png"));
            let written = if comm.rank() == 0 {
                heat_plot(&self.heat, &path)
            } else {
                Ok(())
            };
            agree(comm, written)?;
            particle_files.push(path);
        }
        if model.thermal_active && model.contact.is_some() {
            let path = dir.join(format!("{stem}_body_contacts.csv"));
            let per = body_contacts(comm, contacts);
            let written = if comm.rank() == 0 {
                write_body_contacts(model, &per, &path)
            } else {
                Ok(())
            };
            agree(comm, written)?;
            particle_files.push(path);
        }
        Ok(particle_files)
    }

    /// Collective. Close the series.
    pub fn close(self) -> Result<()> {
        self.writer.close()?;
        if let Some(j) = self.joints {
            j.close()?;
        }
        if let Some(p) = self.particles {
            p.close()?;
        }
        if let Some(st) = self.status {
            st.close()?;
        }
        Ok(())
    }
}

/// The crack area (cm², one face per broken joint) and the fracture energy
/// dissipated (mJ) against time, from the outputs of a run with joints.
fn crack_plot(cracks: &[(f64, f64, f64)], path: &std::path::Path) -> Result<()> {
    use crate::io::plot::{write_png, LinePlot, Series};
    let area: Vec<(f64, f64)> = cracks.iter().map(|&(t, a, _)| (t, a * 1e4)).collect();
    let energy: Vec<(f64, f64)> = cracks.iter().map(|&(t, _, e)| (t, e * 1e3)).collect();
    let plot = LinePlot {
        title: "Cracks",
        x_label: "time [s]",
        y_label: "crack area [cm^2], fracture energy [mJ]",
        series: vec![
            Series {
                label: "crack area [cm^2]",
                points: &area,
                dashed: false,
            },
            Series {
                label: "fracture energy [mJ]",
                points: &energy,
                dashed: true,
            },
        ],
    };
    write_png(&plot, path, (1000, 700))
        .map_err(|e| Error::Io(crate::io::IoError::invalid(path, e.to_string())))
}

/// `<stem>_heat.png` (issue 20): the heat in by each mechanism so far, the
/// stored heat's change and the heat moved between bodies through
/// contacts and across gaps (dashed; Σ|q| integrated over the history
/// rows) (J) against time; mechanisms that moved no heat are left out.
fn heat_plot(rows: &[[f64; 11]], path: &std::path::Path) -> Result<()> {
    use crate::io::plot::{write_png, LinePlot, Series};
    let names = [
        "prescribed temperatures",
        "fluxes and sources",
        "convection",
        "radiation",
        "friction",
        "stored (change)",
        "moved through contacts",
        "moved across gaps",
    ];
    let curves: Vec<(&str, Vec<(f64, f64)>)> = names
        .iter()
        .enumerate()
        .map(|(k, &n)| (n, rows.iter().map(|r| (r[0], r[k + 1])).collect::<Vec<_>>()))
        .filter(|(_, p)| p.iter().any(|&(_, q)| q != 0.0))
        .collect();
    let plot = LinePlot {
        title: "Heat in by mechanism",
        x_label: "time [s]",
        y_label: "heat in since the start [J]",
        series: curves
            .iter()
            .map(|(label, points)| Series {
                label,
                points,
                dashed: label.starts_with("stored") || label.starts_with("moved"),
            })
            .collect(),
    };
    write_png(&plot, path, (1000, 700))
        .map_err(|e| Error::Io(crate::io::IoError::invalid(path, e.to_string())))
}

/// The progress bar (rank 0, when asked for).
pub(super) fn progress_bar(
    show: bool,
    steps: u64,
    start_step: u64,
    heat: bool,
    mechanics: bool,
) -> Option<indicatif::ProgressBar> {
    if !show {
        return None;
    }
    let b = indicatif::ProgressBar::new(steps);
    b.set_position(start_step);
    let what = match (heat, mechanics) {
        (true, true) => "thermo-mechanics",
        (false, true) => "mechanics",
        _ => "thermal",
    };
    b.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{spinner}} {what} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} steps ({{eta}})"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(b)
}

/// Per-body statistics of the owned nodes.
struct BodyStats {
    body_of_owned: Vec<u32>,
    weight_of_owned: Vec<f64>,
    nbodies: usize,
}

impl BodyStats {
    fn new(comm: &SimpleCommunicator, model: &Model, part: &Part) -> Result<BodyStats> {
        // Each owned node's weight: V/4 summed over its elements, some of
        // which may be on other ranks.
        let halo = agree(comm, part.node_halo(comm).map_err(Error::Partition))?;
        let w = part.sum_to_owned(comm, &halo, |e| part.mesh.element_volume(e) / 4.0);
        Ok(BodyStats {
            body_of_owned: part
                .owned_gids()
                .iter()
                .map(|&n| model.body_of_node(n) as u32)
                .collect(),
            weight_of_owned: w,
            nbodies: model.bodies.len(),
        })
    }

    /// Collective. (min, volume-weighted mean, max) per body.
    fn compute(&self, comm: &SimpleCommunicator, t: &[f64]) -> Vec<[f64; 3]> {
        let nb = self.nbodies;
        let mut mins = vec![f64::INFINITY; nb];
        let mut maxs = vec![f64::NEG_INFINITY; nb];
        let mut sums = vec![0.0; 2 * nb];
        for (i, &x) in t.iter().enumerate() {
            let b = self.body_of_owned[i] as usize;
            mins[b] = mins[b].min(x);
            maxs[b] = maxs[b].max(x);
            sums[2 * b] += self.weight_of_owned[i] * x;
            sums[2 * b + 1] += self.weight_of_owned[i];
        }
        let mut gmin = vec![0.0; nb];
        let mut gmax = vec![0.0; nb];
        let mut gsum = vec![0.0; 2 * nb];
        comm.all_reduce_into(&mins[..], &mut gmin[..], SystemOperation::min());
        comm.all_reduce_into(&maxs[..], &mut gmax[..], SystemOperation::max());
        comm.all_reduce_into(&sums[..], &mut gsum[..], SystemOperation::sum());
        (0..nb)
            .map(|b| [gmin[b], gsum[2 * b] / gsum[2 * b + 1], gmax[b]])
            .collect()
    }
}

/// Collective. `values` (`width` per owned node of the part) moved to
/// this rank's block of the global node ids: the series is written in
/// global id order, the same file on any number of ranks.
fn node_block(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    values: &[f64],
    width: usize,
) -> Vec<f64> {
    to_blocks(comm, part.owned_gids(), values, width, model.totals().0).1
}

/// Collective. `values` (`width` per element of the part) moved to this
/// rank's block of the global element ids.
fn cell_block(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    values: &[f64],
    width: usize,
) -> Vec<f64> {
    to_blocks(comm, &part.elem_gid, values, width, model.totals().1).1
}

/// Collective. The series writer of `dir`: a new series, or with
/// `continue_after = Some(t)` the existing one reopened to continue after
/// the checkpoint at `t` (the same mesh, checked). Rows are global ids:
/// each rank writes its block of them.
fn open_writer(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    dir: &Path,
    stem: &str,
    continue_after: Option<f64>,
) -> Result<TimeSeriesWriter> {
    let (size, rank) = (comm.size() as usize, comm.rank() as usize);
    let (nodes, cells) = model.totals();
    let no = part.num_owned();
    let x: Vec<f64> = part.mesh.nodes[..no].iter().flatten().copied().collect();
    let coords: Vec<[f64; 3]> = node_block(comm, model, part, &x, 3)
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let t: Vec<f64> = part
        .mesh
        .tets
        .iter()
        .flat_map(|t| t.map(|l| f64::from(part.node_gid[l as usize])))
        .collect();
    let topology: Vec<u32> = cell_block(comm, model, part, &t, 4)
        .iter()
        .map(|&c| c as u32)
        .collect();
    let owner = vec![rank as f64; part.num_elements()];
    let rank_cell: Vec<i32> = cell_block(comm, model, part, &owner, 1)
        .iter()
        .map(|&r| r as i32)
        .collect();
    let (n0, _) = block(nodes, size, rank);
    let (c0, _) = block(cells, size, rank);
    let hex = HexOutput::new(comm, model, part);
    let rows = MeshPart {
        global_nodes: nodes,
        node_offset: n0,
        coords: &coords,
        global_cells: cells,
        cell_offset: c0,
        cells: &topology,
        nodes_per_cell: 4,
        hexes: hex.as_ref().map(HexOutput::rows),
    };
    let node_id: Vec<i32> = (n0..n0 + coords.len() as u64).map(|g| g as i32).collect();
    if let Some(keep_until) = continue_after {
        return Ok(TimeSeriesWriter::reopen(
            comm, dir, stem, &rows, &node_id, keep_until,
        )?);
    }
    let mut w = TimeSeriesWriter::create(comm, dir, stem, &rows)?;
    let body_node: Vec<i32> = node_id
        .iter()
        .map(|&n| model.body_of_node(n as u32) as i32)
        .collect();
    let body_cell: Vec<i32> = (c0..c0 + topology.len() as u64 / 4)
        .map(|e| model.body_of_elem(e as u32) as i32)
        .collect();
    w.write_static_node_field_i32("body", &body_node)?;
    w.write_static_node_field_i32("node_id", &node_id)?;
    w.write_static_cell_field_i32("body", &body_cell)?;
    w.write_static_cell_field_i32("rank", &rank_cell)?;
    Ok(w)
}

/// Collective. Each body's volume and volume-weighted centroid (the
/// reference configuration), summed over the parts.
fn body_moments(comm: &SimpleCommunicator, model: &Model, part: &Part) -> Vec<(f64, [f64; 3])> {
    let nb = model.bodies.len();
    let mut m = vec![0.0; 4 * nb];
    for e in 0..part.num_elements() {
        let b = part.mesh.body[e] as usize;
        let ve = part.mesh.element_volume(e);
        let x = part.mesh.element_coords(e);
        m[4 * b] += ve;
        for d in 0..3 {
            m[4 * b + 1 + d] += ve * (x[0][d] + x[1][d] + x[2][d] + x[3][d]) / 4.0;
        }
    }
    let mut sum = vec![0.0; 4 * nb];
    comm.all_reduce_into(&m[..], &mut sum[..], SystemOperation::sum());
    sum.chunks_exact(4)
        .map(|c| (c[0], [c[1] / c[0], c[2] / c[0], c[3] / c[0]]))
        .collect()
}

/// The particles of `[output.particles]`: their bodies, volumes and
/// distances from the axis.
fn particle_report(
    model: &Model,
    moments: &[(f64, [f64; 3])],
    p: &ParticleOutputSpec,
) -> Option<ParticleReport> {
    let bodies: Vec<usize> = (0..model.bodies.len())
        .filter(|&b| model.bodies[b].template == p.template)
        .collect();
    if bodies.is_empty() {
        return None;
    }
    let volumes = bodies.iter().map(|&b| moments[b].0).collect();
    let radii = bodies
        .iter()
        .map(|&b| {
            let c = moments[b].1;
            (c[0] - p.axis[0]).hypot(c[1] - p.axis[1])
        })
        .collect();
    Some(ParticleReport::new(bodies, volumes, radii, p.radial_bins))
}

/// History columns per body, or per scenario entry (template) when there
/// are more than [`BodyGroups::MAX_BODY_COLUMNS`] bodies.
struct BodyGroups {
    names: Vec<String>,
    /// Group of every body, and each body's volume.
    group: Vec<usize>,
    volume: Vec<f64>,
}

impl BodyGroups {
    const MAX_BODY_COLUMNS: usize = 16;

    fn new(model: &Model, moments: &[(f64, [f64; 3])]) -> BodyGroups {
        let volume: Vec<f64> = moments.iter().map(|m| m.0).collect();
        if model.bodies.len() <= Self::MAX_BODY_COLUMNS {
            return BodyGroups {
                names: model.bodies.iter().map(|b| b.name.clone()).collect(),
                group: (0..model.bodies.len()).collect(),
                volume,
            };
        }
        let mut names: Vec<String> = Vec::new();
        let group = model
            .bodies
            .iter()
            .map(|b| match names.iter().position(|n| *n == b.template) {
                Some(i) => i,
                None => {
                    names.push(b.template.clone());
                    names.len() - 1
                }
            })
            .collect();
        BodyGroups {
            names,
            group,
            volume,
        }
    }

    /// (min, volume-weighted mean, max) per group from per-body values.
    fn reduce(&self, per_body: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let ng = self.names.len();
        let mut out = vec![[f64::INFINITY, 0.0, f64::NEG_INFINITY]; ng];
        let mut vol = vec![0.0; ng];
        for (b, s) in per_body.iter().enumerate() {
            let g = self.group[b];
            out[g][0] = out[g][0].min(s[0]);
            out[g][1] += self.volume[b] * s[1];
            out[g][2] = out[g][2].max(s[2]);
            vol[g] += self.volume[b];
        }
        for (o, v) in out.iter_mut().zip(vol) {
            o[1] /= v;
        }
        out
    }
}

/// Collective. Contact area summed per pair of bodies over the ranks, on rank 0.
fn body_contacts(
    comm: &SimpleCommunicator,
    contacts: &ContactSet,
) -> std::collections::BTreeMap<(u32, u32), (u64, f64)> {
    let mut per: std::collections::BTreeMap<(u32, u32), (u64, f64)> = Default::default();
    for (p, d) in contacts.local.iter().zip(&contacts.dofs) {
        let [a, b] = d.bodies;
        let e = per.entry((a.min(b), a.max(b))).or_default();
        e.0 += 1;
        e.1 += p.area();
    }
    let mine: Vec<f64> = per
        .iter()
        .flat_map(|(&(a, b), &(n, s))| [f64::from(a), f64::from(b), n as f64, s])
        .collect();
    let all = crate::parallel::all_gather_f64(comm, &mine);
    let mut merged: std::collections::BTreeMap<(u32, u32), (u64, f64)> = Default::default();
    for r in all.chunks_exact(4) {
        let e = merged.entry((r[0] as u32, r[1] as u32)).or_default();
        e.0 += r[2] as u64;
        e.1 += r[3];
    }
    merged
}

/// Contact area summed per pair of bodies: `body_a,body_b,name_a,name_b,pairs,area`.
fn write_body_contacts(
    model: &Model,
    per: &std::collections::BTreeMap<(u32, u32), (u64, f64)>,
    path: &Path,
) -> Result<()> {
    let mut text = String::from("body_a,body_b,name_a,name_b,pairs,area\n");
    for (&(a, b), &(n, s)) in per {
        text.push_str(&format!(
            "{a},{b},{},{},{n},{s:.12e}\n",
            model.bodies[a as usize].name, model.bodies[b as usize].name
        ));
    }
    std::fs::write(path, text).map_err(|source| Error::File {
        path: path.display().to_string(),
        source,
    })
}

/// Create the output directory (and its parents), saying that the directory
/// is the problem when a file stands in its place or in a parent's.
fn create_output_dir(dir: &Path) -> Result<()> {
    let bad = |message: String| Error::OutputDir {
        path: dir.display().to_string(),
        message,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(bad(
            "is an existing file, not a directory; name a directory with --output or output.directory"
                .into(),
        ));
    }
    if let Some(file) = dir.ancestors().skip(1).find(|a| a.is_file()) {
        return Err(bad(format!(
            "cannot be created: {} is a file, not a directory",
            file.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| bad(format!("cannot be created: {e}")))
}
