//! The cohesive joints of a rank's jointed bodies (issue 19) in the
//! explicit loop: one [`JointSet`] per fracture material, advanced each
//! substep after the owned nodes' forces are summed. A jointed body is held
//! whole by one rank, so each of its nodes receives its joints' forces on
//! that rank, in the body's joint order: the same sums on any rank count.

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::fracture::set::{JointSet, JointTotals};
use crate::model::Model;
use crate::parallel::Part;

/// The joints of one rank.
#[derive(Debug, Clone, Default)]
pub(super) struct DomainJoints {
    /// One set per fracture material (ascending material index).
    pub(super) sets: Vec<JointSet>,
    /// Each set's forces of the last substep (a's corners, then b's).
    out: Vec<Vec<[Vector3<f64>; 6]>>,
    /// Totals of the last substep, over this rank's sets.
    pub(super) totals: JointTotals,
    /// Broken joints when the thermal rows were last numbered.
    rows_broken: usize,
}

impl DomainJoints {
    /// The joints of `part`'s free jointed bodies (`body_held[b]`: body b
    /// does not move, so its joints are left out). Errors name the
    /// material and the joint whose size makes the law snap back.
    pub(super) fn new(model: &Model, part: &Part, body_held: &[bool]) -> Result<DomainJoints> {
        let mut by_material: std::collections::BTreeMap<u32, Vec<_>> = Default::default();
        for j in &part.joints {
            let e = part
                .elem_gid
                .binary_search(&j.faces.tets[0])
                .expect("a joint's tet is held");
            if body_held[part.mesh.body[e] as usize] {
                continue;
            }
            by_material.entry(j.material).or_default().push(j.faces);
        }
        let mut d = DomainJoints::default();
        for (m, faces) in by_material {
            let mat = &model.materials[m as usize];
            let fm = mat.fracture.ok_or_else(|| {
                Error::Mechanics(format!("material `{}` has no fracture keys", mat.name))
            })?;
            let n = faces.len();
            let set = JointSet::new(faces, &fm)
                .map_err(|e| Error::Mechanics(format!("material `{}`: {e}", mat.name)))?;
            d.sets.push(set);
            d.out.push(vec![[Vector3::zeros(); 6]; n]);
        }
        Ok(d)
    }

    /// Whether there are joints here.
    pub(super) fn is_empty(&self) -> bool {
        self.sets.is_empty()
    }

    /// Advance every joint to the positions `x` at time `t` and add its
    /// forces to the owned nodes' forces `f`, joint by joint.
    pub(super) fn add_forces(&mut self, x: &[Vector3<f64>], t: f64, f: &mut [Vector3<f64>]) {
        let mut tot = JointTotals::default();
        for (set, out) in self.sets.iter_mut().zip(&mut self.out) {
            let s = set.forces(x, t, out);
            for (faces, forces) in set.faces.iter().zip(out.iter()) {
                for (k, &l) in faces.a.iter().chain(&faces.b).enumerate() {
                    f[l as usize] += forces[k];
                }
            }
            tot.stored += s.stored;
            tot.dissipated += s.dissipated;
            tot.broken += s.broken;
            for (t, m) in tot.by_mode.iter_mut().zip(s.by_mode) {
                *t += m;
            }
            tot.crack_area += s.crack_area;
        }
        self.totals = tot;
    }

    /// Joints broken here since the thermal rows were last numbered.
    pub(super) fn broken_since_rows(&self) -> usize {
        self.totals.broken - self.rows_broken
    }

    /// The tets (global ids) of every broken joint here; the rows are
    /// numbered again with them.
    pub(super) fn broken_tets(&mut self) -> std::collections::HashSet<[u32; 2]> {
        self.rows_broken = self.totals.broken;
        self.sets
            .iter()
            .flat_map(|s| {
                s.faces
                    .iter()
                    .zip(&s.states)
                    .filter(|(_, st)| st.broken.is_some())
                    .map(|(f, _)| f.tets)
            })
            .collect()
    }
}
