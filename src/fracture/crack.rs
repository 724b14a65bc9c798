//! Contact across a broken joint (issue 19): the two faces that a joint
//! tied stay paired after it breaks. Pressed together they repel each other
//! with the joint's own compression penalty p_f / h (what an intact joint
//! does in compression, so nothing jumps at the break), and they slide
//! against Coulomb friction μ = tan φ, the Mohr–Coulomb law of the joint
//! with its cohesion gone: a tangential spring of the same stiffness with a
//! slip history (stick, then slip at μ times the normal force). Apart, they
//! exert nothing. Not in the seeds (seed 004 hands broken joints to the
//! penalty contact without a formula).
//!
//! The faces are paired corner by corner, as the joint tied them: valid
//! while the faces slide less than their size along each other (a crack
//! in a thermally loaded body opens by microns). Free of MPI and PETSc.

use nalgebra::Vector3;

/// The history of a crack face pair: the plastic (slipped) part of the
/// tangential relative displacement of the centroids, so that the
/// tangential spring acts on the rest (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrackState {
    /// Slipped tangential displacement of b relative to a (m).
    pub slip: Vector3<f64>,
    /// Whether the faces touched at the last evaluation.
    pub closed: bool,
    /// Whether they slipped at the friction limit at the last evaluation
    /// (output only: not saved, recomputed every substep).
    pub slipping: bool,
    /// Energy this pair has dissipated by slip so far (J).
    pub lost: f64,
}

/// What one evaluation of a crack face pair gives back.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CrackResult {
    /// Elastic energy of the normal and tangential springs (J).
    pub stored: f64,
    /// Normal force pressing the faces together (N, ≥ 0).
    pub normal_force: f64,
    /// Energy dissipated by slip in this evaluation (J, ≥ 0).
    pub dissipated: f64,
}

impl CrackState {
    /// A crack just broken with faces at corners `xa`, `xb`: the present
    /// sliding counts as slipped, so the friction spring starts relaxed.
    pub fn new(xa: &[Vector3<f64>; 3], xb: &[Vector3<f64>; 3]) -> CrackState {
        let (n, mean) = normal_and_mean(xa, xb);
        CrackState {
            slip: mean - n * mean.dot(&n),
            closed: false,
            slipping: false,
            lost: 0.0,
        }
    }
}

/// Unit normal of the pair's mid-surface (from a towards b) and the mean
/// relative displacement of b's corners from a's.
fn normal_and_mean(xa: &[Vector3<f64>; 3], xb: &[Vector3<f64>; 3]) -> (Vector3<f64>, Vector3<f64>) {
    let m = |i: usize| xa[i] + xb[i];
    let c = (m(1) - m(0)).cross(&(m(2) - m(0)));
    let n = c / c.norm();
    let mean = ((xb[0] - xa[0]) + (xb[1] - xa[1]) + (xb[2] - xa[2])) / 3.0;
    (n, mean)
}

/// Normal opening of a joint's or crack's faces at `xa`, `xb`: the mean
/// relative displacement of b's corners from a's along the mid-surface
/// normal (m; negative when pressed into each other).
pub fn opening(xa: &[Vector3<f64>; 3], xb: &[Vector3<f64>; 3]) -> f64 {
    let (n, mean) = normal_and_mean(xa, xb);
    mean.dot(&n)
}

/// Forces `fa`, `fb` (N) on the corners of a crack's faces at `xa`, `xb`
/// (paired corners, coincident when the joint was made), for a penalty `k`
/// (Pa/m), friction coefficient `mu` and reference face area `area` (m²);
/// advances the slip history `st`.
///
/// Normal: each corner pair that interpenetrates (δ_n < 0 along the
/// mid-surface normal) is pushed apart by k |δ_n| A/3. Tangential: the
/// trial traction k (δ_t − slip) on the mean sliding δ_t is capped at
/// μ N / A, the slip taking up the excess; the traction acts equally at the
/// three corners. Apart (N = 0), the slip follows the sliding.
#[allow(clippy::too_many_arguments)]
pub fn crack_forces(
    k: f64,
    mu: f64,
    area: f64,
    xa: &[Vector3<f64>; 3],
    xb: &[Vector3<f64>; 3],
    st: &mut CrackState,
    fa: &mut [Vector3<f64>; 3],
    fb: &mut [Vector3<f64>; 3],
) -> CrackResult {
    *fa = [Vector3::zeros(); 3];
    *fb = [Vector3::zeros(); 3];
    let (n, mean) = normal_and_mean(xa, xb);
    let w = area / 3.0;
    let mut out = CrackResult::default();
    for i in 0..3 {
        let dn = (xb[i] - xa[i]).dot(&n);
        if dn < 0.0 {
            // b is pushed back out along +n, a along −n.
            let f = n * (-k * dn * w);
            fb[i] += f;
            fa[i] -= f;
            out.normal_force += -k * dn * w;
            out.stored += 0.5 * k * dn * dn * w;
        }
    }
    let sliding = mean - n * mean.dot(&n);
    if out.normal_force == 0.0 {
        st.slip = sliding;
        st.closed = false;
        st.slipping = false;
        return out;
    }
    st.closed = true;
    // Only the tangential part of the slip counts (the normal may turn).
    let slip = st.slip - n * st.slip.dot(&n);
    let mut elastic = sliding - slip;
    let trial = k * area * elastic.norm();
    let limit = mu * out.normal_force;
    st.slipping = trial > limit;
    if trial > limit {
        // Return to the cone: keep |k A e| = μ N, slip along e.
        let keep = limit / trial;
        let slipped = elastic * (1.0 - keep);
        out.dissipated = limit * slipped.norm();
        elastic *= keep;
    }
    st.slip = sliding - elastic;
    st.lost += out.dissipated;
    // The tangential force resists b's sliding relative to a.
    let t = elastic * (k * w);
    for i in 0..3 {
        fb[i] -= t;
        fa[i] += t;
    }
    out.stored += 0.5 * k * area * elastic.norm_squared();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face() -> [Vector3<f64>; 3] {
        [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1e-2, 0.0, 0.0),
            Vector3::new(0.0, 1e-2, 0.0),
        ]
    }

    const K: f64 = 1e12;
    const AREA: f64 = 0.5e-4;

    fn eval(xb: [Vector3<f64>; 3], st: &mut CrackState) -> (CrackResult, [Vector3<f64>; 3]) {
        let (mut fa, mut fb) = ([Vector3::zeros(); 3], [Vector3::zeros(); 3]);
        let r = crack_forces(K, 0.5, AREA, &face(), &xb, st, &mut fa, &mut fb);
        let total: Vector3<f64> = fa.iter().chain(&fb).sum();
        assert!(total.norm() <= 1e-9 * (1.0 + fb[0].norm()), "{total}");
        (r, fb)
    }

    #[test]
    fn open_faces_exert_nothing_and_pressed_faces_repel_by_the_penalty() {
        let mut st = CrackState::new(&face(), &face());
        let (r, fb) = eval(face().map(|p| p + Vector3::new(1e-7, 0.0, 1e-6)), &mut st);
        assert_eq!(r, CrackResult::default());
        assert!(fb.iter().all(|f| f.norm() == 0.0) && !st.closed);
        // Pressed by 1e-7 m (where it slid to while open: no shear): N =
        // k δ A, pushing b up (+z, a's normal side).
        let d = 1e-7;
        let (r, fb) = eval(face().map(|p| p + Vector3::new(1e-7, 0.0, -d)), &mut st);
        assert!((r.normal_force / (K * d * AREA) - 1.0).abs() < 1e-12);
        let up: f64 = fb.iter().map(|f| f.z).sum();
        assert!((up / r.normal_force - 1.0).abs() < 1e-12, "{up}");
        assert!((r.stored / (0.5 * K * d * d * AREA) - 1.0).abs() < 1e-12);
        assert!(st.closed);
    }

    #[test]
    fn pressed_faces_stick_then_slide_at_mu_n_and_dissipate_mu_n_per_metre() {
        let d = 1e-7;
        let mut st = CrackState::new(&face(), &face());
        let n = K * d * AREA;
        // Stick: a small sliding is resisted elastically.
        let s = 0.2 * 0.5 * d;
        let (r, fb) = eval(face().map(|p| p + Vector3::new(s, 0.0, -d)), &mut st);
        let fx: f64 = fb.iter().map(|f| f.x).sum();
        assert!((fx / (-K * s * AREA) - 1.0).abs() < 1e-9, "{fx}");
        assert_eq!(r.dissipated, 0.0);
        assert!(st.closed && !st.slipping);
        // Slide: far beyond the stick limit μ N / (k A) = μ d, the
        // friction force is μ N and the work lost is μ N times the slip.
        let mut lost = 0.0;
        let mut fx = 0.0;
        for i in 1..=100 {
            let s = 0.1 * d * i as f64;
            let (r, fb) = eval(face().map(|p| p + Vector3::new(s, 0.0, -d)), &mut st);
            lost += r.dissipated;
            fx = fb.iter().map(|f| f.x).sum();
            // Past the stick limit (at μ d = 0.5 d), every step slips.
            if (s - 0.5 * d).abs() > 0.01 * d {
                assert_eq!(st.slipping, s > 0.5 * d, "step {i}");
            }
        }
        assert!((fx / (-0.5 * n) - 1.0).abs() < 1e-9, "{fx}");
        // Total sliding 10 d, of which μ d stays elastic.
        let want = 0.5 * n * (10.0 * d - 0.5 * d);
        assert!((lost / want - 1.0).abs() < 1e-9, "{lost} vs {want}");
        // Lifted apart, then pressed again: the spring starts relaxed.
        eval(face().map(|p| p + Vector3::new(20.0 * d, 0.0, d)), &mut st);
        assert!(!st.closed && !st.slipping);
        let (r, fb) = eval(face().map(|p| p + Vector3::new(20.0 * d, 0.0, -d)), &mut st);
        assert!(fb.iter().all(|f| f.x.abs() < 1e-9 * r.normal_force));
    }
}
