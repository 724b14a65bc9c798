//! The 6-node joint element that ties two tet faces which were one face of
//! the continuous mesh (seed 004 sec 2.7, Fig 2b): its relative
//! displacement, its damage update and the nodal forces of its tractions.
//! Free of MPI and PETSc.

use super::law::{CohesiveLaw, JointState};
use nalgebra::Vector3;

/// Normal opening and sliding of a relative displacement `d` across a
/// surface of unit normal `n`: (δ_n, |δ_s|, δ_s).
fn split(d: Vector3<f64>, n: &Vector3<f64>) -> (f64, f64, Vector3<f64>) {
    let dn = d.dot(n);
    let sv = d - n * dn;
    (dn, sv.norm(), sv)
}

/// Unit normal of the joint's mid-surface, from face a towards face b
/// (the a face's corners are ordered counter-clockwise seen from b).
fn mid_normal(xa: &[Vector3<f64>; 3], xb: &[Vector3<f64>; 3]) -> Vector3<f64> {
    // Twice the mid-points: the normal is the same (scaling by 2 is exact).
    let m = |i: usize| xa[i] + xb[i];
    let (m0, m1, m2) = (m(0), m(1), m(2));
    let c = (m1 - m0).cross(&(m2 - m0));
    // One division, not three.
    c * (1.0 / c.norm())
}

/// Advance one joint to the current positions of its faces' corners `xa`
/// and `xb` (matching corners, coincident when inserted) and write the
/// forces on them, `fa` and `fb` (N); returns the elastic energy it stores
/// after the step (J, [`joint_energy`] from the same displacements).
/// `area` is the face's reference area (m²). The damage follows the
/// relative displacement of the centroids; the tractions act at the three
/// corner pairs with a third of the area each (nodal integration, exact
/// for a uniform opening). A broken joint exerts no force.
///
/// Inlined into the set's loop so the gathered corners stay in registers
/// (passed through the stack they stalled on store forwarding).
#[inline(always)]
pub fn joint_forces(
    law: &CohesiveLaw,
    area: f64,
    xa: &[Vector3<f64>; 3],
    xb: &[Vector3<f64>; 3],
    st: &mut JointState,
    fa: &mut [Vector3<f64>; 3],
    fb: &mut [Vector3<f64>; 3],
) -> f64 {
    if st.broken.is_some() {
        *fa = [Vector3::zeros(); 3];
        *fb = [Vector3::zeros(); 3];
        return 0.0;
    }
    let n = mid_normal(xa, xb);
    let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
    let mean = (d[0] + d[1] + d[2]) * (1.0 / 3.0);
    let dn = mean.dot(&n);
    let s2 = (mean - n * dn).norm_squared();
    let before = st.damage;
    law.update_squared(dn, s2, st);
    if st.damage > before {
        // The law books ½ k λ² dD of the centroids' λ; the corners, where
        // the tractions act, store more when the faces turn or bend (their
        // mean square exceeds the centroids'): that part is released too.
        let corners = d
            .iter()
            .map(|d| {
                let dn = d.dot(&n);
                dn.max(0.0).powi(2) + (d - n * dn).norm_squared()
            })
            .sum::<f64>()
            / 3.0;
        let extra = corners - (dn.max(0.0).powi(2) + s2);
        st.dissipated += 0.5 * law.k * (st.damage - before) * extra.max(0.0);
    }
    if st.broken.is_some() {
        *fa = [Vector3::zeros(); 3];
        *fb = [Vector3::zeros(); 3];
        return 0.0;
    }
    let w = area / 3.0;
    // Shear stiffness left, (1 − D) k: the shear traction is that times the
    // sliding vector (its length and direction at once, no square root).
    let ks = (1.0 - st.damage) * law.k;
    let mut stored = 0.0;
    for (i, d) in d.iter().enumerate() {
        let dn = d.dot(&n);
        let sv = d - n * dn;
        // Opening is softened by 1 − D, compression is the undamaged
        // penalty ([`CohesiveLaw::traction`], [`CohesiveLaw::stored`]).
        let kn = if dn > 0.0 { ks } else { law.k };
        let t = n * (kn * dn) + sv * ks;
        // The traction resists the separation: b is pulled back to a, a to b.
        let tw = t * w;
        fb[i] = -tw;
        fa[i] = tw;
        stored += kn * dn * dn + ks * sv.norm_squared();
    }
    0.5 * stored * w
}

/// Elastic energy stored in an intact joint at the current positions (J).
pub fn joint_energy(
    law: &CohesiveLaw,
    area: f64,
    xa: &[Vector3<f64>; 3],
    xb: &[Vector3<f64>; 3],
    st: &JointState,
) -> f64 {
    if st.broken.is_some() {
        return 0.0;
    }
    let n = mid_normal(xa, xb);
    (0..3)
        .map(|i| {
            let (dn, s, _) = split(xb[i] - xa[i], &n);
            law.stored(dn, s, st.damage)
        })
        .sum::<f64>()
        * area
        / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    /// Seed 004 Table 2's joint at h = 5 mm (the paper's mesh).
    fn law() -> CohesiveLaw {
        crate::fracture::law::table2().law(5e-3).unwrap()
    }

    fn face() -> [Vector3<f64>; 3] {
        [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1e-2, 0.0, 0.0),
            Vector3::new(0.0, 1e-2, 0.0),
        ]
    }

    #[test]
    fn a_rigid_motion_of_both_faces_exerts_no_force() {
        let law = law();
        let rot = Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let shift = Vector3::new(0.2, -0.1, 0.05);
        let x: [Vector3<f64>; 3] = face().map(|p| rot * p + shift);
        let mut st = JointState::default();
        let (mut fa, mut fb) = ([Vector3::zeros(); 3], [Vector3::zeros(); 3]);
        joint_forces(&law, 5e-5, &x, &x, &mut st, &mut fa, &mut fb);
        assert!(fa.iter().chain(&fb).all(|f| f.norm() == 0.0));
        assert_eq!(st.damage, 0.0);
    }

    #[test]
    fn opening_pulls_the_faces_together_with_balanced_forces() {
        let law = law();
        let xa = face();
        let area = 0.5e-4;
        // Open by half the peak opening along +z (b's side), then slide.
        let d = 0.5 * 10e6 / law.k;
        let xb = xa.map(|p| p + Vector3::new(0.3 * d, 0.0, d));
        let mut st = JointState::default();
        let (mut fa, mut fb) = ([Vector3::zeros(); 3], [Vector3::zeros(); 3]);
        let stored = joint_forces(&law, area, &xa, &xb, &mut st, &mut fa, &mut fb);
        let total: Vector3<f64> = fa.iter().chain(&fb).sum();
        assert!(total.norm() < 1e-9 * fa[0].norm());
        // Each b corner is pulled back by k δ area / 3 (no damage yet).
        for f in &fb {
            let want = -law.k * Vector3::new(0.3 * d, 0.0, d) * area / 3.0;
            assert!((f - want).norm() < 1e-6 * want.norm(), "{f} vs {want}");
        }
        // Stored energy ½ k |δ|² A.
        let e = joint_energy(&law, area, &xa, &xb, &st);
        assert!((stored / e - 1.0).abs() < 1e-12, "{stored} vs {e}");
        let want = 0.5 * law.k * (d * d * 1.09) * area;
        assert!((e / want - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_tilted_opening_dissipates_the_work_done_on_the_joint() {
        // b's corners open by x, 2x and 3x (the faces turn about a line):
        // the corners store more than the centroids' opening says, and all
        // of it is released by the time the joint breaks.
        let law = law();
        let (xa, area) = (face(), 0.5e-4);
        let mut st = JointState::default();
        let (mut fa, mut fb) = ([Vector3::zeros(); 3], [Vector3::zeros(); 3]);
        let nf = 2.0 * 50.0 / 10e6;
        let tilt = [1.0, 2.0, 3.0];
        let at = |x: f64| {
            let mut xb = xa;
            for (p, t) in xb.iter_mut().zip(tilt) {
                p.z += t * x;
            }
            xb
        };
        let (steps, mut work, mut x) = (20_000, 0.0, 0.0);
        let dx = nf / 2.0 / 10_000.0;
        let mut f_old = [Vector3::zeros(); 3];
        for _ in 0..steps {
            if st.broken.is_some() {
                break;
            }
            x += dx;
            joint_forces(&law, area, &xa, &at(x), &mut st, &mut fa, &mut fb);
            // Work done on b's corners against the joint (trapezoidal).
            for (i, t) in tilt.iter().enumerate() {
                work -= 0.5 * (f_old[i].z + fb[i].z) * t * dx;
            }
            f_old = fb;
        }
        assert!(st.broken.is_some());
        let booked = st.dissipated * area;
        assert!(
            (booked / work - 1.0).abs() < 5e-3,
            "dissipated {booked:e} J against the work {work:e} J"
        );
    }

    #[test]
    fn a_joint_pulled_past_its_final_opening_breaks_and_lets_go() {
        let law = law();
        let xa = face();
        let mut st = JointState::default();
        let (mut fa, mut fb) = ([Vector3::zeros(); 3], [Vector3::zeros(); 3]);
        let nf = 2.0 * 50.0 / 10e6;
        let mut x = 0.0;
        while st.broken.is_none() {
            x += nf / 1000.0;
            let xb = xa.map(|p| p + Vector3::new(0.0, 0.0, x));
            joint_forces(&law, 0.5e-4, &xa, &xb, &mut st, &mut fa, &mut fb);
        }
        assert!(x >= nf && x < nf * 1.002);
        assert!(fb.iter().all(|f| f.norm() == 0.0));
        assert!((st.dissipated / 50.0 - 1.0).abs() < 1e-12);
    }
}
