//! Convex geometry kernels for contact: clipping a triangle by a tet's
//! half-spaces (seed 000 sec 3.1), polygon areas, and a separating-axis
//! overlap test for two tets; Tet4 shape-function geometry; rigid
//! rotations and translations. Pure functions over `[f64; 3]`.

mod clip;
pub mod overlap;
pub mod placement;
pub mod point_grid;
pub mod sphere_sites;
mod tet4;
pub mod transform;

pub use clip::{
    face_tet_clip, polygon_area, shapes_overlap, tet_tet_overlap, triangle_in_tet_area, Polygon,
    TetShape,
};
pub use overlap::{
    face_planes, intersect_tets, pair_size2, planes_within, separated_along, separating_axis,
    tet_tet_intersection, tet_tet_intersection_with, tets_within, FacePatch, Intersection, Overlap,
    TetPlanes,
};
pub use tet4::{tet4_geometry, Tet4Geometry};

/// Axis-aligned bounds (min, max corners) of a tet.
#[inline]
pub fn tet_bounds(x: &[[f64; 3]; 4]) -> ([f64; 3], [f64; 3]) {
    let mut lo = x[0];
    let mut hi = x[0];
    for p in &x[1..] {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (lo, hi)
}

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
