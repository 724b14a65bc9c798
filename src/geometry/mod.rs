//! Convex geometry kernels for contact: clipping a triangle by a tet's
//! half-spaces (seed 000 sec 3.1), polygon areas, and a separating-axis
//! overlap test for two tets. Pure functions over `[f64; 3]`.

mod clip;
pub mod overlap;
pub mod placement;

pub use clip::{face_tet_clip, polygon_area, tet_tet_overlap, triangle_in_tet_area, Polygon};
pub use overlap::{tet_tet_intersection, tets_within, FacePatch, Intersection, TetPlanes};

/// a − b.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a · b.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
