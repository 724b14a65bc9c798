//! A set of free discrete-element spheres of one kind (issue 21, "Beyond
//! the papers") advanced by the explicit central difference among
//! themselves and against the boundary triangles of Tet4 bodies. Pure:
//! no MPI or PETSc; the serial kernel a rank would run on the spheres it
//! holds.
//!
//! One step ([`FreeSpheres::step`]):
//! 1. sphere pairs from a uniform cell grid (cell = one diameter), taken
//!    in ascending (i, j) order; sphere–triangle touches per (sphere, body)
//!    from a grid of the triangles (cells a diameter or the largest
//!    triangle wide) through [`distinct_features`], in ascending triangle
//!    order;
//! 2. Hertz normal force, viscous damping and Coulomb friction with a
//!    tangential history per sphere pair, and per sphere and body the
//!    history of the contact with the nearest normal the step before
//!    (so rolling from triangle to triangle keeps it) (`contact::sphere`),
//!    with the moments
//!    about each sphere's centre; a triangle's share goes to its nodes with
//!    the contact point's barycentric weights;
//! 3. translation and rotation by the damped central difference of the
//!    bonded particles (`bond::update_particles`) with gravity;
//! 4. with a thermal kind, the pipe-network heat flows of each touch
//!    (`contact::sphere_heat`) and a forward-Euler update of the sphere
//!    temperatures (seed 000 eq 36, θ = 0, as the seed's pipe network);
//!    a face's heat goes to its nodes with the same weights.
//!
//! Every sum runs in that fixed order, so a step repeats bitwise.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;

use super::bond::update_particles;
use crate::contact::sphere::{
    distinct_features, effective_modulus, effective_radius, effective_shear_modulus,
    sphere_triangle, HertzLaw,
};
use crate::contact::sphere_heat::{pipe_flow, pipe_resistance, sphere_capacity};
use crate::geometry::point_grid::PointGrid;

type V3 = Vector3<f64>;

/// The spheres' size and material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereKind {
    /// Radius (m).
    pub radius: f64,
    /// Density (kg/m³).
    pub density: f64,
    /// Young's modulus (Pa) and Poisson's ratio.
    pub young: f64,
    pub poisson: f64,
    /// Conductivity (W/(m K)) and specific heat (J/(kg K)); thermal runs
    /// need both positive.
    pub conductivity: f64,
    pub specific_heat: f64,
}

impl SphereKind {
    /// Mass (kg) and moment of inertia (kg m²) of one sphere:
    /// m = (4/3) π ρ r³, I = (2/5) m r².
    pub fn mass_inertia(&self) -> (f64, f64) {
        let m = 4.0 / 3.0 * std::f64::consts::PI * self.density * self.radius.powi(3);
        (m, 0.4 * m * self.radius * self.radius)
    }

    /// The errors of the kind's constants, naming them under `key`.
    pub fn check(&self, key: &str, thermal: bool) -> Result<(), String> {
        let mut named = vec![
            ("radius", self.radius),
            ("density", self.density),
            ("young", self.young),
        ];
        if thermal {
            named.push(("conductivity", self.conductivity));
            named.push(("specific_heat", self.specific_heat));
        }
        for (name, v) in named {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key}.{name}: must be positive, got {v}"));
            }
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(format!(
                "{key}.poisson: must lie in (-1, 0.5), got {}",
                self.poisson
            ));
        }
        Ok(())
    }
}

/// The contact constants of the spheres with each other and with faces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereContact {
    /// Damping ratio ζ of the normal force.
    pub damping: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
    /// Contact resistance per unit area (K m²/W), FDEM's R_c.
    pub resistance: f64,
}

/// The boundary triangles the spheres meet, over a node array the caller
/// owns: each triangle's nodes, its body and the body's E and ν.
#[derive(Debug, Clone, Default)]
pub struct Faces {
    pub nodes: Vec<[u32; 3]>,
    pub body: Vec<u32>,
    /// Per body: Young's modulus (Pa) and Poisson's ratio.
    pub elastic: Vec<(f64, f64)>,
}

/// The nodes' side of a step: positions and velocities in, forces (N) and
/// heat flows (W) added out. `temperature` is `None` in a run without heat.
pub struct NodeSide<'a> {
    pub x: &'a [V3],
    pub v: &'a [V3],
    pub temperature: Option<&'a [f64]>,
    pub force: &'a mut [V3],
    pub heat: &'a mut [f64],
}

/// What a step reports.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SphereStep {
    /// Touching sphere pairs and sphere–face contacts.
    pub pairs: usize,
    pub faces: usize,
    /// Hertz elastic energy of all contacts (J).
    pub contact_energy: f64,
    /// Largest overlap (m).
    pub max_overlap: f64,
}

/// The spheres and their contact histories.
#[derive(Debug, Clone)]
pub struct FreeSpheres {
    pub kind: SphereKind,
    pub contact: SphereContact,
    /// Mass-proportional damping (1/s) and gravity (m/s²).
    pub damping: f64,
    pub gravity: V3,
    pub x: Vec<V3>,
    pub v: Vec<V3>,
    pub w: Vec<V3>,
    /// One temperature per sphere (K or °C); empty without heat.
    pub t: Vec<f64>,
    /// Spheres held still.
    pub fixed: Vec<bool>,
    pair_history: HashMap<(u32, u32), V3>,
    /// Per sphere, its face contacts' histories: (body, normal, ξ).
    face_history: HashMap<u32, Vec<(u32, V3, V3)>>,
    force: Vec<V3>,
    moment: Vec<V3>,
    heat: Vec<f64>,
}

impl FreeSpheres {
    /// Spheres at rest at `x`, with temperatures `t` (empty without heat).
    ///
    /// # Panics
    /// If `t` is neither empty nor one temperature per sphere.
    pub fn new(kind: SphereKind, contact: SphereContact, x: Vec<V3>, t: Vec<f64>) -> Self {
        let n = x.len();
        assert!(
            t.is_empty() || t.len() == n,
            "free spheres: {} temperatures for {n} spheres",
            t.len()
        );
        FreeSpheres {
            kind,
            contact,
            damping: 0.0,
            gravity: V3::zeros(),
            v: vec![V3::zeros(); n],
            w: vec![V3::zeros(); n],
            fixed: vec![false; n],
            x,
            t,
            pair_history: HashMap::new(),
            face_history: HashMap::new(),
            force: vec![V3::zeros(); n],
            moment: vec![V3::zeros(); n],
            heat: vec![0.0; n],
        }
    }

    /// The touching sphere pairs (i < j), ascending, found on a grid of
    /// cells one diameter wide.
    fn touching_pairs(&self) -> Vec<(u32, u32)> {
        let d = 2.0 * self.kind.radius;
        let grid = PointGrid::of(d, self.x.iter().map(|x| [x.x, x.y, x.z]));
        let mut out = Vec::new();
        for (i, x) in self.x.iter().enumerate() {
            grid.near([x.x, x.y, x.z], |j| {
                if j as usize > i && (self.x[j as usize] - x).norm_squared() < d * d {
                    out.push((i as u32, j));
                }
                true
            });
        }
        out.sort_unstable();
        out
    }

    fn law(&self, e_star: f64, g_star: f64, r_star: f64, mass: f64) -> HertzLaw {
        HertzLaw {
            e_star,
            g_star,
            r_star,
            mass,
            damping: self.contact.damping,
            friction: self.contact.friction,
        }
    }

    /// Advance by `dt`: contact forces and heat with each other and with
    /// `faces` over the nodes of `nodes`, then the motion and the
    /// temperatures. A thermal step (`t` not empty) exchanges heat with the
    /// faces only where `nodes.temperature` is given.
    ///
    /// Errors if a sphere's position, velocity or temperature became
    /// non-finite (an unstable step), naming the sphere.
    pub fn step(&mut self, dt: f64, faces: &Faces, nodes: NodeSide) -> Result<SphereStep, String> {
        let k = self.kind;
        let (mass, inertia) = k.mass_inertia();
        let r = k.radius;
        let thermal = !self.t.is_empty();
        self.force.iter_mut().for_each(|f| *f = self.gravity * mass);
        self.moment.iter_mut().for_each(|m| *m = V3::zeros());
        self.heat.iter_mut().for_each(|q| *q = 0.0);
        let mut report = SphereStep::default();
        // Sphere against sphere.
        let e_ss = effective_modulus(k.young, k.poisson, k.young, k.poisson);
        let g_ss = effective_shear_modulus(k.young, k.poisson, k.young, k.poisson);
        let law = self.law(e_ss, g_ss, effective_radius(r, Some(r)), 0.5 * mass);
        let mut history = std::mem::take(&mut self.pair_history);
        let mut kept = HashMap::with_capacity(history.len());
        for (i, j) in self.touching_pairs() {
            let (a, b) = (i as usize, j as usize);
            let d = self.x[b] - self.x[a];
            let dist = d.norm();
            // Coincident centres (never from `box_sites`) push along x.
            let n = if dist > 0.0 { d / dist } else { V3::x() };
            let delta = 2.0 * r - dist;
            // Contact point velocities: v + ω × (arm), arms ±r n.
            let va = self.v[a] + self.w[a].cross(&(n * r));
            let vb = self.v[b] + self.w[b].cross(&(-n * r));
            let mut xi = history.remove(&(i, j)).unwrap_or_else(V3::zeros);
            let f = law.force(delta, &n, &(va - vb), dt, &mut xi);
            kept.insert((i, j), xi);
            self.force[a] += f.force;
            self.force[b] -= f.force;
            self.moment[a] += (n * r).cross(&f.force);
            self.moment[b] += (-n * r).cross(&(-f.force));
            if thermal {
                let r_ab = pipe_resistance(
                    k.conductivity,
                    Some(k.conductivity),
                    f.radius,
                    self.contact.resistance,
                );
                let q = pipe_flow(self.t[a], self.t[b], r_ab);
                self.heat[a] += q;
                self.heat[b] -= q;
            }
            report.pairs += 1;
            report.contact_energy += f.energy;
            report.max_overlap = report.max_overlap.max(delta);
        }
        self.pair_history = kept;
        // Sphere against the faces: per sphere, the touches of each body,
        // from the triangles of the grid cells its box meets.
        let mut history = std::mem::take(&mut self.face_history);
        let mut kept: HashMap<u32, Vec<(u32, V3, V3)>> = HashMap::with_capacity(history.len());
        let tri_of = |f: usize| faces.nodes[f].map(|n| nodes.x[n as usize]);
        let grid = FaceGrid::new(faces.nodes.len(), 2.0 * r, tri_of);
        let mut near = Vec::new();
        for s in 0..self.x.len() {
            grid.near(&self.x[s], r, &mut near);
            let mut by_body: BTreeMap<u32, Vec<_>> = BTreeMap::new();
            for &f in &near {
                if let Some(touch) = sphere_triangle(&self.x[s], r, &tri_of(f as usize)) {
                    by_body
                        .entry(faces.body[f as usize])
                        .or_default()
                        .push((f, touch));
                }
            }
            let old = history.remove(&(s as u32)).unwrap_or_default();
            for (body, touches) in by_body {
                let (eb, nub) = faces.elastic[body as usize];
                let law = self.law(
                    effective_modulus(k.young, k.poisson, eb, nub),
                    effective_shear_modulus(k.young, k.poisson, eb, nub),
                    effective_radius(r, None),
                    mass,
                );
                for (f, touch) in distinct_features(touches) {
                    let tri = faces.nodes[f as usize];
                    let wts = touch.weights;
                    let arm = touch.point - self.x[s];
                    let vs = self.v[s] + self.w[s].cross(&arm);
                    let vf: V3 = (0..3).map(|c| nodes.v[tri[c] as usize] * wts[c]).sum();
                    let mut xi = crate::contact::sphere::kept_spring(&old, body, &touch.normal);
                    let out = law.force(touch.depth, &touch.normal, &(vs - vf), dt, &mut xi);
                    kept.entry(s as u32)
                        .or_default()
                        .push((body, touch.normal, xi));
                    self.force[s] += out.force;
                    self.moment[s] += arm.cross(&out.force);
                    for c in 0..3 {
                        nodes.force[tri[c] as usize] -= out.force * wts[c];
                    }
                    if let (true, Some(tn)) = (thermal, nodes.temperature) {
                        let r_ab = pipe_resistance(
                            k.conductivity,
                            None,
                            out.radius,
                            self.contact.resistance,
                        );
                        let tf: f64 = (0..3).map(|c| tn[tri[c] as usize] * wts[c]).sum();
                        let q = pipe_flow(self.t[s], tf, r_ab);
                        self.heat[s] += q;
                        for c in 0..3 {
                            nodes.heat[tri[c] as usize] -= q * wts[c];
                        }
                    }
                    report.faces += 1;
                    report.contact_energy += out.energy;
                    report.max_overlap = report.max_overlap.max(touch.depth);
                }
            }
        }
        self.face_history = kept;
        update_particles(
            mass,
            inertia,
            self.damping,
            dt,
            &self.fixed,
            &self.force,
            &self.moment,
            &mut self.x,
            &mut self.v,
            &mut self.w,
        );
        if thermal {
            let c = sphere_capacity(k.density, k.specific_heat, r);
            for (t, q) in self.t.iter_mut().zip(&self.heat) {
                // Seed 000 eq 36 (θ = 0): C_A dT_A/dt = Σ Q.
                *t += dt * q / c;
            }
        }
        let bad = (0..self.x.len()).find(|&i| {
            !(self.x[i]
                .iter()
                .chain(self.v[i].iter())
                .all(|c| c.is_finite())
                && self.t.get(i).is_none_or(|t| t.is_finite()))
        });
        match bad {
            Some(i) => Err(format!(
                "free sphere {i} became non-finite (NaN or infinite): the step {dt:e} s is \
                 above the contacts' stable step (FreeSpheres::stable_dt, stable_heat_dt)"
            )),
            None => Ok(report),
        }
    }

    /// The stable step of the spheres' contacts at overlap up to
    /// `max_overlap`: 0.1 √(m/k_n) with m a sphere's mass and k_n the Hertz
    /// stiffness there against the stiffer partner (a sphere or `faces`'
    /// stiffest body). A pair alone allows 2 √(m*/k_n) = 1.4 √(m/k_n); its
    /// tangential springs and spins (k_t/k_n = 4 G*/E*, I = 0.4 m r²) and
    /// up to 12 touching neighbours bring that to about 0.24 √(m/k_n).
    pub fn stable_dt(&self, faces: &Faces, max_overlap: f64) -> f64 {
        let k = self.kind;
        let (mass, _) = k.mass_inertia();
        let mut e = effective_modulus(k.young, k.poisson, k.young, k.poisson);
        for &(eb, nub) in &faces.elastic {
            e = e.max(effective_modulus(k.young, k.poisson, eb, nub));
        }
        let kn = 2.0 * e * (k.radius * max_overlap).sqrt();
        0.1 * (mass / kn).sqrt()
    }

    /// The largest forward-Euler heat step: the spheres' capacity over
    /// the conductance of `touches` contacts at overlap `max_overlap`,
    /// halved.
    pub fn stable_heat_dt(&self, touches: usize, max_overlap: f64) -> f64 {
        let k = self.kind;
        let a = (k.radius * max_overlap).sqrt();
        let g = 1.0 / pipe_resistance(k.conductivity, None, a, self.contact.resistance);
        0.5 * sphere_capacity(k.density, k.specific_heat, k.radius) / (touches.max(1) as f64 * g)
    }
}

/// The faces binned on a grid of cubes at least a sphere diameter and the
/// largest triangle's box wide, so a triangle lies in at most 8 cells and
/// a sphere's box meets at most 8.
pub(crate) struct FaceGrid {
    h: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl FaceGrid {
    pub(crate) fn new(n: usize, diameter: f64, tri: impl Fn(usize) -> [V3; 3]) -> FaceGrid {
        let boxes: Vec<(V3, V3)> = (0..n)
            .map(|f| {
                let t = tri(f);
                (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]))
            })
            .collect();
        let h = boxes
            .iter()
            .map(|(lo, hi)| (hi - lo).max())
            .fold(diameter, f64::max);
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (f, (lo, hi)) in boxes.iter().enumerate() {
            for_cells(lo, hi, h, |c| cells.entry(c).or_default().push(f as u32));
        }
        FaceGrid { h, cells }
    }

    /// The faces (ascending, once each) in the cells the box of the sphere
    /// at `x` of radius `r` meets.
    pub(crate) fn near(&self, x: &V3, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let e = V3::repeat(r);
        for_cells(&(x - e), &(x + e), self.h, |c| {
            if let Some(list) = self.cells.get(&c) {
                out.extend_from_slice(list);
            }
        });
        out.sort_unstable();
        out.dedup();
    }
}

/// Each grid cell (side `h`) the box [lo, hi] meets.
fn for_cells(lo: &V3, hi: &V3, h: f64, mut f: impl FnMut([i64; 3])) {
    let c = |v: f64| (v / h).floor() as i64;
    for i in c(lo.x)..=c(hi.x) {
        for j in c(lo.y)..=c(hi.y) {
            for k in c(lo.z)..=c(hi.z) {
                f([i, j, k]);
            }
        }
    }
}
