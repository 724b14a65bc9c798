//! The free surfaces' exchange with the surroundings (issue 20; seed 001
//! secs 7.1.2, 7.1.5, 7.1.6: free-surface convection and radiation), resolved to bodies.

use super::Body;
use crate::scenario::AmbientSpec;

/// Convection and radiation of free surfaces to an ambient.
#[derive(Debug, Clone, PartialEq)]
pub struct Ambient {
    /// Ambient temperature (scenario unit).
    pub temperature: f64,
    /// Film coefficient h (W/m²/K).
    pub h: f64,
    /// Radiation with the materials' emissivities.
    pub radiation: bool,
    /// Per body: whether its free surface exchanges heat with the ambient.
    pub body: Vec<bool>,
}

impl Ambient {
    /// The ambient of `spec` over `bodies` (a body is in when its name or
    /// its scenario entry is listed, or the list is empty).
    pub fn new(spec: &AmbientSpec, bodies: &[Body]) -> Ambient {
        let listed = |b: &Body| {
            spec.bodies.is_empty() || spec.bodies.iter().any(|n| *n == b.name || *n == b.template)
        };
        Ambient {
            temperature: spec.temperature,
            h: spec.h,
            radiation: spec.radiation,
            body: bodies.iter().map(listed).collect(),
        }
    }
}

impl super::Model {
    /// Whether the run has any of issue 20's thermal contact physics: an
    /// ambient, gaps, a pressure-dependent conductance or frictional heating.
    pub fn has_contact_physics(&self) -> bool {
        self.thermal.ambient.is_some()
            || self.contact.as_ref().is_some_and(|c| {
                c.gap.is_some()
                    || c.friction_heating.is_some()
                    || c.cmy.iter().flatten().any(Option::is_some)
            })
    }
}
