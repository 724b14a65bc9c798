//! The bonded particles of a rank's bodies (issue 21, seed 002) in the
//! explicit loop. A body with particles is held whole by one rank
//! (`parallel::build` never splits it), so its spheres, bonds, ghosts and
//! links live there: each substep, after the owned nodes' forces are
//! summed, the bonds (eqs 12–15, `mechanics::bond`) and the links to the
//! elements (`mechanics::interface_link`) are evaluated in the body's
//! fixed bond and link order, the links' forces go to the element nodes
//! with N_I at the bond midpoint (eq 17 there), and the spheres advance by
//! the damped central difference with the same mass-proportional damping
//! as the nodes. The sums do not depend on the rank count.
//!
//! Thermal expansion: each sphere has a temperature (the thermal system's
//! row of the sphere in a coupled run, the body's prescribed heating in a
//! mechanics run); when they are set, each bond's and link's free
//! elongation α ΔT̄ ℓ is made from them (ΔT above the body's reference
//! temperature, as the elements' thermal split; a link's ΔT̄ is the mean of
//! the sphere's and its element point's, Σ N_I T_I at the midpoint), and
//! the springs act on d_n less it (`mechanics::bond::advance_bond`).

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::io::checkpoint_particles::{GlobalRows, SAVED_BOND, SAVED_PARTICLE};
use crate::mechanics::bond::{
    bond_forces, free_elongation, sphere_mass_inertia, update_particles, BondState, BondStiffness,
};
use crate::mechanics::interface_link::{advance_link, LinkEnds};
use crate::mesh::lattice::LatticeBond;
use crate::model::Model;
use crate::parallel::Part;

/// A link with the element nodes as local node numbers.
#[derive(Debug, Clone)]
struct DomainLink {
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

/// One body's particles.
#[derive(Debug, Clone)]
pub(super) struct BodyParticles {
    /// Global body id.
    body: u32,
    /// Global number of its first particle, bond and link.
    first: u64,
    first_bond: u64,
    first_link: u64,
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
    bonds: Vec<LatticeBond>,
    state: Vec<BondState>,
    links: Vec<DomainLink>,
    link_state: Vec<BondState>,
    /// The links' force on the spheres in the last substep (the
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

impl DomainParticles {
    /// The particles of the bodies `part` holds; their link nodes must be
    /// owned (`n_owned`). Errors name the body.
    pub(super) fn new(model: &Model, part: &Part, n_owned: usize) -> Result<DomainParticles> {
        let (offsets, total) = model.particle_offsets();
        let mut out = DomainParticles::default();
        let (mut next_bond, mut next_link) = (0u64, 0u64);
        for (b, body) in model.bodies.iter().enumerate() {
            let Some(p) = model.body_particles(body) else {
                continue;
            };
            let (first_bond, first_link) = (next_bond, next_link);
            next_bond += p.region.bonds.len() as u64;
            next_link += p.region.links.len() as u64;
            let local = |src_elem: u32| {
                part.elem_gid
                    .binary_search(&(body.elem_range.0 + src_elem))
                    .ok()
            };
            let region = &p.region;
            if local(region.links[0].point_elem).is_none() {
                continue;
            }
            let err =
                |msg: String| Error::Mechanics(format!("body `{}`: particles: {msg}", body.name));
            let nodes_of = |src_elem: u32| -> Result<[u32; 4]> {
                let e = local(src_elem)
                    .ok_or_else(|| err(format!("element {} is not on this rank", src_elem)))?;
                let t = part.mesh.tets[e];
                if t.iter().any(|&l| l as usize >= n_owned) {
                    return Err(err(format!("element {src_elem} has nodes of another rank")));
                }
                Ok(t)
            };
            let mat = &model.materials[p.material as usize];
            let el = mat
                .elastic
                .ok_or_else(|| err(format!("material `{}` has no elastic constants", mat.name)))?;
            let stiffness = BondStiffness::seed002(el.young, el.poisson, region.radius)
                .map_err(|e| err(format!("material `{}`: {e}", mat.name)))?;
            let (mass, inertia) = sphere_mass_inertia(el.density, region.radius);
            let x0: Vec<Vector3<f64>> = region.centres.iter().map(|&c| Vector3::from(c)).collect();
            let n = x0.len();
            let mut links = Vec::with_capacity(region.links.len());
            for l in &region.links {
                let k = l.kind as usize;
                links.push(DomainLink {
                    sphere: l.sphere,
                    ghost_nodes: nodes_of(l.ghost_elem)?,
                    ghost_shape: l.ghost_shape,
                    point_nodes: nodes_of(l.point_elem)?,
                    point_shape: l.point_shape,
                    kn: stiffness.normal[k] * l.weight,
                    ks: stiffness.tangential[k] * l.weight,
                    half2: 0.0,
                });
            }
            let x_nodes: Vec<Vector3<f64>> =
                part.mesh.nodes.iter().map(|&q| Vector3::from(q)).collect();
            for l in &mut links {
                let g = interpolate(&l.ghost_shape, &l.ghost_nodes, &x_nodes);
                l.half2 = 0.25 * (g - x0[l.sphere as usize]).norm_squared();
            }
            let link_state = links
                .iter()
                .map(|l| {
                    let g = interpolate(&l.ghost_shape, &l.ghost_nodes, &x_nodes);
                    BondState::new(&x0[l.sphere as usize], &g)
                })
                .collect();
            let state = region
                .bonds
                .iter()
                .map(|bd| BondState::new(&x0[bd.i as usize], &x0[bd.j as usize]))
                .collect();
            let rest = region
                .bonds
                .iter()
                .map(|bd| (x0[bd.j as usize] - x0[bd.i as usize]).norm())
                .collect();
            let (n_bonds, n_links) = (region.bonds.len(), links.len());
            out.bodies.push(BodyParticles {
                body: b as u32,
                first: offsets[b],
                first_bond,
                first_link,
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
                bonds: region.bonds.clone(),
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
            });
        }
        out.totals = [total, next_bond, next_link];
        Ok(out)
    }

    /// This rank's spheres' motion and bonds' and links' states for a
    /// checkpoint, by global number (`io::checkpoint_particles`).
    pub(super) fn saved(&self) -> [GlobalRows; 3] {
        let mut out: [GlobalRows; 3] = Default::default();
        for (r, &total) in out.iter_mut().zip(&self.totals) {
            r.total = total;
        }
        let bond_row = |s: &BondState| [s.d.x, s.d.y, s.d.z, s.n.x, s.n.y, s.n.z];
        for p in &self.bodies {
            for k in 0..p.x.len() {
                out[0].gid.push((p.first + k as u64) as u32);
                for a in [p.x[k], p.v[k], p.w[k]] {
                    out[0].values.extend_from_slice(a.as_slice());
                }
            }
            for (k, s) in p.state.iter().enumerate() {
                out[1].gid.push((p.first_bond + k as u64) as u32);
                out[1].values.extend_from_slice(&bond_row(s));
            }
            for (k, s) in p.link_state.iter().enumerate() {
                out[2].gid.push((p.first_link + k as u64) as u32);
                out[2].values.extend_from_slice(&bond_row(s));
            }
        }
        out
    }

    /// The global numbers of this rank's spheres, bonds and links, and
    /// the model's totals (what [`Self::restore`] takes rows of).
    pub(super) fn saved_ids(&self) -> ([Vec<u32>; 3], [u64; 3]) {
        let mut ids: [Vec<u32>; 3] = Default::default();
        for p in &self.bodies {
            let firsts = [p.first, p.first_bond, p.first_link];
            let counts = [p.x.len(), p.state.len(), p.link_state.len()];
            for ((v, f), n) in ids.iter_mut().zip(firsts).zip(counts) {
                v.extend((0..n as u64).map(|k| (f + k) as u32));
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

    /// Sets the temperatures of the spheres numbered `gid` (global particle
    /// numbers of bodies here) to `t`; then [`Self::update_free`].
    pub(super) fn set_temperatures(
        &mut self,
        gid: &[u64],
        t: &[f64],
        node_t: &[f64],
    ) -> Result<()> {
        for (&g, &v) in gid.iter().zip(t) {
            let b = self.bodies.partition_point(|p| p.first <= g);
            let p = b
                .checked_sub(1)
                .map(|b| &mut self.bodies[b])
                .filter(|p| g - p.first < p.t.len() as u64)
                .ok_or_else(|| {
                    Error::Mechanics(format!("particle {g} has a temperature but is not here"))
                })?;
            p.t[(g - p.first) as usize] = v;
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

    /// Per body here, a bound on the square of the highest frequency the
    /// particles add (Gershgorin: per sphere over its bonds and links
    /// 2k_n/m + k_s (2/m + 2(ℓ/2)²/I); per element node over the links at
    /// it, k |N_I| (1 + Σ|N_J|)/m_I with k the larger stiffness), given the
    /// owned nodes' masses.
    pub(super) fn frequencies(&self, node_mass: &[f64]) -> Vec<(u32, f64)> {
        self.bodies
            .iter()
            .map(|p| {
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
                let s_max = sphere.iter().copied().fold(0.0, f64::max);
                let n_max = node
                    .iter()
                    .map(|(&q, &k)| k / node_mass[q as usize])
                    .fold(0.0, f64::max);
                (p.body, s_max.max(n_max))
            })
            .collect()
    }

    /// One substep's forces: bonds and links at the spheres' and the
    /// nodes' positions `x` and velocities `v` (local nodes) over `dt`;
    /// the links' forces on the elements are added to `f`. Returns the
    /// energy stored in the bonds and links.
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
                energy += s.energy(&p.stiffness, b, e);
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
                p.link_total += fs;
                for (q, nq) in l.point_nodes.iter().zip(&l.point_shape) {
                    // seed 002 eq 17 at the midpoint: the element's point takes −f with N_I.
                    f[*q as usize] -= fs * *nq;
                }
                let dn = s.d.dot(&s.n);
                let dt2 = (s.d.norm_squared() - dn * dn).max(0.0);
                energy += 0.5 * (l.kn * (dn - e) * (dn - e) + l.ks * dt2);
            }
        }
        energy
    }

    /// Advance the spheres over `dt` with `gravity` and the mass damping
    /// (1/s) `damping(body)` gives each body. Returns the kinetic energy
    /// and momentum at the time level of the forces (t_n: translation and
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
            let damping = damping(p.body);
            let weight = gravity * p.mass;
            p.force.iter_mut().for_each(|a| *a += weight);
            let (v_old, w_old) = (p.v.clone(), p.w.clone());
            update_particles(
                p.mass, p.inertia, damping, dt, &p.fixed, &p.force, &p.moment, &mut p.x, &mut p.v,
                &mut p.w,
            );
            for k in 0..p.x.len() {
                if !(p.x[k].iter().all(|c| c.is_finite()) && p.w[k].iter().all(|c| c.is_finite())) {
                    return Err(Error::Mechanics(format!(
                        "particle {} became non-finite (NaN or infinite): the explicit step \
                         is unstable; reduce mechanics.dt or mechanics.safety",
                        p.first + k as u64
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

    /// Per body here, the links' force on its spheres in the last substep
    /// (the bonds' cancel): with the nodes' forces it sums to the contact
    /// force on the body.
    pub(super) fn link_totals(&self) -> impl Iterator<Item = (u32, Vector3<f64>)> + '_ {
        self.bodies.iter().map(|p| (p.body, p.link_total))
    }

    /// This rank's particles for the output, bodies in global order.
    pub fn rows(&self) -> ParticleRows {
        let mut r = ParticleRows::default();
        for p in &self.bodies {
            for k in 0..p.x.len() {
                let (x, x0, v) = (p.x[k], p.x0[k], p.v[k]);
                r.gid.push(p.first + k as u64);
                r.reference.extend_from_slice(&[x0.x, x0.y, x0.z]);
                r.displacement
                    .extend_from_slice(&[x.x - x0.x, x.y - x0.y, x.z - x0.z]);
                r.velocity.extend_from_slice(&[v.x, v.y, v.z]);
            }
        }
        r
    }
}
