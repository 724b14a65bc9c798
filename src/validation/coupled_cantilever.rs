//! Serial reference driver for the coupled cantilever of seed 002 (Fig 7):
//! Hex8 segments on [0, x₁] and [x₂, L], a bonded sphere lattice on
//! [x₁, x₂], joined through one layer of ghost particles on each side
//! (eq 5: x_g = x_b − 2 r n, inside the boundary elements), coupled as
//! [`super::fede_coupling`] says ([`Coupling::Interface`] by default,
//! [`Coupling::Seed`] for eqs 16–17 as written).
//!
//! The lattice is generated over [x₁ − 2r, x₂ + 2r]: its first and last
//! layers are the ghosts. Ghost–ghost bonds are dropped (the elements carry
//! that material). Relaxation, loads and measures as in
//! [`super::cantilever`].

use nalgebra::Vector3;

use super::cantilever::{Cantilever, CantileverError, Relaxation, StaticSolution};
use super::fede_coupling::{schur_bound, Coupling, GhostLayer};
use crate::mechanics::bond::{sphere_mass_inertia, update_particles, BondStiffness};
use crate::mechanics::hex8_element::{hex8_forces, Hex8Reference};
use crate::mechanics::ThermalState;
use crate::mesh::hex8::hex_box;
use crate::mesh::lattice::cubic_lattice;
use crate::mesh::MeshError;

/// The coupled beam: elements of side `size`, spheres of radius `radius`
/// on [x₁, x₂] = `de_segment` (multiples of `size` and of 2r), joined by
/// `coupling`.
pub fn coupled_cantilever(
    beam: &Cantilever,
    size: f64,
    radius: f64,
    de_segment: [f64; 2],
    coupling: Coupling,
    relaxation: &Relaxation,
) -> Result<StaticSolution, CantileverError> {
    let [x1, x2] = de_segment;
    if !(0.0 < x1 && x1 < x2 && x2 < beam.length) {
        return Err(MeshError::InvalidParameter(format!(
            "DE segment [{x1}, {x2}] must lie inside the beam (0, {})",
            beam.length
        ))
        .into());
    }
    let n = [beam.length, beam.width, beam.height].map(|d| ((d / size).round() as usize).max(1));
    let full = hex_box([0.0; 3], [beam.length, beam.width, beam.height], n)?;
    let material = beam.material();
    let x0: Vec<Vector3<f64>> = full.nodes.iter().map(|p| Vector3::from(*p)).collect();
    let nodes = x0.len();
    // Elements of the FE segments; `kept[e]` maps a box element to its index here.
    let mut hexes = Vec::new();
    let mut refs = Vec::new();
    let mut kept = vec![usize::MAX; full.hexes.len()];
    let mut mass = vec![0.0; nodes];
    let mut dt = f64::INFINITY;
    for (e, h) in full.hexes.iter().enumerate() {
        let centre: f64 = h.iter().map(|&p| x0[p as usize][0]).sum::<f64>() / 8.0;
        if centre > x1 && centre < x2 {
            continue;
        }
        let r = Hex8Reference::new(&h.map(|a| x0[a as usize])).map_err(|err| err.at_element(e))?;
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
        [x2 + 2.0 * radius, beam.width, beam.height],
        radius,
        false,
    )?;
    let stiffness = BondStiffness::seed002(beam.young, beam.poisson, radius)?;
    let (pmass, inertia) = sphere_mass_inertia(beam.density, radius);
    let c = lattice.counts;
    let p0: Vec<Vector3<f64>> = lattice.centres.iter().map(|p| Vector3::from(*p)).collect();
    let count = p0.len();
    // Ghosts: the first and last layers, normals from FE into DE.
    let normal: Vec<Option<Vector3<f64>>> = (0..count)
        .map(|p| match p % c[0] {
            0 => Some(Vector3::x()),
            i if i == c[0] - 1 => Some(-Vector3::x()),
            _ => None,
        })
        .collect();
    let locate = |xg: &Vector3<f64>| {
        let cell = [0, 1, 2].map(|a| ((xg[a] / size).floor().max(0.0) as usize).min(n[a] - 1));
        kept[cell[0] + n[0] * (cell[1] + n[1] * cell[2])]
    };
    let mut layer = GhostLayer::new(coupling, &lattice, &normal, &hexes, &x0, locate)?;
    let omega_max = schur_bound(layer.all_bonds(), &stiffness, &p0, pmass, inertia);
    dt = dt.min(0.95 * 2.0 / omega_max);
    // FE boundary conditions and load, as in the FE-only driver.
    let mut fixed_node: Vec<bool> = mass.iter().map(|m| *m == 0.0).collect();
    for &p in &full.node_sets["xmin"] {
        fixed_node[p as usize] = true;
    }
    let tip_nodes = &full.node_sets["xmax"];
    let np = [n[0] + 1, n[1] + 1, n[2] + 1];
    let weights: Vec<f64> = tip_nodes
        .iter()
        .map(|&p| {
            let p = p as usize;
            let (j, k) = ((p / np[0]) % np[1], p / (np[0] * np[1]));
            let edge = |c: usize, m: usize| if c == 0 || c == m { 0.5 } else { 1.0 };
            edge(j, n[1]) * edge(k, n[2])
        })
        .collect();
    let wsum: f64 = weights.iter().sum();
    let mut external = vec![Vector3::zeros(); nodes];
    for (&p, w) in tip_nodes.iter().zip(&weights) {
        external[p as usize] = Vector3::new(0.0, 0.0, -beam.load * w / wsum);
    }
    let damping = relaxation.damping * beam.first_frequency();
    let (a, b) = (1.0 - 0.5 * damping * dt, 1.0 / (1.0 + 0.5 * damping * dt));
    let fixed_particle: Vec<bool> = normal.iter().map(Option::is_some).collect();
    let (mut x, mut v, mut f) = (
        x0.clone(),
        vec![Vector3::zeros(); nodes],
        vec![Vector3::zeros(); nodes],
    );
    let (mut px, mut pv) = (p0.clone(), vec![Vector3::zeros(); count]);
    let (mut pw, mut pf, mut pm) = (
        vec![Vector3::zeros(); count],
        vec![Vector3::zeros(); count],
        vec![Vector3::zeros(); count],
    );
    let check =
        ((2.0 * std::f64::consts::PI / beam.first_frequency()) / (50.0 * dt)).ceil() as usize;
    let (tip, steps) = super::cantilever::relax(relaxation, check, || {
        f.copy_from_slice(&external);
        for (e, (h, r)) in hexes.iter().zip(&refs).enumerate() {
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
        }
        pf.iter_mut().for_each(|z| *z = Vector3::zeros());
        pm.iter_mut().for_each(|z| *z = Vector3::zeros());
        layer.add_forces(
            &stiffness, &hexes, &x, &v, dt, &mut f, &mut px, &mut pv, &mut pw, &mut pf, &mut pm,
        );
        for p in 0..nodes {
            if fixed_node[p] {
                continue;
            }
            v[p] = (v[p] * a + f[p] * (dt / mass[p])) * b;
            x[p] += v[p] * dt;
        }
        update_particles(
            pmass,
            inertia,
            damping,
            dt,
            &fixed_particle,
            &pf,
            &pm,
            &mut px,
            &mut pv,
            &mut pw,
        );
        let u: f64 = tip_nodes
            .iter()
            .zip(&weights)
            .map(|(&p, w)| (x0[p as usize][2] - x[p as usize][2]) * w)
            .sum();
        Ok(u / wsum)
    })?;
    // Profile: FE cross-sections (nodes with mass) and DE layers (no ghosts).
    let mut profile = Vec::new();
    for i in 0..np[0] {
        let cols: Vec<usize> = (0..nodes)
            .filter(|&p| p % np[0] == i && mass[p] > 0.0)
            .collect();
        if !cols.is_empty() {
            let s: f64 = cols.iter().map(|&p| x0[p][2] - x[p][2]).sum();
            profile.push((x0[i][0], s / cols.len() as f64));
        }
    }
    for i in 1..c[0] - 1 {
        let layer: Vec<usize> = (0..count).filter(|&p| p % c[0] == i).collect();
        let s: f64 = layer.iter().map(|&p| p0[p][2] - px[p][2]).sum();
        profile.push((p0[i][0], s / layer.len() as f64));
    }
    profile.sort_by(|l, r| l.0.total_cmp(&r.0));
    Ok(StaticSolution {
        tip_x: beam.length,
        tip,
        profile,
        steps,
        dt,
    })
}
