//! The FE │ DE │ FE box of the serial coupled drivers
//! ([`super::coupled_cantilever`], [`super::fede_wave`]): Hex8 elements on
//! [0, x₁] and [x₂, L] of a box L × W × H, a bonded sphere lattice on
//! [x₁, x₂], joined through one layer of ghost particles on each side
//! (seed 002 eq 5: x_g = x_b − 2 r n, inside the boundary elements), coupled
//! as [`super::fede_coupling`] says.
//!
//! The lattice is generated over [x₁ − 2r, x₂ + 2r]: its first and last
//! layers are the ghosts. Ghost–ghost bonds are dropped (the elements carry
//! that material).

use std::collections::BTreeMap;

use nalgebra::Vector3;

use super::cantilever::CantileverError;
use super::fede_coupling::{schur_bound, Coupling, GhostLayer};
use crate::mechanics::bond::{sphere_mass_inertia, BondStiffness};
use crate::mechanics::hex8_element::{hex8_forces, Hex8Material, Hex8Reference};
use crate::mechanics::{ElasticMaterial, ThermalState};
use crate::mesh::hex8::hex_box;
use crate::mesh::lattice::cubic_lattice;
use crate::mesh::MeshError;

/// The coupled box and its interface.
#[derive(Debug, Clone)]
pub(crate) struct CoupledBar {
    /// Hex8 divisions of the whole box along x, y, z.
    pub n: [usize; 3],
    /// Reference nodes of the whole box (nodes inside the DE segment have no mass).
    pub x0: Vec<Vector3<f64>>,
    /// Node sets of the whole box ([`hex_box`]).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Elements of the FE segments.
    pub hexes: Vec<[u32; 8]>,
    /// Their reference data.
    pub refs: Vec<Hex8Reference>,
    /// Lumped nodal masses (kg).
    pub mass: Vec<f64>,
    /// The material of both regions.
    pub material: ElasticMaterial,
    /// Spheres per axis of the lattice (ghost layers included).
    pub counts: [usize; 3],
    /// Sphere centres.
    pub p0: Vec<Vector3<f64>>,
    /// Interface normal (FE into DE) of the ghosts, `None` for spheres.
    pub normal: Vec<Option<Vector3<f64>>>,
    /// The ghost layer and the bonds.
    pub layer: GhostLayer,
    /// Bond stiffnesses (seed 002 eq 4).
    pub stiffness: BondStiffness,
    /// Sphere mass (kg).
    pub pmass: f64,
    /// Sphere moment of inertia (kg m²).
    pub inertia: f64,
    /// Stable time step: 0.9 of the smallest Hex8 bound, 0.95 of the lattice's.
    pub dt: f64,
    /// Strain energy of each element at the last [`CoupledBar::forces`] (J).
    pub strain_energy: Vec<f64>,
}

/// Positions, velocities and forces of the nodes and particles.
#[derive(Debug, Clone)]
pub(crate) struct BarState {
    pub x: Vec<Vector3<f64>>,
    pub v: Vec<Vector3<f64>>,
    pub f: Vec<Vector3<f64>>,
    pub px: Vec<Vector3<f64>>,
    pub pv: Vec<Vector3<f64>>,
    pub pw: Vec<Vector3<f64>>,
    pub pf: Vec<Vector3<f64>>,
    pub pm: Vec<Vector3<f64>>,
}

impl CoupledBar {
    /// The box [0, L] × [0, W] × [0, H] (`dims`) in Hex8 of side `size`,
    /// spheres of radius `radius` on [x₁, x₂] = `de_segment` (multiples of
    /// `size` and of 2r), of `material`, joined by `coupling`.
    pub fn new(
        dims: [f64; 3],
        size: f64,
        radius: f64,
        de_segment: [f64; 2],
        material: ElasticMaterial,
        coupling: Coupling,
    ) -> Result<Self, CantileverError> {
        let [x1, x2] = de_segment;
        if !(0.0 < x1 && x1 < x2 && x2 < dims[0]) {
            return Err(MeshError::InvalidParameter(format!(
                "DE segment [{x1}, {x2}] must lie inside the bar (0, {})",
                dims[0]
            ))
            .into());
        }
        let n = dims.map(|d| ((d / size).round() as usize).max(1));
        let full = hex_box([0.0; 3], dims, n)?;
        let x0: Vec<Vector3<f64>> = full.nodes.iter().map(|p| Vector3::from(*p)).collect();
        // Elements of the FE segments; `kept[e]` maps a box element to its index here.
        let mut hexes = Vec::new();
        let mut refs = Vec::new();
        let mut kept = vec![usize::MAX; full.hexes.len()];
        let mut mass = vec![0.0; x0.len()];
        let mut dt = f64::INFINITY;
        for (e, h) in full.hexes.iter().enumerate() {
            let centre: f64 = h.iter().map(|&p| x0[p as usize][0]).sum::<f64>() / 8.0;
            if centre > x1 && centre < x2 {
                continue;
            }
            let r =
                Hex8Reference::new(&h.map(|a| x0[a as usize])).map_err(|err| err.at_element(e))?;
            for (a, m) in h.iter().zip(r.lumped_masses(material.density)) {
                mass[*a as usize] += m;
            }
            dt = dt.min(0.9 * r.critical_dt(&material));
            kept[e] = hexes.len();
            hexes.push(*h);
            refs.push(r);
        }
        // The lattice with its two ghost layers.
        let lattice = cubic_lattice(
            [x1 - 2.0 * radius, 0.0, 0.0],
            [x2 + 2.0 * radius, dims[1], dims[2]],
            radius,
            false,
        )?;
        let stiffness = BondStiffness::seed002(material.young, material.poisson, radius)?;
        let (pmass, inertia) = sphere_mass_inertia(material.density, radius);
        let counts = lattice.counts;
        let p0: Vec<Vector3<f64>> = lattice.centres.iter().map(|p| Vector3::from(*p)).collect();
        // Ghosts: the first and last layers, normals from FE into DE.
        let normal: Vec<Option<Vector3<f64>>> = (0..p0.len())
            .map(|p| match p % counts[0] {
                0 => Some(Vector3::x()),
                i if i == counts[0] - 1 => Some(-Vector3::x()),
                _ => None,
            })
            .collect();
        let locate = |xg: &Vector3<f64>| {
            let cell = [0, 1, 2].map(|a| ((xg[a] / size).floor().max(0.0) as usize).min(n[a] - 1));
            kept[cell[0] + n[0] * (cell[1] + n[1] * cell[2])]
        };
        let layer = GhostLayer::new(coupling, &lattice, &normal, &hexes, &x0, locate)?;
        let omega_max = schur_bound(layer.all_bonds(), &stiffness, &p0, pmass, inertia);
        dt = dt.min(0.95 * 2.0 / omega_max);
        let strain_energy = vec![0.0; hexes.len()];
        Ok(Self {
            n,
            x0,
            node_sets: full.node_sets,
            hexes,
            refs,
            mass,
            material,
            counts,
            p0,
            normal,
            layer,
            stiffness,
            pmass,
            inertia,
            dt,
            strain_energy,
        })
    }

    /// The reference state at rest (zero forces).
    pub fn state(&self) -> BarState {
        let (nodes, count) = (self.x0.len(), self.p0.len());
        let zeros = |k: usize| vec![Vector3::zeros(); k];
        BarState {
            x: self.x0.clone(),
            v: zeros(nodes),
            f: zeros(nodes),
            px: self.p0.clone(),
            pv: zeros(count),
            pw: zeros(count),
            pf: zeros(count),
            pm: zeros(count),
        }
    }

    /// Adds the element forces and the interface's to `s.f` (which the
    /// caller sets, e.g. to the external loads) and sets the bond forces and
    /// moments `s.pf`, `s.pm`, over a step `dt`; records each element's
    /// strain energy.
    pub fn forces(&mut self, s: &mut BarState, dt: f64) -> Result<(), CantileverError> {
        let energy = &mut self.strain_energy;
        add_hex_forces(
            &self.hexes,
            &self.refs,
            &self.material,
            &s.x,
            &s.v,
            &mut s.f,
            |e, w| energy[e] = w,
        )?;
        s.pf.iter_mut().for_each(|z| *z = Vector3::zeros());
        s.pm.iter_mut().for_each(|z| *z = Vector3::zeros());
        self.layer.add_forces(
            &self.stiffness,
            &self.hexes,
            &s.x,
            &s.v,
            dt,
            &mut s.f,
            &mut s.px,
            &mut s.pv,
            &mut s.pw,
            &mut s.pf,
            &mut s.pm,
        );
        Ok(())
    }

    /// x-centre of element `e` (reference).
    pub fn centre_x(&self, e: usize) -> f64 {
        self.hexes[e]
            .iter()
            .map(|&p| self.x0[p as usize][0])
            .sum::<f64>()
            / 8.0
    }
}

/// Adds the elastic forces of the Hex8 elements `hexes` (references
/// `refs`) at positions `x` and velocities `v` to `f`, handing each
/// element's strain energy to `energy`.
pub(super) fn add_hex_forces(
    hexes: &[[u32; 8]],
    refs: &[Hex8Reference],
    material: &ElasticMaterial,
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    f: &mut [Vector3<f64>],
    mut energy: impl FnMut(usize, f64),
) -> Result<(), CantileverError> {
    let material = Hex8Material::new(material);
    for (e, (h, r)) in hexes.iter().zip(refs).enumerate() {
        let res = hex8_forces(
            r,
            &material,
            &h.map(|p| x[p as usize]),
            &h.map(|p| v[p as usize]),
            ThermalState::default(),
        )
        .map_err(|err| err.at_element(e))?;
        for (p, fe) in h.iter().zip(res.forces) {
            f[*p as usize] += fe;
        }
        energy(e, res.strain_energy);
    }
    Ok(())
}
