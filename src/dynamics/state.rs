//! What the domain reports and restores: energies and momentum over the
//! ranks, the owned fields for output, every node's motion for
//! checkpoints, and the continuation from a saved motion.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::{Matrix3, Vector3};

use super::ExplicitDomain;
use crate::error::Result;

/// The motion a checkpoint saves, for this rank's part.
#[derive(Debug, Clone, Copy)]
pub struct SavedMotion<'a> {
    /// Positions x^n of the part's nodes (part order).
    pub positions: &'a [[f64; 3]],
    /// Velocities of the last substep, of the part's nodes.
    pub velocities: &'a [[f64; 3]],
    /// Velocities of the substep before, of the owned nodes, when saved.
    pub velocities_prev: Option<&'a [[f64; 3]]>,
    /// Energy dissipated so far (J).
    pub dissipated: f64,
    /// Each rank's share of it, when saved by a run on as many ranks as
    /// this one: the sum then continues bitwise.
    pub dissipated_per_rank: Option<&'a [f64]>,
    /// Each rank's share of the loads' work so far, when saved (a run on
    /// another number of ranks puts the sum on rank 0).
    pub external_work_per_rank: Option<&'a [f64]>,
}

/// Energies and momentum summed over the ranks.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MechanicsState {
    /// Kinetic energy (J), at the half step.
    pub kinetic: f64,
    /// Stored elastic energy (J).
    pub strain: f64,
    /// Penalty contact energy (J).
    pub contact: f64,
    /// Energy dissipated by contact damping and friction and by the mass
    /// damping so far (J).
    pub dissipated: f64,
    /// Linear momentum (kg m/s).
    pub momentum: [f64; 3],
    /// Contact pairs with overlap in the last substep.
    pub active_pairs: u64,
    /// Candidate pairs.
    pub candidate_pairs: u64,
    /// Elastic energy stored in the intact cohesive joints (J).
    pub joint: f64,
    /// Energy dissipated by joint damage so far (J).
    pub fracture: f64,
    /// Broken joints.
    pub broken_joints: u64,
    /// Of those, broken in opening, sliding and mixed mode.
    pub broken_by_mode: [u64; 3],
    /// Area of the broken joints, one face each (m²).
    pub crack_area: f64,
    /// Cracks (broken joints, initial cracks included) whose faces touch.
    pub closed_cracks: u64,
    /// Energy dissipated by friction on crack faces so far (J).
    pub crack_friction: f64,
    /// Work of the loads (tractions, gravity, prescribed velocities) since
    /// this run started (J).
    pub external_work: f64,
    /// Work of the penalty friction so far, with frictional heating on (J).
    pub friction_work: f64,
}

/// The phases of a contact detection, in order: the carried contacts and
/// margin, the ghost exchange (collective), the pair search (local), the
/// pair balancing (collective), the installation of the pairs (local), and
/// the halo, ghost state and assembly rebuild (collective).
pub const DETECT_PHASES: [&str; 6] = ["prepare", "ghosts", "pairs", "balance", "install", "halo"];

/// The phases of an explicit substep, in order: the contact pairs' forces,
/// the elements next to the halo and the packing of what goes to the
/// neighbours, the interior elements (while messages fly), the wait for
/// the neighbours' contributions, the sum of the owned nodes' forces (and
/// joints), the end of the touching flags' all-reduce (started after the
/// pairs, it waits only for a rank that has not finished its pairs yet),
/// particles and spheres, and the node update with the
/// forwarding of the ghosts' state (collective).
pub const SUBSTEP_PHASES: [&str; 8] = [
    "pairs",
    "boundary",
    "interior",
    "wait",
    "sum",
    "flags",
    "particles",
    "update",
];

/// Counters for the run summary.
#[derive(Debug, Clone, Copy, Default)]
pub struct MechanicsCounters {
    /// Substeps taken.
    pub substeps: u64,
    /// Element updates (sum over ranks is the caller's business).
    pub element_updates: u64,
    /// Pair evaluations.
    pub pair_updates: u64,
    /// Exact overlap evaluations (the rest were boxes apart or linearised).
    pub exact_overlaps: u64,
    /// Contact detections.
    pub detections: u64,
    /// Candidate tet pairs the detections kept (this rank's).
    pub candidates: u64,
    /// Seconds in contact detection and halo rebuilds.
    pub detect_time: f64,
    /// `detect_time` by phase ([`DETECT_PHASES`]), this rank's: where the
    /// search waits for other ranks shows as a collective phase longer
    /// here than on the slowest rank's computing phases.
    pub detect_phases: [f64; 6],
    /// Seconds of the substeps by phase ([`SUBSTEP_PHASES`]), this rank's.
    pub substep_phases: [f64; 8],
    /// Substeps advanced by this process (not restored on restart) and the
    /// bytes it sent to other ranks meanwhile (halo, ghost refresh, pair
    /// balancing).
    pub substeps_run: u64,
    pub bytes_sent: u64,
}

impl ExplicitDomain {
    /// Collective. Energies and momentum over all ranks, at the time
    /// level of the last substep's force evaluation (t_n: potentials at
    /// x^n, velocity (v^{n−½} + v^{n+½})/2).
    pub fn state(&self, comm: &SimpleCommunicator) -> MechanicsState {
        let no = self.n_owned;
        let mut kin = 0.0;
        let mut mom = [0.0; 3];
        for i in 0..no {
            let m = self.mass[i];
            let v = match self.v_prev.get(i) {
                Some(vp) => 0.5 * (vp + self.v[i]),
                None => self.v[i],
            };
            kin += 0.5 * m * v.norm_squared();
            for d in 0..3 {
                mom[d] += m * v[d];
            }
        }
        let mut local = [
            kin + self.particle_kinetic,
            self.strain_energy,
            self.contact_energy,
            self.dissipated,
            mom[0] + self.particle_momentum.x,
            mom[1] + self.particle_momentum.y,
            mom[2] + self.particle_momentum.z,
            self.active_pairs as f64,
            self.candidates.len() as f64,
            self.joints.totals.stored,
            self.joints.totals.dissipated,
            self.joints.totals.broken as f64,
            self.joints.totals.crack_area,
            self.joints.totals.by_mode[0] as f64,
            self.joints.totals.by_mode[1] as f64,
            self.joints.totals.by_mode[2] as f64,
            self.joints.totals.closed as f64,
            self.joints.totals.friction,
            self.external_work,
            self.friction_work,
        ];
        // The free spheres' share (issue 21): `damped` holds their mass
        // damping's and their contacts' dashpot and slip losses.
        if let Some(sp) = self.spheres.as_ref().map(|s| s.report) {
            local[0] += sp.kinetic;
            local[2] += sp.contact_energy;
            local[3] += sp.damped;
            for d in 0..3 {
                local[4 + d] += sp.momentum[d];
            }
            local[18] += sp.gravity_work;
        }
        let mut sum = [0.0; 20];
        comm.all_reduce_into(&local[..], &mut sum[..], SystemOperation::sum());
        MechanicsState {
            kinetic: sum[0],
            strain: sum[1],
            contact: sum[2],
            dissipated: sum[3],
            momentum: [sum[4], sum[5], sum[6]],
            active_pairs: sum[7] as u64,
            candidate_pairs: sum[8] as u64,
            joint: sum[9],
            fracture: sum[10],
            broken_joints: sum[11] as u64,
            crack_area: sum[12],
            broken_by_mode: [sum[13] as u64, sum[14] as u64, sum[15] as u64],
            closed_cracks: sum[16] as u64,
            crack_friction: sum[17],
            external_work: sum[18],
            friction_work: sum[19],
        }
    }

    /// Displacement x − X of the owned nodes (part order), flat.
    pub fn displacement(&self) -> Vec<f64> {
        self.x[..self.n_owned]
            .iter()
            .zip(&self.x0)
            .flat_map(|(x, x0)| {
                let u = x - x0;
                [u.x, u.y, u.z]
            })
            .collect()
    }

    /// Velocity of the owned nodes (part order), flat.
    pub fn velocity(&self) -> Vec<f64> {
        self.v[..self.n_owned]
            .iter()
            .flat_map(|v| [v.x, v.y, v.z])
            .collect()
    }

    /// Cauchy stress of the owned elements in `owned_elems` order, six
    /// values per element in XDMF `Tensor6` order (xx, xy, xz, yy, yz, zz,
    /// [`crate::io::tensor6`]); zero in held bodies.
    pub fn stress_tensor6(&self, owned_elems: &[u32]) -> Vec<f64> {
        let mut pos = std::collections::HashMap::with_capacity(self.elem_ids.len());
        for (i, &e) in self.elem_ids.iter().enumerate() {
            pos.insert(e, i);
        }
        owned_elems
            .iter()
            .flat_map(|e| {
                let s = pos.get(e).map_or(Matrix3::zeros(), |&i| self.stress[i]);
                crate::io::tensor6(&s)
            })
            .collect()
    }

    /// Positions of the owned nodes (part order).
    pub fn owned_positions(&self) -> Vec<[f64; 3]> {
        self.x[..self.n_owned]
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect()
    }

    /// Positions of the part's nodes, owned and ghost (part order).
    pub fn part_positions(&self) -> Vec<[f64; 3]> {
        self.x[..self.n_part_nodes]
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect()
    }

    /// Velocities of the owned nodes (part order).
    pub fn owned_velocities(&self) -> Vec<[f64; 3]> {
        self.v[..self.n_owned]
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect()
    }

    /// Collective. The velocities of the owned nodes at the substep before
    /// the last, `None` on every rank before the first substep (or right
    /// after a restore that had none).
    pub fn owned_velocities_prev(&self, comm: &SimpleCommunicator) -> Option<Vec<[f64; 3]>> {
        let mut have = i32::from(self.v_prev.len() >= self.n_owned);
        let mine = have;
        comm.all_reduce_into(&mine, &mut have, SystemOperation::min());
        (have != 0).then(|| {
            self.v_prev[..self.n_owned]
                .iter()
                .map(|p| [p.x, p.y, p.z])
                .collect()
        })
    }

    /// Collective. Continue from a saved state ([`SavedMotion`]): positions and velocities
    /// of every node (original numbering) and the energy dissipated so
    /// far. Contact candidates are detected afresh; forces depend only on
    /// the overlapping pairs and are summed in a fixed order, so the
    /// trajectory continues exactly as it would have.
    pub fn restore(&mut self, comm: &SimpleCommunicator, saved: SavedMotion) -> Result<()> {
        let SavedMotion {
            positions,
            velocities,
            velocities_prev,
            dissipated,
            dissipated_per_rank,
            external_work_per_rank,
        } = saved;
        for i in 0..self.n_part_nodes {
            self.x[i] = Vector3::from(positions[i]);
            self.v[i] = Vector3::from(velocities[i]);
        }
        self.dissipated = match dissipated_per_rank {
            Some(d) if d.len() == comm.size() as usize => d[comm.rank() as usize],
            _ if comm.rank() == 0 => dissipated,
            _ => 0.0,
        };
        self.external_work = match external_work_per_rank {
            Some(w) if w.len() == comm.size() as usize => w[comm.rank() as usize],
            Some(w) if comm.rank() == 0 => w.iter().sum(),
            _ => 0.0,
        };
        self.v_prev.clear();
        if let Some(vp) = velocities_prev {
            self.v_prev.extend(vp.iter().map(|&p| Vector3::from(p)));
        }
        self.detect(comm)?;
        self.redetect = false;
        Ok(())
    }

    /// Collective. Each rank's share of the loads' work, by rank.
    pub fn gather_external_work(&self, comm: &SimpleCommunicator) -> Vec<f64> {
        crate::parallel::all_gather_f64(comm, &[self.external_work])
    }

    /// Collective. Per group of bodies (`group_of_body[b]`, `groups` of
    /// them), the sum of the last substep's node forces over the group's
    /// nodes (and particles), over all ranks (N): element, joint, bond and
    /// link forces cancel within a body, so this is the contact force the other bodies exert on the
    /// group (the load on a platen or a container). Gravity, tractions and
    /// the reactions of prescribed velocities are not in it.
    pub fn group_forces(
        &self,
        comm: &SimpleCommunicator,
        group_of_body: &[usize],
        groups: usize,
    ) -> Vec<[f64; 3]> {
        let mut local = vec![0.0; 3 * groups];
        for (f, &b) in self.f[..self.n_owned].iter().zip(&self.owned_body) {
            let g = group_of_body[b as usize];
            for d in 0..3 {
                local[3 * g + d] += f[d];
            }
        }
        // The particles' share (issue 21): the links' reaction on the spheres.
        for (b, f) in self.particles.link_totals() {
            let g = group_of_body[b as usize];
            for d in 0..3 {
                local[3 * g + d] += f[d];
            }
        }
        let mut sum = vec![0.0; 3 * groups];
        comm.all_reduce_into(&local[..], &mut sum[..], SystemOperation::sum());
        sum.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// Collective. Each rank's share of the dissipated energy, by rank.
    pub fn gather_dissipated(&self, comm: &SimpleCommunicator) -> Vec<f64> {
        crate::parallel::all_gather_f64(comm, &[self.dissipated])
    }
}

impl ExplicitDomain {
    /// This rank's free spheres for the sphere output (issue 21), None
    /// without spheres.
    pub fn sphere_rows(&self) -> Option<super::SphereRows> {
        self.spheres.as_ref().map(|s| s.rows())
    }

    /// Collective. The free spheres (all ranks), and the touching sphere
    /// pairs and sphere–face contacts of the last substep over the ranks;
    /// zeros without spheres.
    pub fn sphere_counts(&self, comm: &SimpleCommunicator) -> [u64; 3] {
        let r = self.spheres.as_ref().map(|s| s.report).unwrap_or_default();
        let n = self.spheres.as_ref().map_or(0, |s| s.num_owned() as u64);
        let mut all = [0u64; 3];
        comm.all_reduce_into(
            &[n, r.pairs, r.faces][..],
            &mut all[..],
            SystemOperation::sum(),
        );
        all
    }

    /// The heat (J) the free spheres' faces gave this rank's owned nodes
    /// (part order) since the last call, and Σ N_I g Δt (J/K) per node;
    /// None without sphere heat (issue 21).
    pub fn take_sphere_node_heat(&mut self) -> Option<(Vec<f64>, Vec<f64>)> {
        let s = self.spheres.as_mut().filter(|s| s.has_heat())?;
        Some(s.take_node_heat())
    }

    /// Collective. The free spheres' heat over the ranks: stored Σ C T,
    /// heat taken from the faces since the start (J), lowest and highest
    /// temperature, and the largest explicit Fourier number so far; None
    /// without sphere heat.
    pub fn sphere_heat(&self, comm: &SimpleCommunicator) -> Option<SphereHeat> {
        let s = self.spheres.as_ref().filter(|s| s.has_heat())?;
        let (lo, hi) = s.temperature_range();
        let local = [s.stored_heat(), s.report.face_heat_in];
        let mut sum = [0.0; 2];
        comm.all_reduce_into(&local[..], &mut sum[..], SystemOperation::sum());
        let mine = [-lo, hi, s.report.fourier];
        let mut max = [0.0; 3];
        comm.all_reduce_into(&mine[..], &mut max[..], SystemOperation::max());
        Some(SphereHeat {
            initial: s.initial_heat(),
            stored: sum[0],
            from_faces: sum[1],
            min: -max[0],
            max: max[1],
            fourier: max[2],
        })
    }

    /// Take the free spheres out (a repartition builds the domain again).
    pub fn take_spheres(&mut self) -> TakenSpheres {
        TakenSpheres(self.spheres.take())
    }

    /// Put spheres taken from a previous domain back, their faces' shares
    /// now to `part`'s owned nodes.
    pub fn put_spheres(&mut self, taken: TakenSpheres, part: &crate::parallel::Part) {
        if let Some(mut s) = taken.0 {
            s.attach(part);
            self.spheres = Some(s);
        }
    }
}

/// The free spheres' heat over the ranks ([`ExplicitDomain::sphere_heat`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SphereHeat {
    /// Heat stored at the start, Σ C T₀ (J).
    pub initial: f64,
    /// Heat stored, Σ C T (J).
    pub stored: f64,
    /// Heat taken from the Tet4 faces since the start (J).
    pub from_faces: f64,
    /// Lowest and highest sphere temperature.
    pub min: f64,
    pub max: f64,
    /// Largest explicit Fourier number Δt Σg/C of a sphere so far.
    pub fourier: f64,
}

/// A domain's free spheres between two domains ([`ExplicitDomain::take_spheres`]).
pub struct TakenSpheres(Option<super::spheres::DomainSpheres>);
