//! Trilinear Hex8 geometry: shape functions, natural coordinates, Jacobian
//! and the inverse isoparametric mapping (physical point → natural
//! coordinates) for Hex8 and Tet4. Pure functions, free of MPI and PETSc.
//!
//! Seed 002 equations implemented here:
//! - eq 6: x(ξ) = Σ N_I(ξ) x_I;
//! - eq 7 and Table 1: N_I = (1 + ξ_I ξ)(1 + η_I η)(1 + ζ_I ζ)/8 with the
//!   node order of [`HEX8_NATURAL`] (bottom face ζ = −1 counter-clockwise
//!   seen from +ζ, then the top face);
//! - eq 9: J = ∂x/∂ξ (rows: x, y, z; columns: ξ, η, ζ);
//! - eqs 8, 10–11: the Newton iteration ξ_{k+1} = ξ_k + J_k⁻¹ (x − x_k),
//!   stopped when ‖x − x_k‖ < ε ([`hex8_inverse_map`]).
//!
//! A Tet4 is affine, so its inverse map is exact: the barycentric
//! coordinates solve one 3×3 system ([`tet4_inverse_map`]). The ghost
//! particles of seed 002 (eq 5) are placed by these maps once, at the
//! reference configuration.
//!
//! Both inverse maps return [`InverseMapError`] naming the element (the
//! index the caller passes) when the point lies outside the element by
//! more than [`INVERSE_MAP_OUTSIDE_TOL`] in natural coordinates, when the
//! Jacobian is singular, or when Newton does not converge.

use nalgebra::{Matrix3, Vector3};

/// Natural coordinates (ξ_I, η_I, ζ_I) of the eight nodes (seed 002 Table 1).
pub const HEX8_NATURAL: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// How far outside [−1, 1]³ (Hex8) or the unit simplex (Tet4), in natural
/// coordinates, an inverse-mapped point may lie and still count as inside:
/// room for the round-off of points on a face.
pub const INVERSE_MAP_OUTSIDE_TOL: f64 = 1e-10;

/// Most Newton iterations of [`hex8_inverse_map`]; a valid (positive
/// Jacobian) element converges quadratically in a handful.
pub const INVERSE_MAP_MAX_ITERATIONS: usize = 50;

/// Failures of the inverse isoparametric mapping.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InverseMapError {
    /// The point maps outside the element.
    #[error(
        "point ({:.6e}, {:.6e}, {:.6e}) lies outside {kind} element {elem}: natural coordinates \
         ({:.6}, {:.6}, {:.6})",
        .point[0], .point[1], .point[2], .natural[0], .natural[1], .natural[2]
    )]
    Outside {
        /// "Hex8" or "Tet4".
        kind: &'static str,
        /// Element index given by the caller.
        elem: usize,
        /// The physical point.
        point: [f64; 3],
        /// Its natural coordinates (Hex8: ξ, η, ζ; Tet4: λ1, λ2, λ3).
        natural: [f64; 3],
    },
    /// Newton's iteration (seed 002 eq 10) did not reach the tolerance.
    #[error(
        "inverse mapping into Hex8 element {elem} did not converge in {iterations} iterations: \
         residual {residual:.3e} m, tolerance {tolerance:.3e} m"
    )]
    NotConverged {
        /// Element index given by the caller.
        elem: usize,
        /// Iterations done.
        iterations: usize,
        /// Last ‖x − x_k‖ (m).
        residual: f64,
        /// The tolerance ε of eq 11 (m).
        tolerance: f64,
    },
    /// The Jacobian is singular or not finite at an iterate.
    #[error("{kind} element {elem} has a singular Jacobian (det {det:.3e}) at the iterate")]
    Singular {
        /// "Hex8" or "Tet4".
        kind: &'static str,
        /// Element index given by the caller.
        elem: usize,
        /// The determinant.
        det: f64,
    },
}

/// Seed 002 eq 7: the eight shape functions at natural coordinates `xi`.
pub fn hex8_shape(xi: &Vector3<f64>) -> [f64; 8] {
    let mut n = [0.0; 8];
    for (i, c) in HEX8_NATURAL.iter().enumerate() {
        // seed 002 eq 7: N_I = (1 + ξ_I ξ)(1 + η_I η)(1 + ζ_I ζ)/8.
        n[i] = 0.125 * (1.0 + c[0] * xi[0]) * (1.0 + c[1] * xi[1]) * (1.0 + c[2] * xi[2]);
    }
    n
}

/// Natural derivatives ∂N_I/∂ξ of the eight shape functions at `xi`.
pub fn hex8_shape_derivatives(xi: &Vector3<f64>) -> [Vector3<f64>; 8] {
    let mut d = [Vector3::zeros(); 8];
    for (i, c) in HEX8_NATURAL.iter().enumerate() {
        let a = 1.0 + c[0] * xi[0];
        let b = 1.0 + c[1] * xi[1];
        let g = 1.0 + c[2] * xi[2];
        d[i] = Vector3::new(c[0] * b * g, a * c[1] * g, a * b * c[2]) * 0.125;
    }
    d
}

/// Seed 002 eq 6: the physical point x(ξ) = Σ N_I(ξ) x_I.
pub fn hex8_map(x: &[Vector3<f64>; 8], xi: &Vector3<f64>) -> Vector3<f64> {
    let n = hex8_shape(xi);
    x.iter().zip(n).map(|(xi, ni)| xi * ni).sum()
}

/// Seed 002 eq 9: the Jacobian J = ∂x/∂ξ = Σ x_I ⊗ ∂N_I/∂ξ at `xi`.
pub fn hex8_jacobian(x: &[Vector3<f64>; 8], xi: &Vector3<f64>) -> Matrix3<f64> {
    let d = hex8_shape_derivatives(xi);
    let mut j = Matrix3::zeros();
    for (xi, di) in x.iter().zip(d.iter()) {
        j += xi * di.transpose();
    }
    j
}

/// Longest edge of the Hex8 (m), the length scale of its tolerances.
pub fn hex8_size(x: &[Vector3<f64>; 8]) -> f64 {
    const EDGES: [[usize; 2]; 12] = [
        [0, 1],
        [1, 2],
        [2, 3],
        [3, 0],
        [4, 5],
        [5, 6],
        [6, 7],
        [7, 4],
        [0, 4],
        [1, 5],
        [2, 6],
        [3, 7],
    ];
    EDGES
        .iter()
        .map(|e| (x[e[1]] - x[e[0]]).norm())
        .fold(0.0, f64::max)
}

/// Natural coordinates ξ of the physical point `p` in the Hex8 with nodes
/// `x` (seed 002 eqs 8–11), starting from the centre ξ = 0.
///
/// The tolerance ε of eq 11 is 1e-14 times the longest edge plus the
/// round-off of the coordinates (8 ulps of the largest |coordinate|: an
/// element far from the origin cannot resolve 1e-14 of its own size); the
/// iteration also stops once the Newton step is below 1e-15 (round-off). `elem` only
/// names the element in errors. Errors: [`InverseMapError::Outside`] if a
/// coordinate exceeds 1 + [`INVERSE_MAP_OUTSIDE_TOL`] in magnitude,
/// [`InverseMapError::Singular`] for a singular Jacobian,
/// [`InverseMapError::NotConverged`] after [`INVERSE_MAP_MAX_ITERATIONS`].
pub fn hex8_inverse_map(
    x: &[Vector3<f64>; 8],
    p: &Vector3<f64>,
    elem: usize,
) -> Result<Vector3<f64>, InverseMapError> {
    let scale = x.iter().chain([p]).map(|v| v.amax()).fold(0.0, f64::max);
    let tolerance = 1e-14 * hex8_size(x) + 8.0 * f64::EPSILON * scale;
    let mut xi = Vector3::zeros();
    let mut residual = f64::INFINITY;
    for _ in 0..INVERSE_MAP_MAX_ITERATIONS {
        let r = p - hex8_map(x, &xi);
        residual = r.norm();
        // seed 002 eq 11: stop when ‖x − x_k‖ < ε.
        if residual < tolerance {
            return check_hex8_inside(xi, p, elem);
        }
        let j = hex8_jacobian(x, &xi);
        let det = j.determinant();
        let inv = match j.try_inverse() {
            Some(inv) if det.is_finite() && det != 0.0 => inv,
            _ => {
                return Err(InverseMapError::Singular {
                    kind: "Hex8",
                    elem,
                    det,
                })
            }
        };
        // seed 002 eq 10: ξ_{k+1} = ξ_k + J_k⁻¹ (x − x_k).
        let step = inv * r;
        xi += step;
        if !xi.iter().all(|v| v.is_finite()) {
            break;
        }
        // Far outside the element the trilinear map is meaningless: stop early.
        if xi.amax() > 1e3 {
            return Err(InverseMapError::Outside {
                kind: "Hex8",
                elem,
                point: [p[0], p[1], p[2]],
                natural: [xi[0], xi[1], xi[2]],
            });
        }
        if step.amax() < 1e-15 {
            residual = (p - hex8_map(x, &xi)).norm();
            // A round-off floor just above ε still means converged.
            if residual < 1e3 * tolerance {
                return check_hex8_inside(xi, p, elem);
            }
        }
    }
    Err(InverseMapError::NotConverged {
        elem,
        iterations: INVERSE_MAP_MAX_ITERATIONS,
        residual,
        tolerance,
    })
}

fn check_hex8_inside(
    xi: Vector3<f64>,
    p: &Vector3<f64>,
    elem: usize,
) -> Result<Vector3<f64>, InverseMapError> {
    if xi.amax() > 1.0 + INVERSE_MAP_OUTSIDE_TOL {
        return Err(InverseMapError::Outside {
            kind: "Hex8",
            elem,
            point: [p[0], p[1], p[2]],
            natural: [xi[0], xi[1], xi[2]],
        });
    }
    Ok(xi)
}

/// Tet4 shape functions at barycentric coordinates λ = (λ1, λ2, λ3):
/// N = (1 − λ1 − λ2 − λ3, λ1, λ2, λ3).
pub fn tet4_shape(lambda: &Vector3<f64>) -> [f64; 4] {
    [
        1.0 - lambda[0] - lambda[1] - lambda[2],
        lambda[0],
        lambda[1],
        lambda[2],
    ]
}

/// Barycentric coordinates (λ1, λ2, λ3) of `p` in the Tet4 with nodes `x`:
/// the exact inverse of the affine map x = x0 + [x1−x0, x2−x0, x3−x0] λ.
///
/// Errors: [`InverseMapError::Singular`] for a degenerate tet,
/// [`InverseMapError::Outside`] if any of the four shape functions is below
/// −[`INVERSE_MAP_OUTSIDE_TOL`].
pub fn tet4_inverse_map(
    x: &[Vector3<f64>; 4],
    p: &Vector3<f64>,
    elem: usize,
) -> Result<Vector3<f64>, InverseMapError> {
    let e = Matrix3::from_columns(&[x[1] - x[0], x[2] - x[0], x[3] - x[0]]);
    let det = e.determinant();
    let scale = (x[1] - x[0])
        .norm()
        .max((x[2] - x[0]).norm())
        .max((x[3] - x[0]).norm());
    let singular = InverseMapError::Singular {
        kind: "Tet4",
        elem,
        det,
    };
    if !(det.is_finite() && det.abs() > 1e-12 * scale.powi(3)) {
        return Err(singular);
    }
    let inv = e.try_inverse().ok_or(singular)?;
    let lambda = inv * (p - x[0]);
    if tet4_shape(&lambda)
        .iter()
        .any(|n| *n < -INVERSE_MAP_OUTSIDE_TOL)
    {
        return Err(InverseMapError::Outside {
            kind: "Tet4",
            elem,
            point: [p[0], p[1], p[2]],
            natural: [lambda[0], lambda[1], lambda[2]],
        });
    }
    Ok(lambda)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// A distorted Hex8: a unit cube with every node moved by up to 0.15.
    fn distorted_hex(rng: &mut Pcg64) -> [Vector3<f64>; 8] {
        HEX8_NATURAL.map(|c| {
            Vector3::new(
                0.5 * (c[0] + 1.0) + rng.gen_range(-0.15..0.15),
                0.7 * (c[1] + 1.0) + rng.gen_range(-0.15..0.15),
                0.4 * (c[2] + 1.0) + rng.gen_range(-0.15..0.15),
            )
        })
    }

    #[test]
    fn shape_functions_are_a_partition_of_unity_and_interpolate_nodes() {
        let xi = Vector3::new(0.3, -0.7, 0.1);
        let n = hex8_shape(&xi);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let d = hex8_shape_derivatives(&xi);
        assert!(d.iter().sum::<Vector3<f64>>().norm() < 1e-15);
        for (i, c) in HEX8_NATURAL.iter().enumerate() {
            let ni = hex8_shape(&Vector3::from(*c));
            for (j, v) in ni.iter().enumerate() {
                assert_eq!(*v, if i == j { 1.0 } else { 0.0 });
            }
        }
        // Derivatives against central differences of N.
        let h = 1e-6;
        for k in 0..3 {
            let mut a = xi;
            let mut b = xi;
            a[k] += h;
            b[k] -= h;
            let (na, nb) = (hex8_shape(&a), hex8_shape(&b));
            for i in 0..8 {
                assert!(((na[i] - nb[i]) / (2.0 * h) - d[i][k]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn jacobian_of_a_box_is_diagonal_half_lengths() {
        let x = HEX8_NATURAL.map(|c| Vector3::new(2.0 * c[0], 3.0 * c[1], 0.5 * c[2]));
        let j = hex8_jacobian(&x, &Vector3::new(0.2, 0.4, -0.9));
        let expect = Matrix3::from_diagonal(&Vector3::new(2.0, 3.0, 0.5));
        assert!((j - expect).norm() < 1e-14);
    }

    #[test]
    fn hex8_inverse_map_recovers_random_points_to_1e_12() {
        let mut rng = Pcg64::seed_from_u64(21);
        for _ in 0..20 {
            let x = distorted_hex(&mut rng);
            for _ in 0..50 {
                let xi = Vector3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                let p = hex8_map(&x, &xi);
                let back = hex8_inverse_map(&x, &p, 7).unwrap();
                assert!((back - xi).amax() < 1e-12, "{xi} -> {back}");
            }
            // The nodes map to their Table 1 coordinates.
            for (i, c) in HEX8_NATURAL.iter().enumerate() {
                let back = hex8_inverse_map(&x, &x[i], 0).unwrap();
                assert!((back - Vector3::from(*c)).amax() < 1e-12);
            }
        }
    }

    #[test]
    fn hex8_point_outside_is_an_error_naming_the_element() {
        let mut rng = Pcg64::seed_from_u64(3);
        let x = distorted_hex(&mut rng);
        let p = hex8_map(&x, &Vector3::new(0.2, 1.05, -0.3));
        let err = hex8_inverse_map(&x, &p, 42).unwrap_err();
        match &err {
            InverseMapError::Outside { elem, natural, .. } => {
                assert_eq!(*elem, 42);
                assert!((natural[1] - 1.05).abs() < 1e-9);
            }
            other => panic!("expected Outside, got {other:?}"),
        }
        assert!(err.to_string().contains("Hex8 element 42"), "{err}");
        // Far away: still a clean error, not a panic.
        let far = Vector3::new(100.0, -50.0, 3.0);
        assert!(hex8_inverse_map(&x, &far, 1).is_err());
    }

    #[test]
    fn hex8_inverse_map_far_from_the_origin() {
        // Elements of side h at 30 and 200 h from the origin: round-off of the coordinates
        // exceeds 1e-14 h there (issue 21's wave bar found it at 15 mm with h = 0.5 mm).
        let mut rng = Pcg64::seed_from_u64(7);
        let h = 0.5e-3;
        for offset in [30.0 * h, 200.0 * h] {
            let x = HEX8_NATURAL
                .map(|c| Vector3::new(offset, 0.3 * h, -2.0 * h) + Vector3::from(c) * (0.5 * h));
            for _ in 0..200 {
                let xi = Vector3::from_fn(|_, _| rng.gen_range(-1.0..1.0));
                let got = hex8_inverse_map(&x, &hex8_map(&x, &xi), 0).unwrap();
                assert!((got - xi).amax() < 1e-12, "{offset}: {got} vs {xi}");
            }
        }
    }

    #[test]
    fn hex8_collapsed_element_is_singular() {
        let x = HEX8_NATURAL.map(|c| Vector3::new(c[0], c[1], 0.0));
        let err = hex8_inverse_map(&x, &Vector3::new(0.1, 0.1, 0.5), 5).unwrap_err();
        assert!(
            matches!(err, InverseMapError::Singular { elem: 5, .. }),
            "{err:?}"
        );
    }

    #[test]
    fn tet4_inverse_map_recovers_random_points_to_1e_12() {
        let mut rng = Pcg64::seed_from_u64(4);
        for _ in 0..20 {
            let x = [
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(1.0, 0.1, -0.2),
                Vector3::new(0.2, 0.9, 0.1),
                Vector3::new(-0.1, 0.3, 1.2),
            ]
            .map(|v| v + Vector3::new(rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1), 0.0));
            for _ in 0..50 {
                let mut l = Vector3::new(rng.gen::<f64>(), rng.gen::<f64>(), rng.gen::<f64>());
                let s = l.sum();
                if s > 1.0 {
                    l /= s * 1.01;
                }
                let n = tet4_shape(&l);
                let p: Vector3<f64> = (0..4).map(|i| x[i] * n[i]).sum();
                let back = tet4_inverse_map(&x, &p, 0).unwrap();
                assert!((back - l).amax() < 1e-12);
            }
        }
        let x = [Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()];
        let err = tet4_inverse_map(&x, &Vector3::new(0.5, 0.5, 0.1), 9).unwrap_err();
        assert!(err.to_string().contains("Tet4 element 9"), "{err}");
    }
}
