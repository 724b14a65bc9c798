//! Serial patch test of the FE–DE interface (issue 21): a bar along x,
//! Hex8 elements on [0, x₁] and a bonded sphere lattice on [x₁, L], joined
//! by one layer of ghosts ([`super::fede_coupling`]), in uniform uniaxial
//! tension ε along x.
//!
//! Both ends are held on the exact field u = (ε X, −ν ε (Y − W/2),
//! −ν ε (Z − H/2)): the FE nodes of the face X = 0 and the last two layers
//! of spheres (centres at X = L − r and L + r: the lattice runs one layer
//! past L, so the bonds into the first held layer keep their interior
//! weights, as if the body went on), moved there with a constant velocity over
//! a ramp (the bond kernel is incremental, so prescribed spheres must move
//! by velocity). Lateral faces are free. The exact field is then the static
//! solution of the continuum; a discretisation that passes the patch test
//! reproduces it, with σ_xx = E ε everywhere. Damped explicit dynamics
//! (mass-proportional damping at twice the lowest axial frequency
//! π √(E/ρ)/L) runs to static.
//!
//! Measured:
//! - each element's volume-mean σ_xx (and the largest |σ_yy|, |σ_zz|);
//! - the DE stress at each plane between sphere layers: the x-force the
//!   bonds (and ghost–sphere bonds) crossing it carry, over W H;
//! - the DE strain between consecutive layers of spheres, from their mean
//!   x-displacements;
//! - the largest deviation of any node or sphere from the exact field;
//! - the spurious force of the ghost layer: with the exact field imposed on
//!   every node and sphere (one step from the reference), the net force on
//!   each free node and sphere, which is zero for a discretisation that
//!   passes the patch test.

use nalgebra::Vector3;

use super::cantilever::{relax, CantileverError, Relaxation};
use super::fede_coupling::{schur_bound, Coupling, GhostLayer};
use crate::mechanics::bond::{sphere_mass_inertia, update_particles, BondStiffness};
use crate::mechanics::hex8_element::{hex8_forces, Hex8Material, Hex8Reference};
use crate::mechanics::{ElasticMaterial, ThermalState};
use crate::mesh::hex8::hex_box;
use crate::mesh::lattice::cubic_lattice;
use crate::mesh::MeshError;

/// The bar of the patch test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchBar {
    /// Length L (m).
    pub length: f64,
    /// End of the FE region x₁ (m), a multiple of `size` and of 2r.
    pub interface: f64,
    /// Width W along y (m).
    pub width: f64,
    /// Height H along z (m).
    pub height: f64,
    /// Element side h (m).
    pub size: f64,
    /// Sphere radius r (m).
    pub radius: f64,
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Axial strain ε.
    pub strain: f64,
}

impl PatchBar {
    /// Hex8 divisions of the FE region [0, x₁] along x, y, z; an error if
    /// the interface is not inside the bar.
    pub fn fe_divisions(&self) -> Result<[usize; 3], MeshError> {
        let (h, x1) = (self.size, self.interface);
        if !(0.0 < x1 && x1 < self.length) {
            return Err(MeshError::InvalidParameter(format!(
                "interface {x1} must lie inside the bar (0, {})",
                self.length
            )));
        }
        Ok([x1, self.width, self.height].map(|d| ((d / h).round() as usize).max(1)))
    }

    /// 4 mm × 2 mm × 2 mm, FE half and DE half, with the seed 002 material,
    /// mesh (h = 0.5 mm) and spheres (r = 0.125 mm); ε = 1e-4.
    pub fn seed002() -> Self {
        Self {
            length: 4e-3,
            interface: 2e-3,
            width: 2e-3,
            height: 2e-3,
            size: 0.5e-3,
            radius: 0.125e-3,
            young: 1e9,
            poisson: 0.23,
            density: 1000.0,
            strain: 1e-4,
        }
    }

    /// The exact displacement at X.
    pub fn exact(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let e = self.strain;
        Vector3::new(
            e * p[0],
            -self.poisson * e * (p[1] - 0.5 * self.width),
            -self.poisson * e * (p[2] - 0.5 * self.height),
        )
    }
}

/// What the patch test measured.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchResult {
    /// (centre x, σ_xx) of every element (Pa).
    pub fe_stress: Vec<(f64, f64)>,
    /// Largest |σ_yy|, |σ_zz| over the elements (Pa).
    pub fe_lateral: f64,
    /// The elements that carry ghosts or interface points (their centre x).
    pub coupled_x: Vec<f64>,
    /// (plane x, σ_xx) at each plane between consecutive particle layers,
    /// the interface (ghosts | first spheres) first (Pa).
    pub de_section: Vec<(f64, f64)>,
    /// (mid x, ε_xx) between consecutive layers of spheres (ghosts excluded).
    pub de_strain: Vec<(f64, f64)>,
    /// Largest |u − u_exact| over free nodes and spheres (m).
    pub max_deviation: f64,
    /// Imposed exact field: (reference position, net force (N)) of each
    /// free FE node.
    pub fe_residual: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Imposed exact field: (reference centre, net force (N)) of each free
    /// sphere.
    pub de_residual: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// Explicit steps to static.
    pub steps: usize,
    /// Time step (s).
    pub dt: f64,
}

/// The bar, its interface and its state.
struct Model {
    hexes: Vec<[u32; 8]>,
    refs: Vec<Hex8Reference>,
    x0: Vec<Vector3<f64>>,
    mass: Vec<f64>,
    fixed_node: Vec<bool>,
    p0: Vec<Vector3<f64>>,
    fixed_particle: Vec<bool>,
    ghost: Vec<bool>,
    layer: GhostLayer,
    stiffness: BondStiffness,
    material: ElasticMaterial,
    pmass: f64,
    inertia: f64,
    nx: usize,
    dt: f64,
}

/// Mutable state of nodes and particles.
struct State {
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    f: Vec<Vector3<f64>>,
    px: Vec<Vector3<f64>>,
    pv: Vec<Vector3<f64>>,
    pw: Vec<Vector3<f64>>,
    pf: Vec<Vector3<f64>>,
    pm: Vec<Vector3<f64>>,
}

impl Model {
    fn new(bar: &PatchBar, coupling: Coupling) -> Result<Self, CantileverError> {
        let (h, r, x1) = (bar.size, bar.radius, bar.interface);
        let n = bar.fe_divisions()?;
        let mesh = hex_box([0.0; 3], [x1, bar.width, bar.height], n)?;
        let material = ElasticMaterial {
            young: bar.young,
            poisson: bar.poisson,
            density: bar.density,
            expansion: 0.0,
            viscosity: 0.0,
        };
        let x0: Vec<Vector3<f64>> = mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let mut refs = Vec::with_capacity(mesh.hexes.len());
        let mut mass = vec![0.0; x0.len()];
        let mut dt = f64::INFINITY;
        for (e, hx) in mesh.hexes.iter().enumerate() {
            let re =
                Hex8Reference::new(&hx.map(|a| x0[a as usize])).map_err(|err| err.at_element(e))?;
            for (a, m) in hx.iter().zip(re.lumped_masses(material.density)) {
                mass[*a as usize] += m;
            }
            dt = dt.min(0.9 * re.critical_dt(&material));
            refs.push(re);
        }
        let mut fixed_node = vec![false; x0.len()];
        for &p in &mesh.node_sets["xmin"] {
            fixed_node[p as usize] = true;
        }
        let lattice = cubic_lattice(
            [x1 - 2.0 * r, 0.0, 0.0],
            [bar.length + 2.0 * r, bar.width, bar.height],
            r,
            false,
        )?;
        let stiffness = BondStiffness::seed002(bar.young, bar.poisson, r)?;
        let (pmass, inertia) = sphere_mass_inertia(bar.density, r);
        let nx = lattice.counts[0];
        let (p0, normal) = super::fede_coupling::x_interface(&lattice);
        let locate = |p: &Vector3<f64>| {
            let cell = [0, 1, 2].map(|a| ((p[a] / h).floor().max(0.0) as usize).min(n[a] - 1));
            cell[0] + n[0] * (cell[1] + n[1] * cell[2])
        };
        let layer = GhostLayer::new(coupling, &lattice, &normal, &mesh.hexes, &x0, locate)?;
        dt = dt.min(0.95 * 2.0 / schur_bound(layer.all_bonds(), &stiffness, &p0, pmass, inertia));
        let ghost: Vec<bool> = normal.iter().map(Option::is_some).collect();
        let fixed_particle = (0..p0.len())
            .map(|p| ghost[p] || p % nx >= nx - 2)
            .collect();
        Ok(Self {
            hexes: mesh.hexes,
            refs,
            x0,
            mass,
            fixed_node,
            p0,
            fixed_particle,
            ghost,
            layer,
            stiffness,
            material,
            pmass,
            inertia,
            nx,
            dt,
        })
    }

    fn state(&self) -> State {
        let (nodes, count) = (self.x0.len(), self.p0.len());
        State {
            x: self.x0.clone(),
            v: vec![Vector3::zeros(); nodes],
            f: vec![Vector3::zeros(); nodes],
            px: self.p0.clone(),
            pv: vec![Vector3::zeros(); count],
            pw: vec![Vector3::zeros(); count],
            pf: vec![Vector3::zeros(); count],
            pm: vec![Vector3::zeros(); count],
        }
    }

    /// Element forces and the interface at the current state: `s.f`, `s.pf`, `s.pm`.
    fn forces(&mut self, s: &mut State) -> Result<(), CantileverError> {
        s.f.iter_mut().for_each(|a| *a = Vector3::zeros());
        s.pf.iter_mut().for_each(|a| *a = Vector3::zeros());
        s.pm.iter_mut().for_each(|a| *a = Vector3::zeros());
        super::fede_bar::add_hex_forces(
            &self.hexes,
            &self.refs,
            &self.material,
            &s.x,
            &s.v,
            &mut s.f,
            |_, _| {},
        )?;
        self.layer.add_forces(
            &self.stiffness,
            &self.hexes,
            &s.x,
            &s.v,
            self.dt,
            &mut s.f,
            &mut s.px,
            &mut s.pv,
            &mut s.pw,
            &mut s.pf,
            &mut s.pm,
        );
        Ok(())
    }
}

/// Runs the patch test with `coupling` and relaxes to static.
pub fn fede_patch(
    bar: &PatchBar,
    coupling: Coupling,
    relaxation: &Relaxation,
) -> Result<PatchResult, CantileverError> {
    let mut model = Model::new(bar, coupling)?;
    let dt = model.dt;
    let coupled = model.layer.coupled_elements();
    let centre =
        |m: &Model, e: usize| m.hexes[e].iter().map(|&p| m.x0[p as usize][0]).sum::<f64>() / 8.0;
    let coupled_x: Vec<f64> = coupled.iter().map(|&e| centre(&model, e)).collect();
    // Spurious force: the exact field imposed everywhere in one step from the reference.
    let mut s = model.state();
    for (p, x) in s.x.iter_mut().enumerate() {
        let u = bar.exact(&model.x0[p]);
        *x += u;
        s.v[p] = u / dt;
    }
    for (p, x) in s.px.iter_mut().enumerate() {
        let u = bar.exact(&model.p0[p]);
        *x += u;
        s.pv[p] = u / dt;
    }
    model.forces(&mut s)?;
    let fe_residual = (0..s.f.len())
        .filter(|&p| !model.fixed_node[p])
        .map(|p| (model.x0[p], s.f[p]))
        .collect();
    let de_residual = (0..s.pf.len())
        .filter(|&p| !model.fixed_particle[p])
        .map(|p| (model.p0[p], s.pf[p]))
        .collect();

    // Relaxation from rest, the ends moved to the exact field over a ramp.
    let mut model = Model::new(bar, coupling)?;
    let mut s = model.state();
    let wave = (bar.young / bar.density).sqrt();
    let omega1 = std::f64::consts::PI * wave / bar.length;
    let period = 2.0 * std::f64::consts::PI / omega1;
    let ramp = (period / dt).ceil() as usize;
    let damping = relaxation.damping * omega1;
    let (a, b) = (1.0 - 0.5 * damping * dt, 1.0 / (1.0 + 0.5 * damping * dt));
    let node_rate: Vec<Vector3<f64>> = model
        .x0
        .iter()
        .map(|p| bar.exact(p) / (ramp as f64 * dt))
        .collect();
    let particle_rate: Vec<Vector3<f64>> = model
        .p0
        .iter()
        .map(|p| bar.exact(p) / (ramp as f64 * dt))
        .collect();
    let first: Vec<usize> = (0..model.p0.len()).filter(|&p| p % model.nx == 1).collect();
    let mut step = 0usize;
    let check = (period / (10.0 * dt)).ceil() as usize;
    let (_, steps) = relax(relaxation, check, || {
        model.forces(&mut s)?;
        let moving = step < ramp;
        step += 1;
        for (p, rate) in node_rate.iter().enumerate() {
            if model.fixed_node[p] {
                s.v[p] = if moving { *rate } else { Vector3::zeros() };
            } else {
                s.v[p] = (s.v[p] * a + s.f[p] * (dt / model.mass[p])) * b;
            }
            s.x[p] += s.v[p] * dt;
        }
        update_particles(
            model.pmass,
            model.inertia,
            damping,
            dt,
            &model.fixed_particle,
            &s.pf,
            &s.pm,
            &mut s.px,
            &mut s.pv,
            &mut s.pw,
        );
        for (p, rate) in particle_rate.iter().enumerate() {
            if model.fixed_particle[p] && !model.ghost[p] && moving {
                s.pv[p] = *rate;
                s.px[p] += s.pv[p] * dt;
            }
        }
        if moving {
            // No settling check while the ends move.
            return Ok(f64::NAN);
        }
        // Settling measure: mean x-displacement of the first layer of spheres.
        Ok(first
            .iter()
            .map(|&p| s.px[p][0] - model.p0[p][0])
            .sum::<f64>()
            / first.len() as f64)
    })?;
    // One more force evaluation at the final state (v ≈ 0) for the bond states.
    model.forces(&mut s)?;

    let mut fe_stress = Vec::new();
    let mut fe_lateral: f64 = 0.0;
    for (e, (hx, re)) in model.hexes.iter().zip(&model.refs).enumerate() {
        let res = hex8_forces(
            re,
            &Hex8Material::new(&model.material),
            &hx.map(|p| s.x[p as usize]),
            &hx.map(|p| s.v[p as usize]),
            ThermalState::default(),
        )
        .map_err(|err| err.at_element(e))?;
        let sigma = res.mean_stress;
        fe_stress.push((centre(&model, e), sigma[(0, 0)]));
        fe_lateral = fe_lateral.max(sigma[(1, 1)].abs()).max(sigma[(2, 2)].abs());
    }
    let (nx, r) = (model.nx, bar.radius);
    let layer_of = |p: usize| p % nx;
    let area = bar.width * bar.height;
    // Planes up to the first held layer (the last plane joins the two held layers).
    let mut crossing = vec![0.0; nx - 2];
    for (i, j, f) in model.layer.bond_force_list(&model.stiffness) {
        let (li, lj) = (layer_of(i), layer_of(j));
        // Tension: the force on the left particle points along +x.
        let (lo, hi, t) = if li < lj {
            (li, lj, f[0])
        } else {
            (lj, li, -f[0])
        };
        for c in crossing.iter_mut().take(hi.min(nx - 2)).skip(lo) {
            *c += t;
        }
    }
    let x_layer = |i: usize| model.p0[i][0];
    let de_section = crossing
        .iter()
        .enumerate()
        .map(|(i, c)| (x_layer(i) + r, c / area))
        .collect();
    let mean_u = |i: usize| {
        let (mut sum, mut cnt) = (0.0, 0usize);
        for p in (0..s.px.len()).filter(|&p| layer_of(p) == i) {
            sum += s.px[p][0] - model.p0[p][0];
            cnt += 1;
        }
        sum / cnt as f64
    };
    let de_strain = (1..nx - 2)
        .map(|i| (x_layer(i) + r, (mean_u(i + 1) - mean_u(i)) / (2.0 * r)))
        .collect();
    let mut max_deviation: f64 = 0.0;
    for p in (0..s.x.len()).filter(|&p| !model.fixed_node[p]) {
        max_deviation = max_deviation.max((s.x[p] - model.x0[p] - bar.exact(&model.x0[p])).norm());
    }
    for p in (0..s.px.len()).filter(|&p| !model.fixed_particle[p]) {
        max_deviation = max_deviation.max((s.px[p] - model.p0[p] - bar.exact(&model.p0[p])).norm());
    }
    Ok(PatchResult {
        fe_stress,
        fe_lateral,
        coupled_x,
        de_section,
        de_strain,
        max_deviation,
        fe_residual,
        de_residual,
        steps,
        dt,
    })
}
