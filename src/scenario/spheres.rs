//! The `[[spheres]]` tables: sets of free discrete-element spheres
//! (issue 21, beyond the papers) placed at random in a box beside the
//! Tet4 bodies, and their checks (errors name the key).

use serde::{Deserialize, Serialize};

use super::Scenario;

/// One set of free spheres of one radius and material.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Material (by name): `density`, `young` and `poisson` are used, and
    /// with `[thermal]` its `conductivity` and `specific_heat`.
    pub material: String,
    /// Radius (m).
    pub radius: f64,
    /// Number of spheres.
    pub count: u64,
    /// The box the centres are drawn in: every sphere lies wholly inside.
    #[serde(rename = "box")]
    pub region: SphereBox,
    /// Seed of the random placement.
    #[serde(default)]
    pub seed: u64,
    /// Smallest surface-to-surface distance between two placed spheres (m).
    #[serde(default)]
    pub gap: f64,
    /// Damping ratio ζ of the spheres' normal contacts.
    #[serde(default = "default_sphere_damping")]
    pub damping: f64,
    /// Coulomb friction coefficient μ of the spheres' contacts.
    #[serde(default = "default_sphere_friction")]
    pub friction: f64,
    /// Initial temperature of every sphere of the set (a run with
    /// `[thermal]`; default 0, as a body's `initial_temperature`).
    #[serde(default)]
    pub temperature: Option<f64>,
}

/// An axis-aligned box, low and high corner (m).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

fn default_sphere_damping() -> f64 {
    0.3
}

fn default_sphere_friction() -> f64 {
    0.5
}

impl Scenario {
    /// Checks of the `[[spheres]]` tables; (key path, message).
    pub(super) fn validate_spheres(&self) -> Result<(), (String, String)> {
        for (i, s) in self.spheres.iter().enumerate() {
            let key = |k: &str| format!("spheres[{i}].{k}");
            let bad = |k: &str, m: String| Err((key(k), m));
            let Some(mat) = self.materials.iter().find(|m| m.name == s.material) else {
                return bad("material", format!("no material named `{}`", s.material));
            };
            match (mat.young, mat.poisson) {
                (Some(e), Some(nu)) if e.is_finite() && e > 0.0 && nu > -1.0 && nu < 0.5 => {}
                _ => {
                    return bad(
                        "material",
                        format!(
                            "material `{}` needs a positive `young` and a `poisson` in \
                             (-1, 0.5) for the spheres' Hertz contact",
                            s.material
                        ),
                    )
                }
            }
            if !(mat.density.is_finite() && mat.density > 0.0) {
                return bad(
                    "material",
                    format!("material `{}` needs a positive `density`", s.material),
                );
            }
            if !(s.radius.is_finite() && s.radius > 0.0) {
                return bad("radius", format!("must be positive, got {}", s.radius));
            }
            if s.count == 0 || s.count > u64::from(u32::MAX) {
                return bad(
                    "count",
                    format!("must be between 1 and {}, got {}", u32::MAX, s.count),
                );
            }
            let b = &s.region;
            for d in 0..3 {
                if !(b.min[d].is_finite()
                    && b.max[d].is_finite()
                    && b.max[d] - b.min[d] >= 2.0 * s.radius)
                {
                    return bad(
                        "box",
                        format!(
                            "min {:?} .. max {:?} must be finite and at least a diameter ({}) \
                             wide along every axis",
                            b.min,
                            b.max,
                            2.0 * s.radius
                        ),
                    );
                }
            }
            // More than random close packing cannot fit (placement would
            // try for long before saying so).
            let room: f64 = (0..3).map(|d| b.max[d] - b.min[d]).product();
            let solid = s.count as f64 * 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
            if solid > 0.64 * room {
                return bad(
                    "count",
                    format!(
                        "{} spheres of radius {} fill {:.0} % of the box's {room:e} m³, more \
                         than any packing (64 %): enlarge the box or lower the count",
                        s.count,
                        s.radius,
                        100.0 * solid / room
                    ),
                );
            }
            if !(s.gap.is_finite() && s.gap >= 0.0) {
                return bad("gap", format!("must be non-negative, got {}", s.gap));
            }
            if !(s.damping.is_finite() && s.damping >= 0.0) {
                return bad(
                    "damping",
                    format!("must be non-negative, got {}", s.damping),
                );
            }
            if !(s.friction.is_finite() && s.friction >= 0.0) {
                return bad(
                    "friction",
                    format!("must be non-negative, got {}", s.friction),
                );
            }
            // What the spheres do not have yet (issue 21): say so at once.
            if self.mechanics.is_none() {
                return bad("material", "free spheres need a [mechanics] table".into());
            }
            if let Some(t) = s.temperature {
                if !t.is_finite() {
                    return bad("temperature", format!("must be finite, got {t}"));
                }
            }
            if self.thermal.is_some() {
                let k = mat.conductivity.unwrap_or(0.0);
                let c = mat.specific_heat.unwrap_or(0.0);
                if !(k.is_finite() && k > 0.0 && c.is_finite() && c > 0.0) {
                    return bad(
                        "material",
                        format!(
                            "material `{}` needs a positive `conductivity` and \
                             `specific_heat` for the spheres' heat ([thermal])",
                            s.material
                        ),
                    );
                }
            }
            // What the spheres' heat does not have (issue 21): say so at once.
            if self.thermal.as_ref().is_some_and(|t| t.ambient.is_some()) {
                return Err((
                    "thermal.ambient".into(),
                    "free spheres exchange heat through their contacts only: a run with \
                     [[spheres]] takes no [thermal.ambient] (convection, radiation)"
                        .into(),
                ));
            }
            if self
                .contact
                .as_ref()
                .is_some_and(|c| c.friction_heating.is_some())
            {
                return Err((
                    "contact.friction_heating".into(),
                    "the free spheres' contacts make no frictional heat: a run with \
                     [[spheres]] takes no contact.friction_heating"
                        .into(),
                ));
            }
            // The spheres' pipes take a constant R_c only.
            if let Some(c) = &self.contact {
                let own = c.pair.iter().any(|p| {
                    p.materials.contains(&s.material) && (p.cmy.is_some() || p.table.is_some())
                });
                if c.cmy.is_some() || c.table.is_some() || own {
                    return Err((
                        "contact".into(),
                        format!(
                            "free spheres (spheres[{i}], material `{}`) conduct through a \
                             constant contact resistance only: give their material pairs \
                             `resistance` or `conductance`, not `cmy` or `table`",
                            s.material
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
