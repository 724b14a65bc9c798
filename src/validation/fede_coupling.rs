//! The FE–DE interface of the serial coupled drivers
//! ([`super::coupled_cantilever`], [`super::fede_patch`]): one layer of
//! ghost particles inside the boundary Hex8 elements (seed 002 eq 5), the
//! bonds of the lattice, and the forces the two sides exchange, in one of
//! two forms ([`Coupling`]).
//!
//! [`Coupling::Seed`] is seed 002 as written (eqs 16–17), plus the ghost
//! spin of [`crate::mechanics::ghost`]: a ghost–sphere bond is an ordinary
//! bond whose ghost end moves with the element, and the force (and moment)
//! on the ghost go back to the element's nodes with N_I at the ghost. A
//! ghost sits a distance r inside the element, so in uniform tension the
//! boundary element's inner nodes receive r/h of the interface force
//! directly and the element carries only 1 − r/h of the stress (measured by
//! the patch test, `docs/validation.md`).
//!
//! [`Coupling::Interface`] (the default) evaluates each ghost–sphere bond at
//! its midpoint, which lies on the interface: the FE end of the bond is the
//! element's material point there (velocity Σ N_I(ξ_o) v_I, eq 16 at ξ_o),
//! its force goes back with N_I(ξ_o) (eq 17 at ξ_o), and the bond is the
//! sphere's half only (stiffness doubled: two half springs of 2k in series
//! make the lattice's k; the element already holds the ghost's half cell).
//! Velocity and force are taken at the same point, so the coupling is
//! work-conjugate (it conserves energy) and needs no ghost spin: the
//! element's material point carries the rotation. The ghost's position only
//! gives the bond's direction. For any uniform strain the half bond carries
//! exactly the force of the lattice's full bond, so uniform tension passes
//! the patch test.

use nalgebra::Vector3;

use crate::mechanics::bond::{advance_bond, bond_forces, bond_heat, BondState, BondStiffness};
use crate::mechanics::ghost::{ghost_position, hex8_ghost, Ghost};
use crate::mechanics::hex8::InverseMapError;
use crate::mesh::heat_links::{outward_edge, split_weights, Beside};
use crate::mesh::lattice::{BondKind, Lattice, LatticeBond};

/// How a ghost–sphere bond acts on the finite elements (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coupling {
    /// Seed 002 eqs 16–17 at the ghost (with the ghost spin).
    Seed,
    /// The bond's sphere half, attached to the element at the bond's
    /// midpoint on the interface.
    #[default]
    Interface,
}

/// A ghost–sphere bond of [`Coupling::Interface`].
#[derive(Debug, Clone, PartialEq)]
struct Link {
    /// The sphere.
    sphere: usize,
    /// The ghost particle (its position gives the direction).
    ghost: usize,
    /// The element's material point at the bond's midpoint.
    point: Ghost,
    /// Neighbour group.
    kind: BondKind,
    /// Weight of the half bond (twice the lattice's weight).
    weight: f64,
}

/// A half bond that carries heat between a sphere and an element's point,
/// for [`Coupling::Interface`]: each link with its conductance weight, and
/// the outward edge half bonds of the spheres on the lattice's lateral
/// faces ([`crate::mesh::heat_links`]).
#[derive(Debug, Clone, PartialEq)]
struct HeatPoint {
    /// The sphere.
    sphere: usize,
    /// The ghost across the interface (for the section the flow crosses).
    ghost: usize,
    /// The element's material point at the half bond's far end.
    point: Ghost,
    /// Neighbour group.
    kind: BondKind,
    /// Weight of the half bond's conductance.
    weight: f64,
}

/// The ghost layer and the bonds of a coupled lattice.
#[derive(Debug, Clone)]
pub(crate) struct GhostLayer {
    coupling: Coupling,
    /// (particle, ghost in its element).
    ghosts: Vec<(usize, Ghost)>,
    /// Bonds handled by [`bond_forces`]: sphere–sphere, and ghost–sphere for
    /// [`Coupling::Seed`].
    pub bonds: Vec<LatticeBond>,
    /// Their states.
    pub state: Vec<BondState>,
    /// Ghost–sphere bonds of [`Coupling::Interface`].
    links: Vec<Link>,
    /// Their states.
    link_state: Vec<BondState>,
    /// The links as lattice bonds (for the time-step bound and the section forces).
    link_bonds: Vec<LatticeBond>,
    /// The half bonds that carry heat ([`Coupling::Interface`]).
    heat_links: Vec<HeatPoint>,
}

impl GhostLayer {
    /// The layer for `lattice` whose particles with `normal[p] = Some(n)`
    /// are ghosts mirrored from the sphere at `p + δ` along n (n points from
    /// the FE into the DE region, along a lattice axis). `hexes` and `x0`
    /// are the FE elements and reference nodes; `locate(x)` gives the
    /// element (index into `hexes`) that holds the point x. Ghost–ghost
    /// bonds are dropped (the elements carry that material).
    pub fn new(
        coupling: Coupling,
        lattice: &Lattice,
        normal: &[Option<Vector3<f64>>],
        hexes: &[[u32; 8]],
        x0: &[Vector3<f64>],
        locate: impl Fn(&Vector3<f64>) -> usize,
    ) -> Result<Self, InverseMapError> {
        let radius = lattice.radius;
        let c = lattice.counts;
        let p0: Vec<Vector3<f64>> = lattice.centres.iter().map(|p| Vector3::from(*p)).collect();
        let is_ghost = |p: usize| normal[p].is_some();
        let elem_nodes = |e: usize| hexes[e].map(|a| x0[a as usize]);
        let mut ghosts = Vec::new();
        for (p, n) in normal.iter().enumerate() {
            let Some(n) = n else { continue };
            // The boundary sphere one spacing along n.
            let xb = p0[p] + n * (2.0 * radius);
            let xg = ghost_position(&xb, radius, n);
            debug_assert!((xg - p0[p]).norm() < 1e-9 * radius);
            let e = locate(&xg);
            ghosts.push((p, hex8_ghost(&elem_nodes(e), &xg, e)?));
        }
        // Does sphere s have a neighbour at lattice offset o?
        let has = |s: usize, o: [i64; 3]| {
            let q = [s % c[0], (s / c[0]) % c[1], s / (c[0] * c[1])];
            (0..3).all(|a| {
                let v = q[a] as i64 + o[a];
                v >= 0 && v < c[a] as i64
            })
        };
        let mut bonds = Vec::new();
        let mut links = Vec::new();
        let mut link_bonds = Vec::new();
        let mut heat_links = Vec::new();
        // The particle at offset d from particle s, if inside the lattice's box.
        let at = |s: usize, d: [i64; 3]| {
            let q = [s % c[0], (s / c[0]) % c[1], s / (c[0] * c[1])];
            let v: [i64; 3] = std::array::from_fn(|a| q[a] as i64 + d[a]);
            ((0..3).all(|a| v[a] >= 0 && v[a] < c[a] as i64))
                .then(|| (v[0] + c[0] as i64 * (v[1] + c[1] as i64 * v[2])) as usize)
        };
        for b in &lattice.bonds {
            let (i, j) = (b.i as usize, b.j as usize);
            match (is_ghost(i), is_ghost(j)) {
                (true, true) => continue,
                (false, false) => {
                    bonds.push(*b);
                    continue;
                }
                _ => {}
            }
            let (s, g) = if is_ghost(i) { (j, i) } else { (i, j) };
            let o = ((p0[g] - p0[s]) / (2.0 * radius)).map(|v| v.round() as i64);
            // The lattice's boundary weight w = (f_s + f_g)/2 (mesh::lattice docs): f = 2/c with c
            // the neighbours along ±o. The sphere's: 2 without a neighbour on its far side. The
            // ghost's as if the lattice went on through the FE region: 2 only if its own far
            // neighbour leaves the body sideways.
            let f_s = if has(s, [-o[0], -o[1], -o[2]]) {
                1.0
            } else {
                2.0
            };
            let n_g = normal[g].unwrap_or_default();
            let lateral = |a: usize| n_g[a] == 0.0;
            let q = [g % c[0], (g / c[0]) % c[1], g / (c[0] * c[1])];
            let far_inside = (0..3).filter(|&a| lateral(a)).all(|a| {
                let v = q[a] as i64 + o[a];
                v >= 0 && v < c[a] as i64
            });
            let f_g = if far_inside { 1.0 } else { 2.0 };
            let weight = 0.5 * (f_s + f_g);
            match coupling {
                Coupling::Seed => bonds.push(LatticeBond { weight, ..*b }),
                Coupling::Interface => {
                    let mid = (p0[s] + p0[g]) * 0.5;
                    // The midpoint is on the element face: locate it from just inside the ghost side.
                    let e = locate(&(mid + (p0[g] - mid) * 1e-6));
                    let point = hex8_ghost(&elem_nodes(e), &mid, e)?;
                    // Half bond: twice the stiffness (module docs).
                    let w = 2.0 * weight;
                    // Heat: the outward edge half bond of a sphere on a lateral face (heat_links docs).
                    let beside = |d: [i64; 3]| match at(s, d) {
                        None => Beside::Empty,
                        Some(q) if is_ghost(q) => Beside::Ghost,
                        Some(_) => Beside::Sphere,
                    };
                    let mut heat = HeatPoint {
                        sphere: s,
                        ghost: g,
                        point: point.clone(),
                        kind: b.kind,
                        weight: w,
                    };
                    if let Some((star, p)) = outward_edge([o[0], o[1], o[2]], beside) {
                        let mut across = [0; 3];
                        across[p] = star[p];
                        let face_ghost = at(s, across).expect("outward_edge found a ghost there");
                        let end = p0[s] + Vector3::from(star.map(|v| v as f64)) * radius;
                        let e = locate(&(end + (p0[face_ghost] - end) * 1e-6));
                        let (inward, out) = split_weights(weight);
                        heat.weight = inward;
                        heat_links.push(heat);
                        heat_links.push(HeatPoint {
                            sphere: s,
                            ghost: face_ghost,
                            point: hex8_ghost(&elem_nodes(e), &end, e)?,
                            kind: b.kind,
                            weight: out,
                        });
                    } else {
                        heat_links.push(heat);
                    }
                    links.push(Link {
                        sphere: s,
                        ghost: g,
                        point,
                        kind: b.kind,
                        weight: w,
                    });
                    link_bonds.push(LatticeBond {
                        i: s as u32,
                        j: g as u32,
                        kind: b.kind,
                        weight: w,
                    });
                }
            }
        }
        let state = bonds
            .iter()
            .map(|b| BondState::new(&p0[b.i as usize], &p0[b.j as usize]))
            .collect();
        let link_state = links
            .iter()
            .map(|l| BondState::new(&p0[l.sphere], &p0[l.ghost]))
            .collect();
        Ok(Self {
            coupling,
            ghosts,
            bonds,
            state,
            links,
            link_state,
            link_bonds,
            heat_links,
        })
    }

    /// The elements that carry ghosts or interface points.
    pub fn coupled_elements(&self) -> Vec<usize> {
        let mut e: Vec<usize> = self
            .ghosts
            .iter()
            .map(|(_, g)| g.elem)
            .chain(self.links.iter().map(|l| l.point.elem))
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    /// All bonds with their weights, links included (time-step bound).
    pub fn all_bonds(&self) -> impl Iterator<Item = &LatticeBond> {
        self.bonds.iter().chain(&self.link_bonds)
    }

    /// Energy stored in the bonds (J): lattice bonds and, for
    /// [`Coupling::Interface`], the links (the spheres' halves of the
    /// ghost–sphere bonds), each ½ k_n d_n² + ½ k_s |d_t|² with its weight.
    pub fn stored_energy(&self, stiffness: &BondStiffness) -> f64 {
        let lattice: f64 = (self.bonds.iter().zip(&self.state))
            .map(|(b, s)| s.energy(stiffness, b, 0.0))
            .sum();
        let links: f64 = (self.link_bonds.iter().zip(&self.link_state))
            .map(|(b, s)| s.energy(stiffness, b, 0.0))
            .sum();
        lattice + links
    }

    /// Each bond's force on its particle i (weights included), with i and j:
    /// lattice bonds first, then links (i = sphere, j = ghost).
    pub fn bond_force_list(&self, stiffness: &BondStiffness) -> Vec<(usize, usize, Vector3<f64>)> {
        let force = |s: &BondState, kn: f64, ks: f64| {
            let dn = s.d.dot(&s.n);
            s.n * (kn * dn) + (s.d - s.n * dn) * ks
        };
        let mut out: Vec<_> = self
            .bonds
            .iter()
            .zip(&self.state)
            .map(|(b, s)| {
                let k = b.kind as usize;
                let f = force(
                    s,
                    stiffness.normal[k] * b.weight,
                    stiffness.tangential[k] * b.weight,
                );
                (b.i as usize, b.j as usize, f)
            })
            .collect();
        out.extend(self.links.iter().zip(&self.link_state).map(|(l, s)| {
            let k = l.kind as usize;
            let w = l.weight;
            let f = force(s, stiffness.normal[k] * w, stiffness.tangential[k] * w);
            (l.sphere, l.ghost, f)
        }));
        out
    }

    /// One step of the interface and the lattice: places the ghosts on the
    /// elements' nodes `x` (velocities `v`), updates every bond over `dt`,
    /// adds the bond forces and moments to the spheres' `pf`, `pm` and the
    /// coupling forces to the nodes' `f`. `px`, `pv`, `pw` are the particles'
    /// positions and velocities (the ghosts' entries are overwritten).
    #[allow(clippy::too_many_arguments)]
    pub fn add_forces(
        &mut self,
        stiffness: &BondStiffness,
        hexes: &[[u32; 8]],
        x: &[Vector3<f64>],
        v: &[Vector3<f64>],
        dt: f64,
        f: &mut [Vector3<f64>],
        px: &mut [Vector3<f64>],
        pv: &mut [Vector3<f64>],
        pw: &mut [Vector3<f64>],
        pf: &mut [Vector3<f64>],
        pm: &mut [Vector3<f64>],
    ) {
        // seed 002 eq 16: ghosts follow their elements (and spin with them for Seed, ghost module docs).
        for (p, g) in &self.ghosts {
            let h = hexes[g.elem];
            let hv = h.map(|q| v[q as usize]);
            px[*p] = g.interpolate(&h.map(|q| x[q as usize]));
            pv[*p] = g.interpolate(&hv);
            pw[*p] = match self.coupling {
                Coupling::Seed => g.spin(&hv),
                Coupling::Interface => Vector3::zeros(),
            };
        }
        bond_forces(
            &self.bonds,
            &mut self.state,
            stiffness,
            px,
            pv,
            pw,
            dt,
            None,
            pf,
            pm,
        );
        match self.coupling {
            Coupling::Seed => {
                // seed 002 eq 17: ghost forces (and moments) back to the element's nodes.
                for (p, g) in &self.ghosts {
                    let h = hexes[g.elem];
                    let mut nodal = [Vector3::zeros(); 8];
                    g.scatter_force(&pf[*p], &mut nodal);
                    g.scatter_moment(&pm[*p], &mut nodal);
                    for (q, fq) in h.iter().zip(nodal) {
                        f[*q as usize] += fq;
                    }
                }
            }
            Coupling::Interface => {
                for (l, s) in self.links.iter().zip(self.link_state.iter_mut()) {
                    let h = hexes[l.point.elem];
                    let branch = px[l.ghost] - px[l.sphere];
                    let n = branch.normalize();
                    // seed 002 eq 16 at the midpoint: the element's material point there.
                    let v_point = l.point.interpolate(&h.map(|q| v[q as usize]));
                    // Moment arm at mid-step, as in bond_forces.
                    let half = (branch - (pv[l.ghost] - pv[l.sphere]) * (0.5 * dt)) * 0.5;
                    // seed 002 eq 15 for the sphere, eq 14 for the relative velocity.
                    let vo = pv[l.sphere] + pw[l.sphere].cross(&half);
                    let (k, w) = (l.kind as usize, l.weight);
                    let (kn, ks) = (stiffness.normal[k] * w, stiffness.tangential[k] * w);
                    let fb = advance_bond(s, kn, ks, &n, &(v_point - vo), dt, 0.0);
                    pf[l.sphere] += fb;
                    pm[l.sphere] += half.cross(&fb);
                    // seed 002 eq 17 at the midpoint: the force on the element, −f, with N_I(ξ_o).
                    let mut nodal = [Vector3::zeros(); 8];
                    l.point.scatter_force(&(-fb), &mut nodal);
                    for (q, fq) in h.iter().zip(nodal) {
                        f[*q as usize] += fq;
                    }
                }
            }
        }
    }
}

impl GhostLayer {
    /// Heat flows of the lattice and the interface at nodal temperatures
    /// `t` and particle temperatures `pt` (the ghosts' entries are
    /// overwritten with Σ N_I T_I): each bond conducts with `h` per group
    /// (times its weight); the heat into the spheres is added to `pq`, the
    /// heat the interface gives the elements to the nodes' `q` (W).
    /// [`Coupling::Seed`]: a ghost takes its element's temperature at the
    /// ghost and returns its heat with N_I there; [`Coupling::Interface`]:
    /// each ghost–sphere bond is the sphere's half (conductance doubled)
    /// between the sphere and the element's material point at the bond
    /// midpoint, temperature and heat with N_I there, and a sphere on a
    /// lateral face also conducts through its outward edge half bond to the
    /// face's edge (weights of [`crate::mesh::heat_links`]). Either way the
    /// heat is conserved and the flows are symmetric in the temperatures.
    #[allow(clippy::too_many_arguments)]
    pub fn add_heat(
        &self,
        h: &[f64; 3],
        hexes: &[[u32; 8]],
        t: &[f64],
        pt: &mut [f64],
        q: &mut [f64],
        pq: &mut [f64],
    ) {
        for (p, g) in &self.ghosts {
            pt[*p] = g.temperature(&hexes[g.elem].map(|a| t[a as usize]));
        }
        // Flux equivalence (mechanics::bond docs): Q_{j→i} = h w (T_j − T_i).
        bond_heat(&self.bonds, h, pt, pq);
        match self.coupling {
            Coupling::Seed => {
                for (p, g) in &self.ghosts {
                    let mut nodal = [0.0; 8];
                    g.scatter_heat(pq[*p], &mut nodal);
                    for (a, qa) in hexes[g.elem].iter().zip(nodal) {
                        q[*a as usize] += qa;
                    }
                    pq[*p] = 0.0;
                }
            }
            Coupling::Interface => {
                for l in &self.heat_links {
                    let e = hexes[l.point.elem];
                    let t_point = l.point.temperature(&e.map(|a| t[a as usize]));
                    // Half bond of conductance 2 h w: Q into the sphere from the point.
                    let flow = h[l.kind as usize] * l.weight * (t_point - pt[l.sphere]);
                    pq[l.sphere] += flow;
                    let mut nodal = [0.0; 8];
                    l.point.scatter_heat(-flow, &mut nodal);
                    for (a, qa) in e.iter().zip(nodal) {
                        q[*a as usize] += qa;
                    }
                }
            }
        }
    }
}

impl GhostLayer {
    /// Each bond's heat flow (W) from its particle i to j at nodal
    /// temperatures `t` and particle temperatures `pt` (ghosts' entries as
    /// [`GhostLayer::add_heat`] leaves them): lattice bonds first, then the
    /// links of [`Coupling::Interface`] (i = sphere, j = ghost, the flow from
    /// the sphere to the element's point at the bond midpoint).
    pub fn heat_flows(
        &self,
        h: &[f64; 3],
        hexes: &[[u32; 8]],
        t: &[f64],
        pt: &[f64],
    ) -> Vec<(usize, usize, f64)> {
        let mut out: Vec<_> = self
            .bonds
            .iter()
            .map(|b| {
                let (i, j) = (b.i as usize, b.j as usize);
                (i, j, h[b.kind as usize] * b.weight * (pt[i] - pt[j]))
            })
            .collect();
        out.extend(self.heat_links.iter().map(|l| {
            let e = hexes[l.point.elem];
            let t_point = l.point.temperature(&e.map(|a| t[a as usize]));
            (
                l.sphere,
                l.ghost,
                h[l.kind as usize] * l.weight * (pt[l.sphere] - t_point),
            )
        }));
        out
    }
}

/// Bound on the highest circular frequency of bonded spheres of mass
/// `mass` and inertia `inertia` at `x` (Schur test over bonds: per bond
/// 2k_n/m + k_s (2/m + 2(ℓ/2)²/I), weights included).
pub(crate) fn schur_bound<'a>(
    bonds: impl Iterator<Item = &'a LatticeBond>,
    k: &BondStiffness,
    x: &[Vector3<f64>],
    mass: f64,
    inertia: f64,
) -> f64 {
    let mut bound = vec![0.0; x.len()];
    for b in bonds {
        let (i, j) = (b.i as usize, b.j as usize);
        let half2 = 0.25 * (x[j] - x[i]).norm_squared();
        let kind = b.kind as usize;
        let lam = b.weight
            * (2.0 * k.normal[kind] / mass
                + k.tangential[kind] * (2.0 / mass + 2.0 * half2 / inertia));
        bound[i] += lam;
        bound[j] += lam;
    }
    bound.iter().copied().fold(0.0, f64::max).sqrt()
}

/// The centres of `lattice`, and the interface normal (+x) of its first
/// layer in x: the spheres that meet an FE region below them in x.
pub fn x_interface(lattice: &Lattice) -> (Vec<Vector3<f64>>, Vec<Option<Vector3<f64>>>) {
    let nx = lattice.counts[0];
    let p0: Vec<Vector3<f64>> = lattice.centres.iter().map(|p| Vector3::from(*p)).collect();
    let normal = (0..p0.len())
        .map(|p| (p % nx == 0).then(Vector3::x))
        .collect();
    (p0, normal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::bond::bond_conductance;
    use crate::mesh::hex8::hex_box;
    use crate::mesh::lattice::cubic_lattice;

    const R: f64 = 0.125e-3;

    /// The layer, the elements, their nodes and the particles.
    type Setup = (
        GhostLayer,
        Vec<[u32; 8]>,
        Vec<Vector3<f64>>,
        Vec<Vector3<f64>>,
    );

    /// 2×2×2 Hex8 of side 4r on [0, 8r]³, spheres on [8r, 16r] × [0, 8r]²
    /// with their ghost layer inside the elements.
    fn setup(coupling: Coupling) -> Setup {
        let h = 4.0 * R;
        let mesh = hex_box([0.0; 3], [2.0 * h; 3], [2; 3]).unwrap();
        let x0: Vec<Vector3<f64>> = mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let lattice = cubic_lattice(
            [2.0 * h - 2.0 * R, 0.0, 0.0],
            [4.0 * h, 2.0 * h, 2.0 * h],
            R,
            false,
        )
        .unwrap();
        let (p0, normal) = super::x_interface(&lattice);
        let locate = |p: &Vector3<f64>| {
            let c = [0, 1, 2].map(|a| ((p[a] / h).floor().max(0.0) as usize).min(1));
            c[0] + 2 * (c[1] + 2 * c[2])
        };
        let layer = GhostLayer::new(coupling, &lattice, &normal, &mesh.hexes, &x0, locate).unwrap();
        (layer, mesh.hexes, x0, p0)
    }

    #[test]
    fn interface_heat_is_conserved_and_symmetric() {
        for coupling in [Coupling::Seed, Coupling::Interface] {
            let (layer, hexes, x0, p0) = setup(coupling);
            let cond = bond_conductance(2.0, R);
            let ghosts: Vec<usize> = layer.ghosts.iter().map(|(p, _)| *p).collect();
            let flows = |t: &[f64], pt: &[f64]| {
                let mut pt = pt.to_vec();
                let (mut q, mut pq) = (vec![0.0; x0.len()], vec![0.0; p0.len()]);
                layer.add_heat(&cond, &hexes, t, &mut pt, &mut q, &mut pq);
                (q, pq)
            };
            // Arbitrary temperatures: the heat is conserved.
            let t: Vec<f64> = (0..x0.len()).map(|i| ((i * 37) % 11) as f64).collect();
            let pt: Vec<f64> = (0..p0.len()).map(|i| ((i * 13) % 7) as f64).collect();
            let (q, pq) = flows(&t, &pt);
            let total: f64 = q.iter().sum::<f64>() + pq.iter().sum::<f64>();
            let scale: f64 = q.iter().chain(&pq).map(|v| v.abs()).sum();
            assert!(
                total.abs() < 1e-13 * scale,
                "{coupling:?}: {total} of {scale}"
            );
            assert!(ghosts
                .iter()
                .all(|&g| pq[g] == 0.0 || coupling == Coupling::Interface));
            // Symmetric: the heat into node a from a unit temperature at sphere s equals the
            // heat into sphere s from a unit temperature at node a.
            let s = layer.links.first().map_or(1, |l| l.sphere);
            let a = hexes[1][1] as usize;
            let mut ts = vec![0.0; p0.len()];
            ts[s] = 1.0;
            let (q_a, _) = flows(&vec![0.0; x0.len()], &ts);
            let mut ta = vec![0.0; x0.len()];
            ta[a] = 1.0;
            let (_, pq_s) = flows(&ta, &vec![0.0; p0.len()]);
            assert!((q_a[a] - pq_s[s]).abs() < 1e-15 * cond[0], "{coupling:?}");
            assert!(
                q_a[a] != 0.0,
                "{coupling:?}: node {a} and sphere {s} are not coupled"
            );
        }
    }

    #[test]
    fn rigid_rotation_gives_no_interface_force() {
        // The ghost spin of Seed uses the reference gradients (small rotations, ghost docs):
        // 0.005 rad; the interface points carry any rotation: 0.5 rad.
        for (coupling, steps) in [(Coupling::Seed, 10), (Coupling::Interface, 1000)] {
            let (mut layer, hexes, x0, p0) = setup(coupling);
            let stiffness = BondStiffness::seed002(1e9, 0.23, R).unwrap();
            let omega = Vector3::new(0.3, -0.5, 0.8) * 1e3;
            let centre = Vector3::repeat(4.0 * R);
            let rigid = |x: &[Vector3<f64>], t: f64| -> Vec<Vector3<f64>> {
                let rot = nalgebra::Rotation3::from_scaled_axis(omega * t);
                x.iter().map(|p| centre + rot * (p - centre)).collect()
            };
            let dt = 5e-7;
            let (mut x, mut px) = (x0.clone(), p0.clone());
            let mut pw = vec![omega; p0.len()];
            let (mut f, mut pf, mut pm) = (
                vec![Vector3::zeros(); x0.len()],
                vec![Vector3::zeros(); p0.len()],
                vec![Vector3::zeros(); p0.len()],
            );
            for step in 1..=steps {
                let (nx, npx) = (rigid(&x0, step as f64 * dt), rigid(&p0, step as f64 * dt));
                let v: Vec<Vector3<f64>> = nx.iter().zip(&x).map(|(a, b)| (a - b) / dt).collect();
                let mut pv: Vec<Vector3<f64>> =
                    npx.iter().zip(&px).map(|(a, b)| (a - b) / dt).collect();
                (x, px) = (nx, npx);
                f.iter_mut().for_each(|a| *a = Vector3::zeros());
                pf.iter_mut().for_each(|a| *a = Vector3::zeros());
                pm.iter_mut().for_each(|a| *a = Vector3::zeros());
                layer.add_forces(
                    &stiffness, &hexes, &x, &v, dt, &mut f, &mut px, &mut pv, &mut pw, &mut pf,
                    &mut pm,
                );
                pw.iter_mut().for_each(|w| *w = omega);
            }
            // |ω|Δt = 5e-4; time-discretisation error O(steps (|ω|Δt)³ ℓ).
            let bound = 1e-5 * stiffness.normal[0] * 2.0 * R;
            let worst = f.iter().chain(&pf).map(|a| a.norm()).fold(0.0, f64::max);
            assert!(worst < bound, "{coupling:?}: {worst} vs {bound}");
        }
    }
}
