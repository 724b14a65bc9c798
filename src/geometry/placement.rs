//! Placing particles for a deposition run, with seeded random
//! orientations: either sites in a vertical column above a container floor,
//! far enough apart that bounding spheres cannot touch ([`column_sites`]),
//! or a sequential drop of each particle's convex hull onto those placed
//! before ([`drop_sites`]), a loose bed a little over half as tall as the
//! column. Pure functions; the same seed gives the same placement on every
//! machine and rank count.

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::math::Point;
use parry3d_f64::query::{cast_shapes, ShapeCastOptions};
use parry3d_f64::shape::ConvexPolyhedron;
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

/// Centres of particles dropped one after another, each at the lowest of
/// `trials` random spots (seeded), into the column `col`.
///
/// Particle i is the convex hull of `hull` (points relative to the
/// particle's centroid), turned by `rotations[i]`. For each trial spot
/// (x, y), uniform over the disc where the turned hull keeps `gap` from the
/// column's wall, it falls straight down from above everything placed until
/// its hull comes within `gap` of the floor or of a placed particle's hull
/// (a shape cast). From the lowest of its trial spots it then slides
/// downhill: horizontal moves in eight directions, halving the step from
/// r/2 to r/20, as long as one lowers its resting height (rolling without
/// turning: the random orientation is kept). The result is a loose bed
/// with arches, without overlap (hulls at least `gap` apart, so the
/// particles are too), which gravity then settles: for 2000 nuts it is
/// 0.85 m tall against 1.54 m for the column of bounding spheres.
pub fn drop_sites(
    hull: &[[f64; 3]],
    rotations: &[Rotation3<f64>],
    gap: f64,
    trials: usize,
    seed: u64,
    col: &Column,
) -> Result<Vec<[f64; 3]>, String> {
    if !(gap >= 0.0 && gap.is_finite()) || trials == 0 {
        return Err(format!(
            "gap {gap} must be finite and not negative, trials {trials} positive"
        ));
    }
    let pts: Vec<Point<f64>> = hull.iter().map(|p| Point::from(*p)).collect();
    let degenerate = || "the particle's convex hull is degenerate (flat or fewer than 4 points)";
    let shape = ConvexPolyhedron::from_convex_hull(&pts).ok_or_else(degenerate)?;
    let r = hull
        .iter()
        .map(|p| Vector3::from(*p).norm())
        .fold(0.0, f64::max);
    use parry3d_f64::shape::Shape;
    let volume = shape.mass_properties(1.0).mass();
    if volume.is_nan() || volume <= 1e-9 * r * r * r {
        return Err(degenerate().into());
    }
    // Horizontal grid of cells 2r + gap wide: particles whose centres are
    // further apart horizontally cannot touch.
    let cell = 2.0 * r + gap;
    let key = |x: f64, y: f64| ((x / cell).floor() as i64, (y / cell).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> =
        std::collections::HashMap::new();
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x5eed_d20b);
    let mut placed: Vec<(Isometry3<f64>, [f64; 3])> = Vec::with_capacity(rotations.len());
    let [fx, fy, fz] = col.floor_center;
    let mut near: Vec<usize> = Vec::new();
    for (i, rot) in rotations.iter().enumerate() {
        let q = UnitQuaternion::from_rotation_matrix(rot);
        let turned: Vec<Vector3<f64>> = hull.iter().map(|p| rot * Vector3::from(*p)).collect();
        let below = turned
            .iter()
            .map(|p| -p.z)
            .fold(f64::NEG_INFINITY, f64::max);
        let reach = turned.iter().map(|p| p.x.hypot(p.y)).fold(0.0, f64::max);
        let avail = col.radius - reach - gap;
        if avail < 0.0 {
            return Err(format!(
                "the container's inner radius {} m is smaller than particle {i}'s horizontal \
                 reach {reach:.4} m plus the gap {gap} m: it does not fit",
                col.radius
            ));
        }
        // The centre's height when the hull rests `gap` above the floor.
        let z_floor = fz + gap + below;
        // Resting height of the centre dropped at (x, y).
        let mut rest =
            |x: f64, y: f64| -> Result<f64, String> {
                near.clear();
                let (kx, ky) = key(x, y);
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        if let Some(v) = grid.get(&(kx + dx, ky + dy)) {
                            near.extend(v.iter().filter(|&&j| {
                                (placed[j].1[0] - x).hypot(placed[j].1[1] - y) < cell
                            }));
                        }
                    }
                }
                // Highest first: once a placed particle is too low to reach the
                // resting height found so far, so are the rest.
                near.sort_unstable_by(|&a, &b| {
                    placed[b].1[2].total_cmp(&placed[a].1[2]).then(a.cmp(&b))
                });
                let mut z = z_floor;
                for &j in near.iter() {
                    let zj = placed[j].1[2];
                    if zj + cell < z {
                        break;
                    }
                    // Start with the bounding spheres more than `gap` apart.
                    let start = zj + cell * (1.0 + 1e-9) + 1e-12;
                    let pos = Isometry3::from_parts(Translation3::new(x, y, start), q);
                    let opts = ShapeCastOptions {
                        max_time_of_impact: start - z,
                        target_distance: gap,
                        stop_at_penetration: true,
                        compute_impact_geometry_on_penetration: false,
                    };
                    let hit = cast_shapes(
                        &pos,
                        &Vector3::new(0.0, 0.0, -1.0),
                        &shape,
                        &placed[j].0,
                        &Vector3::zeros(),
                        &shape,
                        opts,
                    )
                    .map_err(|_| "convex hull shape cast unsupported".to_string())?;
                    if let Some(h) = hit {
                        z = z.max(start - h.time_of_impact);
                    }
                }
                Ok(z)
            };
        let mut p = [0.0, 0.0, f64::INFINITY];
        for _ in 0..trials {
            // Uniform over the disc of radius `avail`.
            let (u, t): (f64, f64) = (rng.gen(), rng.gen());
            let (s, c) = (std::f64::consts::TAU * t).sin_cos();
            let (x, y) = (fx + avail * u.sqrt() * c, fy + avail * u.sqrt() * s);
            let z = rest(x, y)?;
            if z < p[2] {
                p = [x, y, z];
            }
        }
        // Slide down: from the best spot, horizontal moves in eight
        // directions that lower the resting height, with halving steps
        // (a particle's own hollow, as if it rolled without turning).
        let mut step = 0.5 * r;
        while step > 0.05 * r {
            let mut moved = false;
            for k in 0..8 {
                let (s, c) = (std::f64::consts::FRAC_PI_4 * k as f64).sin_cos();
                let (x, y) = (p[0] + step * c, p[1] + step * s);
                if (x - fx).hypot(y - fy) > avail {
                    continue;
                }
                let z = rest(x, y)?;
                if z < p[2] - 1e-9 * r {
                    p = [x, y, z];
                    moved = true;
                    break;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        let pos = Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), q);
        grid.entry(key(p[0], p[1])).or_default().push(i);
        placed.push((pos, p));
    }
    Ok(placed.into_iter().map(|(_, p)| p).collect())
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

    /// A hexagonal prism (the convex hull of a nut), about its centroid.
    fn prism_points() -> Vec<[f64; 3]> {
        let mut p = Vec::new();
        for k in 0..6 {
            let (s, c) = (std::f64::consts::FRAC_PI_3 * k as f64).sin_cos();
            for z in [-0.008, 0.008] {
                p.push([0.023 * c, 0.023 * s, z]);
            }
        }
        p
    }

    #[test]
    fn dropped_particles_rest_apart_inside_the_column() {
        let hull = prism_points();
        let col = Column {
            floor_center: [0.1, -0.2, 0.5],
            radius: 0.12,
        };
        let (n, gap) = (150, 0.001);
        let rots = random_rotations(n, 11);
        let s = drop_sites(&hull, &rots, gap, 4, 11, &col).unwrap();
        assert_eq!(
            s,
            drop_sites(&hull, &rots, gap, 4, 11, &col).unwrap(),
            "not reproducible"
        );
        let shape = ConvexPolyhedron::from_convex_hull(
            &hull.iter().map(|p| Point::from(*p)).collect::<Vec<_>>(),
        )
        .unwrap();
        let pose = |i: usize| {
            Isometry3::from_parts(
                Translation3::new(s[i][0], s[i][1], s[i][2]),
                UnitQuaternion::from_rotation_matrix(&rots[i]),
            )
        };
        let turned = |i: usize| -> Vec<Vector3<f64>> {
            hull.iter()
                .map(|p| Vector3::from(s[i]) + rots[i] * Vector3::from(*p))
                .collect()
        };
        for i in 0..n {
            let pts = turned(i);
            let low = pts.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
            let wall = pts
                .iter()
                .map(|p| (p.x - 0.1).hypot(p.y + 0.2))
                .fold(0.0, f64::max);
            assert!(
                low >= 0.5 + gap - 1e-9,
                "particle {i} below the floor gap: {low}"
            );
            assert!(
                wall <= col.radius - gap + 1e-9,
                "particle {i} in the wall: {wall}"
            );
            // Apart from every particle before it, and resting: on the
            // floor or within gap (+ round-off) of one of them.
            let mut support = low <= 0.5 + gap + 1e-6;
            for j in 0..i {
                let d = parry3d_f64::query::distance(&pose(i), &shape, &pose(j), &shape).unwrap();
                assert!(
                    d >= gap * (1.0 - 1e-6),
                    "particles {j} and {i}: distance {d}"
                );
                if d <= gap * 1.01 + 1e-6 && s[j][2] < s[i][2] {
                    support = true;
                }
            }
            assert!(support, "particle {i} at {:?} hangs in the air", s[i]);
        }
    }

    #[test]
    fn dropped_particles_make_a_lower_bed_than_the_sphere_column() {
        let hull = prism_points();
        let r = hull
            .iter()
            .map(|p| Vector3::from(*p).norm())
            .fold(0.0, f64::max);
        let col = Column {
            floor_center: [0.0; 3],
            radius: 0.225,
        };
        let n = 600;
        let top = |s: &[[f64; 3]]| s.iter().map(|p| p[2]).fold(0.0, f64::max);
        let dropped = drop_sites(&hull, &random_rotations(n, 5), 0.05 * r, 8, 5, &col).unwrap();
        let column = column_sites(n, r, 0.1 * r, &col).unwrap();
        assert!(
            top(&dropped) < 0.75 * top(&column),
            "dropped top {} vs column top {}",
            top(&dropped),
            top(&column)
        );
    }

    #[test]
    fn a_drop_into_a_too_narrow_column_is_an_error() {
        let col = Column {
            floor_center: [0.0; 3],
            radius: 0.02,
        };
        let e =
            drop_sites(&prism_points(), &random_rotations(3, 1), 0.001, 4, 1, &col).unwrap_err();
        assert!(e.contains("does not fit"), "{e}");
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let wide = Column {
            floor_center: [0.0; 3],
            radius: 5.0,
        };
        let e = drop_sites(&flat, &random_rotations(3, 1), 0.001, 4, 1, &wide).unwrap_err();
        assert!(e.contains("degenerate"), "{e}");
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
