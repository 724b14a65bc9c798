//! The bonded particles of a rank's bodies (issue 21, seed 002) in the
//! explicit loop. A body with particles may be split over the ranks like
//! any large body (`parallel::spheres`): each rank advances the spheres it
//! owns and holds ghost copies of the others its bonds and links reach,
//! whose motion and temperature their owners forward after each update.
//! Each substep, after the owned nodes' forces are summed, the bonds with
//! an owned end (eqs 12–15, `mechanics::bond`) and the links to the
//! elements at an owned sphere or node (`mechanics::interface_link`) are
//! evaluated in the body's fixed bond and link order, the links' forces go
//! to the element nodes with N_I at the bond midpoint (eq 17 there), and
//! the owned spheres advance by the damped central difference with the
//! same mass-proportional damping as the nodes. A bond or link on two
//! ranks is evaluated on both from the same values, and each owned sphere
//! and node takes its terms in the body's order, so the trajectories do
//! not depend on the rank count (bitwise, as the joints).
//!
//! Thermal expansion: each sphere has a temperature (the thermal system's
//! row of the sphere in a coupled run, the body's prescribed heating in a
//! mechanics run); when they are set, each bond's and link's free
//! elongation α ΔT̄ ℓ is made from them (ΔT above the body's reference
//! temperature, as the elements' thermal split; a link's ΔT̄ is the mean of
//! the sphere's and its element point's, Σ N_I T_I at the midpoint), and
//! the springs act on d_n less it (`mechanics::bond::advance_bond`).

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::io::checkpoint_particles::{GlobalRows, SAVED_BOND, SAVED_PARTICLE};
use crate::mechanics::bond::{
    bond_forces, free_elongation, sphere_mass_inertia, update_particles, BondState, BondStiffness,
};
use crate::mechanics::interface_link::{advance_link, LinkEnds};
use crate::mesh::lattice::LatticeBond;
use crate::model::{BodySource, Model};
use crate::parallel::{Halo, Part, PartSpheres};

/// A link with the element nodes as local node numbers.
#[derive(Debug, Clone)]
struct DomainLink {
    /// Local sphere.
    sphere: u32,
    ghost_nodes: [u32; 4],
    ghost_shape: [f64; 4],
    point_nodes: [u32; 4],
    point_shape: [f64; 4],
    kn: f64,
    ks: f64,
    /// (ℓ/2)² of the reference bond (time-step bound); ℓ/2 is the half
    /// bond's rest length.
    half2: f64,
}

/// One body's particles here: the owned spheres (ascending number), then
/// the ghosts (ascending); the bonds and links in the body's order.
#[derive(Debug, Clone)]
pub(super) struct BodyParticles {
    /// Global body id.
    body: u32,
    /// Global number of its first particle, bond and link.
    first: u64,
    first_bond: u64,
    first_link: u64,
    /// Per local sphere, bond and link: its number in the body.
    sphere_id: Vec<u32>,
    bond_id: Vec<u32>,
    link_id: Vec<u32>,
    /// Owned spheres (the first ones).
    n_owned: usize,
    /// Owners forward the ghosts' values.
    halo: Halo,
    stiffness: BondStiffness,
    mass: f64,
    inertia: f64,
    x0: Vec<Vector3<f64>>,
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    w: Vec<Vector3<f64>>,
    force: Vec<Vector3<f64>>,
    moment: Vec<Vector3<f64>>,
    fixed: Vec<bool>,
    /// Bonds over local spheres.
    bonds: Vec<LatticeBond>,
    state: Vec<BondState>,
    links: Vec<DomainLink>,
    link_state: Vec<BondState>,
    /// The links' force on the owned spheres in the last substep (the
    /// elements took its opposite).
    link_total: Vector3<f64>,
    /// Expansion coefficient α (1/K) of the particles' material.
    alpha: f64,
    /// The body's reference (stress-free) temperature.
    reference_t: f64,
    /// Sphere temperatures.
    t: Vec<f64>,
    /// Rest length ℓ of each bond (m).
    rest: Vec<f64>,
    /// Free thermal elongation of each bond and each link (m), from `t`
    /// and the nodes' temperatures when they were last set.
    bond_free: Vec<f64>,
    link_free: Vec<f64>,
}

/// The particles of one rank.
#[derive(Debug, Clone, Default)]
pub(super) struct DomainParticles {
    pub(super) bodies: Vec<BodyParticles>,
    /// Particles, bonds and links of the whole model.
    totals: [u64; 3],
    /// The model's bodies with particles (ascending id), the same on every rank.
    with_particles: Vec<u32>,
}

/// What a substep of the spheres gives the domain's energies and momentum.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ParticleStep {
    /// Kinetic energy (J), translation and rotation.
    pub(super) kinetic: f64,
    /// Energy the mass damping took over the substep (J).
    pub(super) damped: f64,
    /// Linear momentum (kg m/s).
    pub(super) momentum: Vector3<f64>,
}

/// This rank's particles for the output: global numbers, reference
/// positions, displacements and velocities (flat, 3 per particle).
#[derive(Debug, Clone, Default)]
pub struct ParticleRows {
    pub gid: Vec<u64>,
    pub reference: Vec<f64>,
    pub displacement: Vec<f64>,
    pub velocity: Vec<f64>,
}

fn interpolate(shape: &[f64; 4], nodes: &[u32; 4], a: &[Vector3<f64>]) -> Vector3<f64> {
    // seed 002 eq 16: Σ N_I a_I.
    (0..4).map(|k| a[nodes[k] as usize] * shape[k]).sum()
}

fn flat(v: &mut [Vector3<f64>]) -> &mut [f64] {
    const _: () = assert!(std::mem::size_of::<Vector3<f64>>() == 3 * std::mem::size_of::<f64>());
    // SAFETY: Vector3<f64> is a #[repr(C)] matrix over an array storage of
    // exactly three f64 (size asserted above), so a slice of them is
    // 3 × len contiguous f64 with no padding.
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut f64, v.len() * 3) }
}

impl DomainParticles {
    /// Collective. The particles `part` holds (`part.spheres`), with the
    /// links' element nodes among its local nodes. Errors name the body.
    pub(super) fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
    ) -> Result<DomainParticles> {
        let (offsets, total) = model.particle_offsets();
        let mut out = DomainParticles::default();
        let local_node: std::collections::HashMap<u32, u32> = part
            .node_gid
            .iter()
            .enumerate()
            .map(|(l, &g)| (g, l as u32))
            .collect();
        let node_x: Vec<Vector3<f64>> = part.mesh.nodes.iter().map(|&q| Vector3::from(q)).collect();
        let (mut next_bond, mut next_link) = (0u64, 0u64);
        let empty = PartSpheres::default();
        let mut first_error = None;
        for (b, body) in model.bodies.iter().enumerate() {
            let Some(p) = model.body_particles(body) else {
                continue;
            };
            out.with_particles.push(b as u32);
            let (first_bond, first_link) = (next_bond, next_link);
            next_bond += p.region.bonds.len() as u64;
            next_link += p.region.links.len() as u64;
            let here = part.spheres.iter().find(|s| s.body == b as u32);
            let held = here.unwrap_or(&empty);
            // The halo of the body's spheres (every rank takes part).
            let first = offsets[b] as u32;
            let n_owned = held.owned.len();
            let ghosts: Vec<(u32, u32, u32)> = held
                .ghosts
                .iter()
                .zip(&held.ghost_owner)
                .enumerate()
                .map(|(k, (&s, &o))| (first + s, o, (n_owned + k) as u32))
                .collect();
            let owned = &held.owned;
            let halo = Halo::new(comm, &ghosts, |g| {
                owned
                    .binary_search(&(g.wrapping_sub(first)))
                    .ok()
                    .map(|k| k as u32)
            });
            let made = halo
                .map_err(|e| Error::Mechanics(format!("body `{}`: particles: {e}", body.name)))
                .and_then(|halo| {
                    here.map(|h| {
                        let firsts = [offsets[b], first_bond, first_link];
                        BodyParticles::new(model, b, h, halo, &local_node, &node_x, firsts)
                    })
                    .transpose()
                });
            match made {
                Ok(Some(bp)) => out.bodies.push(bp),
                Ok(None) => {}
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        if let Some(e) = first_error {
            return Err(e);
        }
        out.totals = [total, next_bond, next_link];
        Ok(out)
    }

    /// Collective over the neighbours. Copy the owned spheres' motion to
    /// their ghosts on other ranks.
    pub(super) fn forward_motion(&mut self, comm: &SimpleCommunicator) {
        for p in &mut self.bodies {
            let fields: &mut [&mut [f64]] = &mut [flat(&mut p.x), flat(&mut p.v), flat(&mut p.w)];
            p.halo.forward(comm, fields, 3);
        }
    }

    /// Collective over the neighbours. Copy the owned spheres'
    /// temperatures to their ghosts.
    fn forward_temperatures(&mut self, comm: &SimpleCommunicator) {
        for p in &mut self.bodies {
            p.halo.forward(comm, &mut [&mut p.t[..]], 1);
        }
    }

    /// This rank's spheres' motion and bonds' and links' states for a
    /// checkpoint, by global number (`io::checkpoint_particles`): the
    /// owned spheres, the bonds whose first end is owned here and the
    /// links of the owned spheres, so each row comes from one rank.
    pub(super) fn saved(&self) -> [GlobalRows; 3] {
        let mut out: [GlobalRows; 3] = Default::default();
        for (r, &total) in out.iter_mut().zip(&self.totals) {
            r.total = total;
        }
        let bond_row = |s: &BondState| [s.d.x, s.d.y, s.d.z, s.n.x, s.n.y, s.n.z];
        for p in &self.bodies {
            for k in 0..p.n_owned {
                out[0]
                    .gid
                    .push((p.first + u64::from(p.sphere_id[k])) as u32);
                for a in [p.x[k], p.v[k], p.w[k]] {
                    out[0].values.extend_from_slice(a.as_slice());
                }
            }
            for (k, s) in p.state.iter().enumerate() {
                if (p.bonds[k].i as usize) < p.n_owned {
                    out[1]
                        .gid
                        .push((p.first_bond + u64::from(p.bond_id[k])) as u32);
                    out[1].values.extend_from_slice(&bond_row(s));
                }
            }
            for (k, s) in p.link_state.iter().enumerate() {
                if (p.links[k].sphere as usize) < p.n_owned {
                    out[2]
                        .gid
                        .push((p.first_link + u64::from(p.link_id[k])) as u32);
                    out[2].values.extend_from_slice(&bond_row(s));
                }
            }
        }
        out
    }

    /// The global numbers of this rank's spheres (owned and ghosts),
    /// bonds and links, and the model's totals (what [`Self::restore`]
    /// takes rows of).
    pub(super) fn saved_ids(&self) -> ([Vec<u32>; 3], [u64; 3]) {
        let mut ids: [Vec<u32>; 3] = Default::default();
        for p in &self.bodies {
            let firsts = [p.first, p.first_bond, p.first_link];
            let lists = [&p.sphere_id, &p.bond_id, &p.link_id];
            for ((v, f), list) in ids.iter_mut().zip(firsts).zip(lists) {
                v.extend(list.iter().map(|&k| (f + u64::from(k)) as u32));
            }
        }
        (ids, self.totals)
    }

    /// Puts saved rows (flat, in the order of [`Self::saved_ids`]) back.
    pub(super) fn restore(&mut self, rows: &[Vec<f64>; 3]) {
        let (mut s, mut b, mut l) = (
            rows[0].chunks_exact(SAVED_PARTICLE),
            rows[1].chunks_exact(SAVED_BOND),
            rows[2].chunks_exact(SAVED_BOND),
        );
        let v3 = |c: &[f64]| Vector3::new(c[0], c[1], c[2]);
        let bond = |c: &[f64]| BondState {
            d: v3(&c[..3]),
            n: v3(&c[3..]),
        };
        for p in &mut self.bodies {
            for k in 0..p.x.len() {
                let c = s.next().expect("a row per sphere");
                (p.x[k], p.v[k], p.w[k]) = (v3(&c[..3]), v3(&c[3..6]), v3(&c[6..]));
            }
            for st in &mut p.state {
                *st = bond(b.next().expect("a row per bond"));
            }
            for st in &mut p.link_state {
                *st = bond(l.next().expect("a row per link"));
            }
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.bodies.is_empty()
    }

    /// Collective over the neighbours. Sets the temperatures of the owned
    /// spheres numbered `gid` (global particle numbers) to `t`, forwards
    /// them to their ghosts; then [`Self::update_free`].
    pub(super) fn set_temperatures(
        &mut self,
        comm: &SimpleCommunicator,
        gid: &[u64],
        t: &[f64],
        node_t: &[f64],
    ) -> Result<()> {
        let mut missing = None;
        for (&g, &v) in gid.iter().zip(t) {
            let b = self.bodies.partition_point(|p| p.first <= g);
            let slot = b.checked_sub(1).and_then(|b| {
                let p = &mut self.bodies[b];
                let k = p.sphere_id[..p.n_owned]
                    .binary_search(&u32::try_from(g - p.first).ok()?)
                    .ok()?;
                Some(&mut p.t[k])
            });
            match slot {
                Some(x) => *x = v,
                None => {
                    missing.get_or_insert(g);
                }
            }
        }
        self.forward_temperatures(comm);
        if let Some(g) = missing {
            return Err(Error::Mechanics(format!(
                "particle {g} has a temperature but is not here"
            )));
        }
        self.update_free(node_t);
        Ok(())
    }

    /// Sets every sphere of body `b` here to the temperature `t(b)`; then
    /// [`Self::update_free`].
    pub(super) fn set_body_temperatures(&mut self, t: impl Fn(u32) -> f64, node_t: &[f64]) {
        for p in &mut self.bodies {
            let v = t(p.body);
            p.t.iter_mut().for_each(|x| *x = v);
        }
        self.update_free(node_t);
    }

    /// The bonds' and links' free elongations from the spheres'
    /// temperatures and the local nodes' `node_t`.
    pub(super) fn update_free(&mut self, node_t: &[f64]) {
        for p in &mut self.bodies {
            if p.alpha == 0.0 {
                continue;
            }
            let dt = |v: f64| v - p.reference_t;
            for ((e, b), &l) in p.bond_free.iter_mut().zip(&p.bonds).zip(&p.rest) {
                *e = free_elongation(p.alpha, dt(p.t[b.i as usize]), dt(p.t[b.j as usize]), l);
            }
            for (e, l) in p.link_free.iter_mut().zip(&p.links) {
                // seed 002 eq 16: the element point's temperature Σ N_I T_I at the midpoint.
                let tp: f64 = (0..4)
                    .map(|k| node_t[l.point_nodes[k] as usize] * l.point_shape[k])
                    .sum();
                let ts = p.t[l.sphere as usize];
                *e = free_elongation(p.alpha, dt(ts), dt(tp), l.half2.sqrt());
            }
        }
    }

    /// Collective. Per body with particles, a bound on the square of the
    /// highest frequency the particles add (Gershgorin: per sphere over
    /// its bonds and links 2k_n/m + k_s (2/m + 2(ℓ/2)²/I); per element node
    /// over the links at it, k |N_I| (1 + Σ|N_J|)/m_I with k the larger
    /// stiffness), given the owned nodes' masses: over the owned spheres
    /// and nodes (each holds all its bonds and links here), the largest
    /// over the ranks, so the same bits as on one rank.
    pub(super) fn frequencies(
        &self,
        comm: &SimpleCommunicator,
        node_mass: &[f64],
        n_owned_nodes: usize,
    ) -> Vec<(u32, f64)> {
        let mut mine = vec![0.0f64; self.with_particles.len()];
        for p in &self.bodies {
            let mut sphere = vec![0.0; p.x0.len()];
            let (m, inertia) = (p.mass, p.inertia);
            let lam = |kn: f64, ks: f64, half2: f64| {
                2.0 * kn / m + ks * (2.0 / m + 2.0 * half2 / inertia)
            };
            for b in &p.bonds {
                let k = b.kind as usize;
                let half2 = 0.25 * (p.x0[b.j as usize] - p.x0[b.i as usize]).norm_squared();
                let l = b.weight * lam(p.stiffness.normal[k], p.stiffness.tangential[k], half2);
                sphere[b.i as usize] += l;
                sphere[b.j as usize] += l;
            }
            let mut node: std::collections::BTreeMap<u32, f64> = Default::default();
            for l in &p.links {
                sphere[l.sphere as usize] += lam(l.kn, l.ks, l.half2);
                let k = l.kn.max(l.ks);
                let sum: f64 = l.point_shape.iter().map(|v| v.abs()).sum();
                for (q, nq) in l.point_nodes.iter().zip(&l.point_shape) {
                    *node.entry(*q).or_insert(0.0) += k * nq.abs() * (1.0 + sum);
                }
            }
            let s_max = sphere[..p.n_owned].iter().copied().fold(0.0, f64::max);
            let n_max = node
                .iter()
                .filter(|(&q, _)| (q as usize) < n_owned_nodes)
                .map(|(&q, &k)| k / node_mass[q as usize])
                .fold(0.0, f64::max);
            let at = self
                .with_particles
                .binary_search(&p.body)
                .expect("a body with particles");
            mine[at] = s_max.max(n_max);
        }
        let mut all = vec![0.0f64; mine.len()];
        comm.all_reduce_into(&mine[..], &mut all[..], SystemOperation::max());
        self.with_particles.iter().copied().zip(all).collect()
    }

    /// One substep's forces: bonds and links at the spheres' and the
    /// nodes' positions `x` and velocities `v` (local nodes) over `dt`;
    /// the links' forces on the elements are added to `f` (the owned
    /// nodes' entries count). Returns the energy stored in the bonds and
    /// links, each counted on one rank.
    pub(super) fn add_forces(
        &mut self,
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        dt: f64,
        f: &mut [Vector3<f64>],
    ) -> f64 {
        let mut energy = 0.0;
        for p in &mut self.bodies {
            p.link_total = Vector3::zeros();
            p.force.iter_mut().for_each(|a| *a = Vector3::zeros());
            p.moment.iter_mut().for_each(|a| *a = Vector3::zeros());
            bond_forces(
                &p.bonds,
                &mut p.state,
                &p.stiffness,
                &p.x,
                &p.v,
                &p.w,
                dt,
                (p.alpha != 0.0).then_some(&p.bond_free[..]),
                &mut p.force,
                &mut p.moment,
            );
            for ((b, s), &e) in p.bonds.iter().zip(&p.state).zip(&p.bond_free) {
                if (b.i as usize) < p.n_owned {
                    energy += s.energy(&p.stiffness, b, e);
                }
            }
            let links = p.links.iter().zip(p.link_state.iter_mut());
            for ((l, s), &e) in links.zip(&p.link_free) {
                let i = l.sphere as usize;
                let ends = LinkEnds {
                    sphere_x: p.x[i],
                    sphere_v: p.v[i],
                    sphere_w: p.w[i],
                    ghost_x: interpolate(&l.ghost_shape, &l.ghost_nodes, x),
                    ghost_v: interpolate(&l.ghost_shape, &l.ghost_nodes, v),
                    point_v: interpolate(&l.point_shape, &l.point_nodes, v),
                };
                let (fs, ms) = advance_link(s, l.kn, l.ks, &ends, dt, e);
                p.force[i] += fs;
                p.moment[i] += ms;
                for (q, nq) in l.point_nodes.iter().zip(&l.point_shape) {
                    // seed 002 eq 17 at the midpoint: the element's point takes −f with N_I.
                    f[*q as usize] -= fs * *nq;
                }
                if i < p.n_owned {
                    p.link_total += fs;
                    let dn = s.d.dot(&s.n);
                    let dt2 = (s.d.norm_squared() - dn * dn).max(0.0);
                    energy += 0.5 * (l.kn * (dn - e) * (dn - e) + l.ks * dt2);
                }
            }
        }
        energy
    }

    /// Advance the owned spheres over `dt` with `gravity` and the mass
    /// damping (1/s) `damping(body)` gives each body (the ghosts follow
    /// with [`Self::forward_motion`]). Returns the kinetic energy and
    /// momentum at the time level of the forces (t_n: translation and
    /// rotation at the mean of the old and new velocities, as for the
    /// nodes) and the energy the damping took; an error names a particle
    /// that became non-finite.
    pub(super) fn advance(
        &mut self,
        dt: f64,
        damping: impl Fn(u32) -> f64,
        gravity: &Vector3<f64>,
    ) -> Result<ParticleStep> {
        let mut out = ParticleStep::default();
        for p in &mut self.bodies {
            let no = p.n_owned;
            let damping = damping(p.body);
            let weight = gravity * p.mass;
            p.force[..no].iter_mut().for_each(|a| *a += weight);
            let (v_old, w_old) = (p.v[..no].to_vec(), p.w[..no].to_vec());
            update_particles(
                p.mass,
                p.inertia,
                damping,
                dt,
                &p.fixed[..no],
                &p.force[..no],
                &p.moment[..no],
                &mut p.x[..no],
                &mut p.v[..no],
                &mut p.w[..no],
            );
            for k in 0..no {
                if !(p.x[k].iter().all(|c| c.is_finite()) && p.w[k].iter().all(|c| c.is_finite())) {
                    return Err(Error::Mechanics(format!(
                        "particle {} became non-finite (NaN or infinite): the explicit step \
                         is unstable; reduce mechanics.dt or mechanics.safety",
                        p.first + u64::from(p.sphere_id[k])
                    )));
                }
                let (vm, wm) = ((p.v[k] + v_old[k]) * 0.5, (p.w[k] + w_old[k]) * 0.5);
                let twice_kinetic = p.mass * vm.norm_squared() + p.inertia * wm.norm_squared();
                out.damped += damping * dt * twice_kinetic;
                out.kinetic += 0.5 * twice_kinetic;
                out.momentum += vm * p.mass;
            }
        }
        Ok(out)
    }

    /// Per body here, the links' force on its owned spheres in the last
    /// substep (the bonds' cancel over the body): with the nodes' forces
    /// it sums to the contact force on the body.
    pub(super) fn link_totals(&self) -> impl Iterator<Item = (u32, Vector3<f64>)> + '_ {
        self.bodies.iter().map(|p| (p.body, p.link_total))
    }

    /// This rank's owned particles for the output, bodies in global order.
    pub fn rows(&self) -> ParticleRows {
        let mut r = ParticleRows::default();
        for p in &self.bodies {
            for k in 0..p.n_owned {
                let (x, x0, v) = (p.x[k], p.x0[k], p.v[k]);
                r.gid.push(p.first + u64::from(p.sphere_id[k]));
                r.reference.extend_from_slice(&[x0.x, x0.y, x0.z]);
                r.displacement
                    .extend_from_slice(&[x.x - x0.x, x.y - x0.y, x.z - x0.z]);
                r.velocity.extend_from_slice(&[v.x, v.y, v.z]);
            }
        }
        r
    }
}

impl BodyParticles {
    /// Body `b`'s particles `held` here, their ghosts forwarded by `halo`;
    /// `local_node` maps global node ids to local ones (reference
    /// positions `node_x`), `firsts` the body's first particle's, bond's
    /// and link's global numbers. Errors name the body.
    fn new(
        model: &Model,
        b: usize,
        held: &PartSpheres,
        halo: Halo,
        local_node: &std::collections::HashMap<u32, u32>,
        node_x: &[Vector3<f64>],
        firsts: [u64; 3],
    ) -> Result<BodyParticles> {
        let body = &model.bodies[b];
        let p = model.body_particles(body).expect("a body with particles");
        let BodySource::Mesh { mesh, .. } = body.source else {
            unreachable!("particles belong to a source mesh")
        };
        let tets = &model.meshes[mesh as usize].mesh.tets;
        let region = &p.region;
        let err = |msg: String| Error::Mechanics(format!("body `{}`: particles: {msg}", body.name));
        let nodes_of = |src_elem: u32| -> Result<[u32; 4]> {
            let t = tets[src_elem as usize];
            let mut out = [0u32; 4];
            for (o, n) in out.iter_mut().zip(t) {
                *o = *local_node.get(&(body.node_range.0 + n)).ok_or_else(|| {
                    err(format!("a node of element {src_elem} is not on this rank"))
                })?;
            }
            Ok(out)
        };
        let mat = &model.materials[p.material as usize];
        let el = mat
            .elastic
            .ok_or_else(|| err(format!("material `{}` has no elastic constants", mat.name)))?;
        let stiffness = BondStiffness::seed002(el.young, el.poisson, region.radius)
            .map_err(|e| err(format!("material `{}`: {e}", mat.name)))?;
        let (mass, inertia) = sphere_mass_inertia(el.density, region.radius);
        // Local spheres: owned, then ghosts.
        let sphere_id: Vec<u32> = held.owned.iter().chain(&held.ghosts).copied().collect();
        let local_of = |s: u32| -> u32 {
            match held.owned.binary_search(&s) {
                Ok(k) => k as u32,
                Err(_) => {
                    let k = held.ghosts.binary_search(&s).expect("a ghost sphere");
                    (held.owned.len() + k) as u32
                }
            }
        };
        let x0: Vec<Vector3<f64>> = sphere_id
            .iter()
            .map(|&s| Vector3::from(region.centres[s as usize]))
            .collect();
        let n = x0.len();
        let mut links = Vec::with_capacity(held.links.len());
        for &k in &held.links {
            let l = &region.links[k as usize];
            let kind = l.kind as usize;
            links.push(DomainLink {
                sphere: local_of(l.sphere),
                ghost_nodes: nodes_of(l.ghost_elem)?,
                ghost_shape: l.ghost_shape,
                point_nodes: nodes_of(l.point_elem)?,
                point_shape: l.point_shape,
                kn: stiffness.normal[kind] * l.weight,
                ks: stiffness.tangential[kind] * l.weight,
                half2: 0.0,
            });
        }
        let bonds: Vec<LatticeBond> = held
            .bonds
            .iter()
            .map(|&k| {
                let bd = &region.bonds[k as usize];
                LatticeBond {
                    i: local_of(bd.i),
                    j: local_of(bd.j),
                    ..*bd
                }
            })
            .collect();
        for l in &mut links {
            let g = interpolate(&l.ghost_shape, &l.ghost_nodes, node_x);
            l.half2 = 0.25 * (g - x0[l.sphere as usize]).norm_squared();
        }
        let link_state = links
            .iter()
            .map(|l| {
                let g = interpolate(&l.ghost_shape, &l.ghost_nodes, node_x);
                BondState::new(&x0[l.sphere as usize], &g)
            })
            .collect();
        let state = bonds
            .iter()
            .map(|bd| BondState::new(&x0[bd.i as usize], &x0[bd.j as usize]))
            .collect();
        let rest = bonds
            .iter()
            .map(|bd| (x0[bd.j as usize] - x0[bd.i as usize]).norm())
            .collect();
        let (n_bonds, n_links) = (bonds.len(), links.len());
        Ok(BodyParticles {
            body: b as u32,
            first: firsts[0],
            first_bond: firsts[1],
            first_link: firsts[2],
            sphere_id,
            bond_id: held.bonds.clone(),
            link_id: held.links.clone(),
            n_owned: held.owned.len(),
            halo,
            stiffness,
            mass,
            inertia,
            x: x0.clone(),
            x0,
            v: vec![Vector3::from(body.initial_velocity); n],
            w: vec![Vector3::zeros(); n],
            force: vec![Vector3::zeros(); n],
            moment: vec![Vector3::zeros(); n],
            fixed: vec![false; n],
            bonds,
            state,
            links,
            link_state,
            link_total: Vector3::zeros(),
            alpha: el.expansion,
            reference_t: body.reference_temperature,
            t: vec![body.initial_temperature; n],
            rest,
            bond_free: vec![0.0; n_bonds],
            link_free: vec![0.0; n_links],
        })
    }
}
