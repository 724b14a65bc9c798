//! Placing particles for a deposition run: sites in a vertical column
//! above a container floor, far enough apart that bounding spheres cannot
//! touch, and seeded random orientations. Pure functions; the same seed
//! gives the same placement on every machine and rank count.

use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// The space particles are dropped into: a vertical cylinder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// Centre of the floor (m); the axis is vertical (z).
    pub floor_center: [f64; 3],
    /// Radius available (the container's inner radius, m).
    pub radius: f64,
}

/// Centres of `count` sites for particles of bounding radius `r` (about
/// their centroids) with clearance `gap`: horizontal layers of a triangular
/// lattice of spacing d = 2r + gap inside the column, alternate layers
/// shifted and stacked d √(2/3) apart (close-packed spheres), the lowest
/// layer resting `gap` above the floor. Lowest sites first.
pub fn column_sites(count: usize, r: f64, gap: f64, col: &Column) -> Result<Vec<[f64; 3]>, String> {
    if !(r > 0.0 && r.is_finite() && gap >= 0.0 && gap.is_finite()) {
        return Err(format!(
            "bounding radius {r} and gap {gap} must be positive and finite"
        ));
    }
    let avail = col.radius - r - gap;
    if avail < 0.0 {
        return Err(format!(
            "the container's inner radius {} m is smaller than a particle's bounding radius {r:.4} m \
             plus the gap {gap} m: no particle fits",
            col.radius
        ));
    }
    let d = 2.0 * r + gap;
    let row = d * 3f64.sqrt() / 2.0;
    // Not in the seeds: close-packed (ABAB) layers of spheres of diameter d lie d √(2/3) apart.
    let layer_gap = d * (2.0f64 / 3.0).sqrt();
    let mut layers: [Vec<[f64; 2]>; 2] = [Vec::new(), Vec::new()];
    for (shift, layer) in layers.iter_mut().enumerate() {
        // Alternate layers shifted by (d/2, row/3): close-packed ABAB stacking.
        let s = shift as f64;
        let nj = (avail / row).floor() as i64 + 1;
        let ni = (avail / d).floor() as i64 + 1;
        for j in -nj..=nj {
            for i in -ni - 1..=ni + 1 {
                let x = (i as f64 + 0.5 * j.rem_euclid(2) as f64 + 0.5 * s) * d;
                let y = (j as f64 + s / 3.0) * row;
                if x.hypot(y) <= avail {
                    layer.push([x, y]);
                }
            }
        }
        // Inner sites first within a layer: a partial top layer stays centred.
        layer.sort_by(|a, b| {
            a[0].hypot(a[1])
                .total_cmp(&b[0].hypot(b[1]))
                .then(a[1].total_cmp(&b[1]))
                .then(a[0].total_cmp(&b[0]))
        });
    }
    if layers[0].is_empty() {
        return Err("no site fits in the column".into());
    }
    let mut out = Vec::with_capacity(count);
    let mut k = 0usize;
    while out.len() < count {
        let layer = &layers[k % 2];
        let z = col.floor_center[2] + gap + r + k as f64 * layer_gap;
        for p in layer {
            if out.len() == count {
                break;
            }
            out.push([col.floor_center[0] + p[0], col.floor_center[1] + p[1], z]);
        }
        k += 1;
    }
    Ok(out)
}

/// `count` rotations uniformly distributed over SO(3), from `seed`
/// (Shoemake's subgroup algorithm on a PCG64 stream).
pub fn random_rotations(count: usize, seed: u64) -> Vec<Rotation3<f64>> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let (u1, u2, u3): (f64, f64, f64) = (rng.gen(), rng.gen(), rng.gen());
            let tau = std::f64::consts::TAU;
            // Not numbered in the seeds: Shoemake (1992) uniform random unit quaternion.
            let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
            let q = nalgebra::Quaternion::new(
                b * (tau * u3).cos(),
                a * (tau * u2).sin(),
                a * (tau * u2).cos(),
                b * (tau * u3).sin(),
            );
            UnitQuaternion::from_quaternion(q).to_rotation_matrix()
        })
        .collect()
}

/// Centroid (volume-weighted) and bounding radius about it of a set of tets.
pub fn centroid_and_radius(nodes: &[[f64; 3]], tets: &[[u32; 4]]) -> ([f64; 3], f64) {
    let mut c = Vector3::zeros();
    let mut vol = 0.0;
    for t in tets {
        let x: Vec<Vector3<f64>> = t
            .iter()
            .map(|&n| Vector3::from(nodes[n as usize]))
            .collect();
        let v = (x[1] - x[0]).cross(&(x[2] - x[0])).dot(&(x[3] - x[0])) / 6.0;
        c += v * (x[0] + x[1] + x[2] + x[3]) / 4.0;
        vol += v;
    }
    let c = if vol > 0.0 { c / vol } else { Vector3::zeros() };
    let r = nodes
        .iter()
        .map(|p| (Vector3::from(*p) - c).norm())
        .fold(0.0, f64::max);
    ([c.x, c.y, c.z], r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sites_are_inside_and_apart() {
        let col = Column {
            floor_center: [0.1, -0.2, 0.5],
            radius: 0.225,
        };
        let (r, gap) = (0.0244, 0.002);
        let s = column_sites(500, r, gap, &col).unwrap();
        assert_eq!(s.len(), 500);
        for (i, a) in s.iter().enumerate() {
            let rad = (a[0] - 0.1).hypot(a[1] + 0.2);
            assert!(rad + r + gap <= col.radius + 1e-12, "site {i} sticks out");
            assert!(a[2] - r >= 0.5 + gap - 1e-12, "site {i} below the floor");
            for b in &s[..i] {
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                assert!(d >= 2.0 * r + gap - 1e-12, "sites too close: {d}");
            }
        }
        // Lowest first.
        assert!(s.windows(2).all(|w| w[1][2] >= w[0][2]));
        // Close-packed: the layers are (2r + gap) √(2/3) apart.
        let mut z: Vec<f64> = s.iter().map(|p| p[2]).collect();
        z.dedup();
        assert!(z.len() > 2, "500 sites fill several layers");
        for w in z.windows(2) {
            let want = (2.0 * r + gap) * (2.0f64 / 3.0).sqrt();
            assert!(
                (w[1] - w[0] - want).abs() < 1e-12,
                "layer gap {}",
                w[1] - w[0]
            );
        }
    }

    #[test]
    fn a_column_narrower_than_a_particle_is_an_error() {
        let col = Column {
            floor_center: [0.0; 3],
            radius: 0.02,
        };
        let e = column_sites(3, 0.0244, 0.001, &col).unwrap_err();
        assert!(e.contains("no particle fits"), "{e}");
    }

    #[test]
    fn rotations_are_reproducible_and_spread() {
        let a = random_rotations(2000, 7);
        let b = random_rotations(2000, 7);
        let c = random_rotations(2000, 8);
        assert_eq!(a, b);
        assert_ne!(a, c);
        // Uniform over SO(3): the rotated z axis is uniform on the sphere, so
        // its mean is ~0 and the mean of z² is 1/3 (sampling error ~1/sqrt(n)).
        let mut mean = Vector3::zeros();
        let mut zz = 0.0;
        for r in &a {
            let z = r * Vector3::z();
            assert!((z.norm() - 1.0).abs() < 1e-12);
            mean += z;
            zz += z.z * z.z;
        }
        mean /= a.len() as f64;
        zz /= a.len() as f64;
        assert!(mean.norm() < 0.06, "mean {mean}");
        assert!((zz - 1.0 / 3.0).abs() < 0.03, "<z²> = {zz}");
    }

    #[test]
    fn centroid_of_a_unit_tet() {
        let nodes = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let (c, r) = centroid_and_radius(&nodes, &[[0, 1, 2, 3]]);
        for x in c {
            assert!((x - 0.25).abs() < 1e-15);
        }
        // Farthest vertex from (¼,¼,¼): (1,0,0), distance sqrt(0.75² + 2·0.25²).
        assert!((r - (0.5625f64 + 0.125).sqrt()).abs() < 1e-15);
    }
}
