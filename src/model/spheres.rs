//! Free discrete-element spheres in the model (issue 21, beyond the
//! papers): each `[[spheres]]` table as a set of one radius and material,
//! and their seeded placement ([`crate::geometry::sphere_sites::box_sites`]).
//! Global sphere numbers run set by set, each set in its placement order.

use crate::geometry::sphere_sites::box_sites;
use crate::scenario::Scenario;

/// One set of free spheres.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereSet {
    /// Material index (density, young, poisson).
    pub material: u32,
    /// Radius (m).
    pub radius: f64,
    /// Density (kg/m³), Young's modulus (Pa), Poisson's ratio.
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
    /// Number of spheres.
    pub count: u32,
    /// Placement box (low, high corner), seed and gap (m).
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub seed: u64,
    pub gap: f64,
    /// Damping ratio ζ and friction coefficient μ of its contacts.
    pub damping: f64,
    pub friction: f64,
    /// Conductivity (W/(m K)), specific heat (J/(kg K)) and initial
    /// temperature (used by a thermal run).
    pub conductivity: f64,
    pub specific_heat: f64,
    pub temperature: f64,
}

/// The sphere sets of a validated scenario (materials resolved by name).
pub(super) fn sphere_sets(s: &Scenario) -> Vec<SphereSet> {
    s.spheres
        .iter()
        .map(|sp| {
            let m = s
                .materials
                .iter()
                .position(|m| m.name == sp.material)
                .expect("validated: the material exists");
            let mat = &s.materials[m];
            SphereSet {
                material: m as u32,
                radius: sp.radius,
                density: mat.density,
                young: mat.young.expect("validated"),
                poisson: mat.poisson.expect("validated"),
                count: sp.count as u32,
                min: sp.region.min,
                max: sp.region.max,
                seed: sp.seed,
                gap: sp.gap,
                damping: sp.damping,
                friction: sp.friction,
                conductivity: mat.conductivity.unwrap_or(0.0),
                specific_heat: mat.specific_heat.unwrap_or(0.0),
                temperature: sp.temperature.unwrap_or(0.0),
            }
        })
        .collect()
}

/// Every sphere's set and centre, by global number: each set placed in
/// its own box (sets do not see each other: give them boxes apart).
/// Errors name the key (`spheres[i].count` when they do not fit).
pub fn place_spheres(sets: &[SphereSet]) -> Result<Vec<(u32, [f64; 3])>, String> {
    let mut out = Vec::new();
    for (i, s) in sets.iter().enumerate() {
        let sites = box_sites(s.count as usize, s.radius, s.gap, s.min, s.max, s.seed)
            .map_err(|e| format!("spheres[{i}].{e}"))?;
        out.extend(sites.into_iter().map(|x| (i as u32, x)));
    }
    Ok(out)
}
