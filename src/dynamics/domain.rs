//! The domain state of one rank and its set-up: local numbering, masses,
//! boundary conditions, initial motion, element temperatures (seed 004
//! sec 2: the element reference data and the thermal split ΔT).

use mpi::topology::SimpleCommunicator;
use nalgebra::{Matrix3, Vector3};

use super::candidates::Candidate;
use super::state::MechanicsCounters;
use super::substep::TetGeometry;
use super::time_step::time_step;
use crate::contact::penalty::{LinearizedOverlap, PenaltyParams};
use std::collections::HashMap;

use crate::contact::{ContactSearch, ContactTets};
use crate::error::{Error, Result};
use crate::geometry::TetPlanes;
use crate::mechanics::{ElasticMaterial, MechElement, Tet4Reference, VelocityBc};
use crate::model::{Body, Model};
use crate::parallel::ghosts::Pieces;
use crate::parallel::{Halo, Part};

/// A tet of a contact pair, as the pair's rank keeps it.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PairTet {
    /// Global element id.
    pub(super) gid: u32,
    /// Global body id.
    pub(super) body: u32,
    /// Material.
    pub(super) material: u32,
    /// Its faces on its body's boundary.
    pub(super) mask: u8,
    /// Its nodes on its body's boundary.
    pub(super) bits: u8,
}

/// One rank's part of the explicit mechanics.
pub struct ExplicitDomain {
    pub(super) n_owned: usize,
    /// Global id of every local node: the part's (owned, then the ghosts
    /// its elements touch), then the ghosts only contacts need.
    pub(super) node_gid: Vec<u32>,
    /// Owner and PETSc number of every local node.
    pub(super) node_owner: Vec<u32>,
    pub(super) node_petsc: Vec<u32>,
    /// Number of the part's nodes (the first ones).
    pub(super) n_part_nodes: usize,
    /// Local index of every contact ghost, by global id.
    pub(super) contact_local: HashMap<u32, u32>,
    pub(super) halo: Halo,
    pub(super) elements: Vec<MechElement>,
    pub(super) elem_ids: Vec<u32>,
    pub(super) elem_tref: Vec<f64>,
    /// The Hex8 elements (issue 21), whose tets in `elements` are HEX_TET.
    pub(super) hexes: super::hexes::DomainHexes,
    pub(super) n_boundary: usize,
    pub(super) materials: Vec<ElasticMaterial>,
    /// Material densities (for the pairs' masses).
    pub(super) density: Vec<f64>,
    /// Lumped mass of every owned node.
    pub(super) mass: Vec<f64>,
    pub(super) x: Vec<Vector3<f64>>,
    pub(super) v: Vec<Vector3<f64>>,
    pub(super) x0: Vec<Vector3<f64>>,
    /// Velocity conditions of every owned node.
    pub(super) bc: Vec<VelocityBc>,
    pub(super) ext: Vec<Vector3<f64>>,
    pub(super) f: Vec<Vector3<f64>>,
    pub(super) stress: Vec<Matrix3<f64>>,
    pub(super) node_t: Vec<f64>,
    pub(super) elem_dt: Vec<f64>,
    pub(super) elem_rate: Vec<f64>,
    /// Whole bodies held (fixed or kinematic), by global body id.
    pub(super) body_held: Vec<bool>,
    /// Whole bodies that never move (their search trees are kept).
    pub(super) body_fixed: Vec<bool>,
    /// The part's tets as the contact search reads them (positions
    /// refreshed at each detection).
    pub(super) part_tets: ContactTets,
    /// The part's tets grouped by body for the ghost exchange.
    pub(super) pieces: Pieces,
    /// The contact search.
    pub(super) search: ContactSearch,
    /// Whether the thermal contact reads the candidates (a coupled run).
    pub(super) thermal: bool,
    /// Candidates for the thermal contact only (a boundary tet against an
    /// interior tet, or two held bodies' tets), as slots in `thermal_tets`.
    pub(super) thermal_only: Vec<(u32, u32)>,
    pub(super) thermal_tets: Vec<[u32; 4]>,
    pub(super) thermal_info: Vec<PairTet>,
    /// Substep count at the last detection.
    pub(super) detected_at: Option<u64>,
    pub(super) penalty: Option<(PenaltyParams, f64)>,
    /// Give each thermal contact pair its penalty pressure (a conductance
    /// that follows it, issue 20).
    pub contact_pressure: bool,
    /// Give each thermal contact pair its mean penetration (a conductance
    /// table depends on it).
    pub penetration: bool,
    /// Search margin (m) of the current candidates, between `margin_min`
    /// and [`MARGIN_GROWTH`] × `margin_min`, chosen at each detection.
    pub(super) margin: f64,
    pub(super) margin_min: f64,
    pub(super) candidates: Vec<Candidate>,
    /// Work (partition units) of the penalty pairs this rank's tets found
    /// at the last detection, per body of the own tet, before balancing.
    pub(super) body_pair_work: HashMap<u32, f64>,
    /// Work of this rank's elements per substep (partition units).
    pub(super) element_work: f64,
    /// Work of the pairs this rank evaluates since the last detection.
    pub(super) pair_share: f64,
    /// The hot pairs this rank found and another rank evaluated since the
    /// last detection: key (`force_sum::pair_key`) to that rank.
    pub(super) pairs_given: HashMap<u64, u32>,
    /// Whether the detection under way may use `pairs_given`: only one
    /// within a step (after its first substep). Detections at a step start,
    /// where a restart starts, share pairs by the positions alone.
    pub(super) sticky_detect: bool,
    /// Whether the last detection shared pairs by the positions alone.
    pub(super) last_detect_fresh: bool,
    /// Local nodes of the tets of the candidate pairs, each tet once, and
    /// what the thermal contact needs of them.
    pub(super) pair_tets: Vec<[u32; 4]>,
    pub(super) pair_info: Vec<PairTet>,
    /// Per substep: corners and bounding box of each of `pair_tets`.
    pub(super) pair_geometry: Vec<TetGeometry>,
    /// Per pair tet, its slot in `pair_planes` (NONE: not needed since
    /// the detection).
    pub(super) planes_of: Vec<u32>,
    /// Planes of the pair tets an exact evaluation needed since the last
    /// detection, with the substep they were built at (at most once per
    /// substep). A fifth or so of the pair tets ever need them: one array
    /// for all of them held 176 B per tet (3.5 MiB on the busiest of 8
    /// ranks in the N = 2000 deposition, whose ghost tets it holds too).
    pub(super) pair_planes: Vec<(u64, TetPlanes)>,
    /// Substeps since set-up (stamps `pair_planes`).
    pub(super) substep_id: u64,
    /// `mechanics.contact.linear_tolerance` (0: every pair exact).
    pub(super) linear_tolerance: f64,
    /// Per candidate, its slot in `linearized` (NONE: none valid).
    pub(super) lin_of: Vec<u32>,
    pub(super) linearized: Vec<LinearizedOverlap>,
    /// Per candidate, a separating axis found when it last did not
    /// overlap (`geometry::separating_axis`; `substep::UNSEEN` before its
    /// first evaluation, `OVERLAPPED` when none separated it).
    pub(super) witness: Vec<u8>,
    /// Tangential springs ξ per candidate (`springs`), zero while apart;
    /// the substep each last touched; springs to hand out at the next
    /// detection.
    pub(super) springs: Vec<crate::contact::penalty::Spring>,
    pub(super) spring_seen: Vec<u64>,
    pub(super) spring_pool: Vec<(super::springs::PairKey, crate::contact::penalty::Spring)>,
    pub(super) x_detect: Vec<Vector3<f64>>,
    /// Element force contributions: 4 per element, then those received
    /// from neighbours' elements for shared nodes.
    pub(super) contrib: Vec<Vector3<f64>>,
    /// Per owned node, its contribution slots in (global) key order.
    pub(super) gather_off: Vec<u32>,
    pub(super) gather_slot: Vec<u32>,
    /// Per halo neighbour: slots sent to it, and where its slots land.
    pub(super) send_slots: Vec<Vec<u32>>,
    pub(super) recv_at: Vec<(usize, usize)>,
    /// Per neighbour, the buffer its ghost contributions are packed into
    /// each substep (kept: the same sizes every substep of a detection).
    pub(super) send_buf: Vec<Vec<f64>>,
    /// The touching pairs' forces of the substep, routed to their owners.
    pub(super) pair_forces: super::pair_sum::PairForces,
    /// Owned velocities before the last substep (v^{n−½}), for energies at t_n.
    pub(super) v_prev: Vec<Vector3<f64>>,
    /// Time step (s).
    pub dt: f64,
    /// Run time (the thermal clock, `time.dt`) per substep: `dt` when the
    /// clocks are coupled, `time.dt / substeps` when they are not. Joint
    /// breaking times are on this clock.
    pub(super) run_time_per_substep: f64,
    pub(super) gravity: Vector3<f64>,
    pub(super) damping: f64,
    /// Damping of bodies that touch nothing (None: `damping` everywhere).
    pub(super) free_damping: Option<f64>,
    /// Body of each owned node.
    pub(super) owned_body: Vec<u32>,
    /// Per body, this substep: 1 if some pair of it overlaps (any rank).
    pub(super) touching: Vec<u8>,
    /// This rank's flags of the last substep (the buffer the next
    /// substep's all-reduce sends from).
    pub(super) touching_here: Vec<u8>,
    pub(super) strain_energy: f64,
    /// Cohesive joints of the jointed bodies held here.
    pub(super) joints: super::joints::DomainJoints,
    /// Self-contact of the jointed bodies held here.
    pub(super) self_contact: super::self_contact::SelfContact,
    /// Bonded particles of the bodies held here (issue 21), and their
    /// kinetic energy after the last substep.
    pub(super) particles: super::particles::DomainParticles,
    pub(super) particle_kinetic: f64,
    /// Their momentum (kg m/s), likewise.
    pub(super) particle_momentum: Vector3<f64>,
    /// Free spheres (issue 21): this rank's slab of them.
    pub(super) spheres: Option<super::spheres::DomainSpheres>,
    pub(super) contact_energy: f64,
    /// Energy dissipated by contact damping and friction and by the mass
    /// damping, this rank's share (J).
    pub(super) dissipated: f64,
    /// Work of the loads (tractions, gravity, prescribed velocities) on
    /// this rank's owned nodes since the run started (J).
    pub(super) external_work: f64,
    /// Frictional heating (issue 20): η and w, when on; the friction work
    /// of each candidate pair since it was last handed over (J); the heat
    /// handed over per PETSc row, not yet taken by the thermal step; and
    /// this rank's friction work so far (J).
    pub(super) friction_heating: Option<(f64, f64)>,
    pub(super) pair_friction: Vec<f64>,
    pub(super) friction_rows: std::collections::BTreeMap<u32, f64>,
    pub(super) friction_work: f64,
    pub(super) active_pairs: u64,
    pub(super) redetect: bool,
    /// Crack faces became boundary faces since the last detection: the
    /// candidates must be found again before the next substep, so that
    /// every pair touching a crack face is a candidate whenever it
    /// overlaps (and a restart, which detects afresh, repeats the run).
    pub(super) cracks_marked: bool,
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
        part: &Part,
        coupling_dt: f64,
    ) -> Result<(ExplicitDomain, u64)> {
        let mm = model.mechanics.as_ref().expect("mechanics model");
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
        let pm = &part.mesh;
        let mut refs: Vec<Option<Tet4Reference>> = vec![None; part.num_elements()];
        let mut local_error = None;
        for (e, r) in refs.iter_mut().enumerate() {
            match Tet4Reference::from_coords(&pm.element_coords(e)) {
                Ok(x) => *r = Some(x),
                Err(err) => {
                    local_error.get_or_insert(Error::Mechanics(format!(
                        "element {}: {err}",
                        part.elem_gid[e]
                    )));
                }
            }
        }
        // Hex8 bodies' hexes (issue 21), each six consecutive tets.
        let part_hexes = crate::parallel::PartHexes::new(model, part);
        let mut hex_list = Vec::with_capacity(part_hexes.hexes.len());
        for h in &part_hexes.hexes {
            let e = h.first as usize;
            let made = super::hexes::DomainHexes::element(
                h,
                part.elem_gid[e],
                |l| pm.nodes[l as usize],
                (part.elem_material[e], pm.body[e]),
            );
            match made {
                Ok(x) => hex_list.push(x),
                Err(err) => {
                    local_error.get_or_insert(Error::Mechanics(format!(
                        "the Hex8 element of tets {}..{}: {err}",
                        part.elem_gid[e],
                        part.elem_gid[e] + 5
                    )));
                }
            }
        }
        crate::parallel::agree(comm, local_error.map_or(Ok(()), Err))?;
        let density_of = |e: usize| model.materials[part.elem_material[e] as usize].density;
        // Lumped masses of the owned nodes, summed in element order over
        // the ranks (the same bits on any rank count).
        let mass = part.sum_corners_to_owned_in_order(comm, |e| {
            match part_hexes.of_element.get(e) {
                Some(&h) if h != crate::parallel::PartHexes::NONE => {
                    let (ph, he) = (&part_hexes.hexes[h as usize], &hex_list[h as usize]);
                    let m = he.reference.lumped_masses(density_of(e));
                    crate::parallel::PartHexes::corner_values(ph, &m, e - ph.first as usize)
                }
                // Not numbered in the seeds: row-sum lumped mass ρ V0/4 per node of a Tet4.
                _ => [density_of(e) * pm.element_volume(e) / 4.0; 4],
            }
        });
        let is_hex_tet = |e: usize| {
            part_hexes
                .of_element
                .get(e)
                .is_some_and(|&h| h != crate::parallel::PartHexes::NONE)
        };
        let free: Vec<usize> = (0..part.num_elements())
            .filter(|&e| !body_held[pm.body[e] as usize])
            .collect();
        let hexes = super::hexes::DomainHexes {
            list: hex_list
                .into_iter()
                .zip(&part_hexes.hexes)
                .filter(|(_, ph)| !body_held[pm.body[ph.first as usize] as usize])
                .map(|(h, _)| h)
                .collect(),
        };
        let free_tets: Vec<usize> = free.iter().copied().filter(|&e| !is_hex_tet(e)).collect();
        let elem_ids: Vec<u32> = free.iter().map(|&e| part.elem_gid[e]).collect();
        let penalty = mm.contact.as_ref().map(|c| {
            (
                PenaltyParams {
                    stiffness: 0.0,
                    damping_ratio: c.damping_ratio,
                    reduced_mass: 0.0,
                    friction: c.friction,
                    slip_velocity: c.slip_velocity,
                    time_step: 0.0,
                    tangential_ratio: c.tangential_stiffness,
                    stick_limit: c.stick_limit,
                },
                c.penalty,
            )
        });
        let pn = penalty.as_ref().map(|(_, pn)| *pn);
        let n_owned = part.num_owned();
        let particles = crate::parallel::agree(
            comm,
            super::particles::DomainParticles::new(comm, model, part),
        )?;
        let particle_w2 = particles.frequencies(comm, &mass, n_owned);
        let owned_body: Vec<u32> = part
            .owned_gids()
            .iter()
            .map(|&n| model.body_of_node(n) as u32)
            .collect();
        let spheres = super::spheres::DomainSpheres::new(comm, model, part)?;
        let sphere_dt = spheres.as_ref().map_or(f64::INFINITY, |s| {
            s.stable_dt(comm, part, &mass, &owned_body, &body_held)
        });
        let (dt, substeps, min_len_all) = time_step(
            comm,
            model,
            part,
            &materials,
            &free_tets,
            hexes.time_step(&materials, pn, &particle_w2),
            pn,
            coupling_dt,
            &particle_w2,
            sphere_dt,
        )?;
        let margin = mm
            .contact
            .as_ref()
            .and_then(|c| c.margin)
            .unwrap_or(0.5 * min_len_all);
        let np = part.node_gid.len();
        let joints = crate::parallel::agree(
            comm,
            super::joints::DomainJoints::new(model, part, &body_held),
        )?;
        let self_contact = super::self_contact::SelfContact::new(model, part, &body_held);
        let mut dom = ExplicitDomain {
            n_owned,
            node_gid: part.node_gid.clone(),
            node_owner: part.node_owner.clone(),
            node_petsc: part.petsc.clone(),
            n_part_nodes: np,
            contact_local: HashMap::new(),
            halo: Halo::default(),
            elements: free
                .iter()
                .map(|&e| MechElement {
                    nodes: pm.tets[e],
                    reference: refs[e].expect("checked above"),
                    material: if is_hex_tet(e) {
                        crate::mechanics::explicit::HEX_TET
                    } else {
                        part.elem_material[e]
                    },
                })
                .collect(),
            elem_tref: free
                .iter()
                .map(|&e| model.bodies[pm.body[e] as usize].reference_temperature)
                .collect(),
            elem_ids,
            hexes,
            n_boundary: 0,
            density: materials.iter().map(|m| m.density).collect(),
            materials,
            mass,
            x: pm.nodes.iter().map(|&p| Vector3::from(p)).collect(),
            v: part
                .node_gid
                .iter()
                .map(|&n| {
                    let b = &model.bodies[model.body_of_node(n)];
                    if b.velocity != [0.0; 3] {
                        Vector3::from(b.velocity)
                    } else {
                        Vector3::from(b.initial_velocity)
                    }
                })
                .collect(),
            x0: pm.nodes[..n_owned]
                .iter()
                .map(|&p| Vector3::from(p))
                .collect(),
            bc: part.bc.velocity[..n_owned].to_vec(),
            ext: part.bc.traction.iter().map(|&t| Vector3::from(t)).collect(),
            f: vec![Vector3::zeros(); np],
            stress: Vec::new(),
            node_t: part.bc.initial_t.clone(),
            elem_dt: Vec::new(),
            elem_rate: Vec::new(),
            body_fixed: model.bodies.iter().map(|b| b.fixed).collect(),
            body_held,
            part_tets: part.contact_tets(None),
            pieces: Pieces::default(),
            search: ContactSearch::new(),
            thermal: model.thermal_active && model.contact.is_some(),
            thermal_only: Vec::new(),
            thermal_tets: Vec::new(),
            thermal_info: Vec::new(),
            detected_at: None,
            penalty,
            contact_pressure: model.contact.as_ref().is_some_and(|c| {
                c.cmy
                    .iter()
                    .flatten()
                    .any(|m| m.is_some_and(|m| m.pressure.is_none()))
                    || c.tables
                        .iter()
                        .any(|t| t.depends_on_pressure() && t.prescribed_pressure.is_none())
            }),
            penetration: model
                .contact
                .as_ref()
                .is_some_and(|c| c.needs_penetration()),
            margin,
            margin_min: margin,
            candidates: Vec::new(),
            body_pair_work: HashMap::new(),
            element_work: part
                .mesh
                .body
                .iter()
                .map(|&b| crate::parallel::element_work(model, b as usize))
                .sum(),
            pair_share: 0.0,
            pairs_given: HashMap::new(),
            sticky_detect: false,
            last_detect_fresh: true,
            pair_tets: Vec::new(),
            pair_info: Vec::new(),
            pair_geometry: Vec::new(),
            planes_of: Vec::new(),
            pair_planes: Vec::new(),
            substep_id: 0,
            linear_tolerance: mm.contact.as_ref().map_or(0.0, |c| c.linear_tolerance),
            lin_of: Vec::new(),
            linearized: Vec::new(),
            witness: Vec::new(),
            springs: Vec::new(),
            spring_seen: Vec::new(),
            spring_pool: Vec::new(),
            x_detect: Vec::new(),
            v_prev: Vec::new(),
            contrib: Vec::new(),
            gather_off: Vec::new(),
            gather_slot: Vec::new(),
            send_slots: Vec::new(),
            recv_at: Vec::new(),
            send_buf: Vec::new(),
            pair_forces: Default::default(),
            dt,
            run_time_per_substep: coupling_dt / substeps.max(1) as f64,
            gravity: Vector3::from(mm.gravity),
            damping: mm.damping,
            free_damping: mm.free_damping,
            owned_body,
            touching: vec![0; model.bodies.len()],
            touching_here: vec![0; model.bodies.len()],
            strain_energy: 0.0,
            joints,
            self_contact,
            particles,
            particle_kinetic: 0.0,
            particle_momentum: Vector3::zeros(),
            spheres,
            contact_energy: 0.0,
            dissipated: 0.0,
            external_work: 0.0,
            friction_heating: model
                .contact
                .as_ref()
                .and_then(|c| c.friction_heating)
                .map(|f| (f.fraction, f.weight)),
            pair_friction: Vec::new(),
            friction_rows: Default::default(),
            friction_work: 0.0,
            active_pairs: 0,
            redetect: false,
            cracks_marked: false,
            counters: MechanicsCounters::default(),
        };
        dom.pieces = Pieces::new(&dom.part_tets);
        // Initial cracks are boundary faces from the start.
        dom.mark_cracks();
        dom.detect(comm)?;
        dom.update_element_temperatures(None);
        dom.particles.update_free(&dom.node_t);
        Ok((dom, substeps))
    }

    /// Arrays sized by the local node count, after the contact ghosts
    /// changed (their values arrive with the next forward).
    pub(super) fn refresh_local_arrays(&mut self) {
        let nl = self.node_gid.len();
        self.f.resize(nl, Vector3::zeros());
        self.x.resize(nl, Vector3::zeros());
        self.v.resize(nl, Vector3::zeros());
        self.node_t.resize(nl, 0.0);
    }

    /// Give back the buffers the substeps' messages to the neighbours are
    /// packed in and land in (held for reuse; only ranks with neighbours
    /// have them), before an output allocates its blocks.
    pub fn release_message_buffers(&mut self) {
        self.send_buf = Vec::new();
        self.pair_forces.release_messages();
    }

    pub(super) fn forward_state(&mut self, comm: &SimpleCommunicator) {
        let (x, v) = (flat_mut(&mut self.x), flat_mut(&mut self.v));
        self.halo.forward(comm, &mut [x, v], 3);
    }

    /// Collective. New nodal temperatures of the owned nodes (part
    /// order), reached over `dt` seconds (for the temperature rate in the
    /// viscous stress; `None`: no rate).
    pub fn set_temperatures(&mut self, comm: &SimpleCommunicator, owned: &[f64], dt: Option<f64>) {
        self.node_t[..self.n_owned].copy_from_slice(owned);
        let t = &mut self.node_t[..];
        self.halo.forward(comm, &mut [t], 1);
        self.update_element_temperatures(dt);
        self.particles.update_free(&self.node_t);
    }

    /// The temperatures of this rank's particles numbered `gid` (global
    /// particle numbers; issue 21), from the thermal system's sphere rows:
    /// their bonds' free thermal elongations follow. Call after
    /// [`Self::set_temperatures`] (the links read the nodes'). Collective
    /// over the neighbours (the ghost spheres take their owners').
    pub fn set_particle_temperatures(
        &mut self,
        comm: &SimpleCommunicator,
        gid: &[u64],
        t: &[f64],
    ) -> Result<()> {
        self.particles.set_temperatures(comm, gid, t, &self.node_t)
    }

    /// This rank's particles' motion and bond and link states for a
    /// checkpoint (issue 21): spheres, bonds, links by global number.
    pub fn saved_particles(&self) -> [crate::io::checkpoint_particles::GlobalRows; 3] {
        self.particles.saved()
    }

    /// The global numbers of this rank's spheres, bonds and links and the
    /// model's totals, the rows [`Self::restore_particles`] takes.
    pub fn particle_ids(&self) -> ([Vec<u32>; 3], [u64; 3]) {
        self.particles.saved_ids()
    }

    /// Puts the saved rows of [`Self::particle_ids`] (flat) back.
    pub fn restore_particles(&mut self, rows: &[Vec<f64>; 3]) {
        self.particles.restore(rows);
    }

    /// Every particle of body `b` here at the temperature `t(b)` (a
    /// prescribed heating), as [`Self::set_particle_temperatures`].
    pub fn set_particle_body_temperatures(&mut self, t: impl Fn(u32) -> f64) {
        self.particles.set_body_temperatures(t, &self.node_t);
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
        let mut new = new;
        self.hexes
            .element_temperatures(&self.node_t, &self.elem_tref, &mut new);
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

    /// Cohesive joints this rank advances and owns (a joint across a cut
    /// is advanced on both sides' ranks, owned on one).
    pub fn num_joints(&self) -> usize {
        self.joints.num_owned()
    }

    /// Joints broken on this rank since the thermal rows were last numbered.
    pub fn joints_broken_since_rows(&self) -> usize {
        self.joints.broken_since_rows()
    }

    /// This rank's joints' histories for a checkpoint: global joint
    /// numbers and the values of each ([`crate::fracture::set::SAVED_JOINT`]).
    pub fn saved_joints(&self) -> (Vec<u32>, Vec<f64>) {
        self.joints.saved()
    }

    /// The global joint numbers of this rank's joints.
    pub fn joint_gids(&self) -> Vec<u32> {
        self.joints.gids()
    }

    /// Put back the saved histories of this rank's joints (in the order of
    /// [`Self::joint_gids`]); the broken ones' faces become boundary faces.
    pub fn restore_joints(&mut self, values: &[[f64; crate::fracture::set::SAVED_JOINT]]) {
        self.joints.restore(values);
        self.mark_cracks();
    }

    /// Per jointed body here: `[body, joints, broken, crack area, fracture
    /// energy, first break, centroid x, y, z]`.
    pub fn body_cracks(&self) -> Vec<[f64; 9]> {
        self.joints.body_cracks()
    }

    /// This rank's joints for the joint output grid.
    pub fn joint_rows(&self) -> super::JointRows {
        self.joints.output_rows(&self.x)
    }

    /// This rank's particles for the particle output (issue 21).
    pub fn particle_rows(&self) -> super::ParticleRows {
        self.particles.rows()
    }

    /// Whether the cracks whose faces touch changed since the last call
    /// (their contact conducts heat, so the thermal contacts must follow).
    pub fn crack_contacts_changed(&mut self) -> bool {
        self.joints.closed_changed()
    }

    /// The broken joints' tets (global ids), marking the rows as numbered
    /// with them.
    pub fn take_broken_joints(&mut self) -> std::collections::HashSet<[u32; 2]> {
        self.joints.broken_tets()
    }

    /// After `part`'s rows were numbered again: the part's nodes take
    /// their new rows, and the next contact detection (collective) fetches
    /// the ghosts' afresh.
    pub fn renumber_rows(&mut self, part: &Part) {
        let np = self.n_part_nodes;
        self.node_petsc[..np].copy_from_slice(&part.petsc);
        self.part_tets.node_petsc.copy_from_slice(&part.petsc);
        self.redetect = true;
    }

    /// Number of elements this rank integrates.
    pub fn num_elements(&self) -> usize {
        self.elements.len()
    }
}

/// The coordinates of a slice of 3-vectors as one flat slice.
fn flat_mut(v: &mut [Vector3<f64>]) -> &mut [f64] {
    const _: () = assert!(std::mem::size_of::<Vector3<f64>>() == 3 * std::mem::size_of::<f64>());
    // SAFETY: Vector3<f64> is a #[repr(C)] matrix over an array storage of
    // exactly three f64 (size asserted above, alignment that of f64), so a
    // slice of them is 3 × len contiguous f64 with no padding.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut f64, v.len() * 3) }
}
