//! The contact forces on one rank's free spheres (issue 21, beyond the
//! papers), over the spheres it owns and the ghost copies of its
//! neighbours' spheres near them, and the boundary triangles of the Tet4
//! bodies near them. Pure: no MPI or PETSc; the caller brings the ghosts
//! and the triangles and routes the triangles' shares to their nodes.
//!
//! The laws are those of [`crate::contact::sphere`] (Hertz normal force
//! with viscous damping, Mindlin spring capped by Coulomb friction) as the
//! serial [`super::free_spheres::FreeSpheres`] applies them, with spheres
//! of several sets (radius, material) and global numbers:
//! - every pair of touching spheres with an owned end, in ascending
//!   (lower, higher global number) order, evaluated from the same values
//!   on both ends' ranks, its force added to the owned ends;
//! - per owned sphere and body, the touching triangles in ascending global
//!   face key order through [`distinct_features`];
//!
//! With a [`HeatView`] (a thermal run) each contact also conducts
//! through the pipe network of [`crate::contact::sphere_heat`] (seed 000
//! eqs 33–35 carried to spheres, contact radius a = √(R* δ)): a pair's
//! flow goes to its owned ends, a face's to the sphere and, with the
//! contact point's weights N_I, to the face's nodes (the shares).
//!
//! So every owned sphere sums its forces (and heat) in an order that does not depend
//! on the rank count, and a triangle's share of a contact is keyed by
//! (sphere number, contact order, corner) for the node's owner to add in
//! that order.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;

use super::free_spheres::FaceGrid;
use crate::contact::sphere::{
    distinct_features, effective_modulus, effective_radius, effective_shear_modulus,
    sphere_triangle, HertzLaw,
};
use crate::contact::sphere_heat::{contact_radius, pipe_conductance};
use crate::geometry::point_grid::PointGrid;

type V3 = Vector3<f64>;

/// The overlap (a fraction of the radius) the stable step is sized for.
pub const DESIGN_OVERLAP: f64 = 0.01;
/// The largest overlap (a fraction of the radius) a run accepts: the
/// step sized at [`DESIGN_OVERLAP`] stays stable to about 0.3 (k_n ∝ √δ).
pub const MAX_OVERLAP: f64 = 0.1;

/// The constants of one sphere set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetConstants {
    /// Radius (m), mass (kg), moment of inertia (kg m²).
    pub radius: f64,
    pub mass: f64,
    pub inertia: f64,
    /// Young's modulus (Pa) and Poisson's ratio.
    pub young: f64,
    pub poisson: f64,
    /// Damping ratio ζ and Coulomb coefficient μ of its contacts.
    pub damping: f64,
    pub friction: f64,
}

impl SetConstants {
    /// A set of spheres of `radius` and `density`: m = (4/3) π ρ r³,
    /// I = (2/5) m r² (a solid sphere).
    pub fn new(
        radius: f64,
        density: f64,
        young: f64,
        poisson: f64,
        damping: f64,
        friction: f64,
    ) -> Self {
        let mass = 4.0 / 3.0 * std::f64::consts::PI * density * radius.powi(3);
        SetConstants {
            radius,
            mass,
            inertia: 0.4 * mass * radius * radius,
            young,
            poisson,
            damping,
            friction,
        }
    }
}

/// The spheres a rank holds: the owned ones first (ascending global
/// number), then the ghosts.
pub struct SphereView<'a> {
    pub gid: &'a [u64],
    pub set: &'a [u32],
    pub x: &'a [V3],
    pub v: &'a [V3],
    pub w: &'a [V3],
    pub n_owned: usize,
}

/// Boundary triangles, ascending by `key` (unique), over their own node
/// arrays.
#[derive(Debug, Clone, Default)]
pub struct FaceView {
    pub key: Vec<u64>,
    pub body: Vec<u32>,
    /// Per face: its body's Young's modulus (Pa) and Poisson's ratio.
    pub elastic: Vec<(f64, f64)>,
    pub nodes: Vec<[u32; 3]>,
    pub x: Vec<V3>,
    pub v: Vec<V3>,
    /// Per face: its body's material (for the contact resistance).
    pub material: Vec<u32>,
}

/// What a thermal run's contacts conduct with: the held spheres'
/// temperatures (owned then ghosts, as [`SphereView`]), the face nodes'
/// (as [`FaceView::x`]), per set its conductivity (W/(m K)) and material,
/// and the contact resistance per unit area R_c (K m²/W) per material
/// pair (infinite: the pair does not conduct).
pub struct HeatView<'a> {
    pub t: &'a [f64],
    pub node_t: &'a [f64],
    pub conductivity: &'a [f64],
    pub material: &'a [u32],
    pub rc: &'a [Vec<f64>],
}

/// The tangential springs: per sphere pair (lower, higher number), and
/// per sphere its face contacts' (body, normal, ξ).
#[derive(Debug, Clone, Default)]
pub struct Histories {
    pub pair: HashMap<(u64, u64), V3>,
    pub face: HashMap<u64, Vec<(u32, V3, V3)>>,
}

/// A triangle corner's share of a sphere–face contact force (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeShare {
    /// Index into [`FaceView::x`].
    pub node: u32,
    /// The sphere's number and 3 × (its face contact's order) + corner.
    pub sphere: u64,
    pub order: u32,
    pub force: V3,
    /// Heat flow into the node (W) and its share N_I g of the conductance
    /// (W/K); zero without heat.
    pub heat: f64,
    pub conductance: f64,
}

/// What [`sphere_contacts`] gives.
#[derive(Debug, Clone, Default)]
pub struct ContactForces {
    /// Per owned sphere: force with its weight, moment, and whether it touches anything.
    pub force: Vec<V3>,
    pub moment: Vec<V3>,
    pub touching: Vec<bool>,
    /// Per owned sphere with heat: the heat flow into it (W) and the sum
    /// of its contacts' conductances (W/K); empty without heat.
    pub heat: Vec<f64>,
    pub conductance: Vec<f64>,
    /// The triangles' shares, in the sphere's order.
    pub shares: Vec<NodeShare>,
    /// Touching pairs whose lower number is owned, and face contacts.
    pub pairs: usize,
    pub faces: usize,
    /// Hertz and tangential-spring energy of the contacts, half of a pair
    /// per owned end (J).
    pub energy: f64,
    /// Energy the contacts' dashpots and slips dissipated over the step,
    /// half of a pair per owned end (J).
    pub lost: f64,
    /// Largest overlap over the radius of the smaller partner.
    pub max_overlap_ratio: f64,
}

/// The Hertz–Mindlin constants of sphere set `a` against set `b`, or
/// against a body of E and ν `body` (an infinitely heavy plane).
fn law(a: &SetConstants, b: Option<&SetConstants>, body: (f64, f64)) -> HertzLaw {
    let (e, nu, r, m, damping, friction) = match b {
        Some(b) => (
            b.young,
            b.poisson,
            Some(b.radius),
            a.mass * b.mass / (a.mass + b.mass),
            0.5 * (a.damping + b.damping),
            0.5 * (a.friction + b.friction),
        ),
        None => (body.0, body.1, None, a.mass, a.damping, a.friction),
    };
    // Johnson 1985 secs 4.2, 7.2 (Hertz, Mindlin): E*, G*, R*; m* = m₁ m₂/(m₁ + m₂).
    HertzLaw {
        e_star: effective_modulus(a.young, a.poisson, e, nu),
        g_star: effective_shear_modulus(a.young, a.poisson, e, nu),
        r_star: effective_radius(a.radius, r),
        mass: m,
        damping,
        friction,
    }
}

/// The touching pairs with an owned end, as local indices (a, b) with
/// gid[a] < gid[b], ascending by global numbers; found on a grid of cells
/// the largest diameter wide.
fn touching_pairs(s: &SphereView, sets: &[SetConstants]) -> Vec<(usize, usize)> {
    let d = 2.0 * sets.iter().map(|c| c.radius).fold(0.0, f64::max);
    let grid = PointGrid::of(d, s.x.iter().map(|x| [x.x, x.y, x.z]));
    let mut out = Vec::new();
    for i in 0..s.n_owned {
        let ri = sets[s.set[i] as usize].radius;
        grid.near([s.x[i].x, s.x[i].y, s.x[i].z], |j| {
            let j = j as usize;
            // Two owned ends: found once, from the lower number.
            if j == i || (j < s.n_owned && s.gid[j] < s.gid[i]) {
                return true;
            }
            let reach = ri + sets[s.set[j] as usize].radius;
            if (s.x[j] - s.x[i]).norm_squared() < reach * reach {
                out.push(if s.gid[i] < s.gid[j] { (i, j) } else { (j, i) });
            }
            true
        });
    }
    out.sort_unstable_by_key(|&(a, b)| (s.gid[a], s.gid[b]));
    out
}

/// The forces of the spheres' contacts over `dt` (module header), with
/// `gravity` (m/s²) on the owned spheres; the springs of `history` are
/// advanced (those of contacts that ended go).
pub fn sphere_contacts(
    sets: &[SetConstants],
    s: &SphereView,
    faces: &FaceView,
    gravity: &V3,
    dt: f64,
    history: &mut Histories,
    heat: Option<&HeatView>,
) -> ContactForces {
    let no = s.n_owned;
    let n_heat = if heat.is_some() { no } else { 0 };
    let mut out = ContactForces {
        force: (0..no)
            .map(|i| gravity * sets[s.set[i] as usize].mass)
            .collect(),
        moment: vec![V3::zeros(); no],
        touching: vec![false; no],
        heat: vec![0.0; n_heat],
        conductance: vec![0.0; n_heat],
        ..ContactForces::default()
    };
    let mut kept = HashMap::with_capacity(history.pair.len());
    for (a, b) in touching_pairs(s, sets) {
        let (ca, cb) = (&sets[s.set[a] as usize], &sets[s.set[b] as usize]);
        let d = s.x[b] - s.x[a];
        let dist = d.norm();
        // Coincident centres (never from the placement) push along x.
        let n = if dist > 0.0 { d / dist } else { V3::x() };
        let delta = ca.radius + cb.radius - dist;
        let va = s.v[a] + s.w[a].cross(&(n * ca.radius));
        let vb = s.v[b] + s.w[b].cross(&(-n * cb.radius));
        let key = (s.gid[a], s.gid[b]);
        let mut xi = history.pair.remove(&key).unwrap_or_else(V3::zeros);
        let f = law(ca, Some(cb), (0.0, 0.0)).force(delta, &n, &(va - vb), dt, &mut xi);
        kept.insert(key, xi);
        // The pipe's conductance and its flow into a, from the same values on both ends' ranks.
        let (g, q) = heat.map_or((0.0, 0.0), |h| {
            let (sa, sb) = (s.set[a] as usize, s.set[b] as usize);
            let rc = h.rc[h.material[sa] as usize][h.material[sb] as usize];
            let r_star = effective_radius(ca.radius, Some(cb.radius));
            let contact = contact_radius(r_star, delta);
            let g = pipe_conductance(h.conductivity[sa], Some(h.conductivity[sb]), contact, rc);
            // Seed 000 eq 35: Q_AB = (T_B − T_A)/R_AB into A.
            (g, g * (h.t[b] - h.t[a]))
        });
        for (i, sign, r) in [(a, 1.0, ca.radius), (b, -1.0, cb.radius)] {
            if i < no {
                out.force[i] += f.force * sign;
                out.moment[i] += (n * (sign * r)).cross(&(f.force * sign));
                out.touching[i] = true;
                out.energy += 0.5 * (f.energy + f.spring_energy);
                out.lost += 0.5 * f.lost;
                if heat.is_some() {
                    out.heat[i] += sign * q;
                    out.conductance[i] += g;
                }
            }
        }
        // Counted by the lower number's owner: once over the ranks.
        out.pairs += usize::from(a < no);
        out.max_overlap_ratio = out.max_overlap_ratio.max(delta / ca.radius.min(cb.radius));
    }
    history.pair = kept;
    let r_max = sets.iter().map(|c| c.radius).fold(0.0, f64::max);
    let tri_of = |f: usize| faces.nodes[f].map(|n| faces.x[n as usize]);
    let grid = FaceGrid::new(faces.nodes.len(), 2.0 * r_max, tri_of);
    let mut near = Vec::new();
    let mut kept: HashMap<u64, Vec<(u32, V3, V3)>> = HashMap::new();
    for i in 0..no {
        let c = &sets[s.set[i] as usize];
        grid.near(&s.x[i], c.radius, &mut near);
        let mut by_body: BTreeMap<u32, Vec<_>> = BTreeMap::new();
        for &f in &near {
            if let Some(touch) = sphere_triangle(&s.x[i], c.radius, &tri_of(f as usize)) {
                by_body
                    .entry(faces.body[f as usize])
                    .or_default()
                    .push((f, touch));
            }
        }
        let old = history.face.remove(&s.gid[i]).unwrap_or_default();
        let mut order = 0u32;
        for (body, touches) in by_body {
            for (f, touch) in distinct_features(touches) {
                let f_id = f as usize;
                let law = law(c, None, faces.elastic[f as usize]);
                let tri = faces.nodes[f as usize];
                let wts = touch.weights;
                let arm = touch.point - s.x[i];
                let vs = s.v[i] + s.w[i].cross(&arm);
                let vf: V3 = (0..3).map(|k| faces.v[tri[k] as usize] * wts[k]).sum();
                let mut xi = crate::contact::sphere::kept_spring(&old, body, &touch.normal);
                let f = law.force(touch.depth, &touch.normal, &(vs - vf), dt, &mut xi);
                kept.entry(s.gid[i])
                    .or_default()
                    .push((body, touch.normal, xi));
                out.force[i] += f.force;
                out.moment[i] += arm.cross(&f.force);
                out.touching[i] = true;
                // The face side has no particle resistance: its conduction is its FE's.
                let (g, q) = heat.map_or((0.0, 0.0), |h| {
                    let set = s.set[i] as usize;
                    let rc = h.rc[h.material[set] as usize][faces.material[f_id] as usize];
                    let contact = contact_radius(c.radius, touch.depth);
                    let g = pipe_conductance(h.conductivity[set], None, contact, rc);
                    let t_face: f64 = (0..3).map(|k| h.node_t[tri[k] as usize] * wts[k]).sum();
                    // Seed 000 eq 35: Q = (T_face − T_sphere)/R, T_face = Σ N_I T_I.
                    (g, g * (t_face - h.t[i]))
                });
                if heat.is_some() {
                    out.heat[i] += q;
                    out.conductance[i] += g;
                }
                for (k, &node) in tri.iter().enumerate() {
                    out.shares.push(NodeShare {
                        node,
                        sphere: s.gid[i],
                        order: 3 * order + k as u32,
                        force: -f.force * wts[k],
                        heat: -q * wts[k],
                        conductance: g * wts[k],
                    });
                }
                order += 1;
                out.faces += 1;
                out.energy += f.energy + f.spring_energy;
                out.lost += f.lost;
                out.max_overlap_ratio = out.max_overlap_ratio.max(touch.depth / c.radius);
            }
        }
    }
    history.face = kept;
    out
}

/// The stable explicit step of the spheres' contacts: 0.1 √(m/k_n) with
/// k_n = 2 E* √(r δ) the Hertz stiffness at δ = [`DESIGN_OVERLAP`] r
/// against the stiffest partner (another set, or a body of `bodies`' E
/// and ν) and m the lightest mass a contact moves (the set's,
/// another set's, or `node_mass`, the lightest free boundary node). As
/// [`super::free_spheres::FreeSpheres::stable_dt`]: a pair alone allows
/// 1.4 √(m/k_n); springs, spins and up to 12 neighbours bring that to
/// about 0.24 √(m/k_n).
pub fn stable_dt(sets: &[SetConstants], bodies: &[(f64, f64)], node_mass: f64) -> f64 {
    let m_min = sets.iter().map(|c| c.mass).fold(node_mass, f64::min);
    let mut dt = f64::INFINITY;
    for c in sets {
        let partners = sets
            .iter()
            .map(|o| (o.young, o.poisson))
            .chain(bodies.iter().copied());
        let e = partners
            .map(|(e, nu)| effective_modulus(c.young, c.poisson, e, nu))
            .fold(0.0, f64::max);
        // Johnson 1985 sec 4.2 (Hertz): k_n = dF/dδ = 2 E* √(R δ).
        let kn = 2.0 * e * (c.radius * DESIGN_OVERLAP * c.radius).sqrt();
        dt = dt.min(0.1 * (m_min.min(c.mass) / kn).sqrt());
    }
    dt
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass() -> SetConstants {
        SetConstants::new(0.005, 2500.0, 1e8, 0.25, 0.3, 0.5)
    }

    /// Two spheres pressed together: equal and opposite forces on owned
    /// ends, only the owned end's on a rank holding the other as a ghost,
    /// and the same bits either way.
    #[test]
    fn pair_split_over_ranks_gives_the_same_forces() {
        let sets = [glass()];
        let x = [V3::new(0.0, 0.0, 0.0), V3::new(0.0099, 0.0, 0.0)];
        let v = [V3::new(0.1, 0.0, 0.0), V3::zeros()];
        let w = [V3::zeros(); 2];
        let g = V3::new(0.0, 0.0, -9.81);
        let both = SphereView {
            gid: &[3, 7],
            set: &[0, 0],
            x: &x,
            v: &v,
            w: &w,
            n_owned: 2,
        };
        let mut h = Histories::default();
        let all = sphere_contacts(&sets, &both, &FaceView::default(), &g, 1e-6, &mut h, None);
        assert_eq!(all.pairs, 1);
        let m = sets[0].mass;
        assert!((all.force[0] + all.force[1] - 2.0 * m * g).norm() < 1e-15);
        assert!(all.force[0].x < 0.0 && all.touching == [true, true]);
        // The rank owning sphere 7 only, sphere 3 its ghost (after it).
        let (x2, v2) = ([x[1], x[0]], [v[1], v[0]]);
        let one = SphereView {
            gid: &[7, 3],
            set: &[0, 0],
            x: &x2,
            v: &v2,
            w: &w,
            n_owned: 1,
        };
        let mut h2 = Histories::default();
        let part = sphere_contacts(&sets, &one, &FaceView::default(), &g, 1e-6, &mut h2, None);
        assert_eq!(part.force[0], all.force[1]);
        assert_eq!(h.pair, h2.pair);
    }

    /// One still triangle of body 0 (E = 1 GPa, ν = 0.3) in the plane
    /// z = 0 around the origin.
    fn one_triangle() -> FaceView {
        FaceView {
            key: vec![40],
            body: vec![0],
            elastic: vec![(1e9, 0.3)],
            nodes: vec![[0, 1, 2]],
            x: vec![
                V3::new(-1.0, -1.0, 0.0),
                V3::new(1.0, -1.0, 0.0),
                V3::new(0.0, 1.0, 0.0),
            ],
            v: vec![V3::zeros(); 3],
            material: vec![0],
        }
    }

    /// A sphere on a triangle: the reaction's shares sum to minus the
    /// contact force, keyed in corner order.
    #[test]
    fn face_shares_balance_the_sphere() {
        let sets = [glass()];
        let faces = one_triangle();
        let x = [V3::new(0.0, 0.0, 0.0049)];
        let z = [V3::zeros()];
        let s = SphereView {
            gid: &[0],
            set: &[0],
            x: &x,
            v: &z,
            w: &z,
            n_owned: 1,
        };
        let mut h = Histories::default();
        let out = sphere_contacts(&sets, &s, &faces, &V3::zeros(), 1e-6, &mut h, None);
        assert_eq!((out.faces, out.shares.len()), (1, 3));
        let back: V3 = out.shares.iter().map(|s| s.force).sum();
        assert!((back + out.force[0]).norm() < 1e-12 * out.force[0].norm());
        assert_eq!(
            out.shares.iter().map(|s| s.order).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        // Hertz: F = 4/3 E* √r δ^{3/2} on a plane.
        let e = effective_modulus(1e8, 0.25, 1e9, 0.3);
        let want = 4.0 / 3.0 * e * 0.005f64.sqrt() * 1e-4f64.powf(1.5);
        assert!((out.force[0].z - want).abs() < 1e-9 * want);
    }

    #[test]
    fn stable_step_falls_with_a_stiffer_partner() {
        let sets = [glass()];
        let soft = stable_dt(&sets, &[(1e8, 0.25)], f64::INFINITY);
        let hard = stable_dt(&sets, &[(1e11, 0.25)], f64::INFINITY);
        assert!(hard < soft && soft.is_finite());
    }

    /// Heat: a pair split over two ranks gives each owned end the same
    /// bits, equal and opposite; a face's node shares take minus the
    /// sphere's flow, weighted by N_I; the flows follow seed 000 eq 35.
    #[test]
    fn heat_flows_balance_and_split_over_ranks() {
        use crate::contact::sphere_heat::pipe_resistance;
        let sets = [glass()];
        let rc = [vec![1e-5]];
        let (k, mat) = ([1.2], [0u32]);
        let x = [V3::new(0.0, 0.0, 0.0), V3::new(0.0099, 0.0, 0.0)];
        let z = [V3::zeros(); 2];
        let t = [300.0, 400.0];
        let view = SphereView {
            gid: &[3, 7],
            set: &[0, 0],
            x: &x,
            v: &z,
            w: &z,
            n_owned: 2,
        };
        let heat = HeatView {
            t: &t,
            node_t: &[],
            conductivity: &k,
            material: &mat,
            rc: &rc,
        };
        let mut h = Histories::default();
        let g0 = V3::zeros();
        let all = sphere_contacts(
            &sets,
            &view,
            &FaceView::default(),
            &g0,
            1e-6,
            &mut h,
            Some(&heat),
        );
        let a = (0.5 * 0.005 * 1e-4f64).sqrt();
        let q = (t[1] - t[0]) / pipe_resistance(1.2, Some(1.2), a, 1e-5);
        assert!((all.heat[0] - q).abs() < 1e-12 * q.abs());
        assert_eq!(all.heat[0], -all.heat[1]);
        let (x2, t2) = ([x[1], x[0]], [t[1], t[0]]);
        let one = SphereView {
            gid: &[7, 3],
            set: &[0, 0],
            x: &x2,
            v: &z,
            w: &z,
            n_owned: 1,
        };
        let heat2 = HeatView { t: &t2, ..heat };
        let mut h2 = Histories::default();
        let part = sphere_contacts(
            &sets,
            &one,
            &FaceView::default(),
            &g0,
            1e-6,
            &mut h2,
            Some(&heat2),
        );
        assert_eq!(part.heat[0], all.heat[1]);
        assert_eq!(part.conductance[0], all.conductance[1]);
        // A sphere at 300 on a face whose nodes are at 400, 500, 600.
        let faces = one_triangle();
        let xs = [V3::new(0.1, 0.2, 0.0049)];
        let s = SphereView {
            gid: &[0],
            set: &[0],
            x: &xs,
            v: &z[..1],
            w: &z[..1],
            n_owned: 1,
        };
        let heat = HeatView {
            t: &[300.0],
            node_t: &[400.0, 500.0, 600.0],
            ..heat
        };
        let mut h = Histories::default();
        let out = sphere_contacts(&sets, &s, &faces, &g0, 1e-6, &mut h, Some(&heat));
        let back: f64 = out.shares.iter().map(|s| s.heat).sum();
        assert!((back + out.heat[0]).abs() < 1e-14 * out.heat[0]);
        let gsum: f64 = out.shares.iter().map(|s| s.conductance).sum();
        assert!((gsum - out.conductance[0]).abs() < 1e-14 * gsum);
        let a = (0.005 * 1e-4f64).sqrt();
        // Barycentric weights of (0.1, 0.2) in the triangle: T_face = 400 N₀ + 500 N₁ + 600 N₂.
        let (n2, n1) = (0.6, 0.25);
        let t_face = 400.0 * (1.0 - n1 - n2) + 500.0 * n1 + 600.0 * n2;
        let q = (t_face - 300.0) / pipe_resistance(1.2, None, a, 1e-5);
        assert!((out.heat[0] - q).abs() < 1e-9 * q, "{} {q}", out.heat[0]);
    }
}
