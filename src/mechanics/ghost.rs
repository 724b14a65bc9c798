//! Ghost particles of the FE–DE interface (seed 002 eqs 5, 16–17): a ghost
//! sits inside a boundary finite element, mirrored from a boundary sphere,
//! keeps the natural coordinates found once by the inverse map (eqs 8–11,
//! [`super::hex8`]), moves with the element (no rotation) and returns the
//! forces and heat it receives to the element's nodes with N_I. Pure
//! kernels over one ghost, for Hex8 (8 nodes) or Tet4 (4 nodes): the shape
//! values are a slice.
//!
//! Departure from the seed: eq 16 gives the ghost no rotation. A bond
//! between a ghost and a sphere then resists the sphere's rotation as if
//! the element did not rotate, a rotational spring to ground: measured, the
//! coupled cantilever of seed 002 came out 24 % too stiff along its whole
//! length. Here the ghost spins with the element's material spin
//! ω_g = ½ curl v = ½ Σ ∇N_I × v_I at its natural coordinates, and the
//! moment the bonds put on it goes back to the nodes as f_I = ½ M × ∇N_I
//! (the forces conjugate to that spin: they sum to zero and their moment
//! is M), so the interface conserves momentum and angular momentum. The
//! gradients are those of the reference element (small rotations).
//!
//! Eq 17 returns a ghost's force at the ghost, a distance r inside the
//! element, not at the interface. In uniform tension with elements of side
//! h the element face inside the FE region then takes r/h of the interface
//! force and the boundary element carries only 1 − r/h of the stress:
//! measured by the patch test (`validation::fede_patch`,
//! `docs/validation.md`), 0.77 of E ε for h = 4r, and a net force of 0.26
//! σh² on those inner nodes. The coupled drivers therefore default to
//! evaluating each ghost–sphere bond at its midpoint on the interface, with
//! the velocity and the force of the element's material point there
//! ([`crate::validation::fede_coupling`]; a [`Ghost`] built at the
//! midpoint gives its N_I); eq 17 as written stays available for comparison.

use nalgebra::{Matrix3, Vector3};

use super::hex8::{
    hex8_inverse_map, hex8_jacobian, hex8_shape, hex8_shape_derivatives, tet4_inverse_map,
    tet4_shape, InverseMapError,
};

/// A ghost particle: the element that carries it and its shape-function
/// values there (fixed for the whole run).
#[derive(Debug, Clone, PartialEq)]
pub struct Ghost {
    /// Index of the carrying element (in the caller's element list).
    pub elem: usize,
    /// N_I at the ghost's natural coordinates (8 for Hex8, 4 for Tet4).
    pub shape: Vec<f64>,
    /// Reference ∂N_I/∂X there.
    pub grad: Vec<Vector3<f64>>,
}

/// Seed 002 eq 5: the ghost position x_g = x_b − 2 r n of the boundary
/// sphere at `boundary` with radius `radius` and unit interface normal `n`
/// (pointing from the FE region into the DE region).
pub fn ghost_position(boundary: &Vector3<f64>, radius: f64, n: &Vector3<f64>) -> Vector3<f64> {
    // seed 002 eq 5: x_g = x_b − 2 r n.
    boundary - n * (2.0 * radius)
}

/// The ghost at `x` in the Hex8 `elem` with reference nodes `nodes`
/// (natural coordinates by seed 002 eqs 8–11, once).
pub fn hex8_ghost(
    nodes: &[Vector3<f64>; 8],
    x: &Vector3<f64>,
    elem: usize,
) -> Result<Ghost, InverseMapError> {
    let xi = hex8_inverse_map(nodes, x, elem)?;
    let j = hex8_jacobian(nodes, &xi);
    let jinv_t = j
        .try_inverse()
        .ok_or(InverseMapError::Singular {
            kind: "Hex8",
            elem,
            det: j.determinant(),
        })?
        .transpose();
    Ok(Ghost {
        elem,
        shape: hex8_shape(&xi).to_vec(),
        grad: hex8_shape_derivatives(&xi)
            .iter()
            .map(|d| jinv_t * d)
            .collect(),
    })
}

/// The ghost at `x` in the Tet4 `elem` with reference nodes `nodes`.
pub fn tet4_ghost(
    nodes: &[Vector3<f64>; 4],
    x: &Vector3<f64>,
    elem: usize,
) -> Result<Ghost, InverseMapError> {
    let l = tet4_inverse_map(nodes, x, elem)?;
    let e = Matrix3::from_columns(&[
        nodes[1] - nodes[0],
        nodes[2] - nodes[0],
        nodes[3] - nodes[0],
    ]);
    // The inverse map succeeded, so the edge matrix is invertible; its rows are ∇N_1..3.
    let inv = e.try_inverse().ok_or(InverseMapError::Singular {
        kind: "Tet4",
        elem,
        det: e.determinant(),
    })?;
    let g: Vec<Vector3<f64>> = (0..3).map(|r| inv.row(r).transpose()).collect();
    Ok(Ghost {
        elem,
        shape: tet4_shape(&l).to_vec(),
        grad: vec![-(g[0] + g[1] + g[2]), g[0], g[1], g[2]],
    })
}

impl Ghost {
    /// Seed 002 eqs 6 and 16: Σ N_I a_I of nodal vectors `a` (positions or
    /// velocities of the element's nodes, in element order).
    pub fn interpolate(&self, a: &[Vector3<f64>]) -> Vector3<f64> {
        // seed 002 eq 16: ẋ = Σ N_I ẋ_I (and eq 6 for positions).
        self.shape.iter().zip(a).map(|(n, v)| v * *n).sum()
    }

    /// The material spin ½ curl v = ½ Σ ∇N_I × v_I of nodal velocities `v`
    /// (module docs: replaces the zero rotation of eq 16).
    pub fn spin(&self, v: &[Vector3<f64>]) -> Vector3<f64> {
        self.grad
            .iter()
            .zip(v)
            .map(|(g, vi)| g.cross(vi) * 0.5)
            .sum()
    }

    /// The moment `m` acting on the ghost, returned to the nodes as
    /// ½ m × ∇N_I (added to `nodal`): zero resultant, moment m.
    pub fn scatter_moment(&self, m: &Vector3<f64>, nodal: &mut [Vector3<f64>]) {
        for (g, out) in self.grad.iter().zip(nodal.iter_mut()) {
            *out += m.cross(g) * 0.5;
        }
    }

    /// The ghost temperature Σ N_I T_I of nodal temperatures `t`.
    pub fn temperature(&self, t: &[f64]) -> f64 {
        self.shape.iter().zip(t).map(|(n, v)| n * v).sum()
    }

    /// Seed 002 eq 17: the force `f` acting on the ghost, returned to the
    /// element's nodes as N_I f (added to `nodal`). The seed writes
    /// f_I = −N_I f with f the force the ghost exerts on its sphere; this
    /// kernel takes the force on the ghost, hence no minus sign.
    pub fn scatter_force(&self, f: &Vector3<f64>, nodal: &mut [Vector3<f64>]) {
        for (n, out) in self.shape.iter().zip(nodal.iter_mut()) {
            // seed 002 eq 17: f_I = N_I f (f on the ghost).
            *out += f * *n;
        }
    }

    /// The heat flow `q` (W) into the ghost, returned to the nodes as N_I q.
    pub fn scatter_heat(&self, q: f64, nodal: &mut [f64]) {
        for (n, out) in self.shape.iter().zip(nodal.iter_mut()) {
            *out += n * q;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::hex8::{hex8_map, HEX8_NATURAL};

    fn hex() -> [Vector3<f64>; 8] {
        HEX8_NATURAL.map(|c| {
            Vector3::new(
                c[0] + 0.1 * c[1] * c[2],
                0.8 * c[1],
                0.6 * c[2] + 0.05 * c[0],
            )
        })
    }

    #[test]
    fn ghost_moves_with_the_element_and_returns_force_and_moment() {
        let x0 = hex();
        let xi = Vector3::new(0.3, -0.4, 0.7);
        let p = hex8_map(&x0, &xi);
        let g = hex8_ghost(&x0, &p, 3).unwrap();
        assert!((g.interpolate(&x0) - p).norm() < 1e-13);
        // A rigid motion of the nodes carries the ghost rigidly.
        let rot = nalgebra::Rotation3::from_euler_angles(0.2, -0.3, 0.5);
        let shift = Vector3::new(1.0, -2.0, 0.5);
        let x = x0.map(|a| rot * a + shift);
        assert!((g.interpolate(&x) - (rot * p + shift)).norm() < 1e-13);
        // The returned nodal forces have the ghost force's resultant and its moment about the origin.
        let f = Vector3::new(0.3, -1.0, 2.0);
        let mut nodal = [Vector3::zeros(); 8];
        g.scatter_force(&f, &mut nodal);
        let sum: Vector3<f64> = nodal.iter().sum();
        assert!((sum - f).norm() < 1e-14);
        let moment: Vector3<f64> = x0.iter().zip(&nodal).map(|(a, b)| a.cross(b)).sum();
        assert!((moment - p.cross(&f)).norm() < 1e-13);
        // Temperature: a linear nodal field gives its value at the ghost; heat is conserved.
        let t: Vec<f64> = x0.iter().map(|a| 2.0 * a[0] - a[2] + 5.0).collect();
        assert!((g.temperature(&t) - (2.0 * p[0] - p[2] + 5.0)).abs() < 1e-13);
        // Spin of a rigid rotation of the nodes is its angular velocity; a moment goes
        // back as forces with zero resultant and that moment.
        let w = Vector3::new(0.4, -0.2, 0.9);
        let v = x0.map(|a| w.cross(&a) + shift);
        assert!((g.spin(&v) - w).norm() < 1e-13);
        let m = Vector3::new(-1.0, 0.5, 2.0);
        let mut nodal = [Vector3::zeros(); 8];
        g.scatter_moment(&m, &mut nodal);
        assert!(nodal.iter().sum::<Vector3<f64>>().norm() < 1e-13);
        let mm: Vector3<f64> = x0.iter().zip(&nodal).map(|(a, b)| a.cross(b)).sum();
        assert!((mm - m).norm() < 1e-13);
        let mut heat = [0.0; 8];
        g.scatter_heat(3.0, &mut heat);
        assert!((heat.iter().sum::<f64>() - 3.0).abs() < 1e-14);
    }

    #[test]
    fn mirrored_position_and_outside_error() {
        let xb = Vector3::new(1.125, 0.3, -0.2);
        let xg = ghost_position(&xb, 0.125, &Vector3::x());
        assert!((xg - Vector3::new(0.875, 0.3, -0.2)).norm() < 1e-15);
        // A ghost that falls outside its element is an error naming the element.
        let err = hex8_ghost(&hex(), &Vector3::new(3.0, 0.0, 0.0), 11).unwrap_err();
        assert!(err.to_string().contains("element 11"), "{err}");
        let tet = [Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()];
        let g = tet4_ghost(&tet, &Vector3::new(0.2, 0.3, 0.1), 0).unwrap();
        assert!((g.shape.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((g.interpolate(&tet) - Vector3::new(0.2, 0.3, 0.1)).norm() < 1e-15);
    }
}
