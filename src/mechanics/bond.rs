//! Bonded discrete elements (seed 002 sec "Discrete element model" and
//! eqs 2–4, 12–15): spring stiffnesses and thermal conductances of the
//! cubic sphere lattice ([`crate::mesh::lattice`]), the incremental bond
//! kernel with particle rotations, bond heat flows and the damped
//! central-difference update of sphere velocities. Pure kernels over slices
//! of bonds and particles, free of MPI and PETSc: a per-rank loop calls
//! [`bond_forces`] / [`bond_heat`] on its bonds and [`update_particles`] on
//! its particles.
//!
//! # Stiffnesses (seed 002 eq 4) and what they reproduce
//!
//! Under a uniform small strain ε the relative displacement of a bond of
//! direction n and length ℓ is ℓ ε n, so its energy is
//! ½ ℓ² [k_n (n·εn)² + k_s |εn − (n·εn) n|²]. Summing the 3 face bonds
//! (ℓ = 2r) and 6 edge bonds (ℓ = 2√2 r) per sphere over the cell volume
//! (2r)³ gives a cubic material with C11 = (3k_n + 2k_s)/(2r),
//! C12 = (k_n − k_s)/(2r), C44 = (2k_n + 3k_s)/(4r). With k_n and k_s of
//! eq 4 these are exactly the isotropic λ + 2μ, λ and μ of (E, ν): the
//! energy equivalence is exact for uniform strain (the corner bonds, k³ = 0,
//! add nothing), so a lattice in uniform strain carries the continuum
//! stress to round-off; the test holds it to 1e-10. Eq 4's k_s is negative
//! for ν > 1/4, so [`BondStiffness::seed002`] refuses those.
//!
//! # Bond conductance (flux equivalence, derived as eq 4)
//!
//! Under a uniform gradient g a bond of direction n, length ℓ and
//! conductance h carries Q = −h ℓ (g·n) from i to j. The mean flux of a
//! cell is q = (1/V) Σ_bonds Q ℓ n = −(1/V) Σ h ℓ² n⊗n g, V = (2r)³. Per
//! sphere Σ n⊗n = I over its 3 face bonds, 2I over its 6 edge bonds and
//! (4/3) I over its 4 corner bonds, so q = −(h₁ + 4h₂ + 4h₃)/(2r) g: the
//! lattice is isotropic for any h and reproduces k when
//! h₁ + 4h₂ + 4h₃ = 2rk. As in eq 4, face and edge bonds take the same
//! value and corner bonds none: h₁ = h₂ = 2kr/5, h₃ = 0 (the normal-spring
//! formula of eq 4 with ν = 0). The same sum over energies shows the
//! dissipation ½ Σ h (ΔT)² equals ½ k |g|² V, the energy equivalence.
//!
//! # Particles
//!
//! Each sphere stands for its cube of side 2r: mass m = ρ (2r)³, so the
//! lattice has the continuum's mass; moment of inertia of a sphere of that
//! mass, I = 2/5 m r². Heat capacity likewise ρ c (2r)³.

use nalgebra::Vector3;

use crate::mesh::lattice::LatticeBond;

/// Errors of the bond kernels.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BondError {
    /// A constant is outside the range where eq 4 gives stable springs.
    #[error("bonded lattice: {0}")]
    InvalidParameter(String),
}

/// Spring stiffnesses (N/m) per neighbour group (index [`BondKind`] as usize).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondStiffness {
    /// Normal stiffness k_n per group.
    pub normal: [f64; 3],
    /// Tangential stiffness k_s = k_t per group.
    pub tangential: [f64; 3],
}

impl BondStiffness {
    /// Seed 002 eq 4 for Young's modulus `young`, Poisson's ratio `poisson`
    /// and sphere radius `radius`. Errors unless E > 0, r > 0 and
    /// −1 < ν <= 1/4 (k_s < 0 beyond 1/4).
    pub fn seed002(young: f64, poisson: f64, radius: f64) -> Result<Self, BondError> {
        if !(young.is_finite() && young > 0.0 && radius.is_finite() && radius > 0.0) {
            return Err(BondError::InvalidParameter(format!(
                "need E > 0 and r > 0, got E = {young}, r = {radius}"
            )));
        }
        if !(poisson > -1.0 && poisson <= 0.25) {
            return Err(BondError::InvalidParameter(format!(
                "eq 4 needs -1 < nu <= 1/4 (the tangential springs turn negative beyond), got {poisson}"
            )));
        }
        let nu = poisson;
        // seed 002 eq 4: k_n¹ = k_n² = 2Er/(5(1 − 2ν)).
        let kn = 2.0 * young * radius / (5.0 * (1.0 - 2.0 * nu));
        // seed 002 eq 4: k_s¹ = k_t¹ = k_s² = k_t² = 2Er(1 − 4ν)/(5(1 − 2ν)(1 + ν)).
        let ks = 2.0 * young * radius * (1.0 - 4.0 * nu) / (5.0 * (1.0 - 2.0 * nu) * (1.0 + nu));
        // seed 002 eq 4: k_n³ = k_s³ = k_t³ = 0 (corner neighbours).
        Ok(Self {
            normal: [kn, kn, 0.0],
            tangential: [ks, ks, 0.0],
        })
    }
}

/// Bond conductances (W/K) per neighbour group that reproduce the
/// continuum conductivity `k` (W/m/K): h₁ = h₂ = 2kr/5, h₃ = 0 (module docs).
pub fn bond_conductance(k: f64, radius: f64) -> [f64; 3] {
    // Flux equivalence (module docs, the analogue of seed 002 eq 4): h₁ + 4h₂ + 4h₃ = 2rk with h₁ = h₂, h₃ = 0.
    let h = 2.0 * k * radius / 5.0;
    [h, h, 0.0]
}

/// Mass m = ρ (2r)³ and moment of inertia I = 2/5 m r² of a lattice sphere.
pub fn sphere_mass_inertia(density: f64, radius: f64) -> (f64, f64) {
    let m = density * (2.0 * radius).powi(3);
    (m, 0.4 * m * radius * radius)
}

/// Incremental state of one bond: the accumulated relative displacement d
/// (seed 002 eq 12) in the global frame and the unit direction n of the
/// centre line when d was last updated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondState {
    /// Relative displacement d of j with respect to i at the midpoint (m).
    pub d: Vector3<f64>,
    /// Unit direction from i to j at the last update.
    pub n: Vector3<f64>,
}

impl BondState {
    /// Unstressed state of the bond between centres `xi` and `xj`.
    pub fn new(xi: &Vector3<f64>, xj: &Vector3<f64>) -> Self {
        Self {
            d: Vector3::zeros(),
            n: (xj - xi).normalize(),
        }
    }

    /// Stored energy w (½ k_n (d_n − e)² + ½ k_s |d_t|²) (J) of `bond`
    /// with free thermal elongation `free` = e (m; [`advance_bond`]).
    pub fn energy(&self, stiffness: &BondStiffness, bond: &LatticeBond, free: f64) -> f64 {
        let dn = self.d.dot(&self.n);
        let dt2 = (self.d.norm_squared() - dn * dn).max(0.0);
        let k = bond.kind as usize;
        let de = dn - free;
        0.5 * bond.weight * (stiffness.normal[k] * de * de + stiffness.tangential[k] * dt2)
    }
}

/// Rotates `d` by the smallest rotation taking unit `a` to unit `b`.
fn rotate_between(d: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let v = a.cross(b);
    let c = a.dot(b);
    // Rodrigues with sin θ folded into v: R d = d + v×d + v×(v×d)/(1 + c); bonds never reverse (c > 0).
    d + v.cross(d) + v.cross(&v.cross(d)) / (1.0 + c)
}

/// One bond's incremental update (seed 002 eqs 12–13 and 3): carries d
/// along with the rotation of the centre line to the unit direction `n`,
/// adds the relative midpoint velocity `v_rel` (ẋ_o^j − ẋ_o^i, eq 14) over
/// `dt`, and returns the force on i, f = k_n (d_n − e) n + k_s d_t (the
/// force on j is −f), with `free` = e the bond's free thermal elongation
/// (m, [`free_elongation`]; 0 without expansion). `kn` and `ks` include the
/// bond's weight.
///
/// The free elongation is not accumulated into d: d stays the total
/// relative displacement and e, a function of the current temperatures,
/// is subtracted in the force. Under a uniform ΔT the free expansion
/// x = (1 + α ΔT) x₀ makes d = α ΔT ℓ n exactly as the FE split
/// F_T = (1 + α ΔT) I does, so the force is zero to round-off at any time
/// and from any start (an initial temperature away from the reference, a
/// restart), whereas subtracting increments of e would lose the part of e
/// present before the first increment and sum the round-off of every one.
#[inline]
pub fn advance_bond(
    s: &mut BondState,
    kn: f64,
    ks: f64,
    n: &Vector3<f64>,
    v_rel: &Vector3<f64>,
    dt: f64,
    free: f64,
) -> Vector3<f64> {
    let d_old = rotate_between(&s.d, &s.n, n);
    // seed 002 eqs 12–13: d_{n+1} = d_n + ẋ^ij_{n+1/2} Δt.
    let d = d_old + v_rel * dt;
    s.d = d;
    s.n = *n;
    let dn = d.dot(n);
    // seed 002 eq 3: f = k d, with (f_n, f_s, f_t) = (k_n d_n, k_s d_s, k_t d_t) and k_s = k_t; d_n less the free elongation.
    n * (kn * (dn - free)) + (d - n * dn) * ks
}

/// Free thermal elongation e = α ΔT̄ ℓ (m) of a bond of rest length `rest`
/// whose ends are `dt_i` and `dt_j` (K) above the material's reference
/// temperature: the FE split's F_T = (1 + α ΔT) I along the bond, at the
/// ends' mean ΔT̄ = (ΔT_i + ΔT_j)/2.
#[inline]
pub fn free_elongation(alpha: f64, dt_i: f64, dt_j: f64, rest: f64) -> f64 {
    // Not numbered in the seeds (seed 004 eqs 16, 26 along the bond): e = α (ΔT_i + ΔT_j)/2 ℓ.
    alpha * 0.5 * (dt_i + dt_j) * rest
}

/// Updates the bonds `bonds` (with `state`, one per bond) over the step
/// `dt` and adds their forces and moments to `force` and `moment`.
///
/// `x` are the particle centres at the end of the step, `v` and `w` the
/// translational and angular velocities over the step (central difference:
/// at t + dt/2; the moment arms are taken at mid-step too, x − v Δt/2).
/// Per bond: d is first carried along with the rotation of the
/// centre line, then incremented by the relative velocity of the midpoint
/// (eqs 12–15); the force is f = k_n (d_n − e) n + k_s d_t (eq 3 with
/// k_s = k_t), e the bond's free thermal elongation from `free` (one per
/// bond; None: no expansion).
#[allow(clippy::too_many_arguments)]
pub fn bond_forces(
    bonds: &[LatticeBond],
    state: &mut [BondState],
    stiffness: &BondStiffness,
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    w: &[Vector3<f64>],
    dt: f64,
    free: Option<&[f64]>,
    force: &mut [Vector3<f64>],
    moment: &mut [Vector3<f64>],
) {
    for (k, (b, s)) in bonds.iter().zip(state.iter_mut()).enumerate() {
        let (i, j) = (b.i as usize, b.j as usize);
        // Boundary weight of the lattice (1 inside: eq 4 as written).
        let kn = stiffness.normal[b.kind as usize] * b.weight;
        let ks = stiffness.tangential[b.kind as usize] * b.weight;
        let branch = x[j] - x[i];
        let n = branch.normalize();
        // Moment arms at mid-step (central difference: the velocities are those of t + dt/2).
        let half = (branch - (v[j] - v[i]) * (0.5 * dt)) * 0.5;
        // seed 002 eq 15: velocities of the midpoint o seen from i and j (r^i = +ℓn/2, r^j = −ℓn/2).
        let vo_i = v[i] + w[i].cross(&half);
        let vo_j = v[j] - w[j].cross(&half);
        // seed 002 eq 14: relative velocity ẋ^ij = ẋ_o^j − ẋ_o^i.
        let e = free.map_or(0.0, |e| e[k]);
        let f = advance_bond(s, kn, ks, &n, &(vo_j - vo_i), dt, e);
        force[i] += f;
        force[j] -= f;
        // seed 002 eq 2: moments of the bond force about each centre, r × f (the same for both ends).
        let m = half.cross(&f);
        moment[i] += m;
        moment[j] += m;
    }
}

/// Adds the heat flows (W, into each particle) of the bonds `bonds` with
/// conductances `h` per group (times the bond weights) at particle
/// temperatures `t` to `heat`.
pub fn bond_heat(bonds: &[LatticeBond], h: &[f64; 3], t: &[f64], heat: &mut [f64]) {
    for b in bonds {
        let (i, j) = (b.i as usize, b.j as usize);
        // Flux equivalence (module docs): Q_{j→i} = h (T_j − T_i).
        let q = h[b.kind as usize] * b.weight * (t[j] - t[i]);
        heat[i] += q;
        heat[j] -= q;
    }
}

/// Damped central-difference update of particle velocities and positions
/// (seed 002 eq 2 with the damping force −c m v, and −c I ω for the spin):
/// v ← ((1 − c Δt/2) v + Δt f/m)/(1 + c Δt/2), x ← x + Δt v, likewise ω with
/// the moment and I. Particles with `fixed[p]` keep zero velocity.
#[allow(clippy::too_many_arguments)]
pub fn update_particles(
    mass: f64,
    inertia: f64,
    damping: f64,
    dt: f64,
    fixed: &[bool],
    force: &[Vector3<f64>],
    moment: &[Vector3<f64>],
    x: &mut [Vector3<f64>],
    v: &mut [Vector3<f64>],
    w: &mut [Vector3<f64>],
) {
    let a = 1.0 - 0.5 * damping * dt;
    let b = 1.0 / (1.0 + 0.5 * damping * dt);
    for p in 0..x.len() {
        if fixed[p] {
            v[p] = Vector3::zeros();
            w[p] = Vector3::zeros();
            continue;
        }
        v[p] = (v[p] * a + force[p] * (dt / mass)) * b;
        w[p] = (w[p] * a + moment[p] * (dt / inertia)) * b;
        x[p] += v[p] * dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::lattice::cubic_lattice;
    use nalgebra::Matrix3;

    const E: f64 = 1e9;
    const NU: f64 = 0.23;
    const R: f64 = 0.125e-3;

    fn lattice() -> (crate::mesh::lattice::Lattice, Vec<Vector3<f64>>) {
        let l = cubic_lattice([0.0; 3], [5.0 * 2.0 * R; 3], R, true).unwrap();
        let x = l.centres.iter().map(|c| Vector3::from(*c)).collect();
        (l, x)
    }

    /// Virial stress σ = (1/V) Σ f_j ⊗ (x_j − x_i) over the bonds of the
    /// centre sphere, halved (each bond is shared by two cells).
    fn centre_stress(
        l: &crate::mesh::lattice::Lattice,
        x: &[Vector3<f64>],
        state: &[BondState],
        k: &BondStiffness,
    ) -> Matrix3<f64> {
        let c = l.index(2, 2, 2) as u32;
        let mut s = Matrix3::zeros();
        for (b, st) in l.bonds.iter().zip(state) {
            if b.i != c && b.j != c {
                continue;
            }
            let n = st.n;
            let dn = st.d.dot(&n);
            let f_on_i = n * (k.normal[b.kind as usize] * dn)
                + (st.d - n * dn) * k.tangential[b.kind as usize];
            // Force on j is −f_on_i; tension: j is pulled back toward i.
            let branch = x[b.j as usize] - x[b.i as usize];
            s += f_on_i * branch.transpose() * 0.5;
        }
        s / l.cell_volume()
    }

    /// A lattice at a uniform ΔT above the reference, expanded freely to
    /// (1 + α ΔT) x₀ over many steps, carries no force when the bonds'
    /// free elongation α ΔT ℓ is subtracted; ignoring it, the surface
    /// spheres feel forces of order k_n α ΔT ℓ.
    #[test]
    fn free_thermal_expansion_leaves_the_bonds_unstressed() {
        let (l, x0) = lattice();
        let k = BondStiffness::seed002(E, NU, R).unwrap();
        let (alpha, delta_t, steps, dt) = (1e-5, 200.0, 50, 1e-3);
        let free: Vec<f64> = l
            .bonds
            .iter()
            .map(|b| {
                let rest = (x0[b.j as usize] - x0[b.i as usize]).norm();
                free_elongation(alpha, delta_t, delta_t, rest)
            })
            .collect();
        let w = vec![Vector3::zeros(); x0.len()];
        let run = |free: Option<&[f64]>| {
            let mut x = x0.clone();
            let mut state: Vec<BondState> = l
                .bonds
                .iter()
                .map(|b| BondState::new(&x0[b.i as usize], &x0[b.j as usize]))
                .collect();
            let v: Vec<Vector3<f64>> = x0
                .iter()
                .map(|p| p * (alpha * delta_t / (steps as f64 * dt)))
                .collect();
            let mut f = vec![Vector3::zeros(); x0.len()];
            for _ in 0..steps {
                let mut m = vec![Vector3::zeros(); x0.len()];
                f.iter_mut().for_each(|a| *a = Vector3::zeros());
                x.iter_mut().zip(&v).for_each(|(x, v)| *x += v * dt);
                bond_forces(
                    &l.bonds, &mut state, &k, &x, &v, &w, dt, free, &mut f, &mut m,
                );
            }
            let energy: f64 = state
                .iter()
                .zip(&l.bonds)
                .zip(free.unwrap_or(&vec![0.0; l.bonds.len()]))
                .map(|((s, b), &e)| s.energy(&k, b, e))
                .sum();
            (f.iter().map(|a| a.norm()).fold(0.0, f64::max), energy)
        };
        let scale = k.normal[0] * alpha * delta_t * 2.0 * R;
        let (with, w_with) = run(Some(&free));
        let (without, w_without) = run(None);
        assert!(with < 1e-9 * scale, "{with:e} against {scale:e}");
        assert!(without > 0.1 * scale, "{without:e} against {scale:e}");
        assert!(w_with < 1e-15 * w_without, "{w_with:e} {w_without:e}");
    }

    #[test]
    fn uniform_strain_gives_the_continuum_stress() {
        let (l, x) = lattice();
        let k = BondStiffness::seed002(E, NU, R).unwrap();
        let eps = Matrix3::new(1e-4, 2e-5, -1e-5, 2e-5, -3e-5, 4e-5, -1e-5, 4e-5, 6e-5);
        // One step of length 1 with v = ε X (no spin) takes every bond to d = ε ℓ n.
        let v: Vec<Vector3<f64>> = x.iter().map(|p| eps * p).collect();
        let w = vec![Vector3::zeros(); x.len()];
        let mut state: Vec<BondState> = l
            .bonds
            .iter()
            .map(|b| BondState::new(&x[b.i as usize], &x[b.j as usize]))
            .collect();
        let mut f = vec![Vector3::zeros(); x.len()];
        let mut m = vec![Vector3::zeros(); x.len()];
        bond_forces(
            &l.bonds, &mut state, &k, &x, &v, &w, 1.0, None, &mut f, &mut m,
        );
        let sigma = centre_stress(&l, &x, &state, &k);
        let mu = E / (2.0 * (1.0 + NU));
        let lambda = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU));
        let expect = eps * (2.0 * mu) + Matrix3::identity() * (lambda * eps.trace());
        // Eq 4 is exact for uniform strain (module docs): round-off tolerance.
        assert!(
            (sigma - expect).norm() < 1e-10 * expect.norm(),
            "{sigma} vs {expect}"
        );
        // Interior spheres are in equilibrium and carry no moment.
        let c = l.index(2, 2, 2);
        assert!(f[c].norm() < 1e-10 * expect.norm() * R * R);
        assert!(m[c].norm() < 1e-10 * expect.norm() * R * R * R);
    }

    #[test]
    fn uniform_gradient_gives_the_continuum_flux() {
        let (l, x) = lattice();
        let k = 2.5;
        let h = bond_conductance(k, R);
        let g = Vector3::new(300.0, -120.0, 50.0);
        let t: Vec<f64> = x.iter().map(|p| g.dot(p)).collect();
        let c = l.index(2, 2, 2) as u32;
        let mut q = Vector3::zeros();
        for b in &l.bonds {
            if b.i != c && b.j != c {
                continue;
            }
            let (i, j) = (b.i as usize, b.j as usize);
            // Heat carried from i to j times the branch vector, halved (shared).
            let flow = h[b.kind as usize] * (t[i] - t[j]);
            q += (x[j] - x[i]) * (0.5 * flow);
        }
        q /= l.cell_volume();
        let expect = -g * k;
        assert!(
            (q - expect).norm() < 1e-10 * expect.norm(),
            "{q} vs {expect}"
        );
        // An interior sphere gains no heat in a linear field.
        let mut heat = vec![0.0; x.len()];
        bond_heat(&l.bonds, &h, &t, &mut heat);
        assert!(heat[c as usize].abs() < 1e-10 * k * g.norm() * R);
    }

    #[test]
    fn rigid_rotation_gives_no_bond_force_and_carries_a_stretch_along() {
        let (l, x0) = lattice();
        let k = BondStiffness::seed002(E, NU, R).unwrap();
        let omega = Vector3::new(0.3, -0.5, 0.8) * 1e3;
        let centre = Vector3::repeat(5.0 * R);
        let mut state: Vec<BondState> = l
            .bonds
            .iter()
            .map(|b| BondState::new(&x0[b.i as usize], &x0[b.j as usize]))
            .collect();
        // Pre-stretch bond 0 along its axis.
        let d0 = state[0].n * 1e-6;
        state[0].d = d0;
        let steps = 10_000;
        let dt = 2e-7;
        let w = vec![omega; x0.len()];
        let mut f = vec![Vector3::zeros(); x0.len()];
        let mut m = vec![Vector3::zeros(); x0.len()];
        let rigid = |t: f64| -> Vec<Vector3<f64>> {
            let rot = nalgebra::Rotation3::from_scaled_axis(omega * t);
            x0.iter().map(|p| centre + rot * (p - centre)).collect()
        };
        let mut x = x0.clone();
        for s in 1..=steps {
            let next = rigid(s as f64 * dt);
            // Central-difference velocities of the rigid motion over the step.
            let v: Vec<Vector3<f64>> = next.iter().zip(&x).map(|(a, b)| (a - b) / dt).collect();
            x = next;
            f.iter_mut().for_each(|a| *a = Vector3::zeros());
            m.iter_mut().for_each(|a| *a = Vector3::zeros());
            bond_forces(
                &l.bonds, &mut state, &k, &x, &v, &w, dt, None, &mut f, &mut m,
            );
        }
        // Total rotation |ω| t ≈ 2 rad. Bonds other than 0 stay unstressed.
        // Time-discretisation error O(steps (|ω|Δt)³ ℓ) ≈ 2e-11 m: under 1e-3 of the stretch.
        for (b, s) in state.iter().enumerate().skip(1) {
            assert!(s.d.norm() < 1e-3 * 1e-6, "bond {b}: {}", s.d);
        }
        // Bond 0 keeps its stretch, now along the rotated axis.
        let dn = state[0].d.dot(&state[0].n);
        assert!((dn - 1e-6).abs() < 1e-3 * 1e-6, "{dn}");
        assert!((state[0].d - state[0].n * dn).norm() < 1e-3 * 1e-6);
        // Spheres away from bond 0 feel no force.
        let (a, b) = (l.bonds[0].i as usize, l.bonds[0].j as usize);
        for (p, fp) in f.iter().enumerate() {
            if p != a && p != b {
                assert!(
                    fp.norm() < 1e-3 * k.normal[0] * 1e-6 * 26.0,
                    "sphere {p}: {fp}"
                );
            }
        }
    }

    #[test]
    fn weighted_lattice_stores_the_continuum_energy_of_the_whole_box() {
        // 8×6×4 spheres. The weights make every cell exact except along the 12 box edges,
        // where a sphere has no neighbour at all along one diagonal pair (lattice docs).
        let l = cubic_lattice([0.0; 3], [16.0 * R, 12.0 * R, 8.0 * R], R, true).unwrap();
        let x: Vec<Vector3<f64>> = l.centres.iter().map(|c| Vector3::from(*c)).collect();
        let k = BondStiffness::seed002(E, NU, R).unwrap();
        let eps = Matrix3::new(1e-4, 2e-5, -1e-5, 2e-5, -3e-5, 4e-5, -1e-5, 4e-5, 6e-5);
        let v: Vec<Vector3<f64>> = x.iter().map(|p| eps * p).collect();
        let w = vec![Vector3::zeros(); x.len()];
        let mut state: Vec<BondState> = l
            .bonds
            .iter()
            .map(|b| BondState::new(&x[b.i as usize], &x[b.j as usize]))
            .collect();
        let mut f = vec![Vector3::zeros(); x.len()];
        let mut m = vec![Vector3::zeros(); x.len()];
        bond_forces(
            &l.bonds, &mut state, &k, &x, &v, &w, 1.0, None, &mut f, &mut m,
        );
        let energy: f64 = state
            .iter()
            .zip(&l.bonds)
            .map(|(s, b)| s.energy(&k, b, 0.0))
            .sum();
        let mu = E / (2.0 * (1.0 + NU));
        let lambda = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU));
        let density = mu * (eps * eps).trace() + 0.5 * lambda * eps.trace().powi(2);
        let expect = density * l.cell_volume() * x.len() as f64;
        let unweighted: f64 = state
            .iter()
            .zip(&l.bonds)
            .map(|(s, b)| s.energy(&k, &LatticeBond { weight: 1.0, ..*b }, 0.0))
            .sum();
        // Measured: weighted 0.954, unweighted 0.710 of the continuum energy; the rest of
        // the weighted deficit is the edge spheres (56 of 192 here, a few % in a beam).
        assert!(
            (energy - expect).abs() < 0.05 * expect,
            "{energy} vs {expect}"
        );
        assert!(unweighted < 0.75 * expect, "{unweighted} vs {expect}");
    }

    #[test]
    fn eq4_refuses_poisson_beyond_a_quarter() {
        assert!(BondStiffness::seed002(E, 0.3, R).is_err());
        let k = BondStiffness::seed002(E, 0.25, R).unwrap();
        assert_eq!(k.tangential[0], 0.0);
        assert_eq!(k.normal[2], 0.0);
    }

    #[test]
    fn damped_update_moves_free_particles_only() {
        let mut x = vec![Vector3::zeros(); 2];
        let mut v = vec![Vector3::zeros(); 2];
        let mut w = vec![Vector3::zeros(); 2];
        let f = vec![Vector3::x(); 2];
        let m = vec![Vector3::z(); 2];
        update_particles(
            2.0,
            0.5,
            0.0,
            0.1,
            &[false, true],
            &f,
            &m,
            &mut x,
            &mut v,
            &mut w,
        );
        assert!((v[0] - Vector3::x() * 0.05).norm() < 1e-15);
        assert!((w[0] - Vector3::z() * 0.2).norm() < 1e-15);
        assert!((x[0] - Vector3::x() * 0.005).norm() < 1e-15);
        assert_eq!(x[1], Vector3::zeros());
        // Damping alone decays the velocity by (1 − cΔt/2)/(1 + cΔt/2).
        let zero = vec![Vector3::zeros(); 2];
        update_particles(
            2.0,
            0.5,
            4.0,
            0.1,
            &[false, true],
            &zero,
            &zero,
            &mut x,
            &mut v,
            &mut w,
        );
        assert!((v[0][0] - 0.05 * 0.8 / 1.2).abs() < 1e-15);
    }
}
