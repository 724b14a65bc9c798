//! The free discrete-element spheres of one rank (issue 21, beyond the
//! papers) in the explicit loop: the spheres of its slab
//! ([`SphereSlabs`]) and ghost copies of its neighbours' spheres within
//! reach, advanced each substep after the Tet4 nodes' force sum.
//!
//! One substep (collective; three all-to-alls and one all-gather):
//! 1. each rank's owned spheres' box goes to every rank; each rank sends
//!    the boundary triangles of its part's tets (global face key, body
//!    material, nodes with owner, position and velocity) to the ranks
//!    whose box they meet;
//! 2. the contact forces of the owned spheres
//!    ([`crate::mechanics::sphere_contacts`]), the triangles' shares sent
//!    to their nodes' owners, who add them to the owned nodes in (sphere,
//!    contact, corner) order: the same order on any rank count;
//! 3. the owned spheres advance by the damped central difference of the
//!    bonded particles ([`update_particles`]) with gravity;
//! 4. spheres that left the slab go to their new owner with their
//!    springs, and every sphere within reach of another slab goes there
//!    as a ghost.
//!
//! Heat (a thermal run): each sphere has one uniform temperature and
//! capacity ρ c (4/3) π r³. Its contacts conduct through the pipe network
//! ([`crate::contact::sphere_heat`]) in the same pass as the forces, from
//! the face nodes' temperatures of the last thermal step (sent with the
//! triangles). Coupling (design (b) of issue 21): the owned spheres'
//! temperatures advance by forward Euler each substep (seed 000 eq 36,
//! θ = 0), checked against the maximum-principle bound Δt Σg/C ≤ 1; the
//! faces' shares of heat (J) go to the nodes' owners with the forces'
//! and are summed per owned node over the thermal step, then handed to
//! the thermal system as a source released over its next step
//! ([`Self::take_node_heat`]). Why not rows of the one PETSc system (as
//! the bonded particles): the spheres migrate between ranks every
//! substep and touch anew each substep, so rows would be re-laid out and
//! the operator rebuilt far more often than the FE contacts are found;
//! the substep is orders of magnitude below the spheres' thermal time
//! (R C), so the explicit update is both stable and accurate, and the
//! energy moved is the same number on both sides (heat leaving the nodes
//! is heat entering the spheres). Migrants and ghosts carry their
//! temperature.
//!
//! Set-up places every sphere on every rank ([`place_spheres`], seeded)
//! and keeps its slab's: the only moment all spheres are on every rank.

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Vector3;

use crate::contact::sphere_heat::{explicit_fourier, sphere_capacity};
use crate::contact::ContactTets;
use crate::error::{Error, Result};
use crate::mechanics::bond::update_particles;
use crate::mechanics::sphere_contacts::{
    sphere_contacts, stable_dt, FaceView, HeatView, Histories, SetConstants, MAX_OVERLAP,
};
use crate::model::{place_spheres, Model};
use crate::parallel::exchange::{all_gather, all_to_all};
use crate::parallel::{Part, SphereSlabs};

mod restart;

type V3 = Vector3<f64>;

/// Values of a face record: key, body, material, 3 node ids, 3 owners,
/// 3 × x, 3 × v; with heat 3 temperatures more.
const FACE: usize = 27;

/// Values of a sphere record before its springs: migrant flag, number,
/// set, x0, x, v, w, temperature.
const SPHERE: usize = 16;

/// The heat constants of a thermal run's spheres: per set its capacity
/// (J/K), conductivity and material; R_c per material pair.
#[derive(Debug, Clone)]
struct HeatConstants {
    /// Per set also its initial temperature and sphere count.
    initial: Vec<f64>,
    count: Vec<u32>,
    capacity: Vec<f64>,
    conductivity: Vec<f64>,
    material: Vec<u32>,
    rc: Vec<Vec<f64>>,
}

/// The spheres of one rank.
#[derive(Debug, Clone)]
pub(super) struct DomainSpheres {
    sets: Vec<SetConstants>,
    /// Per material: Young's modulus and Poisson's ratio (the faces').
    elastic: Vec<(f64, f64)>,
    slabs: SphereSlabs,
    rank: usize,
    size: usize,
    r_max: f64,
    total: u64,
    /// Owned (ascending number) then ghosts: number, set, reference and
    /// current centre, velocity, spin.
    gid: Vec<u64>,
    set: Vec<u32>,
    x0: Vec<V3>,
    x: Vec<V3>,
    v: Vec<V3>,
    w: Vec<V3>,
    n_owned: usize,
    history: Histories,
    /// Temperature of each held sphere (as `gid`).
    t: Vec<f64>,
    /// A thermal run's constants.
    heat: Option<HeatConstants>,
    /// Per owned node of the part: heat (J) from the spheres' faces, and
    /// Σ N_I g Δt (J/K), since the last [`Self::take_node_heat`].
    node_heat: Vec<f64>,
    node_gdt: Vec<f64>,
    /// Owned node of each global node id, for the faces' shares.
    owned_node: HashMap<u32, u32>,
    /// This rank's share of the energies (J) and momentum, and counts.
    pub(super) report: SphereReport,
}

/// What the spheres add to the mechanics' state, this rank's share.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SphereReport {
    pub kinetic: f64,
    pub momentum: V3,
    pub contact_energy: f64,
    pub gravity_work: f64,
    pub damped: f64,
    pub pairs: u64,
    pub faces: u64,
    /// Heat (J) the owned spheres took from faces since the start, on
    /// the rank where it happened (the sum over the ranks is the total),
    /// and the largest explicit Fourier number Δt Σg/C of an owned
    /// sphere so far.
    pub face_heat_in: f64,
    pub fourier: f64,
}

/// The owned spheres for the output: numbers, reference centres,
/// displacements and velocities (flat, 3 per sphere), and the radii.
pub struct SphereRows {
    pub gid: Vec<u64>,
    pub reference: Vec<f64>,
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
    pub radius: Vec<f64>,
    /// Whether the spheres carry heat, and their temperatures (else empty).
    pub heat: bool,
    pub temperature: Vec<f64>,
    /// All spheres of the model.
    pub total: u64,
}

fn v3(s: &[f64]) -> V3 {
    V3::new(s[0], s[1], s[2])
}

impl DomainSpheres {
    /// Collective. This rank's spheres of the model (None without any),
    /// and their ghosts; `part`'s owned nodes take the faces' shares.
    pub(super) fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
    ) -> Result<Option<Self>> {
        if model.spheres.is_empty() {
            return Ok(None);
        }
        let placed = place_spheres(&model.spheres).map_err(Error::Mechanics)?;
        let sets: Vec<SetConstants> = model
            .spheres
            .iter()
            .map(|s| {
                SetConstants::new(
                    s.radius, s.density, s.young, s.poisson, s.damping, s.friction,
                )
            })
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for s in &model.spheres {
            for d in 0..3 {
                lo[d] = lo[d].min(s.min[d]);
                hi[d] = hi[d].max(s.max[d]);
            }
        }
        let centres: Vec<[f64; 3]> = placed.iter().map(|p| p.1).collect();
        let (rank, size) = (comm.rank() as usize, comm.size() as usize);
        let gravity = model.mechanics.as_ref().map_or([0.0; 3], |m| m.gravity);
        let slabs = SphereSlabs::new(&centres, lo, hi, size, gravity);
        let mine: Vec<usize> = (0..placed.len())
            .filter(|&i| slabs.owner(&placed[i].1) == rank)
            .collect();
        let x: Vec<V3> = mine.iter().map(|&i| V3::from(placed[i].1)).collect();
        let n = mine.len();
        let heat = model.thermal_active.then(|| HeatConstants {
            initial: model.spheres.iter().map(|s| s.temperature).collect(),
            count: model.spheres.iter().map(|s| s.count).collect(),
            capacity: model
                .spheres
                .iter()
                .map(|s| sphere_capacity(s.density, s.specific_heat, s.radius))
                .collect(),
            conductivity: model.spheres.iter().map(|s| s.conductivity).collect(),
            material: model.spheres.iter().map(|s| s.material).collect(),
            rc: model.contact.as_ref().map_or_else(
                || vec![vec![f64::INFINITY; model.materials.len()]; model.materials.len()],
                |c| c.resistance.clone(),
            ),
        });
        let t: Vec<f64> = mine
            .iter()
            .map(|&i| model.spheres[placed[i].0 as usize].temperature)
            .collect();
        let mut out = DomainSpheres {
            r_max: sets.iter().map(|c| c.radius).fold(0.0, f64::max),
            sets,
            elastic: model
                .materials
                .iter()
                .map(|m| {
                    m.elastic
                        .map_or((f64::INFINITY, 0.0), |e| (e.young, e.poisson))
                })
                .collect(),
            slabs,
            rank,
            size,
            total: placed.len() as u64,
            gid: mine.iter().map(|&i| i as u64).collect(),
            set: mine.iter().map(|&i| placed[i].0).collect(),
            x0: x.clone(),
            x,
            v: vec![V3::zeros(); n],
            w: vec![V3::zeros(); n],
            n_owned: n,
            history: Histories::default(),
            t,
            heat,
            node_heat: Vec::new(),
            node_gdt: Vec::new(),
            owned_node: HashMap::new(),
            report: SphereReport::default(),
        };
        drop(placed);
        out.attach(part);
        out.exchange(comm, Vec::new());
        Ok(Some(out))
    }

    /// Take the faces' shares on `part`'s owned nodes (after a repartition).
    pub(super) fn attach(&mut self, part: &Part) {
        self.owned_node = part
            .owned_gids()
            .iter()
            .enumerate()
            .map(|(l, &g)| (g, l as u32))
            .collect();
        self.node_heat = vec![0.0; self.owned_node.len()];
        self.node_gdt = vec![0.0; self.owned_node.len()];
    }

    /// Whether the spheres carry heat (a thermal run).
    pub(super) fn has_heat(&self) -> bool {
        self.heat.is_some()
    }

    /// The heat (J) the spheres' faces gave each owned node of the part
    /// since the last call, and Σ N_I g Δt (J/K) per node; both reset.
    pub(super) fn take_node_heat(&mut self) -> (Vec<f64>, Vec<f64>) {
        let n = self.node_heat.len();
        (
            std::mem::replace(&mut self.node_heat, vec![0.0; n]),
            std::mem::replace(&mut self.node_gdt, vec![0.0; n]),
        )
    }

    /// The heat stored in the owned spheres, Σ C T (J), this rank's share.
    pub(super) fn stored_heat(&self) -> f64 {
        let Some(h) = &self.heat else { return 0.0 };
        (0..self.n_owned)
            .map(|i| h.capacity[self.set[i] as usize] * self.t[i])
            .sum()
    }

    /// The heat all spheres stored at the start, Σ C T₀ (J), from the sets.
    pub(super) fn initial_heat(&self) -> f64 {
        self.heat.as_ref().map_or(0.0, |h| {
            (0..self.sets.len())
                .map(|k| h.capacity[k] * h.initial[k] * f64::from(h.count[k]))
                .sum()
        })
    }

    /// The initial temperature of set `k` (0 without heat).
    pub(super) fn initial_temperature(&self, k: u32) -> f64 {
        self.heat.as_ref().map_or(0.0, |h| h.initial[k as usize])
    }

    /// The owned spheres' lowest and highest temperature (±∞ with none).
    pub(super) fn temperature_range(&self) -> (f64, f64) {
        self.t[..self.n_owned]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            })
    }

    /// Collective. The spheres' stable step ([`stable_dt`]) against the
    /// model's materials and the lightest owned boundary node of a free
    /// body (`mass` and `body` per owned node) over the ranks.
    pub(super) fn stable_dt(
        &self,
        comm: &SimpleCommunicator,
        part: &Part,
        mass: &[f64],
        body: &[u32],
        body_held: &[bool],
    ) -> f64 {
        let mut m_node = f64::INFINITY;
        for (l, &m) in mass.iter().enumerate() {
            if part.boundary_node[l] && !body_held[body[l] as usize] {
                m_node = m_node.min(m);
            }
        }
        let mut all = 0.0;
        comm.all_reduce_into(&m_node, &mut all, mpi::collective::SystemOperation::min());
        let bodies: Vec<(f64, f64)> = self
            .elastic
            .iter()
            .copied()
            .filter(|e| e.0.is_finite())
            .collect();
        stable_dt(&self.sets, &bodies, all)
    }

    /// Collective. One substep of `dt` (module header): forces from the
    /// spheres and the boundary triangles of `tets` at the local nodes'
    /// `x` and `v`; the triangles' shares added to the owned nodes' `f`.
    /// `damping(touching)` is the mass damping of a sphere. With heat, the
    /// local nodes' temperatures `node_t` feed the faces (module header).
    /// Errors (after every message) if a sphere became non-finite,
    /// overlaps too much, or its explicit heat step is unstable.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn substep(
        &mut self,
        comm: &SimpleCommunicator,
        tets: &ContactTets,
        x: &[V3],
        v: &[V3],
        dt: f64,
        gravity: &V3,
        damping: impl Fn(bool) -> f64,
        node_t: &[f64],
        f: &mut [V3],
    ) -> Result<()> {
        let (faces, face_gid, face_owner, face_t) = self.gather_faces(comm, tets, x, v, node_t);
        let heat = self.heat.as_ref().map(|h| HeatView {
            t: &self.t,
            node_t: &face_t,
            conductivity: &h.conductivity,
            material: &h.material,
            rc: &h.rc,
        });
        let view = crate::mechanics::sphere_contacts::SphereView {
            gid: &self.gid,
            set: &self.set,
            x: &self.x,
            v: &self.v,
            w: &self.w,
            n_owned: self.n_owned,
        };
        let c = sphere_contacts(
            &self.sets,
            &view,
            &faces,
            gravity,
            dt,
            &mut self.history,
            heat.as_ref(),
        );
        // The triangles' shares to their nodes' owners, keyed.
        let mut send = vec![Vec::new(); self.size];
        for s in &c.shares {
            let n = s.node as usize;
            let to = &mut send[face_owner[n] as usize];
            to.extend_from_slice(&[f64::from(face_gid[n]), s.sphere as f64, f64::from(s.order)]);
            to.extend_from_slice(s.force.as_slice());
            to.extend_from_slice(&[s.heat * dt, s.conductance * dt]);
        }
        let got = all_to_all(comm, send);
        let mut shares: Vec<(u64, u32, u32, V3, f64, f64)> = got
            .iter()
            .flat_map(|l| l.chunks_exact(8))
            .map(|r| {
                (
                    r[1] as u64,
                    r[2] as u32,
                    r[0] as u32,
                    v3(&r[3..6]),
                    r[6],
                    r[7],
                )
            })
            .collect();
        shares.sort_unstable_by_key(|s| (s.0, s.1, s.2));
        let mut error = None;
        for (sphere, _, node, force, q, gdt) in shares {
            match self.owned_node.get(&node) {
                Some(&l) => {
                    f[l as usize] += force;
                    self.node_heat[l as usize] += q;
                    self.node_gdt[l as usize] += gdt;
                }
                None => {
                    error.get_or_insert(Error::Mechanics(format!(
                        "free sphere {sphere}: a contact's share went to node {node}, not owned here"
                    )));
                }
            }
        }
        // The owned spheres advance.
        let no = self.n_owned;
        let mut report = SphereReport {
            contact_energy: c.energy,
            pairs: c.pairs as u64,
            faces: c.faces as u64,
            ..self.report
        };
        report.kinetic = 0.0;
        report.momentum = V3::zeros();
        // The contacts' dashpot and slip losses join the mass damping's.
        report.damped += c.lost;
        if let Some(h) = &self.heat {
            // Heat leaving the faces' nodes is heat entering the spheres (J).
            report.face_heat_in -= c.shares.iter().map(|s| s.heat * dt).sum::<f64>();
            for i in 0..no {
                let cap = h.capacity[self.set[i] as usize];
                // Seed 000 eq 36 with θ = 0: Tⁿ⁺¹ = Tⁿ + Δt Q/C.
                self.t[i] += dt * c.heat[i] / cap;
                report.fourier = report
                    .fourier
                    .max(explicit_fourier(dt, c.conductance[i], cap));
                if !self.t[i].is_finite() {
                    error.get_or_insert(Error::Mechanics(format!(
                        "free sphere {}: its temperature became non-finite",
                        self.gid[i]
                    )));
                }
            }
            if report.fourier > 1.0 {
                error.get_or_insert(Error::Mechanics(format!(
                    "free spheres: the explicit heat step is unstable (Δt Σg/C = {:.3} > 1 at \
                     the substep {dt:e} s): a sphere's contacts conduct too well for its \
                     capacity; reduce mechanics.dt or raise the contact resistance",
                    report.fourier
                )));
            }
        }
        for i in 0..no {
            let k = &self.sets[self.set[i] as usize];
            let alpha = damping(c.touching[i]);
            let (x_old, v_old, w_old) = (self.x[i], self.v[i], self.w[i]);
            let r = i..i + 1;
            update_particles(
                k.mass,
                k.inertia,
                alpha,
                dt,
                &[false],
                &c.force[r.clone()],
                &c.moment[r.clone()],
                &mut self.x[r.clone()],
                &mut self.v[r.clone()],
                &mut self.w[r],
            );
            // Not in the seeds: energies at the half step, the mass damping's
            // loss α (m v² + I ω²) Δt.
            let (v_mid, w_mid) = (0.5 * (v_old + self.v[i]), 0.5 * (w_old + self.w[i]));
            let twice = k.mass * v_mid.norm_squared() + k.inertia * w_mid.norm_squared();
            report.kinetic += 0.5 * twice;
            report.momentum += k.mass * v_mid;
            report.gravity_work += k.mass * gravity.dot(&(self.x[i] - x_old));
            report.damped += alpha * twice * dt;
            let finite = self.x[i]
                .iter()
                .chain(self.v[i].iter())
                .all(|c| c.is_finite());
            if !finite {
                error.get_or_insert(Error::Mechanics(format!(
                    "free sphere {} became non-finite (NaN or infinite): the explicit step \
                     {dt:e} s is unstable; reduce mechanics.dt or mechanics.safety",
                    self.gid[i]
                )));
            }
        }
        if c.max_overlap_ratio > MAX_OVERLAP {
            error.get_or_insert(Error::Mechanics(format!(
                "free spheres overlap by {:.1} % of a radius (more than {:.0} %): the load is \
                 too high for their modulus, or the step too long",
                100.0 * c.max_overlap_ratio,
                100.0 * MAX_OVERLAP
            )));
        }
        self.report = report;
        // Migrants and ghosts.
        let leaving: Vec<usize> = (0..no)
            .filter(|&i| self.slabs.owner(&self.x[i].into()) != self.rank)
            .collect();
        self.exchange(comm, leaving);
        match error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Collective. The boundary triangles of every rank's `tets` that meet
    /// this rank's owned spheres' box, ascending by key, and per face node
    /// its global id and owner.
    fn gather_faces(
        &self,
        comm: &SimpleCommunicator,
        tets: &ContactTets,
        x: &[V3],
        v: &[V3],
        node_t: &[f64],
    ) -> (FaceView, Vec<u32>, Vec<u32>, Vec<f64>) {
        let heat = self.heat.is_some();
        let width = if heat { FACE + 3 } else { FACE };
        let mut mine = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for i in 0..self.n_owned {
            let r = self.sets[self.set[i] as usize].radius;
            for d in 0..3 {
                mine[d] = mine[d].min(self.x[i][d] - r);
                mine[3 + d] = mine[3 + d].max(self.x[i][d] + r);
            }
        }
        let boxes = all_gather(comm, &mine);
        let mut send = vec![Vec::new(); self.size];
        for t in 0..tets.len() {
            let mask = tets.mask[t];
            if mask == 0 {
                continue;
            }
            let nodes = tets.tets[t];
            for face in 0..4 {
                if mask & (1 << face) == 0 {
                    continue;
                }
                let tri: Vec<usize> = (0..4)
                    .filter(|&k| k != face)
                    .map(|k| nodes[k] as usize)
                    .collect();
                let (mut lo, mut hi) = (x[tri[0]], x[tri[0]]);
                for &n in &tri[1..] {
                    lo = lo.inf(&x[n]);
                    hi = hi.sup(&x[n]);
                }
                for (r, b) in boxes.chunks_exact(6).enumerate() {
                    if (0..3).any(|d| lo[d] > b[3 + d] || hi[d] < b[d]) {
                        continue;
                    }
                    let to = &mut send[r];
                    to.push((u64::from(tets.gid[t]) * 4 + face as u64) as f64);
                    to.push(f64::from(tets.body[t]));
                    to.push(f64::from(tets.material[t]));
                    to.extend(tri.iter().map(|&n| f64::from(tets.node_gid[n])));
                    to.extend(tri.iter().map(|&n| f64::from(tets.node_owner[n])));
                    for &n in &tri {
                        to.extend_from_slice(x[n].as_slice());
                    }
                    for &n in &tri {
                        to.extend_from_slice(v[n].as_slice());
                    }
                    if heat {
                        to.extend(tri.iter().map(|&n| node_t[n]));
                    }
                }
            }
        }
        let got = all_to_all(comm, send);
        let mut records: Vec<&[f64]> = got.iter().flat_map(|l| l.chunks_exact(width)).collect();
        records.sort_unstable_by_key(|r| r[0] as u64);
        let mut faces = FaceView::default();
        let (mut node_gid, mut node_owner, mut face_t) = (Vec::new(), Vec::new(), Vec::new());
        let mut local: HashMap<u32, u32> = HashMap::new();
        for r in records {
            let key = r[0] as u64;
            faces.key.push(key);
            faces.body.push(r[1] as u32);
            faces.elastic.push(self.elastic[r[2] as usize]);
            faces.material.push(r[2] as u32);
            let mut tri = [0u32; 3];
            for k in 0..3 {
                let g = r[3 + k] as u32;
                tri[k] = *local.entry(g).or_insert_with(|| {
                    node_gid.push(g);
                    node_owner.push(r[6 + k] as u32);
                    faces.x.push(v3(&r[9 + 3 * k..]));
                    faces.v.push(v3(&r[18 + 3 * k..]));
                    if heat {
                        face_t.push(r[FACE + k]);
                    }
                    (node_gid.len() - 1) as u32
                });
            }
            faces.nodes.push(tri);
        }
        (faces, node_gid, node_owner, face_t)
    }

    /// Collective. Send the owned spheres `leaving` (ascending) to their
    /// new owners with their springs, every owned sphere within reach of
    /// another slab there as a ghost; keep the rest, take what arrives.
    fn exchange(&mut self, comm: &SimpleCommunicator, leaving: Vec<usize>) {
        let no = self.n_owned;
        let mut send = vec![Vec::new(); self.size];
        let mut going = vec![false; no];
        for &i in &leaving {
            going[i] = true;
        }
        // Springs of the pairs with a leaving end, by that end.
        let mut pair_springs: HashMap<u64, Vec<(u64, V3)>> = HashMap::new();
        if !leaving.is_empty() {
            let gone: std::collections::HashSet<u64> =
                leaving.iter().map(|&i| self.gid[i]).collect();
            for (&(a, b), xi) in &self.history.pair {
                for (end, other) in [(a, b), (b, a)] {
                    if gone.contains(&end) {
                        pair_springs.entry(end).or_default().push((other, *xi));
                    }
                }
            }
        }
        for (i, &gone) in going.iter().enumerate() {
            let xa: [f64; 3] = self.x[i].into();
            let owner = self.slabs.owner(&xa);
            let reach = self.sets[self.set[i] as usize].radius + self.r_max;
            let record = |migrant: bool| {
                let mut r = vec![
                    f64::from(u8::from(migrant)),
                    self.gid[i] as f64,
                    f64::from(self.set[i]),
                ];
                for a in [&self.x0[i], &self.x[i], &self.v[i], &self.w[i]] {
                    r.extend_from_slice(a.as_slice());
                }
                r.push(self.t[i]);
                r
            };
            for k in self.slabs.within(&xa, reach, owner) {
                send[k].extend(record(false));
                send[k].push(0.0);
                send[k].push(0.0);
            }
            if gone {
                let mut r = record(true);
                let springs = pair_springs.remove(&self.gid[i]).unwrap_or_default();
                r.push(springs.len() as f64);
                for (other, xi) in springs {
                    r.push(other as f64);
                    r.extend_from_slice(xi.as_slice());
                }
                let faces = self.history.face.remove(&self.gid[i]).unwrap_or_default();
                r.push(faces.len() as f64);
                for (body, n, xi) in faces {
                    r.push(f64::from(body));
                    r.extend_from_slice(n.as_slice());
                    r.extend_from_slice(xi.as_slice());
                }
                send[owner].extend(r);
            }
        }
        let got = all_to_all(comm, send);
        // Kept owned spheres, then the arrivals.
        let mut owned: Vec<(u64, u32, [V3; 4], f64)> = (0..no)
            .filter(|&i| !going[i])
            .map(|i| {
                (
                    self.gid[i],
                    self.set[i],
                    [self.x0[i], self.x[i], self.v[i], self.w[i]],
                    self.t[i],
                )
            })
            .collect();
        let mut ghosts = Vec::new();
        for list in got.iter() {
            let mut at = 0;
            while at < list.len() {
                let r = &list[at..];
                let sphere = (
                    r[1] as u64,
                    r[2] as u32,
                    [v3(&r[3..]), v3(&r[6..]), v3(&r[9..]), v3(&r[12..])],
                    r[15],
                );
                at += SPHERE;
                let np = list[at] as usize;
                at += 1;
                for _ in 0..np {
                    let other = list[at] as u64;
                    let key = (sphere.0.min(other), sphere.0.max(other));
                    self.history
                        .pair
                        .entry(key)
                        .or_insert_with(|| v3(&list[at + 1..]));
                    at += 4;
                }
                let nf = list[at] as usize;
                at += 1;
                if nf > 0 {
                    let h = (0..nf)
                        .map(|k| {
                            let s = &list[at + 7 * k..];
                            (s[0] as u32, v3(&s[1..]), v3(&s[4..]))
                        })
                        .collect();
                    self.history.face.insert(sphere.0, h);
                    at += 7 * nf;
                }
                if r[0] > 0.0 {
                    owned.push(sphere);
                } else {
                    ghosts.push(sphere);
                }
            }
        }
        owned.sort_unstable_by_key(|s| s.0);
        ghosts.sort_unstable_by_key(|s| s.0);
        self.n_owned = owned.len();
        self.gid.clear();
        self.set.clear();
        for a in [&mut self.x0, &mut self.x, &mut self.v, &mut self.w] {
            a.clear();
        }
        self.t.clear();
        for (g, s, m, t) in owned.into_iter().chain(ghosts) {
            self.t.push(t);
            self.gid.push(g);
            self.set.push(s);
            self.x0.push(m[0]);
            self.x.push(m[1]);
            self.v.push(m[2]);
            self.w.push(m[3]);
        }
    }

    /// Number of owned spheres.
    pub(super) fn num_owned(&self) -> usize {
        self.n_owned
    }

    /// The owned spheres for the output.
    pub(super) fn rows(&self) -> SphereRows {
        let no = self.n_owned;
        let flat = |a: &[V3]| {
            a[..no]
                .iter()
                .flat_map(|p| [p.x, p.y, p.z])
                .collect::<Vec<f64>>()
        };
        let disp: Vec<V3> = (0..no).map(|i| self.x[i] - self.x0[i]).collect();
        SphereRows {
            gid: self.gid[..no].to_vec(),
            reference: flat(&self.x0),
            displacement: flat(&disp),
            velocity: flat(&self.v),
            radius: self.set[..no]
                .iter()
                .map(|&s| self.sets[s as usize].radius)
                .collect(),
            heat: self.heat.is_some(),
            temperature: match self.heat {
                Some(_) => self.t[..no].to_vec(),
                None => Vec::new(),
            },
            total: self.total,
        }
    }
}
