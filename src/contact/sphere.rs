//! Free discrete-element spheres (issue 21, "Beyond the papers"): the
//! contact of a sphere with another sphere and with a boundary triangle of
//! a Tet4 body. Pure: no MPI or PETSc.
//!
//! Normal force: Hertz's elastic sphere contact (H. Hertz 1882, "Über die
//! Berührung fester elastischer Körper"; K. L. Johnson, Contact Mechanics,
//! 1985, sec 4.2), F = 4/3 E* √R* δ^{3/2}, with a viscous term
//! 2 ζ √(m* k_n) v_n on the approach speed (ζ a damping ratio of the
//! contact, k_n = dF/dδ), the total never tensile. Tangential force: a
//! spring with history (Mindlin's initial stiffness k_t = 8 G* a, Johnson
//! sec 7.2) capped by Coulomb friction μ F_n, its elongation rotated into
//! each new tangent plane and cut back to the cap when the contact slides.
//!
//! A sphere against a Tet4 body meets the body's boundary triangles; the
//! force acts at the closest point of each touching triangle and goes to
//! the triangle's nodes with the point's barycentric weights. On a
//! tessellated face a sphere near an edge or vertex touches several
//! triangles whose closest points are the same surface seen twice, so per
//! (sphere, body) the touching triangles are taken deepest first and one is
//! kept only if its contact normal differs from every kept one by more
//! than [`DISTINCT_NORMAL_DEG`] ([`distinct_features`]): on a flat or
//! gently curved face that keeps one contact (the normals of a sphere's
//! neighbouring closest points differ by about √(2δ/R), a few degrees),
//! while the floor and wall of a concave corner each push.

use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// Two touching triangles of one body are the same contact unless their
/// normals differ by more than this many degrees.
pub const DISTINCT_NORMAL_DEG: f64 = 25.0;

/// Hertz's effective modulus of two elastic bodies,
/// 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂ (Johnson 1985 sec 4.2).
pub fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    // Johnson 1985 sec 4.2: 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂.
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

/// Mindlin's effective shear modulus, 1/G* = (2 − ν₁)/G₁ + (2 − ν₂)/G₂
/// with G = E/(2(1 + ν)) (Johnson 1985 sec 7.2).
pub fn effective_shear_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    let g = |e: f64, nu: f64| e / (2.0 * (1.0 + nu));
    // Johnson 1985 sec 7.2 (Mindlin): 1/G* = (2 − ν₁)/G₁ + (2 − ν₂)/G₂.
    1.0 / ((2.0 - nu1) / g(e1, nu1) + (2.0 - nu2) / g(e2, nu2))
}

/// Effective radius 1/R* = 1/R₁ + 1/R₂; a plane (`None`) has 1/R = 0.
pub fn effective_radius(r1: f64, r2: Option<f64>) -> f64 {
    match r2 {
        // Johnson 1985 sec 4.2: 1/R* = 1/R₁ + 1/R₂.
        Some(r2) => r1 * r2 / (r1 + r2),
        None => r1,
    }
}

/// Hertz's static overlap of a sphere of weight `weight` (N) on a plane,
/// δ = (3 W / (4 E* √R*))^{2/3}: the inverse of [`hertz_force`].
pub fn hertz_static_overlap(weight: f64, e_star: f64, r_star: f64) -> f64 {
    // Johnson 1985 sec 4.2 inverted: δ = (3 F / (4 E* √R*))^{2/3}.
    (3.0 * weight / (4.0 * e_star * r_star.sqrt())).powf(2.0 / 3.0)
}

/// Hertz's elastic normal force F = 4/3 E* √R* δ^{3/2} and its stiffness
/// k_n = dF/dδ = 2 E* √(R* δ) at overlap `delta` (0 when apart).
pub fn hertz_force(e_star: f64, r_star: f64, delta: f64) -> (f64, f64) {
    if delta <= 0.0 {
        return (0.0, 0.0);
    }
    let a = (r_star * delta).sqrt();
    // Johnson 1985 sec 4.2: F = 4/3 E* √R* δ^{3/2} (= 4/3 E* a δ, a = √(R* δ)).
    (4.0 / 3.0 * e_star * a * delta, 2.0 * e_star * a)
}

/// The elastic energy of a Hertz contact, ∫F dδ = 8/15 E* √R* δ^{5/2}.
pub fn hertz_energy(e_star: f64, r_star: f64, delta: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    8.0 / 15.0 * e_star * r_star.sqrt() * delta.powf(2.5)
}

/// The constants of one contact (a pair of spheres, or a sphere and a
/// body's face).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzLaw {
    /// Effective modulus E* (Pa).
    pub e_star: f64,
    /// Effective shear modulus G* (Pa).
    pub g_star: f64,
    /// Effective radius R* (m).
    pub r_star: f64,
    /// Effective mass m* = m₁ m₂/(m₁ + m₂) (kg); a body's face counts as
    /// infinitely heavy (m* = the sphere's mass).
    pub mass: f64,
    /// Damping ratio ζ of the normal contact.
    pub damping: f64,
    /// Coulomb friction coefficient μ.
    pub friction: f64,
}

/// What a contact gives its first side (the sphere `a`) in one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereContactForce {
    /// Force on side a (N); side b takes its opposite.
    pub force: V3,
    /// Normal force F_n ≥ 0 (N), elastic plus viscous.
    pub normal: f64,
    /// Hertz elastic energy (J).
    pub energy: f64,
    /// Contact radius a = √(R* δ) (m).
    pub radius: f64,
    /// Energy the tangential spring holds after the step, ½ |F_t|²/k_t (J).
    pub spring_energy: f64,
    /// Energy the contact dissipated over the step (J): the normal
    /// dashpot's (F_n − F_e) v_n Δt and, when sliding, what the cut took
    /// from the spring, ½ (|F_t,trial|² − (μ F_n)²)/k_t.
    pub lost: f64,
}

impl HertzLaw {
    /// The force on side a of a contact with overlap `delta` > 0, unit
    /// normal `n` from a towards b, and `v_rel` the velocity of a's
    /// contact point less b's. `xi` is the tangential spring's elongation
    /// (history; zero at first touch), advanced over `dt`.
    pub fn force(
        &self,
        delta: f64,
        n: &V3,
        v_rel: &V3,
        dt: f64,
        xi: &mut V3,
    ) -> SphereContactForce {
        let (elastic, kn) = hertz_force(self.e_star, self.r_star, delta);
        let vn = v_rel.dot(n);
        // Viscous normal damping: c = 2 ζ √(m* k_n) on the approach speed.
        let c = 2.0 * self.damping * (self.mass * kn).sqrt();
        let fn_ = (elastic + c * vn).max(0.0);
        // The spring's elongation, turned into the current tangent plane.
        let old = xi.norm();
        *xi -= *n * xi.dot(n);
        let now = xi.norm();
        if now > 0.0 {
            *xi *= old / now;
        }
        *xi += (v_rel - *n * vn) * dt;
        let a = (self.r_star * delta).sqrt();
        // Johnson 1985 sec 7.2 (Mindlin): k_t = 8 G* a.
        let kt = 8.0 * self.g_star * a;
        let mut ft = -*xi * kt;
        let cap = self.friction * fn_;
        let size = ft.norm();
        // Not in the seeds: the dashpot's loss, its force times the approach over Δt.
        let mut lost = (fn_ - elastic) * vn * dt;
        if size > cap {
            // Sliding: Coulomb, |F_t| = μ F_n, the spring cut back to it.
            let scale = if size > 0.0 { cap / size } else { 0.0 };
            ft *= scale;
            *xi *= scale;
            // Not in the seeds: the slip's loss, the spring energy the cut removed.
            if kt > 0.0 {
                lost += 0.5 * (size * size - cap * cap) / kt;
            }
        }
        let spring_energy = if kt > 0.0 {
            0.5 * ft.norm_squared() / kt
        } else {
            0.0
        };
        SphereContactForce {
            force: -*n * fn_ + ft,
            normal: fn_,
            energy: hertz_energy(self.e_star, self.r_star, delta),
            radius: a,
            spring_energy,
            lost,
        }
    }
}

/// The closest point of the triangle `t` to `p`, and its barycentric
/// weights (w₀, w₁, w₂) on the triangle's corners (each ≥ 0, sum 1).
pub fn closest_point_on_triangle(p: &V3, t: &[V3; 3]) -> (V3, [f64; 3]) {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    // Corner a's region.
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    // Edge regions: the signed areas (in units of the triangle's) opposite
    // each corner of the projection decide.
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let s = d1 / (d1 - d3);
        return (a + ab * s, [1.0 - s, s, 0.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let s = d2 / (d2 - d6);
        return (a + ac * s, [1.0 - s, 0.0, s]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * s, [0.0, 1.0 - s, s]);
    }
    // Inside: the projection onto the plane.
    let sum = va + vb + vc;
    let (v, w) = (vb / sum, vc / sum);
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// A sphere touching a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleTouch {
    /// Overlap δ = r − |q − x| (m).
    pub depth: f64,
    /// Unit normal from the sphere's centre towards the closest point q.
    pub normal: V3,
    /// The closest point q.
    pub point: V3,
    /// Barycentric weights of q on the triangle's corners.
    pub weights: [f64; 3],
}

/// The touch of a sphere (centre `x`, radius `r`) on triangle `t`, if they
/// overlap. A centre on the triangle itself takes the triangle's normal
/// (corner order) as its normal.
pub fn sphere_triangle(x: &V3, r: f64, t: &[V3; 3]) -> Option<TriangleTouch> {
    let (q, weights) = closest_point_on_triangle(x, t);
    let d = q - x;
    let dist = d.norm();
    if dist >= r {
        return None;
    }
    let normal = if dist > 1e-12 * r {
        d / dist
    } else {
        (t[1] - t[0]).cross(&(t[2] - t[0])).normalize()
    };
    Some(TriangleTouch {
        depth: r - dist,
        normal,
        point: q,
        weights,
    })
}

/// The tangential spring a sphere kept last step for its contact with
/// `body` whose normal was nearest `normal` (within
/// [`DISTINCT_NORMAL_DEG`]), whichever triangle had it, or zero: rolling
/// over a body's tessellation keeps the spring. `old`: (body, normal,
/// spring) per contact of the step before.
pub fn kept_spring(old: &[(u32, V3, V3)], body: u32, normal: &V3) -> V3 {
    let cos = DISTINCT_NORMAL_DEG.to_radians().cos();
    old.iter()
        .filter(|h| h.0 == body && h.1.dot(normal) >= cos)
        .max_by(|a, b| a.1.dot(normal).total_cmp(&b.1.dot(normal)))
        .map_or_else(V3::zeros, |h| h.2)
}

/// The touches of one sphere on one body that count (module header):
/// `touches` (triangle index, touch) sorted deepest first (ties by the
/// lower index), each kept only if its normal is more than
/// [`DISTINCT_NORMAL_DEG`] from every kept one's.
pub fn distinct_features(mut touches: Vec<(u32, TriangleTouch)>) -> Vec<(u32, TriangleTouch)> {
    touches.sort_by(|a, b| b.1.depth.total_cmp(&a.1.depth).then(a.0.cmp(&b.0)));
    let cos = DISTINCT_NORMAL_DEG.to_radians().cos();
    let mut kept: Vec<(u32, TriangleTouch)> = Vec::with_capacity(touches.len().min(4));
    for t in touches {
        if kept.iter().all(|k| k.1.normal.dot(&t.1.normal) < cos) {
            kept.push(t);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(friction: f64, damping: f64) -> HertzLaw {
        HertzLaw {
            e_star: 1e9,
            g_star: 4e8,
            r_star: 0.01,
            mass: 0.5,
            damping,
            friction,
        }
    }

    #[test]
    fn effective_constants_of_equal_and_rigid_partners() {
        let e = effective_modulus(2e11, 0.3, 2e11, 0.3);
        assert!((e - 2e11 / (2.0 * 0.91)).abs() < 1e-3);
        // A rigid partner leaves the sphere's plane-strain modulus.
        let e = effective_modulus(1e9, 0.25, f64::INFINITY, 0.3);
        assert!((e - 1e9 / (1.0 - 0.0625)).abs() < 1e-6);
        assert_eq!(effective_radius(0.02, Some(0.02)), 0.01);
        assert_eq!(effective_radius(0.02, None), 0.02);
        let g = effective_shear_modulus(1e9, 0.25, 1e9, 0.25);
        let g1 = 1e9 / 2.5;
        assert!((g - g1 / (2.0 * 1.75)).abs() < 1e-6);
    }

    #[test]
    fn hertz_force_stiffness_energy_and_static_overlap_agree() {
        let (e, r) = (7e10, 0.005);
        for delta in [1e-7, 1e-6, 3e-5] {
            let (f, k) = hertz_force(e, r, delta);
            assert!((f - 4.0 / 3.0 * e * r.sqrt() * delta.powf(1.5)).abs() < 1e-12 * f);
            // k = dF/dδ by a central difference; U' = F likewise.
            let h = 1e-4 * delta;
            let fd = (hertz_force(e, r, delta + h).0 - hertz_force(e, r, delta - h).0) / (2.0 * h);
            assert!((k - fd).abs() < 1e-6 * k, "{k} {fd}");
            let ud = (hertz_energy(e, r, delta + h) - hertz_energy(e, r, delta - h)) / (2.0 * h);
            assert!((ud - f).abs() < 1e-6 * f);
            assert!((hertz_static_overlap(f, e, r) - delta).abs() < 1e-10 * delta);
        }
        assert_eq!(hertz_force(e, r, -1e-6), (0.0, 0.0));
    }

    #[test]
    fn damping_opposes_approach_and_never_pulls() {
        let l = law(0.0, 0.5);
        let n = V3::z();
        let mut xi = V3::zeros();
        let still = l.force(1e-6, &n, &V3::zeros(), 1e-6, &mut xi);
        let closing = l.force(1e-6, &n, &V3::new(0.0, 0.0, 1.0), 1e-6, &mut xi);
        let opening = l.force(1e-6, &n, &V3::new(0.0, 0.0, -1e3), 1e-6, &mut xi);
        assert!(closing.normal > still.normal && still.normal > 0.0);
        assert_eq!(opening.normal, 0.0);
        assert!(still.force.z < 0.0 && still.force.x == 0.0);
    }

    #[test]
    fn friction_sticks_then_slides_at_mu_fn() {
        let l = law(0.3, 0.0);
        let n = V3::z();
        let mut xi = V3::zeros();
        let slow = V3::new(1e-3, 0.0, 0.0);
        let f = l.force(1e-5, &n, &slow, 1e-6, &mut xi);
        // Sticking: the spring's force k_t v dt opposes the slip.
        let kt = 8.0 * l.g_star * (l.r_star * 1e-5).sqrt();
        assert!((f.force.x + kt * 1e-9).abs() < 1e-9 * kt * 1e-9);
        // Far slip: Coulomb's cap.
        let f = l.force(1e-5, &n, &V3::new(1e3, 0.0, 0.0), 1.0, &mut xi);
        assert!((f.force.x + 0.3 * f.normal).abs() < 1e-9 * f.normal);
        assert!((xi.norm() * kt - 0.3 * f.normal).abs() < 1e-9 * f.normal);
        // The history turns with the normal and keeps its size.
        let before = xi.norm();
        let tilted = V3::new(0.1, 0.0, 1.0).normalize();
        l.force(1e-5, &tilted, &V3::zeros(), 0.0, &mut xi);
        assert!(xi.dot(&tilted).abs() < 1e-12 * before);
        assert!((xi.norm() - before).abs() < 1e-12 * before);
    }

    #[test]
    fn closest_point_in_every_region() {
        let t = [V3::zeros(), V3::x(), V3::y()];
        let cases = [
            (V3::new(0.2, 0.2, 1.0), V3::new(0.2, 0.2, 0.0)),
            (V3::new(-1.0, -1.0, 0.5), V3::zeros()),
            (V3::new(2.0, -0.5, 0.0), V3::x()),
            (V3::new(-0.5, 2.0, 0.0), V3::y()),
            (V3::new(0.5, -1.0, 0.3), V3::new(0.5, 0.0, 0.0)),
            (V3::new(-1.0, 0.5, 0.3), V3::new(0.0, 0.5, 0.0)),
            (V3::new(1.0, 1.0, 0.0), V3::new(0.5, 0.5, 0.0)),
        ];
        for (p, want) in cases {
            let (q, w) = closest_point_on_triangle(&p, &t);
            assert!((q - want).norm() < 1e-14, "{p:?}: {q:?}");
            let back = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
            assert!((back - q).norm() < 1e-14 && w.iter().all(|&x| x >= -1e-15));
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        }
        // Against brute force on random points of a skew triangle.
        let t = [
            V3::new(0.1, 0.3, -0.2),
            V3::new(1.3, 0.2, 0.4),
            V3::new(0.4, 1.1, 0.1),
        ];
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.0
        };
        for _ in 0..200 {
            let p = V3::new(rnd(), rnd(), rnd());
            let (q, _) = closest_point_on_triangle(&p, &t);
            let mut best = f64::INFINITY;
            for i in 0..=200 {
                for j in 0..=(200 - i) {
                    let (u, v) = (i as f64 / 200.0, j as f64 / 200.0);
                    let y = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    best = best.min((y - p).norm());
                }
            }
            let d = (q - p).norm();
            assert!(d <= best + 1e-12 && d > best - 1e-2, "{d} {best}");
        }
    }

    #[test]
    fn a_flat_face_counts_once_and_a_corner_twice() {
        // A sphere over the shared edge of two coplanar triangles.
        let floor = [
            [V3::zeros(), V3::x(), V3::new(1.0, 1.0, 0.0)],
            [V3::zeros(), V3::new(1.0, 1.0, 0.0), V3::y()],
        ];
        let x = V3::new(0.51, 0.5, 0.099);
        let touches: Vec<_> = (0..2)
            .filter_map(|i| sphere_triangle(&x, 0.1, &floor[i]).map(|t| (i as u32, t)))
            .collect();
        assert_eq!(touches.len(), 2);
        let kept = distinct_features(touches);
        assert_eq!(kept.len(), 1);
        assert!((kept[0].1.depth - 0.001).abs() < 1e-12);
        assert!((kept[0].1.normal + V3::z()).norm() < 1e-12);
        // In a concave corner, the floor and a wall.
        let wall = [V3::zeros(), V3::new(0.0, 0.0, 1.0), V3::y()];
        let x = V3::new(0.099, 0.5, 0.099);
        let touches: Vec<_> = [floor[1], wall]
            .iter()
            .enumerate()
            .filter_map(|(i, t)| sphere_triangle(&x, 0.1, t).map(|t| (i as u32, t)))
            .collect();
        assert_eq!(distinct_features(touches).len(), 2);
        assert!(sphere_triangle(&V3::new(0.5, 0.2, 0.2), 0.1, &floor[0]).is_none());
    }
}
