//! Rigid placement of point sets: rotations given as angles about the
//! axes, and translations. Used to place scenario bodies and packed
//! particles.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// Rotation by angles (degrees) about x, then y, then z.
pub fn rotation_xyz_degrees(r: [f64; 3]) -> Matrix3<f64> {
    let [ax, ay, az] = r.map(f64::to_radians);
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), ax);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), ay);
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), az);
    (rz * ry * rx).into_inner()
}

/// Rotate every point by `rot` (about the origin).
pub fn rotate_points(points: &mut [[f64; 3]], rot: &Matrix3<f64>) {
    for p in points.iter_mut() {
        let q = rot * Vector3::new(p[0], p[1], p[2]);
        *p = [q.x, q.y, q.z];
    }
}

/// Translate every point by `t`.
pub fn translate_points(points: &mut [[f64; 3]], t: [f64; 3]) {
    for p in points.iter_mut() {
        for d in 0..3 {
            p[d] += t[d];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_compose_x_then_y_then_z() {
        let mut p = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        rotate_points(&mut p, &rotation_xyz_degrees([0.0, 0.0, 90.0]));
        assert!((p[0][1] - 1.0).abs() < 1e-15 && p[0][0].abs() < 1e-15);
        assert!((p[1][0] + 1.0).abs() < 1e-15);
        // About x by 90 (y → z, which z by 90 keeps), then z by 90 (x → y).
        let r = rotation_xyz_degrees([90.0, 0.0, 90.0]);
        let y = r * Vector3::y();
        let x = r * Vector3::x();
        assert!((y - Vector3::z()).norm() < 1e-15);
        assert!((x - Vector3::y()).norm() < 1e-15);
    }

    #[test]
    fn translation_adds() {
        let mut p = [[1.0, 2.0, 3.0]];
        translate_points(&mut p, [0.5, -2.0, 1.0]);
        assert_eq!(p, [[1.5, 0.0, 4.0]]);
    }
}
