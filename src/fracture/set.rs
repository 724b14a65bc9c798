//! The joints of a rank: their faces, laws and histories, advanced together
//! at each substep, with the counts a run reports (broken joints, crack
//! area, energy dissipated). Free of MPI and PETSc: the caller owns the
//! node positions and places the six forces of each joint in its force sum.

use super::crack::{crack_forces, CrackState};
use super::insert::{joint_size, JointFaces};
use super::joint::joint_forces;
use super::law::{CohesiveLaw, FractureMaterial, JointState, Mode};
use nalgebra::Vector3;

/// Joints with their laws and histories.
#[derive(Debug, Clone)]
pub struct JointSet {
    pub faces: Vec<JointFaces>,
    /// The material's law (at the first joint's size).
    pub law: CohesiveLaw,
    /// Each joint's penalty stiffness p_f / h (Pa/m): the law of joint j
    /// is `law.with_stiffness(stiffness[j])`.
    pub stiffness: Vec<f64>,
    pub states: Vec<JointState>,
    /// Time at which each joint broke (s; NaN while intact).
    pub broke_at: Vec<f64>,
    /// The broken joints (index into `faces`), in the order they broke,
    /// each with the history of its faces' contact ([`super::crack`]).
    pub cracks: Vec<(u32, CrackState)>,
    /// Joints broken since the caller last took them ([`Self::take_new_cracks`]).
    new_cracks: Vec<u32>,
    /// Per joint: counted in the totals (false for a joint another owner
    /// counts, advanced here too for its forces on this side).
    counted: Vec<bool>,
}

/// Values per joint in a checkpoint ([`JointSet::save`]).
pub const SAVED_JOINT: usize = 9;

/// What a step of the joints gives back besides the forces.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointTotals {
    /// Elastic energy stored in the intact joints (J).
    pub stored: f64,
    /// Energy dissipated by damage since the start (J).
    pub dissipated: f64,
    /// Joints broken so far.
    pub broken: usize,
    /// Of those, broken in opening (mixity at most 0.1), sliding (at
    /// least 0.9, and every break under compression) and mixed mode.
    pub by_mode: [usize; 3],
    /// Area of the broken joints' faces, one side (m²).
    pub crack_area: f64,
    /// Energy dissipated by friction on crack faces since the start (J).
    pub friction: f64,
    /// Cracks whose faces touch (initial cracks included).
    pub closed: usize,
}

impl JointTotals {
    /// Count a joint of area `area` (m²) in state `st`: its dissipated
    /// energy, and whether and how it broke (initial cracks not counted).
    #[inline]
    fn count(&mut self, st: &JointState, area: f64) {
        self.dissipated += st.dissipated * area;
        match st.broken {
            Some(Mode::Initial) | None => {}
            Some(mode) => {
                self.broken += 1;
                self.by_mode[usize::from(mode.code()) - 1] += 1;
                self.crack_area += area;
            }
        }
    }

    /// Add `o`'s counts and energies to these.
    pub fn add(&mut self, o: &JointTotals) {
        self.stored += o.stored;
        self.dissipated += o.dissipated;
        self.broken += o.broken;
        for (t, m) in self.by_mode.iter_mut().zip(o.by_mode) {
            *t += m;
        }
        self.crack_area += o.crack_area;
        self.friction += o.friction;
        self.closed += o.closed;
    }
}

impl JointSet {
    /// The joints `faces` of one material. Errors name the joint whose
    /// size makes the law snap back (its tets and area).
    pub fn new(faces: Vec<JointFaces>, material: &FractureMaterial) -> Result<JointSet, String> {
        material.validate()?;
        let stiffness = faces
            .iter()
            .map(|f| {
                let law = material.law(joint_size(f.area)).map_err(|e| {
                    format!(
                        "joint between tets {} and {} (area {:.3e} m^2): {e}",
                        f.tets[0], f.tets[1], f.area
                    )
                })?;
                Ok(law.k)
            })
            .collect::<Result<Vec<_>, String>>()?;
        // Only the stiffness depends on a joint's size.
        let law = material.unchecked_law(1.0);
        let n = faces.len();
        Ok(JointSet {
            faces,
            law,
            stiffness,
            states: vec![JointState::default(); n],
            broke_at: vec![f64::NAN; n],
            cracks: Vec::new(),
            new_cracks: Vec::new(),
            counted: vec![true; n],
        })
    }

    /// Count in the totals only the joints `counted` marks (one flag per
    /// joint); the others are advanced all the same.
    pub fn count_only(&mut self, counted: Vec<bool>) {
        assert_eq!(counted.len(), self.faces.len(), "one flag per joint");
        self.counted = counted;
    }

    /// Whether joint `j` is counted here (see [`Self::count_only`]).
    pub fn is_counted(&self, j: usize) -> bool {
        self.counted.get(j).copied().unwrap_or(true)
    }

    /// Break joint `j` before the run (an initial crack of the scenario):
    /// its faces are a crack from the start, not counted as broken.
    pub fn start_broken(&mut self, j: usize, x: &[Vector3<f64>]) {
        if self.states[j].broken.is_some() {
            return;
        }
        self.states[j].broken = Some(Mode::Initial);
        self.broke_at[j] = 0.0;
        self.add_crack(j, x);
    }

    fn add_crack(&mut self, j: usize, x: &[Vector3<f64>]) {
        let f = &self.faces[j];
        let p = |n: u32| x[n as usize];
        let (xa, xb) = (f.a.map(p), f.b.map(p));
        self.cracks.push((j as u32, CrackState::new(&xa, &xb)));
        self.new_cracks.push(j as u32);
    }

    /// Joint `j`'s history for a checkpoint: damage, dissipated energy per
    /// area, mode code (0 intact), time of breaking (NaN while intact), and
    /// its crack's slip (3), closed flag and friction loss (zero while
    /// intact).
    pub fn save(&self, j: usize, crack_of: &[u32]) -> [f64; SAVED_JOINT] {
        let st = &self.states[j];
        let mut v = [0.0; SAVED_JOINT];
        v[0] = st.damage;
        v[1] = st.dissipated;
        v[2] = st.broken.map_or(0.0, |m| f64::from(m.code()));
        v[3] = self.broke_at[j];
        if let Some(&(_, c)) = self.cracks.get(crack_of[j] as usize) {
            v[4..7].copy_from_slice(c.slip.as_slice());
            v[7] = f64::from(u8::from(c.closed));
            v[8] = c.lost;
        }
        v
    }

    /// Per joint, its place in `cracks` (`u32::MAX` while intact).
    pub fn crack_index(&self) -> Vec<u32> {
        let mut at = vec![u32::MAX; self.faces.len()];
        for (k, &(j, _)) in self.cracks.iter().enumerate() {
            at[j as usize] = k as u32;
        }
        at
    }

    /// Put joint `j`'s saved history back ([`Self::save`]); a broken one's
    /// crack joins the cracks (and the new ones, for its faces to become
    /// boundary faces).
    pub fn restore(&mut self, j: usize, v: &[f64; SAVED_JOINT]) {
        let mode = match v[2] as u8 {
            1 => Some(Mode::Opening),
            2 => Some(Mode::Sliding),
            3 => Some(Mode::Mixed),
            4 => Some(Mode::Initial),
            _ => None,
        };
        self.states[j] = JointState {
            damage: v[0],
            dissipated: v[1],
            broken: mode,
        };
        self.broke_at[j] = v[3];
        self.cracks.retain(|c| c.0 as usize != j);
        self.new_cracks.retain(|&c| c as usize != j);
        if mode.is_some() {
            let slip = Vector3::new(v[4], v[5], v[6]);
            self.cracks.push((
                j as u32,
                CrackState {
                    slip,
                    closed: v[7] != 0.0,
                    slipping: false,
                    lost: v[8],
                },
            ));
            self.new_cracks.push(j as u32);
        }
    }

    /// Order the cracks as a run that broke them makes them: by time of
    /// breaking, then by joint (after [`Self::restore`]).
    pub fn sort_cracks(&mut self) {
        let at = &self.broke_at;
        self.cracks.sort_by(|a, b| {
            at[a.0 as usize]
                .total_cmp(&at[b.0 as usize])
                .then(a.0.cmp(&b.0))
        });
    }

    /// The counts and energies of the joints as they are (the stored
    /// energy, known only at a step, left at zero).
    pub fn recount(&self) -> JointTotals {
        let mut tot = JointTotals::default();
        for ((f, st), _) in self
            .faces
            .iter()
            .zip(&self.states)
            .zip(&self.counted)
            .filter(|(_, &c)| c)
        {
            tot.count(st, f.area);
        }
        for (_, c) in self
            .cracks
            .iter()
            .filter(|(j, _)| self.counted[*j as usize])
        {
            tot.friction += c.lost;
            tot.closed += usize::from(c.closed);
        }
        tot
    }

    /// The joints broken since the last call (indices into `faces`).
    pub fn take_new_cracks(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.new_cracks)
    }

    /// Advance every joint to the positions `x` (indexed by the faces'
    /// node numbers) at time `t` and write the forces on a's three corners
    /// to `out` (one entry per joint): an intact joint's tractions, a
    /// broken one's crack contact. The forces on b's corners are exactly
    /// their negatives (both kernels act corner pair by corner pair), so
    /// they are not stored. Returns the totals.
    pub fn forces(
        &mut self,
        x: &[Vector3<f64>],
        t: f64,
        out: &mut [[Vector3<f64>; 3]],
    ) -> JointTotals {
        let mut tot = JointTotals::default();
        let fresh = self.new_cracks.len();
        for (j, f) in self.faces.iter().enumerate() {
            // Gathered element by element (an array `map` here went through
            // the stack and stalled on store forwarding).
            let p = |n: u32| x[n as usize];
            let xa = [p(f.a[0]), p(f.a[1]), p(f.a[2])];
            let xb = [p(f.b[0]), p(f.b[1]), p(f.b[2])];
            let st = &mut self.states[j];
            let was_broken = st.broken.is_some();
            // b's forces are −a's: a local the compiler drops.
            let mut fb = [Vector3::zeros(); 3];
            let law = self.law.with_stiffness(self.stiffness[j]);
            let stored = joint_forces(&law, f.area, &xa, &xb, st, &mut out[j], &mut fb);
            if st.broken.is_some() && !was_broken {
                self.broke_at[j] = t;
                self.new_cracks.push(j as u32);
            }
            if self.counted[j] {
                tot.stored += stored;
                tot.count(st, f.area);
            }
        }
        // The joints that broke in this call start their crack contact
        // relaxed (the slip is their present sliding).
        for k in fresh..self.new_cracks.len() {
            let j = self.new_cracks[k] as usize;
            let f = &self.faces[j];
            let p = |n: u32| x[n as usize];
            let (xa, xb) = (f.a.map(p), f.b.map(p));
            self.cracks.push((j as u32, CrackState::new(&xa, &xb)));
        }
        let mu = self.law.friction();
        for (j, cs) in &mut self.cracks {
            let j = *j as usize;
            let f = &self.faces[j];
            let p = |n: u32| x[n as usize];
            let (xa, xb) = (f.a.map(p), f.b.map(p));
            let mut fb = [Vector3::zeros(); 3];
            let r = crack_forces(
                self.stiffness[j],
                mu,
                f.area,
                &xa,
                &xb,
                cs,
                &mut out[j],
                &mut fb,
            );
            debug_assert!((0..3).all(|i| fb[i] == -out[j][i]));
            if self.counted[j] {
                tot.stored += r.stored;
                tot.friction += cs.lost;
                tot.closed += usize::from(cs.closed);
            }
        }
        tot
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fracture::insert::make_discontinuous;
    use crate::fracture::law::table2;
    use crate::mechanics::element::to_vectors;

    /// Two tets sharing the face z = 0 (apexes at z = ∓h, h = 1 cm), both
    /// positively oriented: h, nodes and tets.
    fn two_tets() -> (f64, Vec<[f64; 3]>, Vec<[u32; 4]>) {
        let h = 0.01;
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [h, 0.0, 0.0],
            [0.0, h, 0.0],
            [0.0, 0.0, -h],
            [0.0, 0.0, h],
        ];
        (h, nodes, vec![[0, 2, 1, 3], [0, 1, 2, 4]])
    }

    /// Two tets sharing the face z = 0 (apexes at z = ∓h), jointed; the
    /// upper tet is pulled up rigidly, the lower held: the joint's force
    /// on the upper corners, summed, is the traction × area; its work is
    /// G_I × area when it breaks.
    #[test]
    fn two_tets_pulled_apart_give_f_t_and_g_i() {
        let (h, nodes, tets) = two_tets();
        // Both positively oriented.
        for t in &tets {
            let x = to_vectors(&t.map(|n| nodes[n as usize]));
            assert!((x[1] - x[0]).cross(&(x[2] - x[0])).dot(&(x[3] - x[0])) > 0.0);
        }
        let j = make_discontinuous(&nodes, &tets, &[true, true]);
        assert_eq!(j.joints.len(), 1);
        let m = table2();
        let mut set = JointSet::new(j.joints.clone(), &m).unwrap();
        let area = set.faces[0].area;
        assert!((area - 0.5 * h * h).abs() < 1e-15);
        let upper: Vec<usize> = (0..j.nodes.len())
            .filter(|&n| j.tets[1].contains(&(n as u32)))
            .collect();
        let x0: Vec<Vector3<f64>> = j.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let nf = 2.0 * m.g_i / m.tensile_strength;
        let steps = 20000;
        let (mut peak, mut work, mut prev) = (0.0f64, 0.0, 0.0);
        let mut out = vec![[Vector3::zeros(); 3]];
        let mut last = JointTotals::default();
        for i in 0..=steps {
            let lift = 1.1 * nf * i as f64 / steps as f64;
            let mut x = x0.clone();
            for &n in &upper {
                x[n].z += lift;
            }
            last = set.forces(&x, i as f64, &mut out);
            // Upward pull on the upper tet = −(the joint's force on it).
            let b_is_upper = upper.contains(&(set.faces[0].b[0] as usize));
            let on_a: f64 = out[0].iter().map(|f| f.z).sum();
            let on_upper = if b_is_upper { -on_a } else { on_a };
            let pull = -on_upper;
            peak = peak.max(pull / area);
            if i > 0 {
                work += 0.5 * (pull + prev) * (1.1 * nf / steps as f64);
            }
            prev = pull;
        }
        assert!(
            (peak / m.tensile_strength - 1.0).abs() < 1e-2,
            "peak {peak}"
        );
        assert!((work / (m.g_i * area) - 1.0).abs() < 1e-2, "work {work}");
        assert_eq!(last.broken, 1);
        assert!((last.crack_area - area).abs() < 1e-18);
        assert!((last.dissipated / (m.g_i * area) - 1.0).abs() < 1e-12);
        assert_eq!(last.stored, 0.0);
        assert!(set.broke_at[0] > 0.0 && set.broke_at[0] <= steps as f64);
    }

    /// Two copies of one broken joint, the second not counted (a joint
    /// another rank owns): the same forces, the totals of one joint.
    #[test]
    fn joints_not_counted_are_advanced_but_not_totalled() {
        let (h, nodes, tets) = two_tets();
        let j = make_discontinuous(&nodes, &tets, &[true, true]);
        let m = table2();
        let faces = vec![j.joints[0]; 2];
        let mut both = JointSet::new(faces.clone(), &m).unwrap();
        let mut one = JointSet::new(faces, &m).unwrap();
        one.count_only(vec![true, false]);
        let mut x: Vec<Vector3<f64>> = j.nodes.iter().map(|p| Vector3::from(*p)).collect();
        // Lift the upper tet well past breaking, in a few steps.
        let upper: Vec<usize> = (0..x.len())
            .filter(|&n| j.tets[1].contains(&(n as u32)))
            .collect();
        let (mut out_both, mut out_one) = (
            vec![[Vector3::zeros(); 3]; 2],
            vec![[Vector3::zeros(); 3]; 2],
        );
        let (mut t_both, mut t_one) = (JointTotals::default(), JointTotals::default());
        for i in 0..200 {
            for &n in &upper {
                x[n].z += 1e-4 * h;
            }
            t_both = both.forces(&x, i as f64, &mut out_both);
            t_one = one.forces(&x, i as f64, &mut out_one);
            assert_eq!(out_both, out_one, "step {i}: forces");
        }
        assert_eq!(t_both.broken, 2);
        assert_eq!(t_one.broken, 1);
        assert_eq!(t_one.crack_area, 0.5 * t_both.crack_area);
        assert_eq!(t_one.dissipated, 0.5 * t_both.dissipated);
        assert_eq!(one.recount().broken, 1);
        assert_eq!(one.take_new_cracks().len(), 2, "both break here");
    }

    #[test]
    fn a_joint_too_large_for_its_penalty_is_named() {
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 0.0, -3.0],
            [0.0, 0.0, 3.0],
        ];
        let tets = vec![[0, 2, 1, 3], [0, 1, 2, 4]];
        let j = make_discontinuous(&nodes, &tets, &[true, true]);
        let err = JointSet::new(j.joints, &table2()).unwrap_err();
        assert!(
            err.contains("tets 0 and 1") && err.contains("`g_i`"),
            "{err}"
        );
    }
}
