//! Finite-strain constant-strain Tet4 kernel: kinematics, thermal split,
//! Cauchy stress, strain energy and nodal internal forces. Pure functions
//! over coordinates and material constants, free of MPI and PETSc.
//!
//! Seed 004 equations implemented here:
//! - eqs 1–6: deformation gradient F = x_cn ∂N/∂X and J = det F. For a
//!   Tet4 F is constant: F = [x1−x0, x2−x0, x3−x0] [X1−X0, X2−X0, X3−X0]⁻¹.
//! - eq 7: left Cauchy–Green tensor B = F Fᵀ.
//! - eqs 11–15: Ḟ = v_cn ∂N/∂X, L = Ḟ F⁻¹, D = (L + Lᵀ)/2.
//! - eqs 16–18, 25–30: thermal split F = F_T F_e with F_T = Υ I,
//!   Υ = 1 + α ΔT, so F_e = F/Υ, J_e = J/Υ³, B_e = B/Υ², and
//!   L = L_T + L_e with L_T = (α Ṫ/Υ) I, hence D_e = D − (α Ṫ/Υ) I.
//! - eqs 34–35: Cauchy stress σ = μ/J_e (B_e − I) + λ/J_e ln(J_e) I + 2 η D_e.
//!
//! Decisions on the seed text (garbled or ambiguous in the extraction):
//! - Eq 34 is written for the total F; with the split of eq 16 only the
//!   elastic part is stressed, so the kernel evaluates eq 34 on F_e (this is
//!   what makes a freely expanding body stress free, sec 3.2).
//! - Eq 35 uses D; this kernel uses the elastic rate D_e = D − D_T (eq 33),
//!   so uniform free heating produces no viscous stress either. When the
//!   temperature rate is not supplied (Ṫ = 0), D_e = D, i.e. exactly eq 35.
//! - Eq 38 reads "λ/(1+αΔT)³ ln(1+αΔT)³": the logarithm is of (1+αΔT)³ (the
//!   only reading giving the quoted 3.332 MPa). Eq 38 evaluates eq 34 with
//!   F = F_T, i.e. the stress the thermal deformation would carry if it were
//!   elastic (tension). An element held fixed has F = I, F_e = F_T⁻¹ and is
//!   in compression of the same magnitude to first order in αΔT
//!   (−3.334 MPa vs 3.332 MPa from eq 38 for Table 1, 0.05 % apart).
//!
//! The explicit loop ([`internal_forces`](super::explicit::internal_forces))
//! evaluates the same equations through `tet4_forces`, a form of
//! [`element_response`] without F⁻¹, the full velocity gradient or per-element
//! `Result`s (see its docs); a unit test holds the two to round-off.
//!
//! Sign conventions: tension positive; nodal forces are the internal forces
//! acting on the nodes (they enter M a = f_int + f_ext), f_i = −v σ ∇N_i,
//! which equals −∂W/∂x_i with W the stored energy ([`ElementResponse::strain_energy`]).
//! The stored energy of the neo-Hookean part is W = J_T V0 ψ(F_e) with
//! ψ = μ/2 (tr B_e − 3) − μ ln J_e + λ/2 (ln J_e)²: ψ is per unit volume of
//! the stress-free, thermally expanded configuration (volume J_T V0).

use nalgebra::{Matrix3, Vector3};

use super::{ElasticMaterial, MechanicsError};
use crate::mesh::DEGENERATE_REL_TOL;

/// Edge matrix [x1−x0, x2−x0, x3−x0] (columns).
fn edge_matrix(x: &[Vector3<f64>; 4]) -> Matrix3<f64> {
    Matrix3::from_columns(&[x[1] - x[0], x[2] - x[0], x[3] - x[0]])
}

/// Converts array coordinates into nalgebra vectors.
pub fn to_vectors(x: &[[f64; 3]; 4]) -> [Vector3<f64>; 4] {
    x.map(Vector3::from)
}

/// Reference data of one Tet4, computed once from the undeformed
/// coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tet4Reference {
    /// Inverse of the reference edge matrix [X1−X0, X2−X0, X3−X0]; its rows
    /// are the reference gradients ∂N_i/∂X of nodes 1, 2, 3.
    pub inv_dx: Matrix3<f64>,
    /// Reference volume V0 (m³), positive.
    pub volume0: f64,
}

impl Tet4Reference {
    /// Builds the reference data. Errors if the element is inverted
    /// (negative signed volume) or degenerate (|V| <= 1e-12 (longest edge)³,
    /// the mesh module's tolerance, or non-finite coordinates).
    pub fn new(x0: &[Vector3<f64>; 4]) -> Result<Self, MechanicsError> {
        let dx = edge_matrix(x0);
        let volume0 = dx.determinant() / 6.0;
        let mut longest: f64 = 0.0;
        for i in 0..4 {
            for j in (i + 1)..4 {
                longest = longest.max((x0[j] - x0[i]).norm());
            }
        }
        let degenerate = MechanicsError::DegenerateReference {
            elem: None,
            volume: volume0,
            longest_edge: longest,
        };
        if !(volume0.is_finite() && volume0.abs() > DEGENERATE_REL_TOL * longest.powi(3)) {
            return Err(degenerate);
        }
        if volume0 < 0.0 {
            return Err(MechanicsError::InvertedReference {
                elem: None,
                volume: volume0,
            });
        }
        let inv_dx = dx.try_inverse().ok_or(degenerate)?;
        Ok(Self { inv_dx, volume0 })
    }

    /// [`Tet4Reference::new`] from array coordinates.
    pub fn from_coords(x0: &[[f64; 3]; 4]) -> Result<Self, MechanicsError> {
        Self::new(&to_vectors(x0))
    }

    /// Reference shape-function gradients ∂N_i/∂X, i = 0..4 (they sum to zero).
    pub fn reference_gradients(&self) -> [Vector3<f64>; 4] {
        let g1: Vector3<f64> = self.inv_dx.row(0).transpose();
        let g2: Vector3<f64> = self.inv_dx.row(1).transpose();
        let g3: Vector3<f64> = self.inv_dx.row(2).transpose();
        [-(g1 + g2 + g3), g1, g2, g3]
    }

    /// Deformation gradient of the current positions `x`.
    pub fn deformation_gradient(&self, x: &[Vector3<f64>; 4]) -> Matrix3<f64> {
        // Seed 004 eq 5: F = x_cn ∂N/∂X, i.e. (current edges)·(reference edges)⁻¹ for a Tet4.
        edge_matrix(x) * self.inv_dx
    }

    /// Full kinematics (F, J, B, L, D) of the current positions `x` and
    /// nodal velocities `v`. Errors if J <= 0 (element turned inside out).
    pub fn kinematics(
        &self,
        x: &[Vector3<f64>; 4],
        v: &[Vector3<f64>; 4],
    ) -> Result<Kinematics, MechanicsError> {
        let f = self.deformation_gradient(x);
        // Seed 004 eq 6: J = det F.
        let j = f.determinant();
        let f_inv = invert_deformation(&f, j)?;
        // Seed 004 eq 7: B = F Fᵀ.
        let b = f * f.transpose();
        // Seed 004 eq 11: Ḟ = ∂v/∂X = v_cn ∂N/∂X.
        let f_dot = edge_matrix(v) * self.inv_dx;
        // Seed 004 eq 14: L = Ḟ F⁻¹.
        let l = f_dot * f_inv;
        // Seed 004 eq 15: D = (L + Lᵀ)/2.
        let d = (l + l.transpose()) * 0.5;
        Ok(Kinematics {
            f,
            f_inv,
            j,
            b,
            f_dot,
            l,
            d,
        })
    }
}

/// F⁻¹ = adj(F)/J, or an error if J = det F is not positive and finite.
#[inline]
fn invert_deformation(f: &Matrix3<f64>, j: f64) -> Result<Matrix3<f64>, MechanicsError> {
    if !(j > 0.0 && j.is_finite()) {
        return Err(MechanicsError::Inverted {
            elem: None,
            what: "J = det F",
            value: j,
        });
    }
    let r = 1.0 / j;
    let m = |a: usize, b: usize| f[(a, b)];
    Ok(Matrix3::new(
        (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) * r,
        (m(0, 2) * m(2, 1) - m(0, 1) * m(2, 2)) * r,
        (m(0, 1) * m(1, 2) - m(0, 2) * m(1, 1)) * r,
        (m(1, 2) * m(2, 0) - m(1, 0) * m(2, 2)) * r,
        (m(0, 0) * m(2, 2) - m(0, 2) * m(2, 0)) * r,
        (m(0, 2) * m(1, 0) - m(0, 0) * m(1, 2)) * r,
        (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0)) * r,
        (m(0, 1) * m(2, 0) - m(0, 0) * m(2, 1)) * r,
        (m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0)) * r,
    ))
}

/// Kinematic tensors of a constant-strain Tet4 (seed 004 eqs 5–15).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    /// Deformation gradient F.
    pub f: Matrix3<f64>,
    /// F⁻¹.
    pub f_inv: Matrix3<f64>,
    /// J = det F (current volume / reference volume).
    pub j: f64,
    /// Left Cauchy–Green tensor B = F Fᵀ.
    pub b: Matrix3<f64>,
    /// Ḟ.
    pub f_dot: Matrix3<f64>,
    /// Velocity gradient L = Ḟ F⁻¹.
    pub l: Matrix3<f64>,
    /// Rate of deformation D = (L + Lᵀ)/2.
    pub d: Matrix3<f64>,
}

/// Thermal state of one element: ΔT = T − T0 (element temperature minus
/// the reference temperature at which the mesh is stress free) and its
/// rate Ṫ (K/s, 0 if unknown).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ThermalState {
    /// Temperature change ΔT (K).
    pub delta_t: f64,
    /// Temperature rate Ṫ (K/s); only the viscous stress uses it.
    pub rate: f64,
}

impl ThermalState {
    /// A temperature change with zero rate.
    pub fn steady(delta_t: f64) -> Self {
        Self { delta_t, rate: 0.0 }
    }
}

/// Elastic part of the kinematics after the thermal split (seed 004 eqs 16–33).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticKinematics {
    /// Thermal stretch Υ = 1 + α ΔT (F_T = Υ I).
    pub stretch: f64,
    /// F_e = F F_T⁻¹ = F/Υ.
    pub f_e: Matrix3<f64>,
    /// J_e = det F_e = J/Υ³.
    pub j_e: f64,
    /// ln J_e, computed as ln_1p(J_e − 1) from the displacement gradient.
    pub ln_j_e: f64,
    /// B_e = F_e F_eᵀ = B/Υ².
    pub b_e: Matrix3<f64>,
    /// B_e − I = H + Hᵀ + H Hᵀ with H = F_e − I, formed without cancelling
    /// against I (the stored energy of small strains ε stays accurate to
    /// round-off × ε instead of round-off).
    pub b_e_minus_i: Matrix3<f64>,
    /// Elastic rate of deformation D_e = D − (α Ṫ/Υ) I.
    pub d_e: Matrix3<f64>,
}

/// Splits the kinematics `k` into thermal and elastic parts for the
/// expansion coefficient `alpha` and the element's thermal state. Errors if
/// Υ = 1 + α ΔT is not positive.
pub fn thermal_split(
    k: &Kinematics,
    alpha: f64,
    thermal: ThermalState,
) -> Result<ElasticKinematics, MechanicsError> {
    // Seed 004 eq 25: Υ = 1 + α ΔT.
    let stretch = 1.0 + alpha * thermal.delta_t;
    if !(stretch > 0.0 && stretch.is_finite()) {
        return Err(MechanicsError::Inverted {
            elem: None,
            what: "1 + alpha dT",
            value: stretch,
        });
    }
    // Seed 004 eqs 16, 26: F = F_T F_e with F_T = Υ I ⇒ F_e = F/Υ.
    let inv_stretch = 1.0 / stretch;
    let f_e = k.f * inv_stretch;
    let h = f_e - Matrix3::identity();
    // Seed 004 eqs 27–28: J = J_T J_e with J_T = Υ³; J_e − 1 = det(I + H) − 1 = I1 + I2 + I3 of H.
    let tr = h.trace();
    let j_e_minus_1 = tr + 0.5 * (tr * tr - (h * h).trace()) + h.determinant();
    let j_e = 1.0 + j_e_minus_1;
    let ln_j_e = j_e_minus_1.ln_1p();
    // Seed 004 eqs 31–32: B = B_T B_e with B_T = Υ² I ⇒ B_e = F_e F_eᵀ = I + H + Hᵀ + H Hᵀ.
    let b_e = k.b * (inv_stretch * inv_stretch);
    let b_e_minus_i = h + h.transpose() + h * h.transpose();
    // Seed 004 eqs 18, 25: L_T = Υ̇/Υ I = α Ṫ/Υ I (symmetric, so D_T = L_T).
    let d_t = alpha * thermal.rate * inv_stretch;
    // Seed 004 eqs 30, 33: D = D_T + D_e ⇒ D_e = D − D_T.
    let d_e = k.d - Matrix3::identity() * d_t;
    Ok(ElasticKinematics {
        stretch,
        f_e,
        j_e,
        ln_j_e,
        b_e,
        b_e_minus_i,
        d_e,
    })
}

/// Cauchy stress (Pa, tension positive) of the compressible neo-Hookean
/// law on the elastic part plus the viscous stress.
pub fn cauchy_stress(mu: f64, lambda: f64, eta: f64, e: &ElasticKinematics) -> Matrix3<f64> {
    let i = Matrix3::identity();
    // Seed 004 eq 34 on the elastic part: σ = μ/J_e (B_e − I) + λ/J_e ln(J_e) I.
    let elastic = (e.b_e_minus_i * mu + i * (lambda * e.ln_j_e)) * (1.0 / e.j_e);
    // Seed 004 eq 35: C_D = 2 η D (with D_e, see the module header).
    elastic + e.d_e * (2.0 * eta)
}

/// Neo-Hookean strain energy density ψ (J/m³ of the thermally expanded,
/// stress-free configuration) of the elastic part; its Kirchhoff stress
/// J_e σ is the elastic part of seed 004 eq 34.
pub fn strain_energy_density(mu: f64, lambda: f64, e: &ElasticKinematics) -> f64 {
    let ln_j = e.ln_j_e;
    // Not numbered in the seeds: ψ = μ/2 (tr B_e − 3) − μ ln J_e + λ/2 (ln J_e)², the potential of eq 34.
    0.5 * mu * e.b_e_minus_i.trace() - mu * ln_j + 0.5 * lambda * ln_j * ln_j
}

/// Everything an element contributes to one explicit step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementResponse {
    /// Cauchy stress σ (Pa, tension positive), constant over the element.
    pub stress: Matrix3<f64>,
    /// J = det F = current volume / reference volume.
    pub j: f64,
    /// J_e = J/(1 + α ΔT)³, the elastic volume ratio.
    pub j_elastic: f64,
    /// Current volume v = J V0 (m³).
    pub volume: f64,
    /// Internal nodal forces f_i = −v σ ∇N_i (N); they sum to zero and
    /// have no net moment.
    pub forces: [Vector3<f64>; 4],
    /// Stored elastic energy W = J_T V0 ψ (J); f_i = −∂W/∂x_i when η = 0.
    pub strain_energy: f64,
}

/// Stress, forces and energy of one Tet4 at positions `x`, velocities `v`
/// and thermal state `thermal`.
///
/// Errors if the element is inverted (J <= 0) or 1 + α ΔT <= 0; the error
/// carries `elem: None` (see [`MechanicsError::at_element`]).
pub fn element_response(
    reference: &Tet4Reference,
    material: &ElasticMaterial,
    x: &[Vector3<f64>; 4],
    v: &[Vector3<f64>; 4],
    thermal: ThermalState,
) -> Result<ElementResponse, MechanicsError> {
    let k = reference.kinematics(x, v)?;
    let e = thermal_split(&k, material.expansion, thermal)?;
    let (mu, lambda) = material.lame();
    let stress = cauchy_stress(mu, lambda, material.viscosity, &e);
    let volume = k.j * reference.volume0;
    // Current gradients ∂N_i/∂x = F⁻ᵀ ∂N_i/∂X; columns of (inv_dx F⁻¹)ᵀ are those of nodes 1..3.
    let grad = (reference.inv_dx * k.f_inv).transpose();
    // Not numbered in the seeds (virtual work of the momentum equation, sec 2.5): f_i = −∫ σ ∇N_i dv = −v σ ∇N_i.
    let h = stress * grad * (-volume);
    let f1: Vector3<f64> = h.column(0).into();
    let f2: Vector3<f64> = h.column(1).into();
    let f3: Vector3<f64> = h.column(2).into();
    let f0 = -(f1 + f2 + f3);
    // Seed 004 eq 37: J_T = Υ³ scales V0 to the stress-free volume on which ψ is measured.
    let strain_energy =
        e.stretch.powi(3) * reference.volume0 * strain_energy_density(mu, lambda, &e);
    Ok(ElementResponse {
        stress,
        j: k.j,
        j_elastic: e.j_e,
        volume,
        forces: [f0, f1, f2, f3],
        strain_energy,
    })
}

/// Material constants of the hot-path kernel [`tet4_forces`], computed
/// once per material rather than once per element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct KernelMaterial {
    /// Lamé constant μ (Pa).
    pub mu: f64,
    /// Lamé constant λ (Pa).
    pub lambda: f64,
    /// 2 η (Pa·s); 0 skips the rate of deformation entirely.
    pub two_eta: f64,
    /// Linear expansion coefficient α (1/K).
    pub alpha: f64,
}

impl KernelMaterial {
    /// The kernel constants of `m`.
    pub(crate) fn new(m: &ElasticMaterial) -> Self {
        let (mu, lambda) = m.lame();
        Self {
            mu,
            lambda,
            two_eta: 2.0 * m.viscosity,
            alpha: m.expansion,
        }
    }
}

/// What the explicit loop needs of one element: [`ElementResponse`]
/// without the volume ratios.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tet4Forces {
    /// Cauchy stress σ (Pa, tension positive).
    pub stress: Matrix3<f64>,
    /// Internal nodal forces f_i = −v σ ∇N_i (N).
    pub forces: [Vector3<f64>; 4],
    /// Stored elastic energy W = J_T V0 ψ (J).
    pub strain_energy: f64,
}

impl From<ElementResponse> for Tet4Forces {
    fn from(r: ElementResponse) -> Self {
        Self {
            stress: r.stress,
            forces: r.forces,
            strain_energy: r.strain_energy,
        }
    }
}

/// Hot path of [`element_response`] for the explicit loop, on the element
/// with nodes `nodes` of the node arrays `x` (positions) and `v`
/// (velocities): the same stress, forces and energy (equal to round-off),
/// or `None` where [`element_response`] may fail, i.e. unless det E (the
/// sign of J = det F), 1 + α ΔT and J_e are all positive and finite. On
/// `None` the caller asks [`element_response`], which gives the error (or,
/// should round-off decide the other way, the response). Panics if a node
/// index is out of range of `x` or `v`.
///
/// It differs in how, not what, it computes (with E = [x1−x0, x2−x0, x3−x0]
/// the current edge matrix and c_k the columns of its cofactor matrix, the
/// area vectors c_0 = e_1 × e_2, c_1 = e_2 × e_0, c_2 = e_0 × e_1):
/// - current gradients ∇N_k = c_{k−1}/det E (k = 1..3) and volume
///   v = det E/6, so f_k = −v σ ∇N_k = −σ c_{k−1}/6 needs neither F⁻¹ nor
///   a division (this uses V0 = 1/(6 det inv_dx), as [`Tet4Reference::new`]
///   builds it);
/// - L = Ḟ F⁻¹ = W E⁻¹ with W = [v1−v0, v2−v0, v3−v0], of which only the
///   symmetric part D is formed, and only when η ≠ 0 (with η = 0 the
///   velocities are not read);
/// - B_e − I and σ are formed as symmetric 6-component tensors.
#[inline(always)]
pub(crate) fn tet4_forces(
    reference: &Tet4Reference,
    mat: &KernelMaterial,
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    nodes: [usize; 4],
    thermal: ThermalState,
) -> Option<Tet4Forces> {
    let [n0, n1, n2, n3] = nodes;
    let x0 = x[n0];
    let (e0, e1, e2) = (x[n1] - x0, x[n2] - x0, x[n3] - x0);
    let m = &reference.inv_dx;
    // Seed 004 eq 5: F = x_cn ∂N/∂X = E inv_dx, F_ij = Σ_k (e_k)_i (inv_dx)_kj.
    let fij = |i: usize, j: usize| e0[i] * m[(0, j)] + e1[i] * m[(1, j)] + e2[i] * m[(2, j)];
    let f = [
        [fij(0, 0), fij(0, 1), fij(0, 2)],
        [fij(1, 0), fij(1, 1), fij(1, 2)],
        [fij(2, 0), fij(2, 1), fij(2, 2)],
    ];
    // Area vectors: columns of cof(E), rows of E⁻¹ times det E.
    let (c0, c1, c2) = (e1.cross(&e2), e2.cross(&e0), e0.cross(&e1));
    // Seed 004 eq 6 as a sign test: J = det F = det E det(inv_dx) = det E/(6 V0) has the sign of det E = 6 v.
    let det_e = e0.dot(&c0);
    // Seed 004 eq 25: Υ = 1 + α ΔT.
    let stretch = 1.0 + mat.alpha * thermal.delta_t;
    if !(det_e > 0.0 && det_e.is_finite() && stretch > 0.0 && stretch.is_finite()) {
        return None;
    }
    // Seed 004 eqs 16, 26: F_e = F/Υ.
    let inv_stretch = 1.0 / stretch;
    let Some(el) = neo_hookean_sym(&f, inv_stretch, mat.mu, mat.lambda) else {
        // Round-off has the volume change disagree with det E (or F overflowed): leave it to element_response.
        return None;
    };
    let [mut s00, mut s11, mut s22, mut s01, mut s02, mut s12] = el.sigma;
    if mat.two_eta != 0.0 {
        let v0 = v[n0];
        let (w0, w1, w2) = (v[n1] - v0, v[n2] - v0, v[n3] - v0);
        // Seed 004 eqs 11, 14: L = Ḟ F⁻¹ = W E⁻¹ = Σ_k w_k ⊗ c_k / det E.
        let l = |a: usize, b: usize| w0[a] * c0[b] + w1[a] * c1[b] + w2[a] * c2[b];
        // Seed 004 eq 15: D = (L + Lᵀ)/2, times 2η.
        let k = mat.two_eta * 0.5 / det_e;
        // Seed 004 eqs 18, 25: D_T = L_T = α Ṫ/Υ I.
        let d_t = mat.alpha * thermal.rate * inv_stretch;
        // Seed 004 eqs 30, 33, 35: C_D = 2 η D_e with D_e = D − D_T (see the module header).
        s00 += (2.0 * l(0, 0) * k) - mat.two_eta * d_t;
        s11 += (2.0 * l(1, 1) * k) - mat.two_eta * d_t;
        s22 += (2.0 * l(2, 2) * k) - mat.two_eta * d_t;
        s01 += (l(0, 1) + l(1, 0)) * k;
        s02 += (l(0, 2) + l(2, 0)) * k;
        s12 += (l(1, 2) + l(2, 1)) * k;
    }
    let stress = Matrix3::new(s00, s01, s02, s01, s11, s12, s02, s12, s22);
    // Not numbered in the seeds (virtual work, sec 2.5): f_k = −v σ ∇N_k = −σ c_{k−1}/6 (v = det E/6, ∇N_k = c_{k−1}/det E).
    let sixth = -1.0 / 6.0;
    let (q00, q11, q22, q01, q02, q12) = (
        s00 * sixth,
        s11 * sixth,
        s22 * sixth,
        s01 * sixth,
        s02 * sixth,
        s12 * sixth,
    );
    let force = |c: Vector3<f64>| {
        Vector3::new(
            q00 * c[0] + q01 * c[1] + q02 * c[2],
            q01 * c[0] + q11 * c[1] + q12 * c[2],
            q02 * c[0] + q12 * c[1] + q22 * c[2],
        )
    };
    let (f1, f2, f3) = (force(c0), force(c1), force(c2));
    let f0 = -(f1 + f2 + f3);
    // Seed 004 eq 37: W = J_T V0 ψ with J_T = Υ³.
    let strain_energy = stretch * stretch * stretch * reference.volume0 * el.psi;
    Some(Tet4Forces {
        stress,
        forces: [f0, f1, f2, f3],
        strain_energy,
    })
}

/// The elastic part of the hot-path law, shared by the Tet4 ([`tet4_forces`])
/// and Hex8 (`hex8_element`) kernels: Cauchy stress and energy density of
/// the neo-Hookean law on F_e = F/Υ as symmetric components.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ElasticSym {
    /// Elastic Cauchy stress (xx, yy, zz, xy, xz, yz) (Pa).
    pub sigma: [f64; 6],
    /// Energy density ψ (J/m³ of the stress-free configuration).
    pub psi: f64,
}

/// [`ElasticSym`] of the deformation gradient `f` with 1/Υ = `inv_stretch`
/// and Lamé constants `mu`, `lambda`; `None` unless J_e is positive and
/// finite (the caller then asks the general path, which gives the error).
#[inline(always)]
pub(crate) fn neo_hookean_sym(
    f: &[[f64; 3]; 3],
    inv_stretch: f64,
    mu: f64,
    lambda: f64,
) -> Option<ElasticSym> {
    // Seed 004 eqs 16, 26: H = F_e − I.
    let hij = |i: usize, j: usize| f[i][j] * inv_stretch - if i == j { 1.0 } else { 0.0 };
    let hh = [
        [hij(0, 0), hij(0, 1), hij(0, 2)],
        [hij(1, 0), hij(1, 1), hij(1, 2)],
        [hij(2, 0), hij(2, 1), hij(2, 2)],
    ];
    // Seed 004 eqs 27–28: J_e − 1 = det(I + H) − 1 = I1 + I2 + I3 of H.
    let tr = hh[0][0] + hh[1][1] + hh[2][2];
    // (Summed in the order of element_response: with a rotation, H is O(1) and J_e − 1 is a small
    // difference of O(1) terms, so a different order would change it by round-off × 1/(J_e − 1).)
    let hh_ii = |i: usize| hh[i][0] * hh[0][i] + hh[i][1] * hh[1][i] + hh[i][2] * hh[2][i];
    let tr_hh = hh_ii(0) + hh_ii(1) + hh_ii(2);
    let det_h = hh[0][0] * (hh[1][1] * hh[2][2] - hh[2][1] * hh[1][2])
        - hh[0][1] * (hh[1][0] * hh[2][2] - hh[2][0] * hh[1][2])
        + hh[0][2] * (hh[1][0] * hh[2][1] - hh[2][0] * hh[1][1]);
    let j_e_minus_1 = tr + 0.5 * (tr * tr - tr_hh) + det_h;
    let j_e = 1.0 + j_e_minus_1;
    if !(j_e > 0.0 && j_e.is_finite()) {
        return None;
    }
    let ln_j_e = ln_1p_small(j_e_minus_1);
    let inv_j_e = 1.0 / j_e;
    // Seed 004 eqs 31–32: B_e − I = H + Hᵀ + H Hᵀ (symmetric).
    let bm = |a: usize, b: usize| {
        hh[a][b] + hh[b][a] + (hh[a][0] * hh[b][0] + hh[a][1] * hh[b][1] + hh[a][2] * hh[b][2])
    };
    let (b00, b11, b22, b01, b02, b12) =
        (bm(0, 0), bm(1, 1), bm(2, 2), bm(0, 1), bm(0, 2), bm(1, 2));
    // Seed 004 eq 34 on the elastic part: σ = μ/J_e (B_e − I) + λ/J_e ln(J_e) I.
    let pressure = lambda * ln_j_e;
    let r = inv_j_e;
    let sigma = [
        (b00 * mu + pressure) * r,
        (b11 * mu + pressure) * r,
        (b22 * mu + pressure) * r,
        b01 * mu * r,
        b02 * mu * r,
        b12 * mu * r,
    ];
    // Not numbered in the seeds: ψ = μ/2 (tr B_e − 3) − μ ln J_e + λ/2 (ln J_e)², the potential of eq 34.
    let psi = 0.5 * mu * (b00 + b11 + b22) - mu * ln_j_e + 0.5 * lambda * ln_j_e * ln_j_e;
    Some(ElasticSym { sigma, psi })
}

/// ln(1 + x), inline for |x| <= 1/32 (volume changes of up to ~3 %, the
/// usual case), [`f64::ln_1p`] otherwise (a library call, which also makes
/// the compiler spill every live register around it).
///
/// For |x| <= 1/32 the Taylor series x − x²/2 + … − x¹⁰/10 + x¹¹/11 leaves
/// out terms of relative size below |x|¹¹/12 < 3e-18; it is evaluated as
/// x + x² P(x), P by Estrin's scheme (short dependency chains), so its
/// round-off enters scaled by |x|/2 and the result is within 1 ulp.
#[inline(always)]
fn ln_1p_small(x: f64) -> f64 {
    if x.abs() <= 1.0 / 32.0 {
        // Not numbered in the seeds: ln(1 + x) = Σ_{k>=1} (−1)^(k+1) x^k/k.
        let x2 = x * x;
        let x4 = x2 * x2;
        let x8 = x4 * x4;
        let a0 = (1.0 / 3.0) * x - 0.5;
        let a1 = 0.2 * x - 0.25;
        let a2 = (1.0 / 7.0) * x - 1.0 / 6.0;
        let a3 = (1.0 / 9.0) * x - 0.125;
        let a4 = (1.0 / 11.0) * x - 0.1;
        let p = (a0 + a1 * x2) + (a2 + a3 * x2) * x4 + a4 * x8;
        x + x2 * p
    } else {
        ln_1p_call(x)
    }
}

/// [`f64::ln_1p`] out of line, so its call does not clutter the hot path.
#[cold]
#[inline(never)]
fn ln_1p_call(x: f64) -> f64 {
    x.ln_1p()
}

/// Smallest height of a tetrahedron, 3 V / (largest face area) (m); 0 for
/// a degenerate one.
pub fn min_height(x: &[Vector3<f64>; 4]) -> f64 {
    let volume = edge_matrix(x).determinant().abs() / 6.0;
    let mut max_area: f64 = 0.0;
    for (a, b, c) in [(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)] {
        max_area = max_area.max(0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])).norm());
    }
    if max_area > 0.0 {
        3.0 * volume / max_area
    } else {
        0.0
    }
}

/// Characteristic length of a Tet4 for the explicit time step (m):
/// L = (Σ_i |∇N_i|²)^(−1/2) = (Σ_i h_i⁻²)^(−1/2), with h_i the height of
/// node i over the opposite face; h_min/2 <= L <= h_min. 0 for a
/// degenerate tet.
///
/// Why not h_min itself: with the lumped mass ρV/4 the Rayleigh quotient of
/// the element stiffness is bounded by ω² <= 4 (λ+2μ)/ρ Σ_i |∇N_i|² (use
/// (tr H)² and |sym H|² <= |U|² Σ|∇N_i|² for H = Σ u_i ⊗ ∇N_i), so
/// Δt = 2/ω_max >= L/c is a rigorous small-strain bound (for λ >= 0, i.e.
/// ν >= 0), whereas h_min/c
/// overestimates the true limit by up to 2× (the limit is 0.51–0.86 of
/// h_min/c on random tets; 1/√2 of it for a regular tet at ν = 0.2).
pub fn characteristic_length(x: &[Vector3<f64>; 4]) -> f64 {
    match edge_matrix(x).try_inverse() {
        Some(inv) => {
            // Rows of inv are ∇N_1..∇N_3; ∇N_0 = −(their sum).
            let g0 = inv.row(0) + inv.row(1) + inv.row(2);
            // Not numbered in the seeds: L = (Σ_i |∇N_i|²)^(−1/2), the Rayleigh bound ω_max <= 2c/L.
            let sum = inv.norm_squared() + g0.norm_squared();
            if sum.is_finite() && sum > 0.0 {
                1.0 / sum.sqrt()
            } else {
                0.0
            }
        }
        None => 0.0,
    }
}

/// Stable explicit time step estimate of one element (s):
/// Δt = (L/c) (sqrt(1 + ξ²) − ξ), with L the [`characteristic_length`],
/// c the P-wave speed and ξ = 2 η c / ((λ + 2μ) L) the damping ratio the
/// viscous stress gives the highest mode (ω_max <= 2c/L). With η = 0 this
/// is L/c.
pub fn element_critical_dt(x: &[Vector3<f64>; 4], material: &ElasticMaterial) -> f64 {
    let len = characteristic_length(x);
    let c = material.p_wave_speed();
    // Not numbered in the seeds: central-difference limit Δt = (2/ω_max)(√(1+ξ²) − ξ), ω_max <= 2c/L.
    let xi = 2.0 * material.viscosity * c / (material.p_wave_modulus() * len);
    len / c * ((1.0 + xi * xi).sqrt() - xi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::explicit::MechElement;
    use crate::mesh::generate::box_mesh;
    use nalgebra::{Rotation3, SymmetricEigen};

    use crate::mechanics::material::table1_concrete as table1;

    /// An irregular, positively oriented tet.
    fn skew_tet() -> [Vector3<f64>; 4] {
        [
            Vector3::new(0.1, 0.2, 0.0),
            Vector3::new(1.3, 0.1, 0.2),
            Vector3::new(0.2, 1.1, -0.1),
            Vector3::new(0.3, 0.2, 0.9),
        ]
    }

    /// Deterministic pseudo-random numbers in [−1, 1] (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
        fn vec(&mut self) -> Vector3<f64> {
            Vector3::new(self.next(), self.next(), self.next())
        }
    }

    fn at_rest() -> [Vector3<f64>; 4] {
        [Vector3::zeros(); 4]
    }

    fn max_abs(m: &Matrix3<f64>) -> f64 {
        m.iter().fold(0.0, |a, v| a.max(v.abs()))
    }

    /// Closed form of the fixed, heated element (F = I): F_e = Υ⁻¹ I,
    /// J_e = Υ⁻³, B_e = Υ⁻² I ⇒ σ = μ/J_e (Υ⁻² − 1) + λ/J_e ln J_e (seed 004
    /// eq 38 with the thermal deformation inverted).
    fn fixed_heated_stress(m: &ElasticMaterial, dt: f64) -> f64 {
        let (mu, lambda) = m.lame();
        let u = 1.0 + m.expansion * dt;
        let j_e = u.powi(-3);
        mu / j_e * (u.powi(-2) - 1.0) + lambda / j_e * j_e.ln()
    }

    /// Seed 004 eq 38 as printed (tension), Ṫ = 0.
    fn eq38(m: &ElasticMaterial, dt: f64) -> f64 {
        let (mu, lambda) = m.lame();
        let u = 1.0 + m.expansion * dt;
        mu / u.powi(3) * (u * u - 1.0) + lambda / u.powi(3) * u.powi(3).ln()
    }

    fn assert_isotropic(s: &Matrix3<f64>, want: f64, rel: f64) {
        for r in 0..3 {
            for c in 0..3 {
                let w = if r == c { want } else { 0.0 };
                assert!(
                    (s[(r, c)] - w).abs() <= rel * want.abs(),
                    "sigma[{r}{c}] = {} want {w}",
                    s[(r, c)]
                );
            }
        }
    }

    /// A random state of `x0`: deformation I + δ R (R random in [−1, 1]),
    /// a rigid rotation and translation, velocities of size ~1 m/s.
    fn random_state(
        rng: &mut Rng,
        x0: &[Vector3<f64>; 4],
        delta: f64,
    ) -> ([Vector3<f64>; 4], [Vector3<f64>; 4]) {
        let a =
            Matrix3::identity() + Matrix3::from_columns(&[rng.vec(), rng.vec(), rng.vec()]) * delta;
        let q = *Rotation3::from_scaled_axis(rng.vec() * 3.0).matrix();
        let shift = rng.vec() * 5.0;
        let x = x0.map(|p| q * a * p + shift);
        let v = [rng.vec(), rng.vec(), rng.vec(), rng.vec()];
        (x, v)
    }

    /// The hot path of the explicit loop ([`tet4_forces`]) agrees with
    /// [`element_response`] on random reference shapes, deformations from
    /// 1e-7 to 0.3, rigid motions, velocities, temperatures and rates, with
    /// and without viscosity: stress and forces to 1e-12 of their largest
    /// entry, the energy to 1e-12 of the terms of ψ (ψ itself is a
    /// cancellation of O(ε) terms at small strain ε).
    #[test]
    fn fast_kernel_matches_element_response() {
        let mut rng = Rng(0x5eed_1234_abcd_0042);
        let mut shapes = vec![skew_tet()];
        while shapes.len() < 12 {
            let t = [rng.vec(), rng.vec(), rng.vec(), rng.vec()];
            let q = crate::mesh::tet_quality(&t.map(|p| p.into()));
            if q > 0.1 && Tet4Reference::new(&t).is_ok() {
                shapes.push(t);
            }
        }
        let mut n_large = 0;
        let mut checked = 0;
        for (k, x0) in shapes.iter().enumerate() {
            let r = Tet4Reference::new(x0).unwrap();
            for (viscosity, alpha) in [(0.0, 1e-5), (5e5, 1e-5), (1e3, 3e-4), (0.0, 3e-4)] {
                let mut m = table1();
                m.viscosity = viscosity;
                m.expansion = alpha;
                m.poisson = [0.2, 0.0, 0.45, -0.3][k % 4];
                let (mu, lambda) = m.lame();
                let km = KernelMaterial::new(&m);
                for delta in [1e-7, 1e-4, 1e-2, 0.1, 0.3] {
                    let (x, v) = random_state(&mut rng, x0, delta);
                    let th = ThermalState {
                        delta_t: 150.0 * rng.next(),
                        rate: [0.0, 1e3 * rng.next()][k % 2],
                    };
                    let want = element_response(&r, &m, &x, &v, th).unwrap();
                    let got = tet4_forces(&r, &km, &x, &v, [0, 1, 2, 3], th).unwrap();
                    let smax = max_abs(&want.stress);
                    assert!(
                        max_abs(&(got.stress - want.stress)) <= 1e-12 * smax,
                        "shape {k} eta {viscosity} delta {delta}: {} vs {}",
                        got.stress,
                        want.stress
                    );
                    let fmax = want.forces.iter().map(|f| f.norm()).fold(0.0, f64::max);
                    for i in 0..4 {
                        assert!((got.forces[i] - want.forces[i]).norm() <= 1e-12 * fmax);
                    }
                    let e = thermal_split(&r.kinematics(&x, &v).unwrap(), alpha, th).unwrap();
                    let terms = 0.5 * mu * e.b_e_minus_i.trace().abs()
                        + mu * e.ln_j_e.abs()
                        + 0.5 * lambda * e.ln_j_e * e.ln_j_e;
                    let w_scale = e.stretch.powi(3) * r.volume0 * terms;
                    assert!((got.strain_energy - want.strain_energy).abs() <= 1e-12 * w_scale);
                    n_large += usize::from((e.j_e - 1.0).abs() > 1.0 / 32.0);
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 12 * 4 * 5);
        // Both branches of ln_1p_small are exercised.
        assert!(
            n_large > 10 && n_large < checked - 10,
            "{n_large} of {checked}"
        );
    }

    /// [`ln_1p_small`] agrees with [`f64::ln_1p`] to 2 ulp (relative 2 ε; 1 ulp
    /// seen) over its inline range and beyond, down to subnormal arguments.
    #[test]
    fn inline_ln_1p_matches_the_library() {
        let mut rng = Rng(99);
        let mut xs = vec![
            0.0,
            1.0 / 32.0,
            -1.0 / 32.0,
            1e-300,
            -1e-300,
            5e-324,
            0.5,
            -0.5,
        ];
        for _ in 0..20000 {
            let t = rng.next();
            xs.push(t / 32.0);
            xs.push(t * 10f64.powf(-20.0 * rng.next().abs()));
            xs.push(t * 0.9);
        }
        for x in xs {
            let (got, want) = (ln_1p_small(x), x.ln_1p());
            assert!(
                (got - want).abs() <= 2.0 * f64::EPSILON * want.abs(),
                "x {x}: {got} vs {want}"
            );
        }
    }

    /// [`internal_forces`](crate::mechanics::explicit::internal_forces)
    /// accumulates per element exactly what [`element_response`] gives (to
    /// round-off), records the stresses, and reports the same errors as
    /// before the hot path existed: node and material indices out of range,
    /// an inverted element and 1 + α ΔT <= 0, with the element's position.
    #[test]
    fn internal_forces_match_element_responses_and_errors() {
        use crate::mechanics::explicit::{internal_forces, mesh_elements, ThermalLoad};
        let mesh = box_mesh([0.0; 3], [1.0; 3], 0.5).unwrap();
        let mut elements = mesh_elements(&mesh, 2).unwrap();
        for (e, el) in elements.iter_mut().enumerate() {
            el.material = (e % 2) as u32;
        }
        let mut mats = [table1(), table1()];
        mats[1].viscosity = 2e5;
        mats[1].expansion = 1e-5;
        let mut rng = Rng(7);
        let x: Vec<Vector3<f64>> = mesh
            .nodes
            .iter()
            .map(|p| Vector3::from(*p) + rng.vec() * 0.02)
            .collect();
        let v: Vec<Vector3<f64>> = x.iter().map(|_| rng.vec()).collect();
        let dt: Vec<f64> = (0..elements.len()).map(|_| 100.0 * rng.next()).collect();
        let rate: Vec<f64> = (0..elements.len()).map(|_| 1e3 * rng.next()).collect();
        let load = ThermalLoad::transient(&dt, &rate);
        let n = x.len();
        let mut got = vec![Vector3::zeros(); n];
        let mut stress = vec![Matrix3::zeros(); elements.len()];
        let w =
            internal_forces(&elements, &mats, &x, &v, load, &mut got, Some(&mut stress)).unwrap();
        let mut want = vec![Vector3::zeros(); n];
        let mut w_want = 0.0;
        for (e, el) in elements.iter().enumerate() {
            let idx = el.nodes.map(|i| i as usize);
            let th = ThermalState {
                delta_t: dt[e],
                rate: rate[e],
            };
            let m = &mats[el.material as usize];
            let r = element_response(&el.reference, m, &idx.map(|i| x[i]), &idx.map(|i| v[i]), th)
                .unwrap();
            for k in 0..4 {
                want[idx[k]] += r.forces[k];
            }
            assert!(max_abs(&(stress[e] - r.stress)) <= 1e-12 * max_abs(&r.stress));
            w_want += r.strain_energy;
        }
        let fmax = want.iter().map(|f| f.norm()).fold(0.0, f64::max);
        for i in 0..n {
            assert!((got[i] - want[i]).norm() <= 1e-12 * fmax);
        }
        // Relative 1e-10: the strains (~2 %) keep ψ's cancellation mild.
        assert!((w - w_want).abs() <= 1e-10 * w_want.abs());

        let run = |els: &[MechElement], mats: &[ElasticMaterial], x: &[Vector3<f64>]| {
            let mut f = vec![Vector3::zeros(); n];
            internal_forces(els, mats, x, &v, load, &mut f, None)
        };
        // Node index out of range.
        let mut bad = elements.clone();
        bad[5].nodes[2] = n as u32;
        assert_eq!(
            run(&bad, &mats, &x),
            Err(MechanicsError::SizeMismatch {
                what: "node index of an element",
                got: n,
                expected: n,
            })
        );
        // Material index out of range.
        let mut bad = elements.clone();
        bad[3].material = 2;
        assert_eq!(
            run(&bad, &mats, &x),
            Err(MechanicsError::SizeMismatch {
                what: "materials",
                got: 2,
                expected: 3,
            })
        );
        // Element 4 turned inside out by moving one node through the opposite face.
        let mut xi = x.clone();
        let nodes = elements[4].nodes.map(|i| i as usize);
        let centroid = (xi[nodes[1]] + xi[nodes[2]] + xi[nodes[3]]) / 3.0;
        xi[nodes[0]] = centroid * 2.0 - xi[nodes[0]];
        let first_bad = elements
            .iter()
            .position(|el| {
                let xe = el.nodes.map(|i| xi[i as usize]);
                el.reference.deformation_gradient(&xe).determinant() <= 0.0
            })
            .unwrap();
        assert!(first_bad <= 4);
        match run(&elements, &mats, &xi) {
            Err(MechanicsError::Inverted {
                elem: Some(e),
                what: "J = det F",
                value,
            }) => {
                assert_eq!(e, first_bad);
                assert!(value <= 0.0);
            }
            other => panic!("expected Inverted, got {other:?}"),
        }
        // 1 + α ΔT <= 0 in element 6 (material 0, α = 1e-6).
        let mut cold = dt.clone();
        cold[6] = -2e6;
        let mut f = vec![Vector3::zeros(); n];
        let err = internal_forces(
            &elements,
            &mats,
            &x,
            &v,
            ThermalLoad::transient(&cold, &rate),
            &mut f,
            None,
        );
        assert!(matches!(
            err,
            Err(MechanicsError::Inverted {
                elem: Some(6),
                what: "1 + alpha dT",
                ..
            })
        ));
    }

    #[test]
    fn reference_rejects_inverted_and_degenerate() {
        let mut x = skew_tet();
        assert!(Tet4Reference::new(&x).is_ok());
        x.swap(2, 3);
        assert!(matches!(
            Tet4Reference::new(&x),
            Err(MechanicsError::InvertedReference { .. })
        ));
        let flat = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        assert!(matches!(
            Tet4Reference::new(&flat),
            Err(MechanicsError::DegenerateReference { .. })
        ));
    }

    #[test]
    fn kinematics_of_a_homogeneous_motion() {
        // x = A X + c and v = W x + w give F = A, L = W exactly (tolerance 1e-13, round-off).
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let a = Matrix3::new(1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2);
        let w = Matrix3::new(0.3, -1.0, 0.5, 2.0, -0.4, 0.1, 0.7, 0.2, 0.6);
        let c = Vector3::new(0.5, -2.0, 3.0);
        let x = x0.map(|p| a * p + c);
        let v = x.map(|p| w * p + Vector3::new(1.0, 2.0, 3.0));
        let k = r.kinematics(&x, &v).unwrap();
        assert!(max_abs(&(k.f - a)) < 1e-13);
        assert!((k.j - a.determinant()).abs() < 1e-13);
        assert!(max_abs(&(k.b - a * a.transpose())) < 1e-13);
        assert!(max_abs(&(k.l - w)) < 1e-13);
        assert!(max_abs(&(k.d - (w + w.transpose()) * 0.5)) < 1e-13);
        assert!(max_abs(&(k.f_dot - w * a)) < 1e-13);
        // Reference gradients sum to zero and reproduce X: Σ X_i ⊗ ∇N_i = I.
        let g = r.reference_gradients();
        let mut s = Matrix3::zeros();
        for i in 0..4 {
            s += x0[i] * g[i].transpose();
        }
        assert!(max_abs(&(s - Matrix3::identity())) < 1e-13);
        assert!((r.volume0 - crate::mesh::tet_signed_volume(&x0.map(|p| p.into()))).abs() < 1e-15);
    }

    #[test]
    fn inverted_current_configuration_is_an_error() {
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let x = x0.map(|p| Vector3::new(p.x, p.y, -p.z));
        let err = element_response(&r, &table1(), &x, &at_rest(), ThermalState::default());
        assert!(matches!(err, Err(MechanicsError::Inverted { .. })));
    }

    /// Seed 004 sec 3.1: a single element fixed in all directions, heated
    /// by 100 K with Table 1 constants.
    #[test]
    fn fixed_heated_single_tet_matches_eq_38() {
        let m = table1();
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let resp = element_response(&r, &m, &x0, &at_rest(), ThermalState::steady(100.0)).unwrap();
        let want = fixed_heated_stress(&m, 100.0);
        // Closed form to round-off (1e-10 relative).
        assert_isotropic(&resp.stress, want, 1e-10);
        assert!(want < 0.0, "a fixed heated element is in compression");
        // Magnitude 3.332 MPa (sec 3.1) and eq 38 as printed, both within 0.1 %.
        assert!((want.abs() / 3.332e6 - 1.0).abs() < 1e-3, "sigma = {want}");
        assert!((want.abs() / eq38(&m, 100.0) - 1.0).abs() < 1e-3);
        // The prestressed element pushes on its (fixed) nodes with
        // f_i = −V0 σ ∇N_i (F = I), which balance (relative 1e-10).
        let g = r.reference_gradients();
        let scale = (r.volume0 * want).abs() * g[0].norm();
        for (fi, gi) in resp.forces.iter().zip(&g) {
            let f = -(r.volume0 * want) * gi;
            assert!((fi - f).norm() < 1e-10 * scale);
        }
        assert!(resp.forces.iter().sum::<Vector3<f64>>().norm() < 1e-10 * scale);
    }

    /// Seed 004 eq 38's viscous term: an element held fixed while heating
    /// at rate Ṫ carries −2 η α Ṫ/Υ on the diagonal.
    #[test]
    fn heating_rate_gives_viscous_stress_of_eq_38() {
        let mut m = table1();
        m.viscosity = 1e6;
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let th = ThermalState {
            delta_t: 100.0,
            rate: 1000.0,
        };
        let resp = element_response(&r, &m, &x0, &at_rest(), th).unwrap();
        let u = 1.0 + m.expansion * 100.0;
        let want = fixed_heated_stress(&m, 100.0) - 2.0 * m.viscosity * m.expansion * 1000.0 / u;
        assert_isotropic(&resp.stress, want, 1e-10);
        // Expanding freely at the thermal rate: no stress at all (1e-9 of E α ΔT).
        let x = x0.map(|p| p * u);
        let v = x0.map(|p| p * (m.expansion * 1000.0));
        let resp = element_response(&r, &m, &x, &v, th).unwrap();
        assert!(max_abs(&resp.stress) < 1e-9 * m.young * m.expansion * 100.0);
    }

    /// The single cube of seed 004 sec 3.2 (box_mesh h = 1 → 6 tets), all
    /// nodes fixed, heated by 100 K: every element has the same isotropic
    /// compression.
    #[test]
    fn fixed_heated_cube_elements_match_eq_38() {
        let m = table1();
        let mesh = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
        assert_eq!(mesh.tets.len(), 6);
        let want = fixed_heated_stress(&m, 100.0);
        let mut net = vec![Vector3::zeros(); mesh.nodes.len()];
        for e in 0..mesh.tets.len() {
            let x0 = to_vectors(&mesh.element_coords(e));
            let r = Tet4Reference::new(&x0).unwrap();
            let resp =
                element_response(&r, &m, &x0, &at_rest(), ThermalState::steady(100.0)).unwrap();
            // Closed form to round-off (1e-10), and 3.332 MPa within 0.1 %.
            assert_isotropic(&resp.stress, want, 1e-10);
            assert!((resp.stress[(0, 0)].abs() / 3.332e6 - 1.0).abs() < 1e-3);
            for (i, &n) in mesh.tets[e].iter().enumerate() {
                net[n as usize] += resp.forces[i];
            }
        }
        // Assembled forces: the thermal pressure p = −σ pushes each outer
        // face outward, so each node carries a share of −σ × (area) along
        // outward normals; their total vanishes (1e-9 of σ·1 m²).
        let total: Vector3<f64> = net.iter().sum();
        assert!(total.norm() < 1e-9 * want.abs());
        // The corner node 7 = (1,1,1) pushes outward (+,+,+) under compression.
        assert!(net[7].iter().all(|c| *c > 0.0), "{:?}", net[7]);
    }

    /// Free thermal expansion about an arbitrary point: stress and forces vanish.
    #[test]
    fn free_thermal_expansion_is_stress_free() {
        let mut m = table1();
        m.viscosity = 0.0;
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let dt = 100.0;
        let u = 1.0 + m.expansion * dt;
        let p = Vector3::new(-3.0, 7.0, 2.5);
        let x = x0.map(|q| p + (q - p) * u);
        let resp = element_response(&r, &m, &x, &at_rest(), ThermalState::steady(dt)).unwrap();
        let scale = m.young * m.expansion * dt;
        // Stress zero to 1e-9 relative of E α ΔT; forces zero to 1e-9 of E α ΔT · (1 m²).
        assert!(max_abs(&resp.stress) < 1e-9 * scale, "{}", resp.stress);
        for f in resp.forces {
            assert!(f.norm() < 1e-9 * scale);
        }
        assert!((resp.j_elastic - 1.0).abs() < 1e-14);
        assert!(resp.strain_energy.abs() < 1e-20 * scale);
        // Same with the larger α of the cube test.
        m.expansion = 1e-5;
        let u = 1.0 + m.expansion * dt;
        let x = x0.map(|q| p + (q - p) * u);
        let resp = element_response(&r, &m, &x, &at_rest(), ThermalState::steady(dt)).unwrap();
        assert!(max_abs(&resp.stress) < 1e-9 * m.young * m.expansion * dt);
    }

    /// Objectivity: a rigid rotation of a stretched element rotates the
    /// stress (σ' = Q σ Qᵀ) and the forces (f' = Q f).
    #[test]
    fn rigid_rotation_rotates_stress() {
        let mut m = table1();
        m.viscosity = 0.0;
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let a = Matrix3::new(1.05, 0.02, 0.0, -0.01, 0.97, 0.03, 0.04, 0.0, 1.02);
        let x = x0.map(|p| a * p);
        let q = *Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7).matrix()
            * *Rotation3::from_axis_angle(&Vector3::x_axis(), -1.3).matrix();
        let shift = Vector3::new(10.0, -4.0, 2.0);
        let xr = x.map(|p| q * p + shift);
        let th = ThermalState::steady(30.0);
        let s = element_response(&r, &m, &x, &at_rest(), th).unwrap();
        let sr = element_response(&r, &m, &xr, &at_rest(), th).unwrap();
        let scale = max_abs(&s.stress);
        // Relative 1e-10 of the stress magnitude.
        assert!(max_abs(&(sr.stress - q * s.stress * q.transpose())) < 1e-10 * scale);
        for i in 0..4 {
            assert!((sr.forces[i] - q * s.forces[i]).norm() < 1e-10 * s.forces[i].norm().max(1.0));
        }
        assert!((sr.strain_energy / s.strain_energy - 1.0).abs() < 1e-10);
        // Invariants of σ are unchanged (eigenvalues, 1e-10 relative).
        let e1 = SymmetricEigen::new(s.stress).eigenvalues;
        let e2 = SymmetricEigen::new(sr.stress).eigenvalues;
        let (mut e1, mut e2) = (e1.as_slice().to_vec(), e2.as_slice().to_vec());
        e1.sort_by(f64::total_cmp);
        e2.sort_by(f64::total_cmp);
        for k in 0..3 {
            assert!((e1[k] - e2[k]).abs() < 1e-10 * scale);
        }
    }

    /// Σ f_i = 0 and Σ x_i × f_i = 0 for an arbitrary deformed, moving state
    /// (viscous part included).
    #[test]
    fn forces_balance_and_have_no_moment() {
        let mut m = table1();
        m.viscosity = 5e5;
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let x = x0.map(|p| p + rng.vec() * 0.15);
        let v = [rng.vec(), rng.vec(), rng.vec(), rng.vec()];
        let resp = element_response(&r, &m, &x, &v, ThermalState::steady(-40.0)).unwrap();
        let fmax = resp.forces.iter().map(|f| f.norm()).fold(0.0, f64::max);
        let sum: Vector3<f64> = resp.forces.iter().sum();
        let moment: Vector3<f64> = (0..4).map(|i| x[i].cross(&resp.forces[i])).sum();
        // Round-off level: 1e-12 of the largest force (× 1 m lever for the moment).
        assert!(sum.norm() < 1e-12 * fmax, "sum {sum}");
        assert!(moment.norm() < 1e-12 * fmax, "moment {moment}");
        // σ is symmetric.
        assert!(max_abs(&(resp.stress - resp.stress.transpose())) < 1e-12 * max_abs(&resp.stress));
        // Power consistency: −Σ f_i·v_i = v σ : D (viscous part included), 1e-10 relative.
        let k = r.kinematics(&x, &v).unwrap();
        let power: f64 = -(0..4).map(|i| resp.forces[i].dot(&v[i])).sum::<f64>();
        let want = resp.volume * resp.stress.component_mul(&k.d).sum();
        assert!((power - want).abs() < 1e-10 * want.abs());
    }

    /// f_i = −∂W/∂x_i with W = J_T V0 ψ(F_e) (η = 0), by central differences.
    #[test]
    fn forces_are_the_energy_gradient() {
        let m = table1();
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let mut rng = Rng(0x0dd_ba11_cafe_f00d);
        for dt in [0.0, 250.0] {
            let x = x0.map(|p| p + rng.vec() * 0.01);
            let th = ThermalState::steady(dt);
            let resp = element_response(&r, &m, &x, &at_rest(), th).unwrap();
            let energy = |y: &[Vector3<f64>; 4]| {
                element_response(&r, &m, y, &at_rest(), th)
                    .unwrap()
                    .strain_energy
            };
            let fmax = resp.forces.iter().map(|f| f.norm()).fold(0.0, f64::max);
            let h = 1e-6;
            for i in 0..4 {
                for d in 0..3 {
                    let (mut xp, mut xm) = (x, x);
                    xp[i][d] += h;
                    xm[i][d] -= h;
                    let fd = -(energy(&xp) - energy(&xm)) / (2.0 * h);
                    // Relative 1e-6 of the largest nodal force.
                    assert!(
                        (fd - resp.forces[i][d]).abs() < 1e-6 * fmax,
                        "dT {dt} node {i} dir {d}: fd {fd} vs {}",
                        resp.forces[i][d]
                    );
                }
            }
        }
    }

    /// Small-strain limit: σ → λ tr(ε) I + 2 μ ε (Hooke), relative 1e-5 at ε ~ 1e-6.
    #[test]
    fn small_strain_limit_is_hooke() {
        let m = table1();
        let (mu, lambda) = m.lame();
        let x0 = skew_tet();
        let r = Tet4Reference::new(&x0).unwrap();
        let eps = Matrix3::new(1.0, 0.3, -0.2, 0.3, -0.5, 0.1, -0.2, 0.1, 0.7) * 1e-6;
        let x = x0.map(|p| p + eps * p);
        let resp = element_response(&r, &m, &x, &at_rest(), ThermalState::default()).unwrap();
        let hooke = Matrix3::identity() * (lambda * eps.trace()) + eps * (2.0 * mu);
        assert!(max_abs(&(resp.stress - hooke)) < 1e-5 * max_abs(&hooke));
    }

    /// The critical step L/c is below the true central-difference limit
    /// 2/ω_max of the lumped-mass element (ω_max from the 12×12 tangent
    /// stiffness, by finite differences of the forces) and within a factor
    /// 2 of it, for the Kuhn tet of box_mesh, a regular tet, a skewed tet
    /// and random tets of shape quality > 0.05, at several Poisson ratios.
    /// h_min/c, in contrast, exceeds the limit.
    #[test]
    fn critical_dt_is_below_the_element_stability_limit() {
        let s3 = 3f64.sqrt();
        let regular = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.5, s3 / 2.0, 0.0),
            Vector3::new(0.5, s3 / 6.0, (2.0f64 / 3.0).sqrt()),
        ];
        let kuhn = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 1.0),
        ];
        let mut shapes = vec![regular, kuhn, skew_tet()];
        let mut rng = Rng(77);
        while shapes.len() < 40 {
            let t = [rng.vec(), rng.vec(), rng.vec(), rng.vec()];
            if crate::mesh::tet_quality(&t.map(|p| p.into())) > 0.05 {
                shapes.push(t);
            }
        }
        for nu in [0.0, 0.2, 0.45] {
            let mut m = table1();
            m.poisson = nu;
            for (k, x0) in shapes.iter().enumerate() {
                let r = Tet4Reference::new(x0).unwrap();
                let mass = m.density * r.volume0 / 4.0;
                let mut stiff = nalgebra::DMatrix::<f64>::zeros(12, 12);
                let h = 1e-7;
                for j in 0..12 {
                    let (mut xp, mut xm) = (*x0, *x0);
                    xp[j / 3][j % 3] += h;
                    xm[j / 3][j % 3] -= h;
                    let th = ThermalState::default();
                    let fp = element_response(&r, &m, &xp, &at_rest(), th)
                        .unwrap()
                        .forces;
                    let fm = element_response(&r, &m, &xm, &at_rest(), th)
                        .unwrap()
                        .forces;
                    for i in 0..12 {
                        stiff[(i, j)] = -(fp[i / 3][i % 3] - fm[i / 3][i % 3]) / (2.0 * h) / mass;
                    }
                }
                let stiff = (&stiff + stiff.transpose()) * 0.5;
                let limit = 2.0 / stiff.symmetric_eigenvalues().max().sqrt();
                let est = element_critical_dt(x0, &m);
                // Rigorous bound (1e-6 slack for the finite-difference stiffness), within 2×.
                assert!(
                    est <= limit * (1.0 + 1e-6),
                    "nu {nu} shape {k}: {est} vs {limit}"
                );
                assert!(est > 0.5 * limit, "nu {nu} shape {k}: {est} vs {limit}");
                if k == 0 {
                    // Regular tet: h_min/c exceeds the true limit (by 15 % at ν = 0, 41 % at ν = 0.2).
                    let hc = min_height(x0) / m.p_wave_speed();
                    assert!(hc > 1.1 * limit, "h_min/c {hc} vs {limit}");
                }
            }
        }
        // Kuhn tet of edge a: ∇N = (−1,0,0), (1,−1,0), (0,1,−1), (0,0,1)/a ⇒ L = a/√6 (round-off).
        assert!((characteristic_length(&kuhn) - 1.0 / 6f64.sqrt()).abs() < 1e-14);
        // Regular tet: |∇N_i| = 1/h ⇒ L = h/2.
        assert!((characteristic_length(&regular) - min_height(&regular) / 2.0).abs() < 1e-14);
        // Viscosity shortens the step: ξ = 1 gives (√2 − 1) L/c.
        let mut mv = table1();
        let len = characteristic_length(&kuhn);
        mv.viscosity = mv.p_wave_modulus() * len / (2.0 * mv.p_wave_speed());
        let want = len / mv.p_wave_speed() * (2f64.sqrt() - 1.0);
        assert!((element_critical_dt(&kuhn, &mv) / want - 1.0).abs() < 1e-12);
    }
}
