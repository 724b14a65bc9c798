//! The cohesive law of a joint: traction against the relative displacement
//! of its two faces, with damage that only grows.
//!
//! Seed 004 sec 2.7 uses the cohesive zone of Munjiza's combined single and
//! smeared crack model (elastic penalty up to the peak, then softening). Its
//! softening curve is an empirical fit whose area is G only after a numeric
//! calibration, and its mixed mode is heuristic. fdem uses instead the
//! bilinear mixed-mode law of Camanho and Dávila (2002): the same penalty
//! branch up to the peak (stiffness p_f / h as in Munjiza's δ_p = 2 h f_t / p),
//! then linear softening whose area is exactly G_I in pure opening, G_II in
//! pure sliding and the Benzeggagh–Kenane interpolation in between, with the
//! Mohr–Coulomb shear strength c + σ_n tan φ under compression. Damage is a
//! scalar that never decreases, so unloading is elastic towards the origin
//! and no energy is created. Free of MPI and PETSc.

/// Fracture constants of a material (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractureMaterial {
    /// Tensile strength f_t (Pa), > 0.
    pub tensile_strength: f64,
    /// Cohesion c (Pa), > 0: the shear strength without normal stress.
    pub cohesion: f64,
    /// Internal friction angle φ (rad), in [0, π/2).
    pub friction_angle: f64,
    /// Mode I fracture energy G_I (J/m²), > 0.
    pub g_i: f64,
    /// Mode II fracture energy G_II (J/m²), > 0.
    pub g_ii: f64,
    /// Fracture penalty p_f (Pa), > 0: a joint of size h has the normal and
    /// tangential stiffness p_f / h per unit area.
    pub penalty: f64,
    /// Benzeggagh–Kenane exponent η (–), > 0: G_c = G_I + (G_II − G_I) B^η.
    pub bk_exponent: f64,
}

impl FractureMaterial {
    /// Checks every constant: the error names the scenario key.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("`{key}` must be positive and finite, got {v}"))
            }
        };
        positive("tensile_strength", self.tensile_strength)?;
        positive("cohesion", self.cohesion)?;
        positive("g_i", self.g_i)?;
        positive("g_ii", self.g_ii)?;
        positive("fracture_penalty", self.penalty)?;
        positive("bk_exponent", self.bk_exponent)?;
        let phi = self.friction_angle;
        if !(phi.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&phi)) {
            return Err(format!(
                "`friction_angle` must lie in [0, 90) degrees, got {}",
                phi.to_degrees()
            ));
        }
        Ok(())
    }

    /// The law of a joint of size `h` (m).
    ///
    /// Errors when the elastic energy at the peak, f_t² h / (2 p_f) (or
    /// c² h / (2 p_f) in shear), exceeds G_I (G_II): softening would have to
    /// give back more than it may dissipate (snap-back). The error names the
    /// key to change.
    pub fn law(&self, h: f64) -> Result<CohesiveLaw, String> {
        let k = self.penalty / h;
        let peak_i = 0.5 * self.tensile_strength * self.tensile_strength / k;
        if peak_i >= self.g_i {
            return Err(format!(
                "`g_i` = {} J/m^2 is not above the elastic energy at the peak, f_t^2 h / (2 p_f) = {:.4e} J/m^2 for a joint of size h = {h:.4e} m (snap-back): raise `g_i` or `fracture_penalty`",
                self.g_i, peak_i
            ));
        }
        let peak_ii = 0.5 * self.cohesion * self.cohesion / k;
        if peak_ii >= self.g_ii {
            return Err(format!(
                "`g_ii` = {} J/m^2 is not above the elastic energy at the peak, c^2 h / (2 p_f) = {:.4e} J/m^2 for a joint of size h = {h:.4e} m (snap-back): raise `g_ii` or `fracture_penalty`",
                self.g_ii, peak_ii
            ));
        }
        Ok(self.unchecked_law(h))
    }

    /// The law of a joint of size `h` without the snap-back check.
    pub(crate) fn unchecked_law(&self, h: f64) -> CohesiveLaw {
        let k = self.penalty / h;
        CohesiveLaw {
            k,
            ft: self.tensile_strength,
            c: self.cohesion,
            tan_phi: self.friction_angle.tan(),
            g_i: self.g_i,
            g_ii: self.g_ii,
            eta: self.bk_exponent,
            min_strength2: self.tensile_strength.min(self.cohesion).powi(2),
            nf: 2.0 * self.g_i / self.tensile_strength,
            sf: 2.0 * self.g_ii / self.cohesion,
        }
    }
}

/// The law of one joint: its stiffness and strengths.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CohesiveLaw {
    /// Penalty stiffness per unit area (Pa/m), normal and tangential.
    pub k: f64,
    ft: f64,
    c: f64,
    tan_phi: f64,
    g_i: f64,
    g_ii: f64,
    eta: f64,
    /// The square of the smaller strength, min(f_t, c)² (Pa²): below the
    /// onset displacement min(f_t, c) / k no mixity or compression damages
    /// the joint.
    min_strength2: f64,
    /// Final openings in pure opening and pure sliding, 2 G_I / f_t and
    /// 2 G_II / c (m): independent of the stiffness.
    nf: f64,
    sf: f64,
}

/// How a joint broke.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Mode mixity B = G_II / (G_I + G_II) at most 0.1.
    Opening,
    /// B at least 0.9 (every joint that breaks under compression).
    Sliding,
    /// In between.
    Mixed,
    /// Broken from the start: an initial crack of the scenario.
    Initial,
}

impl Mode {
    /// The code written to the joint output: 1 opening, 2 sliding, 3 mixed,
    /// 4 initial crack (0 is intact).
    pub fn code(self) -> u8 {
        match self {
            Mode::Opening => 1,
            Mode::Sliding => 2,
            Mode::Mixed => 3,
            Mode::Initial => 4,
        }
    }

    fn of_mixity(b: f64) -> Mode {
        if b <= 0.1 {
            Mode::Opening
        } else if b >= 0.9 {
            Mode::Sliding
        } else {
            Mode::Mixed
        }
    }
}

/// The history of one joint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointState {
    /// Damage D in [0, 1]: the stiffness left is (1 − D) k.
    pub damage: f64,
    /// Energy dissipated per unit area so far (J/m²).
    pub dissipated: f64,
    /// How it broke; `None` while intact.
    pub broken: Option<Mode>,
}

/// The onset and final effective displacements of the envelope and the mode
/// mixity at a relative displacement.
struct Envelope {
    onset: f64,
    last: f64,
    mixity: f64,
}

impl CohesiveLaw {
    /// Coulomb friction coefficient tan φ of the faces once broken.
    pub fn friction(&self) -> f64 {
        self.tan_phi
    }

    /// The same law for a joint of another size: stiffness `k` (Pa/m).
    /// A [`super::set::JointSet`] keeps one law per material and one
    /// stiffness per joint.
    #[inline]
    pub fn with_stiffness(&self, k: f64) -> CohesiveLaw {
        CohesiveLaw { k, ..*self }
    }

    /// The envelope at normal opening `dn` (m, > 0 opens) and sliding `s`
    /// (m, >= 0).
    fn envelope(&self, dn: f64, s2: f64) -> Envelope {
        if dn < 0.0 {
            // Mohr–Coulomb under compression: τ_0 = c + σ_n tan φ, pure sliding.
            let sigma = -self.k * dn;
            let tau0 = self.c + sigma * self.tan_phi;
            return Envelope {
                onset: tau0 / self.k,
                last: 2.0 * self.g_ii / tau0,
                mixity: 1.0,
            };
        }
        let l2 = dn * dn + s2;
        // Camanho–Dávila: B = δ_s² / (δ_s² + δ_n²), the shear share of the energy.
        let b = if l2 > 0.0 { s2 / l2 } else { 0.0 };
        let be = if self.eta == 1.0 { b } else { b.powf(self.eta) };
        let (n0, nf) = (self.ft / self.k, self.nf);
        let (s0, sf) = (self.c / self.k, self.sf);
        // Camanho–Dávila onset δ_0² = δ_n0² + (δ_s0² − δ_n0²) B^η, final δ_f = (δ_n0 δ_nf + (δ_s0 δ_sf − δ_n0 δ_nf) B^η) / δ_0.
        let onset = (n0 * n0 + (s0 * s0 - n0 * n0) * be).sqrt();
        let last = (n0 * nf + (s0 * sf - n0 * nf) * be) / onset;
        Envelope {
            onset,
            last,
            mixity: b,
        }
    }

    /// Advance the damage of `st` to the relative displacement (`dn`, `s`)
    /// of the joint, adding the energy dissipated on the way (per unit
    /// area), and mark it broken when D reaches 1.
    pub fn update(&self, dn: f64, s: f64, st: &mut JointState) {
        self.update_squared(dn, s * s, st);
    }

    /// [`Self::update`] given the square of the sliding, `s2` (m²).
    pub fn update_squared(&self, dn: f64, s2: f64, st: &mut JointState) {
        if st.broken.is_some() {
            return;
        }
        let open = dn.max(0.0);
        let lam2 = open * open + s2;
        // Below every onset (the envelope's lies between δ_n0 and δ_s0, and
        // grows with compression): no new damage, without the envelope.
        if lam2 * (self.k * self.k) <= self.min_strength2 {
            return;
        }
        let lam = lam2.sqrt();
        let e = self.envelope(dn, s2);
        let d_trial = if lam <= e.onset {
            0.0
        } else if lam >= e.last {
            1.0
        } else {
            e.last * (lam - e.onset) / (lam * (e.last - e.onset))
        };
        if d_trial <= st.damage {
            return;
        }
        // Dissipation ½ k λ² dD along the envelope, λ(D) = δ_0 / (1 − D (δ_f − δ_0)/δ_f): ½ k δ_0 δ_f (λ_2 − λ_1) / (δ_f − δ_0).
        let a = (e.last - e.onset) / e.last;
        let lam_of = |d: f64| e.onset / (1.0 - a * d);
        let (l1, l2) = (lam_of(st.damage), lam_of(d_trial).min(e.last));
        st.dissipated += 0.5 * self.k * e.onset * e.last * (l2 - l1) / (e.last - e.onset);
        st.damage = d_trial;
        if d_trial >= 1.0 {
            st.broken = Some(Mode::of_mixity(e.mixity));
        }
    }

    /// Traction (Pa) at normal opening `dn` and sliding `s` with damage `d`:
    /// (normal, shear), both resisting the displacement. Compression is the
    /// undamaged penalty; opening and sliding are softened by 1 − D.
    pub fn traction(&self, dn: f64, s: f64, d: f64) -> (f64, f64) {
        let keep = 1.0 - d;
        let tn = if dn > 0.0 {
            keep * self.k * dn
        } else {
            self.k * dn
        };
        (tn, keep * self.k * s)
    }

    /// Elastic energy per unit area stored at (`dn`, `s`) with damage `d`
    /// (J/m²).
    pub fn stored(&self, dn: f64, s: f64, d: f64) -> f64 {
        let keep = 1.0 - d;
        let n = if dn > 0.0 { keep } else { 1.0 };
        0.5 * self.k * (n * dn * dn + keep * s * s)
    }

    /// Critical energy release rate G_c (J/m²) at mixity B (the area under
    /// the envelope): G_I + (G_II − G_I) B^η.
    pub fn critical_energy(&self, b: f64) -> f64 {
        self.g_i + (self.g_ii - self.g_i) * b.powf(self.eta)
    }
}

/// Seed 004 Table 2's joint: f_t 10 MPa, c 20 MPa, φ 30°, G_I 50,
/// G_II 100 J/m², p_f 10³ GPa (B–K exponent 1).
#[cfg(test)]
pub(crate) fn table2() -> FractureMaterial {
    FractureMaterial {
        tensile_strength: 10e6,
        cohesion: 20e6,
        friction_angle: 30f64.to_radians(),
        g_i: 50.0,
        g_ii: 100.0,
        penalty: 1e12,
        bk_exponent: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Load along a path (dn(t), s(t)) in `n` steps; returns the peak of
    /// the traction along the path, the area under traction·d(displacement)
    /// (trapezoids) and the state.
    fn drive(
        law: &CohesiveLaw,
        path: impl Fn(f64) -> (f64, f64),
        n: usize,
    ) -> (f64, f64, JointState) {
        let mut st = JointState::default();
        let (mut peak, mut work) = (0.0f64, 0.0);
        let mut prev = (0.0, 0.0, 0.0, 0.0);
        for i in 0..=n {
            let (dn, s) = path(i as f64 / n as f64);
            law.update(dn, s, &mut st);
            let (tn, ts) = if st.broken.is_some() {
                (dn.min(0.0) * law.k, 0.0)
            } else {
                law.traction(dn, s, st.damage)
            };
            peak = peak.max(tn.max(0.0).hypot(ts));
            work += 0.5 * (tn + prev.2) * (dn - prev.0) + 0.5 * (ts + prev.3) * (s - prev.1);
            prev = (dn, s, tn, ts);
        }
        (peak, work, st)
    }

    #[test]
    fn pure_opening_peaks_at_the_tensile_strength_and_dissipates_g_i() {
        let m = table2();
        let law = m.law(5e-3).unwrap();
        let reach = 1.2 * 2.0 * m.g_i / m.tensile_strength;
        let (peak, work, st) = drive(&law, |t| (t * reach, 0.0), 20000);
        assert!(
            (peak / m.tensile_strength - 1.0).abs() < 1e-2,
            "peak {peak}"
        );
        assert!((work / m.g_i - 1.0).abs() < 1e-2, "area {work}");
        assert!(
            (st.dissipated / m.g_i - 1.0).abs() < 1e-12,
            "{}",
            st.dissipated
        );
        assert_eq!(st.broken, Some(Mode::Opening));
        // No tensile traction once broken.
        assert_eq!(law.traction(reach, 0.0, st.damage).0, 0.0);
    }

    #[test]
    fn pure_sliding_under_compression_follows_mohr_coulomb_and_dissipates_g_ii() {
        let m = table2();
        let law = m.law(5e-3).unwrap();
        let sigma = 5e6;
        let dn = -sigma / law.k;
        let tau0 = m.cohesion + sigma * m.friction_angle.tan();
        let reach = 1.2 * 2.0 * m.g_ii / tau0;
        let (peak, work, st) = drive(&law, |t| (dn, t * reach), 20000);
        // The peak along the path includes no tension: it is the shear peak.
        assert!((peak / tau0 - 1.0).abs() < 1e-2, "peak {peak} vs {tau0}");
        // Work of the shear traction only (the normal does none at fixed dn).
        assert!((work / m.g_ii - 1.0).abs() < 1e-2, "area {work}");
        assert!((st.dissipated / m.g_ii - 1.0).abs() < 1e-12);
        assert_eq!(st.broken, Some(Mode::Sliding));
    }

    #[test]
    fn mixed_mode_follows_the_benzeggagh_kenane_envelope() {
        let mut m = table2();
        m.bk_exponent = 2.0;
        let law = m.law(5e-3).unwrap();
        // Opening and sliding in proportion 1 : 1 → B = 1/2.
        let b = 0.5f64;
        let gc = m.g_i + (m.g_ii - m.g_i) * b.powf(2.0);
        let n0 = m.tensile_strength / law.k;
        let s0 = m.cohesion / law.k;
        let onset = (n0 * n0 + (s0 * s0 - n0 * n0) * b.powf(2.0)).sqrt();
        let reach = 1.5 * 2.0 * gc / (law.k * onset);
        let r = reach / 2f64.sqrt();
        let (peak, work, st) = drive(&law, |t| (t * r, t * r), 40000);
        assert!((peak / (law.k * onset) - 1.0).abs() < 1e-2, "peak {peak}");
        assert!((work / gc - 1.0).abs() < 1e-2, "area {work} vs {gc}");
        assert!((st.dissipated / law.critical_energy(b) - 1.0).abs() < 1e-12);
        assert_eq!(st.broken, Some(Mode::Mixed));
    }

    #[test]
    fn unloading_is_elastic_and_damage_never_heals() {
        let m = table2();
        let law = m.law(5e-3).unwrap();
        let n0 = m.tensile_strength / law.k;
        let nf = 2.0 * m.g_i / m.tensile_strength;
        let mut st = JointState::default();
        let mid = 0.5 * (n0 + nf);
        law.update(mid, 0.0, &mut st);
        let d = st.damage;
        assert!(d > 0.0 && d < 1.0 && st.broken.is_none());
        let e = st.dissipated;
        // Back to half the opening: no more damage, no more dissipation,
        // the secant stiffness (1 − D) k.
        law.update(0.5 * mid, 0.0, &mut st);
        assert_eq!((st.damage, st.dissipated), (d, e));
        let (tn, _) = law.traction(0.5 * mid, 0.0, st.damage);
        assert!((tn - (1.0 - d) * law.k * 0.5 * mid).abs() <= 1e-9 * tn.abs());
        // Closed: the full penalty pushes back whatever the damage.
        assert_eq!(law.traction(-1e-9, 0.0, d).0, -law.k * 1e-9);
        // Energy: stored + dissipated at `mid` = the work of the envelope.
        let (peak, work, _) = drive(&law, |t| (t * mid, 0.0), 20000);
        assert!(peak > 0.0);
        let total = law.stored(mid, 0.0, d) + e;
        assert!((total / work - 1.0).abs() < 1e-3, "{total} vs {work}");
    }

    #[test]
    fn bad_constants_name_their_key() {
        let mut m = table2();
        m.g_i = 0.0;
        assert!(m.validate().unwrap_err().contains("`g_i`"));
        let mut m = table2();
        m.tensile_strength = -1.0;
        assert!(m.validate().unwrap_err().contains("`tensile_strength`"));
        let mut m = table2();
        m.friction_angle = 95f64.to_radians();
        assert!(m.validate().unwrap_err().contains("`friction_angle`"));
        // Snap-back: f_t² h / (2 p_f) = 1e14 · 1 / 2e12 = 50 J/m² at h = 1 m.
        let m = table2();
        let err = m.law(1.0).unwrap_err();
        assert!(err.contains("`g_i`") && err.contains("snap-back"), "{err}");
        assert!(m.law(0.4).is_ok());
    }
}
