//! Serial "wave across the interface" of issue 21: a compression pulse
//! runs along a bar FE │ DE │ FE ([`super::fede_bar::CoupledBar`]: Hex8 on
//! [0, x₁] and [x₂, L], the bonded sphere lattice on [x₁, x₂], one ghost
//! layer on each side, [`Coupling::Interface`] by default). Undamped
//! explicit dynamics (central differences).
//!
//! Loading: the face X = 0 is driven along +x with the raised-cosine
//! velocity V(t) = V₀ sin²(π t/T) for 0 < t < T and held at rest after;
//! the pulse is L_p = c T long. The far end is free.
//!
//! Lateral motion is restrained everywhere (every node and sphere moves
//! along x only; the spheres keep their rotations), so the wave is the
//! one-dimensional wave of uniaxial strain, with no geometric dispersion
//! from the lateral inertia of a free bar and no dependence on how the
//! lattice's free lateral surfaces are weighted. Its speed is that of the
//! constrained (P-wave) modulus M of each region:
//! - FE: M = λ + 2μ = E(1 − ν)/((1 + ν)(1 − 2ν)), c = √(M/ρ)
//!   ([`constrained_wave_speed`]);
//! - DE: the modulus the lattice has for a uniform strain ε along a lattice
//!   axis, from its eq 4 springs ([`lattice_axial_modulus`]), over the
//!   lattice's density m/(2r)³ ([`lattice_wave_speed`]). Eq 4 is an energy
//!   equivalence, so for ν ≤ 1/4 this equals the FE's M; it is computed
//!   from the springs, not assumed. It is the long-wave limit. In
//!   uniaxial motion the face and edge bonds join each layer of spheres to
//!   the next only, so the lattice is a chain of layers of spacing a = 2r,
//!   ω = 2 √(K/m) sin(ka/2): at wavelengths of 20 spacings and more (where
//!   the energy of a raised cosine 20 spacings long lies) the group
//!   velocity is within 1.2 % of c. The Hex8 segments (lumped mass,
//!   h = 2a) are the same chain with spacing h, within 5 % there.
//!
//! Measured:
//! - the x-velocity history (mean over the cross-section) at two stations
//!   per region, a node plane in FE, a sphere layer in DE; the arrival time
//!   of the pulse at a station is the centroid ∫ t v dt / ∫ v dt of its
//!   velocity over the contiguous interval around the peak where v exceeds
//!   2 % of the peak;
//! - the energy (kinetic, translation and rotation of the spheres, plus
//!   stored: element strain energy, bond energy) of each region, at times
//!   chosen from the geometry and the region speeds: incident, when the
//!   pulse is wholly inside the first FE segment; reflected at FE → DE, the
//!   first FE segment after the pulse has left it and before anything comes
//!   back into it; reflected in all, the first FE segment plus the DE
//!   segment after the pulse has passed into the second FE segment and
//!   before the reflection from the free end comes back.

use nalgebra::Vector3;

use super::cantilever::CantileverError;
use super::fede_bar::CoupledBar;
use super::fede_coupling::Coupling;
use crate::mechanics::bond::{update_particles, BondStiffness};
use crate::mechanics::ElasticMaterial;
use crate::mesh::MeshError;

/// The bar of the wave test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveBar {
    /// Length L (m).
    pub length: f64,
    /// DE segment [x₁, x₂] (m), multiples of `size` and of 2r.
    pub de_segment: [f64; 2],
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
    /// Pulse length L_p = c T in the first FE segment (m).
    pub pulse_length: f64,
    /// Peak strain of the pulse, V₀/c.
    pub strain: f64,
}

impl WaveBar {
    /// The seed 002 material, mesh (h = 0.5 mm) and spheres (r = 0.125 mm);
    /// a 1 mm × 1 mm section (2 × 2 elements, 4 × 4 spheres); a pulse of 20
    /// particle spacings (5 mm); each region 3 pulse lengths long (the
    /// energy windows need more than 1.5, module docs); peak strain 1e-4.
    pub fn seed002() -> Self {
        let pulse = 20.0 * 2.0 * 0.125e-3;
        Self {
            length: 9.0 * pulse,
            de_segment: [3.0 * pulse, 6.0 * pulse],
            width: 1e-3,
            height: 1e-3,
            size: 0.5e-3,
            radius: 0.125e-3,
            young: 1e9,
            poisson: 0.23,
            density: 1000.0,
            pulse_length: pulse,
            strain: 1e-4,
        }
    }

    /// The material (no expansion, no viscosity).
    pub fn material(&self) -> ElasticMaterial {
        ElasticMaterial::elastic(self.young, self.poisson, self.density)
    }

    /// Start and end (m) of region 0 (FE), 1 (DE) and 2 (FE).
    pub fn regions(&self) -> [[f64; 2]; 3] {
        let [x1, x2] = self.de_segment;
        [[0.0, x1], [x1, x2], [x2, self.length]]
    }
}

/// Speed √(M/ρ) of a uniaxial-strain wave in the continuum,
/// M = E(1 − ν)/((1 + ν)(1 − 2ν)) = λ + 2μ (m/s).
pub fn constrained_wave_speed(material: &ElasticMaterial) -> f64 {
    let (e, nu) = (material.young, material.poisson);
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    (m / material.density).sqrt()
}

/// Modulus M (Pa) of the interior cubic lattice of spheres of radius
/// `radius` with the springs `stiffness` for a uniform strain ε along a
/// lattice axis (x), σ_xx = M ε: each sphere owns one bond of each of the
/// 13 directions o (face, edge, corner); a bond of length ℓ = 2r|o| and
/// direction n stretches by ℓ ε n_x e_x, normal part ℓ ε n_x², tangential
/// part of squared length ℓ² ε² n_x² (1 − n_x²); its energy summed over the
/// 13 and set equal to ½ M ε² (2r)³ gives M.
pub fn lattice_axial_modulus(stiffness: &BondStiffness, radius: f64) -> f64 {
    let mut sum = 0.0;
    for k in -1i32..=1 {
        for j in -1i32..=1 {
            for i in -1i32..=1 {
                let o = [i, j, k];
                // Each direction once: the first non-zero component (from z) positive.
                if o.iter().rev().find(|&&c| c != 0).is_none_or(|&c| c < 0) {
                    continue;
                }
                let count: i32 = o.iter().map(|c| c * c).sum();
                let kind = (count - 1) as usize;
                let len2 = 4.0 * radius * radius * f64::from(count);
                let nx2 = f64::from(i * i) / f64::from(count);
                // seed 002 eq 3: bond energy ½ k_n d_n² + ½ k_s |d_t|² (d_t with k_s = k_t).
                sum += len2
                    * (stiffness.normal[kind] * nx2 * nx2
                        + stiffness.tangential[kind] * nx2 * (1.0 - nx2));
            }
        }
    }
    sum / (2.0 * radius).powi(3)
}

/// Long-wave speed √(M/ρ) of the lattice along an axis, M from
/// [`lattice_axial_modulus`] and ρ = m/(2r)³ with `mass` the sphere's (m/s).
pub fn lattice_wave_speed(stiffness: &BondStiffness, radius: f64, mass: f64) -> f64 {
    let density = mass / (2.0 * radius).powi(3);
    (lattice_axial_modulus(stiffness, radius) / density).sqrt()
}

/// A measuring station.
#[derive(Debug, Clone, PartialEq)]
pub struct Station {
    /// Region: 0 (FE), 1 (DE), 2 (FE).
    pub region: usize,
    /// Position (m): the node plane or sphere layer.
    pub x: f64,
    /// Arrival time of the pulse (centroid of the velocity, s).
    pub arrival: f64,
    /// Peak velocity (m/s).
    pub peak: f64,
}

/// What the wave test measured.
#[derive(Debug, Clone, PartialEq)]
pub struct WaveResult {
    /// Wave speed of each region (m/s): FE, DE (from the lattice), FE.
    pub speeds: [f64; 3],
    /// Pulse duration T (s).
    pub duration: f64,
    /// Two stations per region, in order along x.
    pub stations: Vec<Station>,
    /// Incident energy: all energy when the pulse is inside the first FE segment (J).
    pub incident: f64,
    /// Energy of the first FE segment after the pulse has left it (J).
    pub reflected_fe_de: f64,
    /// Energy of the first FE segment and the DE segment after the pulse
    /// has passed into the second FE segment (J).
    pub reflected: f64,
    /// Energy of the second FE segment at that time (J).
    pub transmitted: f64,
    /// Largest |total energy − incident| / incident after the loading (J/J).
    pub energy_drift: f64,
    /// Times (s) of the incident, FE → DE and total measurements.
    pub times: [f64; 3],
    /// Explicit steps.
    pub steps: usize,
    /// Time step (s).
    pub dt: f64,
}

/// Centroid time and peak of a velocity history sampled at `t0 + i dt`:
/// over the contiguous interval around the peak where v > 2 % of the peak.
fn centroid(history: &[f64], t0: f64, dt: f64) -> (f64, f64) {
    let (peak_at, peak) =
        history
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |a, (i, v)| if v > a.1 { (i, v) } else { a },
            );
    let cut = 0.02 * peak;
    let lo = (0..peak_at)
        .rev()
        .find(|&i| history[i] <= cut)
        .map_or(0, |i| i + 1);
    let hi = (peak_at..history.len())
        .find(|&i| history[i] <= cut)
        .unwrap_or(history.len());
    let (mut tv, mut sv) = (0.0, 0.0);
    for (i, v) in history.iter().enumerate().take(hi).skip(lo) {
        tv += (t0 + i as f64 * dt) * v;
        sv += v;
    }
    (tv / sv, peak)
}

/// Runs the pulse across the bar, the interface joined by `coupling`.
pub fn fede_wave(bar: &WaveBar, coupling: Coupling) -> Result<WaveResult, CantileverError> {
    let material = bar.material();
    let dims = [bar.length, bar.width, bar.height];
    let (h, r) = (bar.size, bar.radius);
    let mut model = CoupledBar::new(dims, h, r, bar.de_segment, material, coupling)?;
    let dt = model.dt;
    let c_fe = constrained_wave_speed(&material);
    let c_de = lattice_wave_speed(&model.stiffness, r, model.pmass);
    let speeds = [c_fe, c_de, c_fe];
    let regions = bar.regions();
    let [x1, x2] = bar.de_segment;
    let duration = bar.pulse_length / c_fe;
    let v0 = bar.strain * c_fe;
    // Front arrival at each interface and the clean windows (module docs).
    let cross = |k: usize| (regions[k][1] - regions[k][0]) / speeds[k];
    let (t1, t2) = (cross(0), cross(0) + cross(1));
    let windows = [
        // Pulse inside FE₁: loading over, front not yet at x₁.
        [duration, t1],
        // Pulse out of FE₁; before its reflection off X = 0 or the one from x₂ is back at x₁.
        [t1 + duration, (3.0 * t1).min(t1 + 2.0 * cross(1))],
        // Pulse in FE₂; before the reflection from the free end is back at x₂.
        [t2 + duration, t2 + 2.0 * cross(2)],
    ];
    if let Some(w) = windows.iter().find(|w| w[1] <= w[0]) {
        return Err(MeshError::InvalidParameter(format!(
            "the regions are too short for the pulse: empty window {w:?} s (T = {duration} s)"
        ))
        .into());
    }
    let times = windows.map(|w| 0.5 * (w[0] + w[1]));
    let sample = times.map(|t| (t / dt).round() as usize);

    // Stations at 0.2 and 0.6 of each region: node planes in FE, sphere layers in DE.
    let np0 = model.n[0] + 1;
    let nx = model.counts[0];
    let layer_x = |i: usize| x1 - 2.0 * r + r * (2 * i + 1) as f64;
    let mut stations = Vec::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    for (k, [a, b]) in regions.iter().enumerate() {
        for frac in [0.2, 0.6] {
            let target = a + frac * (b - a);
            let (x, set) = if k == 1 {
                let i = (((target - x1) / (2.0 * r) + 0.5).round() as usize).clamp(1, nx - 2);
                let set = (0..model.p0.len()).filter(|&p| p % nx == i).collect();
                (layer_x(i), set)
            } else {
                let i = (target / h).round() as usize;
                let set = (0..model.x0.len()).filter(|&p| p % np0 == i).collect();
                (model.x0[i][0], set)
            };
            stations.push(Station {
                region: k,
                x,
                arrival: f64::NAN,
                peak: f64::NAN,
            });
            members.push(set);
        }
    }
    let last = stations.last().map_or(0.0, |s| s.x);
    let t_end = times[2].max(t2 + (last - x2) / c_fe + 2.0 * duration);
    let steps = (t_end / dt).ceil() as usize;

    // Regions of nodes, elements and spheres (usize::MAX: not counted).
    let node_region: Vec<usize> = (model.x0.iter().zip(&model.mass))
        .map(|(p, &m)| match p[0] {
            _ if m == 0.0 => usize::MAX,
            x if x <= x1 => 0,
            _ => 2,
        })
        .collect();
    let elem_region: Vec<usize> = (0..model.hexes.len())
        .map(|e| if model.centre_x(e) < x1 { 0 } else { 2 })
        .collect();
    let ghost: Vec<bool> = model.normal.iter().map(Option::is_some).collect();
    let driven = model.node_sets["xmin"].clone();

    let mut s = model.state();
    let (mut v_old, mut pv_old, mut pw_old) = (s.v.clone(), s.pv.clone(), s.pw.clone());
    let mut history = vec![Vec::with_capacity(steps); stations.len()];
    let mut measured = [[0.0; 3]; 3];
    let mut incident = f64::NAN;
    let mut energy_drift: f64 = 0.0;
    let (pmass, inertia) = (model.pmass, model.inertia);
    for step in 0..steps {
        s.f.iter_mut().for_each(|z| *z = Vector3::zeros());
        model.forces(&mut s, dt)?;
        let t_half = (step as f64 + 0.5) * dt;
        // Lateral restraint: motion along x only.
        for z in s.f.iter_mut().chain(s.pf.iter_mut()) {
            z[1] = 0.0;
            z[2] = 0.0;
        }
        for p in 0..s.x.len() {
            if model.mass[p] > 0.0 {
                s.v[p] += s.f[p] * (dt / model.mass[p]);
            }
        }
        let drive = if t_half < duration {
            v0 * (std::f64::consts::PI * t_half / duration).sin().powi(2)
        } else {
            0.0
        };
        for &p in &driven {
            s.v[p as usize] = Vector3::new(drive, 0.0, 0.0);
        }
        for (x, v) in s.x.iter_mut().zip(&s.v) {
            *x += v * dt;
        }
        update_particles(
            pmass, inertia, 0.0, dt, &ghost, &s.pf, &s.pm, &mut s.px, &mut s.pv, &mut s.pw,
        );
        // Energy at step time t = step dt: kinetic as ½ m v(t − dt/2)·v(t + dt/2).
        let mut energy = [0.0; 3];
        for (e, &k) in elem_region.iter().enumerate() {
            energy[k] += model.strain_energy[e];
        }
        for (p, &k) in node_region.iter().enumerate() {
            if k != usize::MAX {
                energy[k] += 0.5 * model.mass[p] * v_old[p].dot(&s.v[p]);
            }
        }
        energy[1] += model.layer.stored_energy(&model.stiffness);
        for p in (0..s.px.len()).filter(|&p| !ghost[p]) {
            energy[1] += 0.5 * pmass * pv_old[p].dot(&s.pv[p]);
            energy[1] += 0.5 * inertia * pw_old[p].dot(&s.pw[p]);
        }
        let total: f64 = energy.iter().sum();
        if step == sample[0] {
            incident = total;
        }
        if step > sample[0] && incident.is_finite() {
            energy_drift = energy_drift.max((total - incident).abs() / incident);
        }
        for (i, &at) in sample.iter().enumerate() {
            if step == at {
                measured[i] = energy;
            }
        }
        for ((hist, set), st) in history.iter_mut().zip(&members).zip(&stations) {
            let v = if st.region == 1 { &s.pv } else { &s.v };
            hist.push(set.iter().map(|&p| v[p][0]).sum::<f64>() / set.len() as f64);
        }
        v_old.clone_from(&s.v);
        pv_old.clone_from(&s.pv);
        pw_old.clone_from(&s.pw);
    }
    for (st, hist) in stations.iter_mut().zip(&history) {
        (st.arrival, st.peak) = centroid(hist, 0.5 * dt, dt);
    }
    Ok(WaveResult {
        speeds,
        duration,
        stations,
        incident,
        reflected_fe_de: measured[1][0],
        reflected: measured[2][0] + measured[2][1],
        transmitted: measured[2][2],
        energy_drift,
        times,
        steps,
        dt,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_axial_modulus_is_the_constrained_modulus() {
        // Eq 4 is an energy equivalence: the lattice's axial modulus is λ + 2μ for ν ≤ 1/4.
        let r = 0.125e-3;
        for nu in [-0.3, 0.0, 0.1, 0.23, 0.25] {
            let material = ElasticMaterial {
                young: 1e9,
                poisson: nu,
                density: 1000.0,
                expansion: 0.0,
                viscosity: 0.0,
            };
            let k = BondStiffness::seed002(material.young, nu, r).unwrap();
            let mass = material.density * (2.0 * r).powi(3);
            let c = constrained_wave_speed(&material);
            assert!(
                (lattice_wave_speed(&k, r, mass) / c - 1.0).abs() < 1e-14,
                "{nu}"
            );
        }
    }

    #[test]
    fn centroid_of_a_shifted_raised_cosine() {
        // sin² over [t₀, t₀ + T] sampled on a fine grid: centroid t₀ + T/2, peak 1.
        let (dt, t0, period) = (1e-3, 0.3, 0.25);
        let v: Vec<f64> = (0..1000)
            .map(|i| {
                let s = (i as f64 * dt - t0) / period;
                if (0.0..1.0).contains(&s) {
                    (std::f64::consts::PI * s).sin().powi(2)
                } else {
                    0.0
                }
            })
            .collect();
        let (t, peak) = centroid(&v, 0.0, dt);
        assert!((t - (t0 + 0.5 * period)).abs() < 1e-9, "{t}");
        assert!((peak - 1.0).abs() < 1e-3);
    }
}
