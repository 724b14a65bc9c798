//! Serial reference driver for the coupled cantilever of seed 002 (Fig 7):
//! Hex8 segments on [0, x₁] and [x₂, L], a bonded sphere lattice on
//! [x₁, x₂], joined through one layer of ghost particles on each side
//! (eq 5: x_g = x_b − 2 r n, inside the boundary elements), coupled as
//! [`super::fede_coupling`] says ([`Coupling::Interface`] by default,
//! [`Coupling::Seed`] for eqs 16–17 as written).
//!
//! The model is [`super::fede_bar::CoupledBar`]. Relaxation, loads and
//! measures as in [`super::cantilever`].

use nalgebra::Vector3;

use super::cantilever::{Cantilever, CantileverError, Relaxation, StaticSolution};
use super::fede_bar::CoupledBar;
use super::fede_coupling::Coupling;
use crate::mechanics::bond::update_particles;

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
    let mut bar = CoupledBar::new(
        [beam.length, beam.width, beam.height],
        size,
        radius,
        de_segment,
        beam.material(),
        coupling,
    )?;
    let (n, dt, nodes, count) = (bar.n, bar.dt, bar.x0.len(), bar.p0.len());
    let c = bar.counts;
    // FE boundary conditions and load, as in the FE-only driver.
    let mut fixed_node: Vec<bool> = bar.mass.iter().map(|m| *m == 0.0).collect();
    for &p in &bar.node_sets["xmin"] {
        fixed_node[p as usize] = true;
    }
    let tip_nodes = bar.node_sets["xmax"].clone();
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
    let fixed_particle: Vec<bool> = bar.normal.iter().map(Option::is_some).collect();
    let mut s = bar.state();
    let check =
        ((2.0 * std::f64::consts::PI / beam.first_frequency()) / (50.0 * dt)).ceil() as usize;
    let (tip, steps) = super::cantilever::relax(relaxation, check, || {
        s.f.copy_from_slice(&external);
        bar.forces(&mut s, dt)?;
        for (p, &fixed) in fixed_node.iter().enumerate() {
            if fixed {
                continue;
            }
            s.v[p] = (s.v[p] * a + s.f[p] * (dt / bar.mass[p])) * b;
            s.x[p] += s.v[p] * dt;
        }
        update_particles(
            bar.pmass,
            bar.inertia,
            damping,
            dt,
            &fixed_particle,
            &s.pf,
            &s.pm,
            &mut s.px,
            &mut s.pv,
            &mut s.pw,
        );
        let u: f64 = tip_nodes
            .iter()
            .zip(&weights)
            .map(|(&p, w)| (bar.x0[p as usize][2] - s.x[p as usize][2]) * w)
            .sum();
        Ok(u / wsum)
    })?;
    let (x0, p0, x, px) = (&bar.x0, &bar.p0, &s.x, &s.px);
    // Profile: FE cross-sections (nodes with mass) and DE layers (no ghosts).
    let mut profile = Vec::new();
    for i in 0..np[0] {
        let cols: Vec<usize> = (0..nodes)
            .filter(|&p| p % np[0] == i && bar.mass[p] > 0.0)
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
