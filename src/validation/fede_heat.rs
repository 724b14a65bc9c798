//! Serial steady heat conduction across the FE–DE interface (issue 21): the
//! bar of [`super::fede_patch`] (Hex8 on [0, x₁], a bonded sphere lattice on
//! [x₁, L] joined by one layer of ghosts, [`super::fede_coupling`]) held at
//! T₁ on the FE face X = 0 and at the linear field T₁ + (T₂ − T₁) X/L on
//! the last two layers of spheres (centres L − r and L + r, so the bonds
//! into the first held layer keep their interior weights), lateral faces
//! adiabatic. The exact steady field is linear, T₁ + (T₂ − T₁) X/L.
//!
//! FE: the Hex8 conductivity K = k ∫ ∇N_I·∇N_J dV ([`crate::thermal::hex8`]);
//! DE: bonds of conductance h = 2kr/5 per face and edge neighbour
//! ([`crate::mechanics::bond::bond_conductance`]) times the lattice weights;
//! interface: [`super::fede_coupling::GhostLayer::add_heat`]. The steady
//! state is solved directly: the operator's columns are the heat flows of
//! unit temperatures (it is linear), then one Cholesky solve.

use nalgebra::{DMatrix, DVector, Vector3};

use super::fede_coupling::{Coupling, GhostLayer};
use super::fede_patch::PatchBar;
use crate::mechanics::bond::bond_conductance;
use crate::mechanics::hex8_element::Hex8Gauss;
use crate::mechanics::MechanicsError;
use crate::mesh::hex8::hex_box;
use crate::mesh::lattice::cubic_lattice;
use crate::mesh::MeshError;
use crate::thermal::hex8::hex8_conductivity;

/// Errors of the heat driver.
#[derive(Debug, thiserror::Error)]
pub enum FedeHeatError {
    /// From the Hex8 reference geometry.
    #[error(transparent)]
    Mechanics(#[from] MechanicsError),
    /// From the mesh or lattice generator.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A ghost could not be placed.
    #[error(transparent)]
    Ghost(#[from] crate::mechanics::hex8::InverseMapError),
    /// The steady system is not positive definite.
    #[error("the steady conduction matrix is not positive definite")]
    Singular,
}

/// The steady solution and what was measured.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatResult {
    /// (X, T) of every free FE node.
    pub fe_temperature: Vec<(Vector3<f64>, f64)>,
    /// (X, T) of every free sphere.
    pub de_temperature: Vec<(Vector3<f64>, f64)>,
    /// (centre x, q_x = −k ∂T/∂x at the centre) of every element (W/m²).
    pub fe_flux: Vec<(f64, f64)>,
    /// (plane x, heat flow along +x through it over W H) at each plane
    /// between particle layers up to the first held one, the interface
    /// (ghosts | first spheres) first (W/m²).
    pub de_flux: Vec<(f64, f64)>,
    /// Heat into the bar through the FE face X = 0 over W H (W/m²).
    pub inflow: f64,
}

/// Solves the steady conduction of `bar` (its geometry, mesh and spheres)
/// with conductivity `k`, T₁ = `t1` at X = 0 and T₂ = `t2` at X = L.
pub fn fede_heat(
    bar: &PatchBar,
    k: f64,
    t1: f64,
    t2: f64,
    coupling: Coupling,
) -> Result<HeatResult, FedeHeatError> {
    let (h, r, x1) = (bar.size, bar.radius, bar.interface);
    let n = bar.fe_divisions()?;
    let exact = |x: f64| t1 + (t2 - t1) * x / bar.length;
    let mesh = hex_box([0.0; 3], [x1, bar.width, bar.height], n)?;
    let x0: Vec<Vector3<f64>> = mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
    let mut refs = Vec::with_capacity(mesh.hexes.len());
    let mut ke = Vec::with_capacity(mesh.hexes.len());
    for (e, hx) in mesh.hexes.iter().enumerate() {
        let re = Hex8Gauss::new(&hx.map(|a| x0[a as usize])).map_err(|err| err.at_element(e))?;
        ke.push(hex8_conductivity(&re, k));
        refs.push(re);
    }
    let lattice = cubic_lattice(
        [x1 - 2.0 * r, 0.0, 0.0],
        [bar.length + 2.0 * r, bar.width, bar.height],
        r,
        false,
    )?;
    let nx = lattice.counts[0];
    let (p0, normal) = super::fede_coupling::x_interface(&lattice);
    let locate = |p: &Vector3<f64>| {
        let cell = [0, 1, 2].map(|a| ((p[a] / h).floor().max(0.0) as usize).min(n[a] - 1));
        cell[0] + n[0] * (cell[1] + n[1] * cell[2])
    };
    let layer = GhostLayer::new(coupling, &lattice, &normal, &mesh.hexes, &x0, locate)?;
    let cond = bond_conductance(k, r);
    let (nodes, count) = (x0.len(), p0.len());
    // Unknowns: nodes then particles. Held: the face X = 0, the last two sphere layers;
    // ghosts are not unknowns (their temperature is interpolated).
    let mut held = vec![false; nodes + count];
    for &p in &mesh.node_sets["xmin"] {
        held[p as usize] = true;
    }
    let ghost: Vec<bool> = normal.iter().map(Option::is_some).collect();
    for p in 0..count {
        held[nodes + p] = p % nx >= nx - 2;
    }
    // Heat flows into every node and particle at temperatures `temp`.
    let flows = |temp: &[f64]| -> Vec<f64> {
        let (t, pt) = temp.split_at(nodes);
        let mut pt = pt.to_vec();
        let mut q = vec![0.0; nodes];
        let mut pq = vec![0.0; count];
        for (hx, m) in mesh.hexes.iter().zip(&ke) {
            for i in 0..8 {
                // seed 000 eq 16: the element's conduction −K T.
                let qi: f64 = (0..8).map(|j| m[8 * i + j] * t[hx[j] as usize]).sum();
                q[hx[i] as usize] -= qi;
            }
        }
        layer.add_heat(&cond, &mesh.hexes, t, &mut pt, &mut q, &mut pq);
        q.extend(pq);
        q
    };
    let free: Vec<usize> = (0..nodes + count)
        .filter(|&d| !(held[d] || d >= nodes && ghost[d - nodes]))
        .collect();
    let mut temp = vec![0.0; nodes + count];
    for d in (0..nodes + count).filter(|&d| held[d]) {
        let x = if d < nodes {
            x0[d][0]
        } else {
            p0[d - nodes][0]
        };
        temp[d] = exact(x);
    }
    // K_ff T_f = q_f(held values): the flows are −K T, linear in T.
    let q_held = flows(&temp);
    let rhs = DVector::from_iterator(free.len(), free.iter().map(|&d| q_held[d]));
    let mut kff = DMatrix::zeros(free.len(), free.len());
    let mut unit = vec![0.0; nodes + count];
    for (c, &d) in free.iter().enumerate() {
        unit[d] = 1.0;
        let q = flows(&unit);
        unit[d] = 0.0;
        for (rw, &e) in free.iter().enumerate() {
            kff[(rw, c)] = -q[e];
        }
    }
    let solution = kff.cholesky().ok_or(FedeHeatError::Singular)?.solve(&rhs);
    for (i, &d) in free.iter().enumerate() {
        temp[d] = solution[i];
    }
    // Measures.
    let q_final = flows(&temp);
    let area = bar.width * bar.height;
    let mut inflow = 0.0;
    for &p in &mesh.node_sets["xmin"] {
        // The held face's reaction: the heat the bar takes from it.
        inflow -= q_final[p as usize];
    }
    let fe_flux = mesh
        .hexes
        .iter()
        .zip(&refs)
        .map(|(hx, re)| {
            let grad: Vector3<f64> = hx
                .iter()
                .zip(&re.mean_gradient())
                .map(|(a, g)| g * temp[*a as usize])
                .sum();
            let centre = hx.iter().map(|&a| x0[a as usize][0]).sum::<f64>() / 8.0;
            // Fourier: q = −k ∇T.
            (centre, -k * grad[0])
        })
        .collect();
    // DE flux: the heat each bond carries along +x through the planes it crosses.
    let (t_nodes, pt) = temp.split_at(nodes);
    let mut pt = pt.to_vec();
    // Ghost temperatures for the bond list.
    let mut scratch_q = vec![0.0; nodes];
    let mut scratch_pq = vec![0.0; count];
    layer.add_heat(
        &cond,
        &mesh.hexes,
        t_nodes,
        &mut pt,
        &mut scratch_q,
        &mut scratch_pq,
    );
    let mut crossing = vec![0.0; nx - 2];
    for (i, j, flow) in layer.heat_flows(&cond, &mesh.hexes, t_nodes, &pt) {
        let (li, lj) = (i % nx, j % nx);
        // Heat from the left end to the right one.
        let (lo, hi, flow) = if li < lj {
            (li, lj, flow)
        } else {
            (lj, li, -flow)
        };
        for cr in crossing.iter_mut().take(hi.min(nx - 2)).skip(lo) {
            *cr += flow;
        }
    }
    let de_flux = crossing
        .iter()
        .enumerate()
        .map(|(i, c)| (p0[i][0] + r, c / area))
        .collect();
    let fe_temperature = (0..nodes)
        .filter(|&d| !held[d])
        .map(|d| (x0[d], temp[d]))
        .collect();
    let de_temperature = (0..count)
        .filter(|&p| !held[nodes + p] && !ghost[p])
        .map(|p| (p0[p], temp[nodes + p]))
        .collect();
    Ok(HeatResult {
        fe_temperature,
        de_temperature,
        fe_flux,
        de_flux,
        inflow: inflow / area,
    })
}
