//! Per-rank explicit mechanics: the subdomain of one rank (its METIS
//! elements, owned nodes and ghost nodes), halo exchange each substep, and
//! penalty-contact candidate lists (seed 004 sec 2 for the element
//! kinematics and stress; seed 000 sec 3.4 for the place of the mechanics
//! in the step; the contact potential in `contact::penalty`).
//!
//! One substep (collective over neighbours, one small all-reduce):
//! 1. contact forces of this rank's candidate pairs (they may touch ghost
//!    nodes), internal forces of the elements next to the halo;
//! 2. ghost forces sent to their owners (non-blocking) while the interior
//!    elements' forces are computed; owners add what they receive;
//! 3. owners advance their nodes (central differences);
//! 4. new positions and velocities copied to the ghosts;
//! 5. one all-reduce agrees on errors and on whether any node moved far
//!    enough (half the search margin) to redo contact detection.
//!
//! Local numbering: owned nodes first, in the layout's (PETSc) order, then
//! the ghosts of the owned elements, then the ghosts that only contacts
//! need. A contact pair joins two boundary tets of different bodies and is
//! found by the rank owning one of them, `a` (the free body's tet against
//! a held body, else the lower body's), so every pair is counted once over
//! the ranks; the found pairs are then shared out so every rank has about
//! the same contact work (`balance_pairs`). With `free_damping`, step 3
//! first agrees (one all-reduce over the bodies) on which bodies touch.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::{Matrix3, Vector3};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

use super::{Halo, Layout};
use crate::contact::penalty::{
    overlap_state, pair_stiffness, penalty_forces, LinearizedOverlap, PenaltyParams,
};
use crate::contact::BoundaryTets;
use crate::error::{Error, Result};
use crate::geometry::{
    face_planes, planes_within, separated_along, separating_axis, tet_bounds, TetPlanes,
};
use crate::mechanics::element::{characteristic_length, element_critical_dt, to_vectors};
use crate::mechanics::explicit::{element_forces, update_nodes_damped, NodeUpdate, ThermalLoad};
use crate::mechanics::frequency::{
    body_max_frequency, stable_step, BodyShape, BODY_EIGEN_MAX_NODES,
};
use crate::mechanics::{ElasticMaterial, MechElement, Tet4Reference, VelocityBc};
use crate::model::{Body, Model};

const NONE: u32 = u32::MAX;

/// Substeps the fastest node should need before contact re-detection.
const DETECT_EVERY: f64 = 10.0;
/// Largest search margin, as a multiple of the configured one.
const MARGIN_GROWTH: f64 = 4.0;
/// Work of a candidate pair whose tets' boxes overlap at detection (it
/// likely runs the overlap kernel each substep), in units of one whose
/// boxes are apart (a box test and zeroed forces).
const HOT_PAIR_WEIGHT: u64 = 32;

/// Corners of a tet and its bounding box (low, high corner).
type TetGeometry = ([[f64; 3]; 4], [f64; 3], [f64; 3]);

/// A box (low, high corner) grown by `g` on every side.
fn grown_aabb((lo, hi): &([f64; 3], [f64; 3]), g: f64) -> Aabb {
    Aabb::new(
        Point::new(lo[0] - g, lo[1] - g, lo[2] - g),
        Point::new(hi[0] + g, hi[1] + g, hi[2] + g),
    )
}

/// A candidate contact pair: boundary tets `a` (of a free body) and `b` (of
/// another body) whose boxes, grown by the margin, overlap.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    a: u32,
    b: u32,
    /// Indices of a and b in `ExplicitDomain::pair_tets`.
    ta: u32,
    tb: u32,
    /// Bodies of a and b.
    body_a: u32,
    body_b: u32,
    stiffness: f64,
    reduced_mass: f64,
}

/// The motion a checkpoint saves, every node in the original numbering.
#[derive(Debug, Clone, Copy)]
pub struct SavedMotion<'a> {
    /// Positions x^n.
    pub positions: &'a [[f64; 3]],
    /// Velocities of the last substep.
    pub velocities: &'a [[f64; 3]],
    /// Velocities of the substep before, when saved.
    pub velocities_prev: Option<&'a [[f64; 3]]>,
    /// Energy dissipated so far (J).
    pub dissipated: f64,
    /// Each rank's share of it, when saved by a run on as many ranks as
    /// this one: the sum then continues bitwise.
    pub dissipated_per_rank: Option<&'a [f64]>,
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
    /// Energy dissipated by contact friction and damping so far (J).
    pub dissipated: f64,
    /// Linear momentum (kg m/s).
    pub momentum: [f64; 3],
    /// Contact pairs with overlap in the last substep.
    pub active_pairs: u64,
    /// Candidate pairs.
    pub candidate_pairs: u64,
}

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
    /// Seconds in contact detection and halo rebuilds.
    pub detect_time: f64,
}

/// One rank's part of the explicit mechanics.
pub struct ExplicitDomain {
    rank: u32,
    n_owned: usize,
    /// Original node id of every local node.
    node_of_local: Vec<u32>,
    n_elem_ghosts: usize,
    /// Local index of every original node (NONE if not local).
    local_of: Vec<u32>,
    halo: Halo,
    elements: Vec<MechElement>,
    elem_ids: Vec<u32>,
    elem_tref: Vec<f64>,
    n_boundary: usize,
    materials: Vec<ElasticMaterial>,
    global_mass: Vec<f64>,
    global_bc: Vec<VelocityBc>,
    mass: Vec<f64>,
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    x0: Vec<Vector3<f64>>,
    bc: Vec<VelocityBc>,
    ext: Vec<Vector3<f64>>,
    f: Vec<Vector3<f64>>,
    stress: Vec<Matrix3<f64>>,
    node_t: Vec<f64>,
    elem_dt: Vec<f64>,
    elem_rate: Vec<f64>,
    /// Positions of every node, refreshed at each detection.
    x_all: Vec<[f64; 3]>,
    orig_of_global: Vec<u32>,
    /// Whole bodies held (fixed or kinematic).
    body_held: Vec<bool>,
    boundary: BoundaryTets,
    /// Per body, its boundary tets (indices into `boundary.elems`), and
    /// those of them this rank owns.
    body_bt: Vec<Vec<u32>>,
    my_body_bt: Vec<Vec<u32>>,
    /// Trees of the fixed bodies' boundary tets (they never move).
    fixed_trees: Vec<Option<Bvh>>,
    /// Per element, its index in `pair_tets` while the lists are built
    /// (NONE otherwise).
    tet_slot: Vec<u32>,
    penalty: Option<(PenaltyParams, f64)>,
    /// Search margin (m) of the current candidates, between `margin_min`
    /// and [`MARGIN_GROWTH`] × `margin_min`, chosen at each detection.
    margin: f64,
    margin_min: f64,
    candidates: Vec<Candidate>,
    /// Local nodes of the tets of the candidate pairs, each tet once.
    pair_tets: Vec<[u32; 4]>,
    /// Per substep: corners and bounding box of each of `pair_tets`.
    pair_geometry: Vec<TetGeometry>,
    /// Planes of each of `pair_tets`, built when an exact evaluation
    /// needs them, at most once per substep (`planes_stamp`).
    pair_planes: Vec<TetPlanes>,
    planes_stamp: Vec<u64>,
    /// Substeps since set-up (stamps `pair_planes`).
    substep_id: u64,
    /// `mechanics.contact.linear_tolerance` (0: every pair exact).
    linear_tolerance: f64,
    /// Per candidate, its slot in `linearized` (NONE: none valid).
    lin_of: Vec<u32>,
    linearized: Vec<LinearizedOverlap>,
    /// Per candidate, a separating axis found when it last did not
    /// overlap (`geometry::separating_axis`; 0: none).
    witness: Vec<u8>,
    x_detect: Vec<Vector3<f64>>,
    /// Force contributions: 4 per element, 8 per candidate pair, then those
    /// received from neighbours for shared nodes.
    contrib: Vec<Vector3<f64>>,
    /// Per owned node, its contribution slots in (global) key order.
    gather_off: Vec<u32>,
    gather_slot: Vec<u32>,
    /// Per halo neighbour: slots sent to it, and where its slots land.
    send_slots: Vec<Vec<u32>>,
    recv_at: Vec<(usize, usize)>,
    /// Owned velocities before the last substep (v^{n−½}), for energies at t_n.
    v_prev: Vec<Vector3<f64>>,
    /// Time step (s).
    pub dt: f64,
    gravity: Vector3<f64>,
    damping: f64,
    /// Damping of bodies that touch nothing (None: `damping` everywhere).
    free_damping: Option<f64>,
    /// Body of each owned node.
    owned_body: Vec<u32>,
    /// Per body, this substep: 1 if some pair of it overlaps (any rank).
    touching: Vec<u8>,
    strain_energy: f64,
    contact_energy: f64,
    dissipated: f64,
    active_pairs: u64,
    redetect: bool,
    /// Counters.
    pub counters: MechanicsCounters,
}

impl ExplicitDomain {
    /// Collective. Set up this rank's subdomain at rest (free bodies at
    /// their initial velocity) in the reference configuration, choose the
    /// time step (the scenario's, checked against the critical one, or
    /// safety × critical), and detect the first contact candidates.
    /// `coupling_dt` is the thermal step the substeps must fill when the
    /// clocks are coupled.
    pub fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
        coupling_dt: f64,
    ) -> Result<(ExplicitDomain, u64)> {
        let mm = model.mechanics.as_ref().expect("mechanics model");
        let mesh = &model.mesh;
        let nn = mesh.nodes.len();
        let materials: Vec<ElasticMaterial> = model
            .materials
            .iter()
            .map(|m| {
                m.elastic.unwrap_or(ElasticMaterial {
                    young: 1.0,
                    poisson: 0.0,
                    density: m.density,
                    expansion: 0.0,
                    viscosity: 0.0,
                })
            })
            .collect();
        for (i, m) in materials.iter().enumerate() {
            m.validate().map_err(|e| {
                Error::Mechanics(format!("material `{}`: {e}", model.materials[i].name))
            })?;
        }
        let body_held: Vec<bool> = model.bodies.iter().map(Body::is_held).collect();
        // Lumped masses of every node from the replicated mesh (no messages).
        let mut global_mass = vec![0.0; nn];
        let mut refs: Vec<Option<Tet4Reference>> = vec![None; mesh.tets.len()];
        let mut local_error = None;
        for &e in &layout.owned_elems {
            let e = e as usize;
            match Tet4Reference::from_coords(&mesh.element_coords(e)) {
                Ok(r) => refs[e] = Some(r),
                Err(err) => {
                    local_error.get_or_insert(Error::Mechanics(format!("element {e}: {err}")));
                }
            }
        }
        super::agree(comm, local_error.map_or(Ok(()), Err))?;
        for (e, t) in mesh.tets.iter().enumerate() {
            // Not numbered in the seeds: row-sum lumped mass ρ V0/4 per node of a Tet4.
            let share = model.material_of(e).density * mesh.element_volume(e) / 4.0;
            for &n in t {
                global_mass[n as usize] += share;
            }
        }
        let rank = layout.rank as u32;
        let mut elem_ids = Vec::new();
        for &e in &layout.owned_elems {
            if !body_held[mesh.body[e as usize] as usize] {
                elem_ids.push(e);
            }
        }
        let mut orig_of_global = vec![0u32; nn];
        for (n, &g) in layout.global_of.iter().enumerate() {
            orig_of_global[g as usize] = n as u32;
        }
        let x_all = mesh.nodes.clone();
        let penalty = mm.contact.as_ref().map(|c| {
            (
                PenaltyParams {
                    stiffness: 0.0,
                    damping_ratio: c.damping_ratio,
                    reduced_mass: 0.0,
                    friction: c.friction,
                    slip_velocity: c.slip_velocity,
                    time_step: 0.0,
                },
                c.penalty,
            )
        });
        // Time step: the exact highest frequency of each small free body
        // (congruent copies share it), the element bound in larger ones; the
        // contact penalty acts as a stiffer modulus.
        let mut dt_local = f64::INFINITY;
        let mut min_len = f64::INFINITY;
        let mut body_elems: Vec<Vec<u32>> = vec![Vec::new(); model.bodies.len()];
        for &e in &elem_ids {
            body_elems[mesh.body[e as usize] as usize].push(e);
        }
        let mut all_elems: Vec<Vec<u32>> = vec![Vec::new(); model.bodies.len()];
        for (e, &b) in mesh.body.iter().enumerate() {
            if !body_elems[b as usize].is_empty() {
                all_elems[b as usize].push(e as u32);
            }
        }
        let mut shapes: Vec<(BodyShape, f64)> = Vec::new();
        let mut local_error = None;
        for (b, owned) in body_elems.iter().enumerate() {
            if owned.is_empty() {
                continue;
            }
            for &e in owned {
                min_len = min_len.min(characteristic_length(&to_vectors(
                    &mesh.element_coords(e as usize),
                )));
            }
            let body_dt = body_frequency(model, &materials, &all_elems[b], &mut shapes)
                .map_err(|err| Error::Mechanics(format!("body `{}`: {err}", model.bodies[b].name)));
            let pn = penalty.as_ref().map(|(_, pn)| *pn);
            match body_dt.unwrap_or_else(|err| {
                local_error.get_or_insert(err);
                None
            }) {
                Some((omega, eta_over_m, m_min)) => {
                    dt_local = dt_local.min(stable_step(omega, eta_over_m * omega));
                    if let Some(pn) = pn {
                        // Not numbered in the seeds: a penalty p_n acts like a modulus, Δt ≤ (2/ω) sqrt(M/p_n).
                        dt_local = dt_local.min(2.0 / omega * (m_min / pn).sqrt());
                    }
                }
                None => {
                    for &e in owned {
                        let e = e as usize;
                        let xe = to_vectors(&mesh.element_coords(e));
                        let mat = &materials[model.elem_material[e] as usize];
                        dt_local = dt_local.min(element_critical_dt(&xe, mat));
                        if let Some(pn) = pn {
                            // Not numbered in the seeds: a penalty p_n acts like a modulus, Δt ≤ L sqrt(ρ/p_n).
                            dt_local = dt_local
                                .min(characteristic_length(&xe) * (mat.density / pn).sqrt());
                        }
                    }
                }
            }
        }
        super::agree(comm, local_error.map_or(Ok(()), Err))?;
        let mut crit: f64 = 0.0;
        comm.all_reduce_into(&dt_local, &mut crit, SystemOperation::min());
        let mut min_len_all: f64 = 0.0;
        comm.all_reduce_into(&min_len, &mut min_len_all, SystemOperation::min());
        if !crit.is_finite() {
            // Nothing deforms (all bodies held): any step works.
            crit = coupling_dt;
        }
        let allowed = mm.safety * crit;
        let (dt, substeps) = match (mm.dt, mm.substeps) {
            (Some(dt), _) if dt > crit * (1.0 + 1e-12) => {
                return Err(Error::Mechanics(format!(
                    "mechanics.dt = {dt:e} s exceeds the critical explicit step {crit:e} s of this \
                     mesh, materials and contact penalty (safety × critical = {allowed:e} s)"
                )))
            }
            (Some(dt), Some(n)) => (dt, n),
            (None, Some(n)) => (allowed, n),
            (given, None) => {
                let limit = given.unwrap_or(allowed);
                let n = (coupling_dt / limit).ceil().max(1.0) as u64;
                (coupling_dt / n as f64, n)
            }
        };
        let margin = mm
            .contact
            .as_ref()
            .and_then(|c| c.margin)
            .unwrap_or(0.5 * min_len_all);
        let global_bc = mm.bc.clone();
        let mut dom = ExplicitDomain {
            rank,
            n_owned: layout.owned_nodes.len(),
            node_of_local: Vec::new(),
            n_elem_ghosts: 0,
            local_of: vec![NONE; nn],
            halo: Halo::default(),
            elements: Vec::new(),
            elem_ids,
            elem_tref: Vec::new(),
            n_boundary: 0,
            materials,
            global_mass,
            global_bc,
            mass: Vec::new(),
            x: Vec::new(),
            v: Vec::new(),
            x0: Vec::new(),
            bc: Vec::new(),
            ext: Vec::new(),
            f: Vec::new(),
            stress: Vec::new(),
            node_t: Vec::new(),
            elem_dt: Vec::new(),
            elem_rate: Vec::new(),
            x_all,
            orig_of_global,
            body_held,
            boundary: BoundaryTets::new(mesh),
            body_bt: Vec::new(),
            my_body_bt: Vec::new(),
            fixed_trees: (0..model.bodies.len()).map(|_| None).collect(),
            tet_slot: vec![NONE; mesh.tets.len()],
            penalty,
            margin,
            margin_min: margin,
            candidates: Vec::new(),
            pair_tets: Vec::new(),
            pair_geometry: Vec::new(),
            pair_planes: Vec::new(),
            planes_stamp: Vec::new(),
            substep_id: 0,
            linear_tolerance: mm.contact.as_ref().map_or(0.0, |c| c.linear_tolerance),
            lin_of: Vec::new(),
            linearized: Vec::new(),
            witness: Vec::new(),
            x_detect: Vec::new(),
            v_prev: Vec::new(),
            contrib: Vec::new(),
            gather_off: Vec::new(),
            gather_slot: Vec::new(),
            send_slots: Vec::new(),
            recv_at: Vec::new(),
            dt,
            gravity: Vector3::from(mm.gravity),
            damping: mm.damping,
            free_damping: mm.free_damping,
            owned_body: layout
                .owned_nodes
                .iter()
                .map(|&n| model.body_of_node(n) as u32)
                .collect(),
            touching: vec![0; model.bodies.len()],
            strain_energy: 0.0,
            contact_energy: 0.0,
            dissipated: 0.0,
            active_pairs: 0,
            redetect: false,
            counters: MechanicsCounters::default(),
        };
        // Owned nodes, then the ghosts of the owned elements.
        dom.node_of_local = layout.owned_nodes.clone();
        for (i, &n) in layout.owned_nodes.iter().enumerate() {
            dom.local_of[n as usize] = i as u32;
        }
        let mut ghosts: Vec<u32> = dom
            .elem_ids
            .iter()
            .flat_map(|&e| mesh.tets[e as usize])
            .filter(|&n| layout.node_owner[n as usize] != rank)
            .collect();
        ghosts.sort_unstable();
        ghosts.dedup();
        for &n in &ghosts {
            dom.local_of[n as usize] = dom.node_of_local.len() as u32;
            dom.node_of_local.push(n);
        }
        dom.n_elem_ghosts = ghosts.len();
        let nl = dom.node_of_local.len();
        dom.x = dom
            .node_of_local
            .iter()
            .map(|&n| Vector3::from(mesh.nodes[n as usize]))
            .collect();
        dom.x0 = dom.x.clone();
        dom.v = dom
            .node_of_local
            .iter()
            .map(|&n| {
                let b = &model.bodies[model.body_of_node(n)];
                if b.velocity != [0.0; 3] {
                    Vector3::from(b.velocity)
                } else {
                    Vector3::from(b.initial_velocity)
                }
            })
            .collect();
        dom.ext = (0..nl)
            .map(|i| {
                if i < dom.n_owned {
                    Vector3::from(mm.traction[dom.node_of_local[i] as usize])
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        dom.node_t = dom
            .node_of_local
            .iter()
            .map(|&n| model.thermal.initial[n as usize])
            .collect();
        dom.elem_tref = dom
            .elem_ids
            .iter()
            .map(|&e| model.bodies[mesh.body[e as usize] as usize].reference_temperature)
            .collect();
        dom.elements = dom
            .elem_ids
            .iter()
            .map(|&e| MechElement {
                nodes: mesh.tets[e as usize].map(|n| dom.local_of[n as usize]),
                reference: refs[e as usize].expect("owned element"),
                material: model.elem_material[e as usize],
            })
            .collect();
        dom.body_bt = vec![Vec::new(); model.bodies.len()];
        dom.my_body_bt = vec![Vec::new(); model.bodies.len()];
        for (i, &e) in dom.boundary.elems.iter().enumerate() {
            let b = mesh.body[e as usize] as usize;
            dom.body_bt[b].push(i as u32);
            if layout.elem_part[e as usize] == rank {
                dom.my_body_bt[b].push(i as u32);
            }
        }
        dom.refresh_local_arrays();
        dom.detect(comm, model, layout)?;
        dom.update_element_temperatures(None);
        Ok((dom, substeps))
    }

    /// Arrays sized by the local node count, after the numbering changed.
    fn refresh_local_arrays(&mut self) {
        let nl = self.node_of_local.len();
        self.mass = self
            .node_of_local
            .iter()
            .map(|&n| self.global_mass[n as usize])
            .collect();
        self.bc = self
            .node_of_local
            .iter()
            .map(|&n| self.global_bc[n as usize])
            .collect();
        self.f.resize(nl, Vector3::zeros());
        self.ext.resize(nl, Vector3::zeros());
        let old = self.x.len();
        for i in old..nl {
            let p = self.x_all[self.node_of_local[i] as usize];
            self.x.push(Vector3::from(p));
            self.v.push(Vector3::zeros());
            self.x0.push(Vector3::zeros());
            self.node_t.push(0.0);
        }
        self.x.truncate(nl);
        self.v.truncate(nl);
        self.x0.truncate(nl);
        self.node_t.truncate(nl);
    }

    /// Collective. Refresh every node's position, rebuild the contact
    /// candidates, the ghost list and the halo; reorder elements so those
    /// touching the halo come first.
    fn detect(&mut self, comm: &SimpleCommunicator, model: &Model, layout: &Layout) -> Result<()> {
        let clock = std::time::Instant::now();
        let mesh = &model.mesh;
        // Every node's current position.
        self.gather_positions(comm);
        // Candidate pairs.
        self.candidates.clear();
        self.margin = self.adapted_margin(comm);
        if let Some((_, penalty)) = self.penalty {
            let weights = self.find_pairs(model, penalty);
            self.balance_pairs(comm, model, penalty, &weights);
        }
        // Ghosts: those of the elements, then those of the contacts, in
        // ascending node order. The tets of the pairs are listed once each
        // (their corners and planes are built once per substep, not once
        // per pair). Marks instead of sorting the ~8 nodes per pair.
        for &n in &self.node_of_local[self.n_owned + self.n_elem_ghosts..] {
            self.local_of[n as usize] = NONE;
        }
        self.node_of_local
            .truncate(self.n_owned + self.n_elem_ghosts);
        let mut tets: Vec<u32> = Vec::new();
        let mut contact_nodes: Vec<u32> = Vec::new();
        for c in self.candidates.iter_mut() {
            for (e, slot) in [(c.a, &mut c.ta), (c.b, &mut c.tb)] {
                let s = &mut self.tet_slot[e as usize];
                if *s == NONE {
                    *s = tets.len() as u32;
                    tets.push(e);
                    for &n in &mesh.tets[e as usize] {
                        if self.local_of[n as usize] == NONE {
                            // Marked as taken until numbered below.
                            self.local_of[n as usize] = NONE - 1;
                            contact_nodes.push(n);
                        }
                    }
                }
                *slot = *s;
            }
        }
        for &e in &tets {
            self.tet_slot[e as usize] = NONE;
        }
        contact_nodes.sort_unstable();
        for n in contact_nodes {
            self.local_of[n as usize] = self.node_of_local.len() as u32;
            self.node_of_local.push(n);
        }
        self.refresh_local_arrays();
        self.pair_tets = tets
            .iter()
            .map(|&e| mesh.tets[e as usize].map(|n| self.local_of[n as usize]))
            .collect();
        // Fresh candidates: planes rebuilt on demand, no linearisations.
        self.pair_planes = vec![TetPlanes::new(&[[0.0; 3]; 4]); tets.len()];
        self.planes_stamp = vec![0; tets.len()];
        self.lin_of = vec![NONE; self.candidates.len()];
        self.linearized.clear();
        self.witness = vec![0; self.candidates.len()];
        let ghosts: Vec<(u32, u32, u32)> = (self.n_owned..self.node_of_local.len())
            .map(|l| {
                let n = self.node_of_local[l];
                (n, layout.node_owner[n as usize], l as u32)
            })
            .collect();
        let n_owned = self.n_owned as u32;
        let local_of = &self.local_of;
        let halo = Halo::new(comm, &ghosts, |g| {
            let l = local_of[g as usize];
            (l < n_owned).then_some(l)
        });
        self.halo = super::agree(comm, halo.map_err(Error::Partition))?;
        // Ghost positions and velocities from their owners.
        self.forward_state(comm);
        // Elements touching a ghost node first (their contributions are
        // sent), each group by element id: the two id-ordered groups of the
        // last detection merged back into id order, then split anew, in
        // linear time.
        let n_owned = self.n_owned;
        let touches = |el: &MechElement| el.nodes.iter().any(|&l| l as usize >= n_owned);
        let (ids, ne, nb_old) = (&self.elem_ids, self.elem_ids.len(), self.n_boundary);
        let mut by_id: Vec<usize> = Vec::with_capacity(ne);
        let (mut i, mut j) = (0, nb_old);
        while i < nb_old || j < ne {
            if j == ne || (i < nb_old && ids[i] < ids[j]) {
                by_id.push(i);
                i += 1;
            } else {
                by_id.push(j);
                j += 1;
            }
        }
        if !by_id.windows(2).all(|w| ids[w[0]] < ids[w[1]]) {
            by_id.sort_by_key(|&i| ids[i]);
        }
        let mut order: Vec<usize> = by_id
            .iter()
            .copied()
            .filter(|&i| touches(&self.elements[i]))
            .collect();
        self.n_boundary = order.len();
        order.extend(
            by_id
                .iter()
                .copied()
                .filter(|&i| !touches(&self.elements[i])),
        );
        self.elements = order.iter().map(|&i| self.elements[i]).collect();
        self.elem_ids = order.iter().map(|&i| self.elem_ids[i]).collect();
        self.elem_tref = order.iter().map(|&i| self.elem_tref[i]).collect();
        if self.elem_dt.len() == order.len() {
            self.elem_dt = order.iter().map(|&i| self.elem_dt[i]).collect();
            self.elem_rate = order.iter().map(|&i| self.elem_rate[i]).collect();
        }
        // Every substep writes every element's stress: no need to permute it.
        self.stress.resize(self.elements.len(), Matrix3::zeros());
        self.build_assembly(comm, layout);
        self.x_detect = self.x[..self.n_owned].to_vec();
        self.counters.detections += 1;
        self.counters.detect_time += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// Collective over the neighbours. The order in which each owned
    /// node's force is summed: its contributions sorted by a global key
    /// (the element id; pairs after all elements, by (a, b)), whichever
    /// rank computed them. Ghost contributions travel one by one, not
    /// pre-summed, so the sums, and hence the trajectories, are bitwise
    /// the same on any number of ranks.
    /// This rank's candidate pairs, with their estimated costs (see
    /// [`Self::balance_pairs`]). Two levels: bodies whose boxes come within
    /// the margin, then, for each such pair, the owned boundary tets of
    /// one tested against a tree of the other's boundary tets, so no query
    /// wades through its own body's tets and a body falling alone costs
    /// one box test. The fixed bodies' trees are built once.
    fn find_pairs(&mut self, model: &Model, penalty: f64) -> Vec<u64> {
        let mesh = &model.mesh;
        let margin = self.margin;
        let x_all = &self.x_all;
        let corners = |e: u32| mesh.tets[e as usize].map(|n| x_all[n as usize]);
        // Not in the seeds: the penalty potential sums over pairs of
        // boundary tets (a face on the surface), like the contact
        // surface of seed 000 sec 3.1; a tet that meets the surface only
        // at an edge or corner overlaps a shallow intruder by O(δ²).
        let bt = &self.boundary.elems;
        let raw: Vec<([f64; 3], [f64; 3])> = bt.iter().map(|&e| tet_bounds(&corners(e))).collect();
        // Face planes of every boundary tet, for the candidates' pruning.
        let planes: Vec<[[f64; 4]; 4]> = bt.iter().map(|&e| face_planes(&corners(e))).collect();
        let nb = model.bodies.len();
        let mut body_box = vec![([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]); nb];
        for (i, &e) in bt.iter().enumerate() {
            let bb = &mut body_box[mesh.body[e as usize] as usize];
            for d in 0..3 {
                bb.0[d] = bb.0[d].min(raw[i].0[d]);
                bb.1[d] = bb.1[d].max(raw[i].1[d]);
            }
        }
        let with_tets: Vec<u32> = (0..nb as u32)
            .filter(|&b| !self.body_bt[b as usize].is_empty())
            .collect();
        let leaves: Vec<Aabb> = with_tets
            .iter()
            .map(|&b| grown_aabb(&body_box[b as usize], 0.0))
            .collect();
        let body_tree = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        let tree_of = |b: usize| {
            let leaves: Vec<Aabb> = self.body_bt[b]
                .iter()
                .map(|&i| grown_aabb(&raw[i as usize], 0.0))
                .collect();
            Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves)
        };
        for b in 0..nb {
            if model.bodies[b].fixed && self.fixed_trees[b].is_none() && !self.body_bt[b].is_empty()
            {
                self.fixed_trees[b] = Some(tree_of(b));
            }
        }
        let mut moving_trees: Vec<Option<Bvh>> = (0..nb).map(|_| None).collect();
        let mut found: Vec<(u32, u32, bool)> = Vec::new();
        for ba in 0..nb {
            // A held body's pairs are found from the free side (the
            // particles' ranks, which the partition balances).
            if self.body_held[ba] || self.my_body_bt[ba].is_empty() {
                continue;
            }
            let mut near: Vec<usize> = body_tree
                .intersect_aabb(&grown_aabb(&body_box[ba], margin))
                .map(|i| with_tets[i as usize] as usize)
                // Of two free bodies, the lower id finds the pairs.
                .filter(|&bb| bb != ba && (self.body_held[bb] || ba < bb))
                .collect();
            near.sort_unstable();
            for bb in near {
                let tree = match &self.fixed_trees[bb] {
                    Some(t) => t,
                    None => moving_trees[bb].get_or_insert_with(|| tree_of(bb)),
                };
                let (lo_b, hi_b) = body_box[bb];
                for &ia in &self.my_body_bt[ba] {
                    let (lo, hi) = raw[ia as usize];
                    if (0..3).any(|d| lo[d] - margin > hi_b[d] || lo_b[d] > hi[d] + margin) {
                        continue;
                    }
                    for leaf in tree.intersect_aabb(&grown_aabb(&raw[ia as usize], margin)) {
                        let ib = self.body_bt[bb][leaf as usize] as usize;
                        let (a, b) = (bt[ia as usize], bt[ib]);
                        if !planes_within(
                            (&corners(a), &planes[ia as usize]),
                            (&corners(b), &planes[ib]),
                            margin,
                        ) {
                            continue;
                        }
                        let (lo_t, hi_t) = raw[ib];
                        let hot = (0..3).all(|d| lo[d] <= hi_t[d] && lo_t[d] <= hi[d]);
                        found.push((a, b, hot));
                    }
                }
            }
        }
        self.candidates = found
            .iter()
            .map(|&(a, b, _)| self.candidate(model, penalty, a, b))
            .collect();
        found
            .iter()
            .map(|&(_, _, hot)| if hot { HOT_PAIR_WEIGHT } else { 1 })
            .collect()
    }

    /// The candidate pair of boundary tets `a` (of a free body) and `b`.
    fn candidate(&self, model: &Model, penalty: f64, a: u32, b: u32) -> Candidate {
        let mesh = &model.mesh;
        let (ba, bb) = (mesh.body[a as usize], mesh.body[b as usize]);
        let (va, vb) = (
            mesh.element_volume(a as usize),
            mesh.element_volume(b as usize),
        );
        let (ma, mb) = (
            model.material_of(a as usize).density * va,
            model.material_of(b as usize).density * vb,
        );
        // a is never held (held bodies do not search).
        let reduced_mass = if self.body_held[bb as usize] {
            ma
        } else {
            ma * mb / (ma + mb)
        };
        Candidate {
            a,
            b,
            ta: NONE,
            tb: NONE,
            body_a: ba,
            body_b: bb,
            stiffness: pair_stiffness(penalty, va, vb),
            reduced_mass,
        }
    }

    /// Collective. Share the pair work evenly over the ranks. Each rank
    /// finds the pairs of the tets it owns, so the ranks holding the
    /// bottom of a settling column (or its contacts) would do all the
    /// contact work while the others wait. With `weights` the estimated
    /// cost of each found pair, the pairs of all ranks, in rank order,
    /// are cut into equal-weight runs and rank r takes run r: an excess
    /// moves to the next ranks as one contiguous, spatially coherent run
    /// (the pair's nodes become ghosts there). The forces do not depend
    /// on which rank evaluates a pair (they are summed by pair key).
    fn balance_pairs(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        penalty: f64,
        weights: &[u64],
    ) {
        let size = comm.size() as usize;
        if size == 1 {
            return;
        }
        let mine: u64 = weights.iter().sum();
        let mut all = vec![0u64; size];
        comm.all_gather_into(&mine, &mut all[..]);
        let total: u64 = all.iter().sum();
        if total == 0 {
            return;
        }
        let mut at: u64 = all[..self.rank as usize].iter().sum();
        let mut out: Vec<Vec<u32>> = vec![Vec::new(); size];
        let mut keep = Vec::with_capacity(self.candidates.len());
        for (c, &w) in self.candidates.iter().zip(weights) {
            // The rank whose equal share holds the pair's mid-point.
            let mid = 2 * u128::from(at) + u128::from(w);
            let dest = ((mid * size as u128) / (2 * u128::from(total))).min(size as u128 - 1);
            at += w;
            if dest == u128::from(self.rank) {
                keep.push(*c);
            } else {
                out[dest as usize].extend_from_slice(&[c.a, c.b]);
            }
        }
        let send_counts: Vec<i32> = out.iter().map(|v| v.len() as i32).collect();
        let mut recv_counts = vec![0i32; size];
        comm.all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let displs = |c: &[i32]| -> Vec<i32> {
            c.iter()
                .scan(0, |acc, &x| {
                    let d = *acc;
                    *acc += x;
                    Some(d)
                })
                .collect()
        };
        let send: Vec<u32> = out.concat();
        let mut recv = vec![0u32; recv_counts.iter().sum::<i32>() as usize];
        {
            let send =
                mpi::datatype::Partition::new(&send[..], send_counts.clone(), displs(&send_counts));
            let mut part = mpi::datatype::PartitionMut::new(
                &mut recv[..],
                recv_counts.clone(),
                displs(&recv_counts),
            );
            comm.all_to_all_varcount_into(&send, &mut part);
        }
        for ab in recv.chunks_exact(2) {
            keep.push(self.candidate(model, penalty, ab[0], ab[1]));
        }
        self.candidates = keep;
    }

    fn build_assembly(&mut self, comm: &SimpleCommunicator, layout: &Layout) {
        const PAIR: u64 = 1 << 63;
        let ne = self.elements.len();
        let pair_base = 4 * ne;
        let nbrs: Vec<i32> = self.halo.neighbours().to_vec();
        let mut owned: Vec<(u32, u64, u32)> = Vec::with_capacity(4 * ne);
        let mut ghost: Vec<Vec<(u32, u64, u32)>> = vec![Vec::new(); nbrs.len()];
        let n_owned = self.n_owned as u32;
        let mut push = |l: u32, key: u64, slot: usize| {
            if l < n_owned {
                owned.push((l, key, slot as u32));
            } else {
                let g = self.node_of_local[l as usize];
                let r = layout.node_owner[g as usize] as i32;
                let i = nbrs
                    .binary_search(&r)
                    .expect("owner of a ghost is a neighbour");
                ghost[i].push((g, key, slot as u32));
            }
        };
        for (i, el) in self.elements.iter().enumerate() {
            for k in 0..4 {
                push(el.nodes[k], u64::from(self.elem_ids[i]), 4 * i + k);
            }
        }
        for (j, c) in self.candidates.iter().enumerate() {
            let key = PAIR | (u64::from(c.a) << 31) | u64::from(c.b);
            for k in 0..4 {
                push(self.pair_tets[c.ta as usize][k], key, pair_base + 8 * j + k);
                push(
                    self.pair_tets[c.tb as usize][k],
                    key,
                    pair_base + 8 * j + 4 + k,
                );
            }
        }
        // Tell each owner which contributions (node, key) it will receive.
        let mut counts_out = Vec::with_capacity(nbrs.len());
        let mut keys_out = Vec::with_capacity(nbrs.len());
        self.send_slots = ghost
            .iter()
            .map(|list| {
                // Any order: the owner sums by key.
                counts_out.push(vec![f64::from_bits(list.len() as u64)]);
                keys_out.push(
                    list.iter()
                        .flat_map(|&(g, key, _)| {
                            [f64::from_bits(u64::from(g)), f64::from_bits(key)]
                        })
                        .collect::<Vec<f64>>(),
                );
                list.iter().map(|&(_, _, s)| s).collect()
            })
            .collect();
        let mut counts_in = vec![vec![0.0]; nbrs.len()];
        self.halo.exchange(comm, &counts_out, &mut counts_in, || {});
        let mut keys_in: Vec<Vec<f64>> = counts_in
            .iter()
            .map(|c| vec![0.0; 2 * c[0].to_bits() as usize])
            .collect();
        self.halo.exchange(comm, &keys_out, &mut keys_in, || {});
        let mut next = pair_base + 8 * self.candidates.len();
        self.recv_at = keys_in
            .iter()
            .map(|keys| {
                let start = next;
                for (i, pair) in keys.chunks_exact(2).enumerate() {
                    let g = pair[0].to_bits() as usize;
                    let l = self.local_of[g];
                    debug_assert!(l < n_owned);
                    owned.push((l, pair[1].to_bits(), (start + i) as u32));
                }
                next += keys.len() / 2;
                (start, keys.len() / 2)
            })
            .collect();
        // Bucket by node (counting sort), then each node's few
        // contributions by key: the order of a full sort of (node, key),
        // in linear time (keys are unique per node).
        self.gather_off = vec![0; self.n_owned + 1];
        for &(l, _, _) in &owned {
            self.gather_off[l as usize + 1] += 1;
        }
        for i in 0..self.n_owned {
            self.gather_off[i + 1] += self.gather_off[i];
        }
        let mut fill: Vec<u32> = self.gather_off[..self.n_owned].to_vec();
        let mut bucket = vec![(0u64, 0u32); owned.len()];
        for &(l, key, s) in &owned {
            let at = &mut fill[l as usize];
            bucket[*at as usize] = (key, s);
            *at += 1;
        }
        for w in self.gather_off.windows(2) {
            bucket[w[0] as usize..w[1] as usize].sort_unstable();
        }
        self.gather_slot = bucket.iter().map(|&(_, s)| s).collect();
        // Reuse the allocation (hundreds of MB in a large packing).
        self.contrib.clear();
        self.contrib.resize(next, Vector3::zeros());
    }

    fn forward_state(&mut self, comm: &SimpleCommunicator) {
        let (x, v) = (flat_mut(&mut self.x), flat_mut(&mut self.v));
        self.halo.forward(comm, &mut [x, v], 3);
    }

    /// Collective. New nodal temperatures of the owned nodes (layout
    /// order), reached over `dt` seconds (for the temperature rate in the
    /// viscous stress; `None`: no rate).
    pub fn set_temperatures(&mut self, comm: &SimpleCommunicator, owned: &[f64], dt: Option<f64>) {
        self.node_t[..self.n_owned].copy_from_slice(owned);
        let t = &mut self.node_t[..];
        self.halo.forward(comm, &mut [t], 1);
        self.update_element_temperatures(dt);
    }

    fn update_element_temperatures(&mut self, dt: Option<f64>) {
        let new: Vec<f64> = self
            .elements
            .iter()
            .zip(&self.elem_tref)
            .map(|(el, &tref)| {
                // Not numbered in the seeds: element ΔT = mean of its four nodal temperatures − the stress-free temperature.
                el.nodes
                    .iter()
                    .map(|&l| self.node_t[l as usize])
                    .sum::<f64>()
                    / 4.0
                    - tref
            })
            .collect();
        self.elem_rate = match (dt, self.elem_dt.len() == new.len()) {
            (Some(dt), true) => new
                .iter()
                .zip(&self.elem_dt)
                .map(|(a, b)| (a - b) / dt)
                .collect(),
            _ => vec![0.0; new.len()],
        };
        self.elem_dt = new;
    }

    /// Collective. Advance by `n` substeps.
    pub fn advance(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
        n: u64,
    ) -> Result<()> {
        // Linearised pairs depend on when their models were made: starting
        // every step with fresh candidates (and models) makes a restart,
        // which detects afresh, repeat the run bitwise.
        if self.linear_tolerance > 0.0 && n > 0 {
            self.redetect = true;
        }
        for i in 0..n {
            if i + 1 == n {
                self.v_prev.clear();
                self.v_prev.extend_from_slice(&self.v[..self.n_owned]);
            }
            if self.redetect {
                self.detect(comm, model, layout)?;
                self.redetect = false;
            }
            let local = self.substep(comm);
            // Agree on errors and on the need to re-detect contacts.
            let moved = if self.penalty.is_some() {
                self.x[..self.n_owned]
                    .iter()
                    .zip(&self.x_detect)
                    .map(|(a, b)| (a - b).norm_squared())
                    .fold(0.0, f64::max)
            } else {
                0.0
            };
            let mine = [f64::from(u8::from(local.is_err())), moved];
            let mut any = [0.0; 2];
            comm.all_reduce_into(&mine[..], &mut any[..], SystemOperation::max());
            if any[0] > 0.0 {
                return match local {
                    Err(e) => Err(e),
                    Ok(()) => Err(Error::OtherRank),
                };
            }
            let half = 0.5 * self.margin;
            self.redetect = any[1] >= half * half;
            self.counters.substeps += 1;
        }
        Ok(())
    }

    /// One substep (collective over neighbours only). Errors are returned
    /// after the messages are exchanged, so no neighbour waits.
    fn substep(&mut self, comm: &SimpleCommunicator) -> Result<()> {
        let mut error: Option<Error> = None;
        let ne = self.elements.len();
        let pair_base = 4 * ne;
        // Contact forces, 8 slots per candidate pair.
        self.contact_energy = 0.0;
        self.active_pairs = 0;
        self.touching.iter_mut().for_each(|t| *t = 0);
        if let Some((params, _)) = &self.penalty {
            let mut power = 0.0;
            self.pair_geometry.clear();
            self.pair_geometry.extend(self.pair_tets.iter().map(|t| {
                let x: [[f64; 3]; 4] = t.map(|l| self.x[l as usize].into());
                let (lo, hi) = tet_bounds(&x);
                (x, lo, hi)
            }));
            self.substep_id += 1;
            let now = self.substep_id;
            let tolerance = self.linear_tolerance;
            let geo = &self.pair_geometry;
            let (planes, stamp) = (&mut self.pair_planes, &mut self.planes_stamp);
            let (lin_of, linearized) = (&mut self.lin_of, &mut self.linearized);
            let witness = &mut self.witness;
            let mut exact = 0u64;
            for (j, c) in self.candidates.iter().enumerate() {
                let out = &mut self.contrib[pair_base + 8 * j..pair_base + 8 * j + 8];
                let (ta, tb) = (c.ta as usize, c.tb as usize);
                let ((xa, lo_a, hi_a), (xb, lo_b, hi_b)) = (&geo[ta], &geo[tb]);
                let slot = lin_of[j] as usize;
                // A contacting pair's linearised overlap, while it holds.
                let lin_volume = linearized
                    .get(slot)
                    .and_then(|m| m.volume_at(xa, xb).map(|v| (m, v)));
                // Most other candidates are apart: their boxes tell, or the
                // axis that separated them when they were last evaluated.
                if lin_volume.is_none()
                    && ((0..3).any(|d| lo_a[d] > hi_b[d] || lo_b[d] > hi_a[d])
                        || separated_along(xa, xb, witness[j]))
                {
                    lin_of[j] = NONE;
                    out.iter_mut().for_each(|f| *f = Vector3::zeros());
                    continue;
                }
                let (la, lb) = (&self.pair_tets[ta], &self.pair_tets[tb]);
                let va = la.map(|l| self.v[l as usize].into());
                let vb = lb.map(|l| self.v[l as usize].into());
                let p = PenaltyParams {
                    stiffness: c.stiffness,
                    reduced_mass: c.reduced_mass,
                    time_step: self.dt,
                    ..*params
                };
                let result = match lin_volume {
                    Some((m, v)) => Some(penalty_forces(&m.state, v, &va, &vb, &p)),
                    None => {
                        for t in [ta, tb] {
                            if stamp[t] != now {
                                planes[t] = TetPlanes::new(&geo[t].0);
                                stamp[t] = now;
                            }
                        }
                        exact += 1;
                        match overlap_state((xa, &planes[ta]), (xb, &planes[tb])) {
                            Some(s) => {
                                witness[j] = 0;
                                if tolerance > 0.0 {
                                    let m = LinearizedOverlap::new(s, xa, xb, tolerance);
                                    if slot < linearized.len() {
                                        linearized[slot] = m;
                                    } else {
                                        lin_of[j] = linearized.len() as u32;
                                        linearized.push(m);
                                    }
                                }
                                Some(penalty_forces(&s, s.volume, &va, &vb, &p))
                            }
                            None => {
                                lin_of[j] = NONE;
                                witness[j] = separating_axis(xa, xb).unwrap_or(0);
                                None
                            }
                        }
                    }
                };
                match result {
                    Some(r) => {
                        for k in 0..4 {
                            out[k] = Vector3::from(r.forces_a[k]);
                            out[4 + k] = Vector3::from(r.forces_b[k]);
                        }
                        self.contact_energy += r.energy;
                        power += r.dissipation;
                        self.active_pairs += 1;
                        self.touching[c.body_a as usize] = 1;
                        self.touching[c.body_b as usize] = 1;
                    }
                    None => out.iter_mut().for_each(|f| *f = Vector3::zeros()),
                }
            }
            self.dissipated += power * self.dt;
            self.counters.pair_updates += self.candidates.len() as u64;
            self.counters.exact_overlaps += exact;
        }
        // Elements next to the halo, then the interior while messages fly.
        let nb = self.n_boundary;
        let (dt_b, dt_i) = self.elem_dt.split_at(nb);
        let (rate_b, rate_i) = self.elem_rate.split_at(nb);
        let (s_b, s_i) = self.stress.split_at_mut(nb);
        let (elem_part, rest) = self.contrib.split_at_mut(pair_base);
        let (f_b, f_i) = elem_part.as_chunks_mut::<4>().0.split_at_mut(nb);
        let mut strain = 0.0;
        let mut elem_error = None;
        match element_forces(
            &self.elements[..nb],
            &self.materials,
            &self.x,
            &self.v,
            ThermalLoad::transient(dt_b, rate_b),
            f_b,
            Some(s_b),
        ) {
            Ok(w) => strain += w,
            Err(e) => elem_error = Some((e, 0)),
        }
        // Ghost contributions, one by one, to their owners.
        let send: Vec<Vec<f64>> = self
            .send_slots
            .iter()
            .map(|slots| {
                let mut buf = Vec::with_capacity(3 * slots.len());
                for &s in slots {
                    let s = s as usize;
                    let f = if s < pair_base {
                        f_b[s / 4][s % 4]
                    } else {
                        rest[s - pair_base]
                    };
                    buf.extend_from_slice(&[f.x, f.y, f.z]);
                }
                buf
            })
            .collect();
        let mut recv: Vec<Vec<f64>> = self
            .recv_at
            .iter()
            .map(|&(_, n)| vec![0.0; 3 * n])
            .collect();
        let interior = &self.elements[nb..];
        let (materials, x, v) = (&self.materials, &self.x, &self.v);
        let mut inner: std::result::Result<f64, crate::mechanics::MechanicsError> = Ok(0.0);
        self.halo.exchange(comm, &send, &mut recv, || {
            inner = element_forces(
                interior,
                materials,
                x,
                v,
                ThermalLoad::transient(dt_i, rate_i),
                f_i,
                Some(s_i),
            );
        });
        match inner {
            Ok(w) => strain += w,
            Err(e) => {
                elem_error.get_or_insert((e, nb));
            }
        }
        for (&(start, n), buf) in self.recv_at.iter().zip(&recv) {
            for i in 0..n {
                self.contrib[start + i] = Vector3::new(buf[3 * i], buf[3 * i + 1], buf[3 * i + 2]);
            }
        }
        if let Some((e, offset)) = elem_error {
            error.get_or_insert(self.element_error(e, offset));
        }
        self.strain_energy = strain;
        self.counters.element_updates += ne as u64;
        // Owned node forces, summed in key order; then the owners advance.
        let no = self.n_owned;
        for i in 0..no {
            let mut f = Vector3::zeros();
            for &s in
                &self.gather_slot[self.gather_off[i] as usize..self.gather_off[i + 1] as usize]
            {
                f += self.contrib[s as usize];
            }
            self.f[i] = f + self.ext[i];
        }
        let p = NodeUpdate {
            dt: self.dt,
            gravity: self.gravity,
            mass_damping: self.damping,
        };
        let free = self.free_damping.unwrap_or(self.damping);
        if self.free_damping.is_some() {
            // Which bodies touch something, over all ranks (a body's pairs
            // may be on another rank than its nodes).
            let mine = self.touching.clone();
            comm.all_reduce_into(&mine[..], &mut self.touching[..], SystemOperation::max());
        }
        let (touching, owned_body, damping) = (&self.touching, &self.owned_body, self.damping);
        // Not in the seeds: packing-stage mass damping only on bodies in contact (free flight undamped).
        let node_damping = |i: usize| {
            if touching[owned_body[i] as usize] != 0 {
                damping
            } else {
                free
            }
        };
        if let Err(e) = update_nodes_damped(
            &p,
            node_damping,
            &self.mass[..no],
            &self.f[..no],
            &self.bc[..no],
            &mut self.x[..no],
            &mut self.v[..no],
        ) {
            let msg = match e {
                crate::mechanics::MechanicsError::NonFinite { node } => format!(
                    "node {} became non-finite (NaN or infinite): the explicit step \
                     is unstable or a contact exploded; reduce mechanics.dt or mechanics.safety",
                    self.node_of_local[node]
                ),
                other => other.to_string(),
            };
            error.get_or_insert(Error::Mechanics(msg));
        }
        self.forward_state(comm);
        match error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn element_error(&self, e: crate::mechanics::MechanicsError, offset: usize) -> Error {
        use crate::mechanics::MechanicsError as M;
        match e {
            M::Inverted {
                elem: Some(i),
                what,
                value,
            } => Error::Mechanics(format!(
                "element {} turned inside out ({what} = {value:.6e}): the run diverged; \
                 reduce mechanics.dt or mechanics.safety, or raise the contact penalty",
                self.elem_ids[offset + i]
            )),
            other => Error::Mechanics(other.to_string()),
        }
    }

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
        let local = [
            kin,
            self.strain_energy,
            self.contact_energy,
            self.dissipated,
            mom[0],
            mom[1],
            mom[2],
            self.active_pairs as f64,
            self.candidates.len() as f64,
        ];
        let mut sum = [0.0; 9];
        comm.all_reduce_into(&local[..], &mut sum[..], SystemOperation::sum());
        MechanicsState {
            kinetic: sum[0],
            strain: sum[1],
            contact: sum[2],
            dissipated: sum[3],
            momentum: [sum[4], sum[5], sum[6]],
            active_pairs: sum[7] as u64,
            candidate_pairs: sum[8] as u64,
        }
    }

    /// Displacement x − X of the owned nodes (layout order), flat.
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

    /// Velocity of the owned nodes (layout order), flat.
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

    /// Current positions of every node, as of the last detection or
    /// [`Self::gather_positions`].
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.x_all
    }

    /// Collective. Refresh [`Self::positions`] from the owners (gathered in
    /// PETSc order).
    pub fn gather_positions(&mut self, comm: &SimpleCommunicator) {
        let owned: Vec<f64> = self.x[..self.n_owned]
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .collect();
        let all = super::all_gather_f64(comm, &owned);
        for (g, c) in all.chunks_exact(3).enumerate() {
            self.x_all[self.orig_of_global[g] as usize] = [c[0], c[1], c[2]];
        }
    }

    /// Collective. The velocities of the substep before the last (original
    /// numbering), `None` before the first substep (or right after a
    /// restore that had none).
    pub fn gather_velocities_prev(&self, comm: &SimpleCommunicator) -> Option<Vec<[f64; 3]>> {
        let mut have = i32::from(self.v_prev.len() >= self.n_owned);
        let mine = have;
        comm.all_reduce_into(&mine, &mut have, SystemOperation::min());
        if have == 0 {
            return None;
        }
        let owned: Vec<f64> = self.v_prev[..self.n_owned]
            .iter()
            .flat_map(|v| [v.x, v.y, v.z])
            .collect();
        let all = super::all_gather_f64(comm, &owned);
        let mut out = vec![[0.0; 3]; self.x_all.len()];
        for (g, c) in all.chunks_exact(3).enumerate() {
            out[self.orig_of_global[g] as usize] = [c[0], c[1], c[2]];
        }
        Some(out)
    }

    /// Collective. Velocities of every node (original numbering).
    pub fn gather_velocities(&self, comm: &SimpleCommunicator) -> Vec<[f64; 3]> {
        let owned = self.velocity();
        let all = super::all_gather_f64(comm, &owned);
        let mut out = vec![[0.0; 3]; self.x_all.len()];
        for (g, c) in all.chunks_exact(3).enumerate() {
            out[self.orig_of_global[g] as usize] = [c[0], c[1], c[2]];
        }
        out
    }

    /// Collective. Continue from a saved state ([`SavedMotion`]): positions and velocities
    /// of every node (original numbering) and the energy dissipated so
    /// far. Contact candidates are detected afresh; forces depend only on
    /// the overlapping pairs and are summed in a fixed order, so the
    /// trajectory continues exactly as it would have.
    pub fn restore(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        layout: &Layout,
        saved: SavedMotion,
    ) -> Result<()> {
        let SavedMotion {
            positions,
            velocities,
            velocities_prev,
            dissipated,
            dissipated_per_rank,
        } = saved;
        self.x_all.copy_from_slice(positions);
        for (i, &n) in self.node_of_local.iter().enumerate() {
            self.x[i] = Vector3::from(positions[n as usize]);
            self.v[i] = Vector3::from(velocities[n as usize]);
        }
        self.dissipated = match dissipated_per_rank {
            Some(d) if d.len() == comm.size() as usize => d[comm.rank() as usize],
            _ if comm.rank() == 0 => dissipated,
            _ => 0.0,
        };
        self.v_prev.clear();
        if let Some(vp) = velocities_prev {
            self.v_prev.extend(
                self.node_of_local[..self.n_owned]
                    .iter()
                    .map(|&n| Vector3::from(vp[n as usize])),
            );
        }
        self.detect(comm, model, layout)?;
        self.redetect = false;
        Ok(())
    }

    /// Collective. Each rank's share of the dissipated energy, by rank.
    pub fn gather_dissipated(&self, comm: &SimpleCommunicator) -> Vec<f64> {
        crate::parallel::all_gather_f64(comm, &[self.dissipated])
    }

    /// Smallest search margin of the contact candidates (m), used at rest
    /// (see [`Self::adapted_margin`]).
    pub fn min_margin(&self) -> f64 {
        self.margin_min
    }

    /// Collective. The margin for the next candidate lists: wide enough
    /// that the fastest node needs [`DETECT_EVERY`] substeps to use up
    /// half of it (re-detection), at least the configured one (half the
    /// smallest element length by default) and at most [`MARGIN_GROWTH`]
    /// times that. Falling particles then re-detect every ~10 substeps
    /// instead of every one or two, and a bed at rest keeps the tight
    /// margin (a wider one only adds candidates). The trajectory does not
    /// depend on it: pairs out of reach have no force.
    fn adapted_margin(&self, comm: &SimpleCommunicator) -> f64 {
        let mine = self.v[..self.n_owned]
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        let mut v_max = 0.0;
        comm.all_reduce_into(&mine, &mut v_max, SystemOperation::max());
        // Not in the seeds: Verlet-list skin, re-detect after the margin/2 a node may move in DETECT_EVERY substeps.
        (2.0 * DETECT_EVERY * v_max * self.dt)
            .clamp(self.margin_min, MARGIN_GROWTH * self.margin_min)
    }

    /// Number of elements this rank integrates.
    pub fn num_elements(&self) -> usize {
        self.elements.len()
    }
}

/// The coordinates of a slice of 3-vectors as one flat slice.
/// For a free body of elements `elems` small enough for its exact highest
/// frequency ([`BODY_EIGEN_MAX_NODES`]): (ω_max, the largest η/M, the
/// smallest P-wave modulus M) of its elements; `None` for larger bodies.
/// `shapes` caches ω_max of the shapes seen (copies of one template).
fn body_frequency(
    model: &Model,
    materials: &[ElasticMaterial],
    elems: &[u32],
    shapes: &mut Vec<(BodyShape, f64)>,
) -> std::result::Result<Option<(f64, f64, f64)>, crate::mechanics::MechanicsError> {
    let mesh = &model.mesh;
    let mut nodes: Vec<u32> = elems.iter().flat_map(|&e| mesh.tets[e as usize]).collect();
    nodes.sort_unstable();
    nodes.dedup();
    if nodes.len() > BODY_EIGEN_MAX_NODES {
        return Ok(None);
    }
    let local = |g: u32| nodes.binary_search(&g).expect("node of the body") as u32;
    let tets: Vec<[u32; 4]> = elems
        .iter()
        .map(|&e| mesh.tets[e as usize].map(local))
        .collect();
    let mat_ids: Vec<u32> = elems
        .iter()
        .map(|&e| model.elem_material[e as usize])
        .collect();
    let x: Vec<Vector3<f64>> = nodes
        .iter()
        .map(|&g| Vector3::from(mesh.nodes[g as usize]))
        .collect();
    let shape = BodyShape::new(&x, &tets, &mat_ids);
    let omega = match shapes.iter().find(|(s, _)| s.congruent(&shape)) {
        Some(&(_, w)) => w,
        None => {
            let mats: Vec<ElasticMaterial> =
                mat_ids.iter().map(|&m| materials[m as usize]).collect();
            let w = body_max_frequency(&x, &tets, &mats)?;
            shapes.push((shape, w));
            w
        }
    };
    let (mut eta_over_m, mut m_min) = (0.0_f64, f64::INFINITY);
    for &m in &mat_ids {
        let mat = &materials[m as usize];
        eta_over_m = eta_over_m.max(mat.viscosity / mat.p_wave_modulus());
        m_min = m_min.min(mat.p_wave_modulus());
    }
    Ok(Some((omega, eta_over_m, m_min)))
}

fn flat_mut(v: &mut [Vector3<f64>]) -> &mut [f64] {
    const _: () = assert!(std::mem::size_of::<Vector3<f64>>() == 3 * std::mem::size_of::<f64>());
    // SAFETY: Vector3<f64> is a #[repr(C)] matrix over an array storage of
    // exactly three f64 (size asserted above, alignment that of f64), so a
    // slice of them is 3 × len contiguous f64 with no padding.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut f64, v.len() * 3) }
}
