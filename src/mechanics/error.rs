//! Error type of the mechanics module ([`MechanicsError`]).
//!
//! Element indices in these errors are positions in the element slice the
//! failing function was given (the global element index when the kernels
//! run on the whole mesh, a rank-local index when they run on a part of
//! it). Errors raised by a single-element
//! kernel carry `elem: None`; the loops over elements fill it in.

/// Errors of the finite-strain mechanics kernels and the explicit integrator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MechanicsError {
    /// A material constant is out of its physical range.
    #[error("invalid material: {0}")]
    InvalidMaterial(String),

    /// The reference (undeformed) element has negative signed volume.
    #[error("element{} is inverted in the reference configuration: signed volume {volume:.3e} m^3", elem_note(.elem))]
    InvertedReference {
        /// Element index, when known.
        elem: Option<usize>,
        /// Signed reference volume (negative).
        volume: f64,
    },

    /// The reference element has (nearly) zero volume:
    /// |V| <= 1e-12 (longest edge)^3, or non-finite coordinates.
    #[error(
        "element{} is degenerate in the reference configuration: volume {volume:.3e} m^3, \
         longest edge {longest_edge:.3e} m",
        elem_note(.elem)
    )]
    DegenerateReference {
        /// Element index, when known.
        elem: Option<usize>,
        /// Signed reference volume.
        volume: f64,
        /// Longest reference edge.
        longest_edge: f64,
    },

    /// The element has turned inside out (J = det F <= 0 or not finite)
    /// during the motion, or its thermal stretch 1 + α ΔT is not positive:
    /// the run has diverged (time step too large, too much penetration, or
    /// an unphysical temperature).
    #[error("element{} is inverted in the current configuration: {what} = {value:.6e}", elem_note(.elem))]
    Inverted {
        /// Element index, when known.
        elem: Option<usize>,
        /// Which quantity is not positive (`J = det F` or `1 + alpha dT`).
        what: &'static str,
        /// Its value.
        value: f64,
    },

    /// Two inputs that must have matching lengths do not, or an index is out of range.
    #[error("size mismatch: {what} has {got} entries, expected {expected}")]
    SizeMismatch {
        /// Which input.
        what: &'static str,
        /// Its length (or the offending index).
        got: usize,
        /// The required length (or the exclusive bound).
        expected: usize,
    },

    /// An invalid integrator parameter (non-positive dt, negative damping, ...).
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),

    /// A node position or velocity became NaN or infinite.
    #[error("non-finite position or velocity at node {node}: the explicit integration diverged")]
    NonFinite {
        /// Node index.
        node: usize,
    },
}

impl MechanicsError {
    /// Fills in the element index of an element-level error that does not
    /// have one yet; other errors are returned unchanged.
    pub fn at_element(self, e: usize) -> Self {
        match self {
            Self::InvertedReference { elem: None, volume } => Self::InvertedReference {
                elem: Some(e),
                volume,
            },
            Self::DegenerateReference {
                elem: None,
                volume,
                longest_edge,
            } => Self::DegenerateReference {
                elem: Some(e),
                volume,
                longest_edge,
            },
            Self::Inverted {
                elem: None,
                what,
                value,
            } => Self::Inverted {
                elem: Some(e),
                what,
                value,
            },
            other => other,
        }
    }
}

fn elem_note(elem: &Option<usize>) -> String {
    match elem {
        Some(e) => format!(" {e}"),
        None => String::new(),
    }
}
