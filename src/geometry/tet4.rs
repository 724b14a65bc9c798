//! Tet4 geometry: the volume and the constant gradients of the linear
//! shape functions (the barycentric coordinates). Shared by the
//! heat-conduction kernels and the contact surface.

/// Shape-function gradients and volume of a Tet4.
#[derive(Debug, Clone, Copy)]
pub struct Tet4Geometry {
    /// Volume (m³), positive for a positively oriented tet.
    pub volume: f64,
    /// ∂N_i/∂x_j for i = 0..4 (seed 000 eq 6: the matrix B).
    pub grad: [[f64; 3]; 4],
}

/// Seed 000 eqs 5–6: linear shape functions N_i and their constant gradients.
pub fn tet4_geometry(x: &[[f64; 3]; 4]) -> Tet4Geometry {
    let d = |a: usize| [x[a][0] - x[0][0], x[a][1] - x[0][1], x[a][2] - x[0][2]];
    let (a, b, c) = (d(1), d(2), d(3));
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let bc = cross(b, c);
    let ca = cross(c, a);
    let ab = cross(a, b);
    let det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    let inv = 1.0 / det;
    // Rows of J^{-T}: gradients of the barycentric coordinates ζ1..ζ3.
    let g1 = [bc[0] * inv, bc[1] * inv, bc[2] * inv];
    let g2 = [ca[0] * inv, ca[1] * inv, ca[2] * inv];
    let g3 = [ab[0] * inv, ab[1] * inv, ab[2] * inv];
    let g0 = [
        -(g1[0] + g2[0] + g3[0]),
        -(g1[1] + g2[1] + g3[1]),
        -(g1[2] + g2[2] + g3[2]),
    ];
    Tet4Geometry {
        volume: det / 6.0,
        grad: [g0, g1, g2, g3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tet() -> [[f64; 3]; 4] {
        [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]]
    }

    #[test]
    fn gradients_reproduce_linear_fields() {
        let x = [
            [0.1, 0.2, 0.0],
            [1.3, 0.1, 0.2],
            [0.2, 1.1, -0.1],
            [0.3, 0.2, 0.9],
        ];
        let g = tet4_geometry(&x);
        assert!(g.volume > 0.0);
        // T = 2x - 3y + 5z + 1 has gradient (2,-3,5) exactly.
        let t: Vec<f64> = x
            .iter()
            .map(|p| 2.0 * p[0] - 3.0 * p[1] + 5.0 * p[2] + 1.0)
            .collect();
        for d in 0..3 {
            let s: f64 = (0..4).map(|i| g.grad[i][d] * t[i]).sum();
            let want = [2.0, -3.0, 5.0][d];
            assert!((s - want).abs() < 1e-12, "component {d}: {s}");
        }
    }

    #[test]
    fn inverted_tet_has_negative_volume() {
        let mut x = unit_tet();
        x.swap(2, 3);
        assert!(tet4_geometry(&x).volume < 0.0);
    }
}
