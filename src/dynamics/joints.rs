//! The cohesive joints of a rank's jointed bodies (issue 19) in the
//! explicit loop: one [`JointSet`] per fracture material, advanced each
//! substep after the owned nodes' forces are summed.
//!
//! A body held whole has all its joints here. Of a jointed body split
//! over the ranks (`parallel::build`), every joint with a corner in a tet
//! here is here (its other corners are ghosts): a joint across the cut is
//! advanced on both its tets' ranks from the same positions, and a joint
//! at a continuum node of a body jointed on a set also on the ranks of
//! that node's other tets, so every joint at an owned node is here. Each
//! rank adds a joint's forces to its owned corners only. Each node thus
//! receives all its joints' forces on its rank, in the global order
//! (material, then body and joint): the same sums on any rank count. A
//! joint is owned once, by the rank of its lower tet: only there is it
//! counted in the totals, written out and checkpointed.

use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::fracture::set::{JointSet, JointTotals, SAVED_JOINT};
use crate::model::Model;
use crate::parallel::Part;

/// The joints of one rank.
#[derive(Debug, Clone, Default)]
pub(super) struct DomainJoints {
    /// One set per fracture material (ascending material index).
    pub(super) sets: Vec<JointSet>,
    /// Each set's forces of the last substep (a's corners, then b's).
    out: Vec<Vec<[Vector3<f64>; 3]>>,
    /// Totals of the last substep, over this rank's sets.
    pub(super) totals: JointTotals,
    /// Broken joints when the thermal rows were last numbered.
    rows_broken: usize,
    /// Which cracks were closed when the thermal contacts were last
    /// found (count, and a sum over their joints of a mix of the index).
    closed_seen: (usize, u64),
    /// Every joint of the part, in the part's order, for the output.
    rows: Vec<JointRow>,
    /// Local nodes below this are owned (receive joint forces here).
    n_owned: usize,
    /// The other tet of each joint owned here across a cut (global id):
    /// its corners (global node ids, in its order) and material, for the
    /// thermal contact of its crack.
    pub(super) remote_tets: std::collections::HashMap<u32, ([u32; 4], u32)>,
}

/// A joint of the part as the output sees it.
#[derive(Debug, Clone, Copy)]
struct JointRow {
    /// Global joint number ([`Model::joint_offsets`]).
    gid: u64,
    /// Its body.
    body: u32,
    /// Its set and place there (`u32::MAX`: a held body's, never advanced).
    set: u32,
    index: u32,
    faces: crate::fracture::insert::JointFaces,
    /// The reference positions of its a face's corners (a corner may be
    /// a ghost here: a continuum node of a body jointed on a set).
    a0: [[f64; 3]; 3],
    /// Owned here (its lower tet is here): counted, written, saved.
    owned: bool,
}

/// This rank's joints for the output, in its order: global numbers, and
/// per joint its a face's reference corners (three points), their
/// displacements, and the cell values.
#[derive(Debug, Clone, Default)]
pub struct JointRows {
    pub gid: Vec<u64>,
    pub corners: Vec<[f64; 3]>,
    pub displacement: Vec<f64>,
    /// Damage D in [0, 1].
    pub damage: Vec<f64>,
    /// 0 intact, 1 opening, 2 sliding, 3 mixed, 4 initial crack.
    pub mode: Vec<f64>,
    /// Time of breaking (s), −1 while intact.
    pub broke_at: Vec<f64>,
    /// Mean normal opening of the faces (m; negative when pressed).
    pub opening: Vec<f64>,
    /// Contact status of a crack's faces, the codes of the boundary
    /// faces' status grid (0 free, 2 closed, 3 sliding at the friction
    /// limit); −1 while the joint is intact (no surface there).
    pub status: Vec<f64>,
}

impl DomainJoints {
    /// The joints of `part`'s free jointed bodies (`body_held[b]`: body b
    /// does not move, so its joints are left out). Errors name the
    /// material and the joint whose size makes the law snap back.
    pub(super) fn new(model: &Model, part: &Part, body_held: &[bool]) -> Result<DomainJoints> {
        let mut by_material: std::collections::BTreeMap<u32, (Vec<_>, Vec<bool>, Vec<usize>)> =
            Default::default();
        let (offsets, _) = model.joint_offsets();
        let mut rows = Vec::with_capacity(part.joints.len());
        let mut remote_tets = std::collections::HashMap::new();
        for (k, j) in part.joints.iter().enumerate() {
            let body = j.body;
            let lower = j.faces.tets[0].min(j.faces.tets[1]);
            let upper = j.faces.tets[0].max(j.faces.tets[1]);
            if part.local_element(lower).is_some() && part.local_element(upper).is_none() {
                remote_tets.insert(upper, model.element_corners(body as usize, upper));
            }
            rows.push(JointRow {
                gid: offsets[body as usize] + u64::from(j.index),
                body,
                set: u32::MAX,
                index: 0,
                faces: j.faces,
                a0: j.faces.a.map(|n| part.mesh.nodes[n as usize]),
                owned: part.local_element(lower).is_some(),
            });
            if body_held[body as usize] {
                continue;
            }
            let e = by_material.entry(j.material).or_default();
            e.0.push(j.faces);
            e.1.push(j.broken);
            e.2.push(k);
        }
        let x: Vec<Vector3<f64>> = part.mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
        let mut d = DomainJoints::default();
        for (m, (faces, broken, at)) in by_material {
            for (i, &k) in at.iter().enumerate() {
                rows[k].set = d.sets.len() as u32;
                rows[k].index = i as u32;
            }
            let mat = &model.materials[m as usize];
            let fm = mat.fracture.ok_or_else(|| {
                Error::Mechanics(format!("material `{}` has no fracture keys", mat.name))
            })?;
            let n = faces.len();
            let mut set = JointSet::new(faces, &fm)
                .map_err(|e| Error::Mechanics(format!("material `{}`: {e}", mat.name)))?;
            for (j, _) in broken.iter().enumerate().filter(|(_, &b)| b) {
                set.start_broken(j, &x);
            }
            set.count_only(at.iter().map(|&k| rows[k].owned).collect());
            d.sets.push(set);
            d.out.push(vec![[Vector3::zeros(); 3]; n]);
        }
        d.rows = rows;
        d.n_owned = part.num_owned();
        d.remote_tets = remote_tets;
        Ok(d)
    }

    /// This rank's joints for the output at positions `x`.
    pub(super) fn output_rows(&self, x: &[Vector3<f64>]) -> JointRows {
        let mut r = JointRows::default();
        let crack_of: Vec<Vec<u32>> = self.sets.iter().map(|s| s.crack_index()).collect();
        for row in self.rows.iter().filter(|r| r.owned) {
            let f = &row.faces;
            r.gid.push(row.gid);
            for (&n, &p0) in f.a.iter().zip(&row.a0) {
                let (p, p0) = (x[n as usize], Vector3::from(p0));
                r.corners.push([p0.x, p0.y, p0.z]);
                r.displacement
                    .extend_from_slice(&[p.x - p0.x, p.y - p0.y, p.z - p0.z]);
            }
            let p = |n: u32| x[n as usize];
            r.opening
                .push(crate::fracture::crack::opening(&f.a.map(p), &f.b.map(p)));
            let (state, t) = match self.sets.get(row.set as usize) {
                Some(s) => (s.states[row.index as usize], s.broke_at[row.index as usize]),
                None => (Default::default(), f64::NAN),
            };
            let state: crate::fracture::JointState = state;
            r.damage.push(state.damage);
            r.mode
                .push(state.broken.map_or(0.0, |m| f64::from(m.code())));
            r.broke_at.push(if t.is_nan() { -1.0 } else { t });
            let crack = (self.sets.get(row.set as usize)).and_then(|s| {
                s.cracks
                    .get(crack_of[row.set as usize][row.index as usize] as usize)
            });
            r.status.push(match (state.broken, crack) {
                (None, _) => -1.0,
                (Some(_), Some((_, c))) => {
                    f64::from(crate::run::face_status(c.closed, c.slipping, false))
                }
                (Some(_), None) => f64::from(crate::run::face_status(false, false, false)),
            });
        }
        r
    }

    /// Joints advanced here whose owner this rank is.
    pub(super) fn num_owned(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.owned && r.set != u32::MAX)
            .count()
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
            // a's corners get the joint's forces, b's their negatives
            // (exactly: f − g is f + (−g) in floating point); a corner
            // owned elsewhere gets them on its own rank.
            let no = self.n_owned;
            for (faces, forces) in set.faces.iter().zip(out.iter()) {
                for ((&a, &b), force) in faces.a.iter().zip(&faces.b).zip(forces) {
                    let (a, b) = (a as usize, b as usize);
                    if a < no {
                        f[a] += force;
                    }
                    if b < no {
                        f[b] -= force;
                    }
                }
            }
            tot.add(&s);
        }
        self.totals = tot;
    }

    /// The faces of the joints broken since the last call: per crack, its
    /// two tets (global ids) and the corners of each side (local nodes).
    pub(super) fn take_new_cracks(&mut self) -> Vec<([u32; 2], [[u32; 3]; 2])> {
        let mut out = Vec::new();
        for s in &mut self.sets {
            for j in s.take_new_cracks() {
                let f = &s.faces[j as usize];
                out.push((f.tets, [f.a, f.b]));
            }
        }
        out
    }

    /// Per jointed body here (ascending id): its joints, broken joints
    /// (initial cracks not counted), crack area (m²), fracture energy (J),
    /// first break (s; NaN if none) and the sum of its joints' reference
    /// face centroids (m): `[body, joints, broken, area, energy, first, x, y, z]`,
    /// over the joints owned here (a split body's rows are summed over
    /// the ranks, [`merge_body_cracks`]).
    pub(super) fn body_cracks(&self) -> Vec<[f64; 9]> {
        let mut by: std::collections::BTreeMap<u32, [f64; 9]> = Default::default();
        for row in self.rows.iter().filter(|r| r.owned) {
            let r = by.entry(row.body).or_insert_with(|| {
                let mut v = [0.0; 9];
                v[0] = f64::from(row.body);
                v[5] = f64::NAN;
                v
            });
            r[1] += 1.0;
            let c = row
                .a0
                .iter()
                .map(|&p| Vector3::from(p))
                .sum::<Vector3<f64>>()
                / 3.0;
            for d in 0..3 {
                r[6 + d] += c[d];
            }
            let Some(s) = self.sets.get(row.set as usize) else {
                continue;
            };
            let (st, at) = (
                &s.states[row.index as usize],
                s.broke_at[row.index as usize],
            );
            r[4] += st.dissipated * row.faces.area;
            if matches!(st.broken, Some(m) if m != crate::fracture::Mode::Initial) {
                r[2] += 1.0;
                r[3] += row.faces.area;
                r[5] = if r[5].is_nan() { at } else { r[5].min(at) };
            }
        }
        by.into_values().collect()
    }

    /// Every owned joint's history for a checkpoint: global joint numbers
    /// and [`SAVED_JOINT`] values per joint (a held body's joints are intact).
    pub(super) fn saved(&self) -> (Vec<u32>, Vec<f64>) {
        let crack_of: Vec<Vec<u32>> = self.sets.iter().map(|s| s.crack_index()).collect();
        let mut gid = Vec::with_capacity(self.rows.len());
        let mut v = Vec::with_capacity(self.rows.len() * SAVED_JOINT);
        for row in self.rows.iter().filter(|r| r.owned) {
            gid.push(row.gid as u32);
            match self.sets.get(row.set as usize) {
                Some(s) => {
                    v.extend_from_slice(&s.save(row.index as usize, &crack_of[row.set as usize]))
                }
                None => {
                    let mut z = [0.0; SAVED_JOINT];
                    z[3] = f64::NAN;
                    v.extend_from_slice(&z);
                }
            }
        }
        (gid, v)
    }

    /// The global joint numbers of every joint here (owned or not), in
    /// the part's order.
    pub(super) fn gids(&self) -> Vec<u32> {
        self.rows.iter().map(|r| r.gid as u32).collect()
    }

    /// Put back the histories `values` of this rank's joints (in the order
    /// of [`Self::gids`]), as if the run had reached them: cracks in
    /// their order, totals, and the thermal rows' and closed cracks'
    /// bookkeeping taken as current.
    pub(super) fn restore(&mut self, values: &[[f64; SAVED_JOINT]]) {
        for (row, v) in self.rows.iter().zip(values) {
            if let Some(s) = self.sets.get_mut(row.set as usize) {
                s.restore(row.index as usize, v);
            }
        }
        let mut tot = JointTotals::default();
        for s in &mut self.sets {
            s.sort_cracks();
            tot.add(&s.recount());
        }
        self.totals = tot;
        self.rows_broken = tot.broken;
        self.closed_changed();
    }

    /// Whether the set of closed cracks differs from the last call's.
    pub(super) fn closed_changed(&mut self) -> bool {
        let mut stamp = (0usize, 0u64);
        for (k, s) in self.sets.iter().enumerate() {
            for (j, c) in &s.cracks {
                if c.closed {
                    let key = (k as u64) << 32 | u64::from(*j);
                    stamp.0 += 1;
                    stamp.1 = stamp
                        .1
                        .wrapping_add(key.wrapping_mul(0x9E37_79B9_7F4A_7C15));
                }
            }
        }
        let changed = stamp != self.closed_seen;
        self.closed_seen = stamp;
        changed
    }

    /// The cracks whose faces touched at the last substep: per crack, its
    /// two tets (global ids), the corners of each side (local nodes) and
    /// the face's reference area (m²).
    pub(super) fn closed_cracks(&self) -> Vec<([u32; 2], [[u32; 3]; 2], f64)> {
        self.sets
            .iter()
            .flat_map(|s| {
                // A crack across a cut meets once, on its joint's owner.
                s.cracks
                    .iter()
                    .filter(|&&(j, c)| c.closed && s.is_counted(j as usize))
                    .map(|&(j, _)| {
                        let f = &s.faces[j as usize];
                        (f.tets, [f.a, f.b], f.area)
                    })
            })
            .collect()
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

impl super::ExplicitDomain {
    /// The faces of joints broken since the last call become boundary
    /// faces of their tets here (and their corners boundary nodes), so that the
    /// contact search of other bodies sees them; each broken joint's own
    /// two faces meet through its crack contact ([`crate::fracture::crack`]).
    pub(super) fn mark_cracks(&mut self) {
        let own = &mut self.part_tets;
        let cracks = self.joints.take_new_cracks();
        self.cracks_marked |= !cracks.is_empty();
        for (tets, sides) in cracks {
            for (gid, face) in tets.iter().zip(&sides) {
                // Every corner here, as on one rank: a continuum node of a
                // body jointed on a set may be in tets here though the
                // face's own tet is on another rank.
                for &n in face {
                    own.node_boundary[n as usize] = true;
                }
                // The other side of a joint across the cut is marked on its rank.
                let Ok(e) = own.gid.binary_search(gid) else {
                    continue;
                };
                let opposite = own.tets[e]
                    .iter()
                    .position(|n| !face.contains(n))
                    .expect("a face of its tet");
                own.mask[e] |= 1 << opposite;
            }
        }
    }
}

/// Per jointed body, its row of [`DomainJoints::body_cracks`] summed over
/// the ranks' rows `rows` (any order; a split body has one per rank
/// owning some of its joints), the centroid sums made means: by body.
pub fn merge_body_cracks<'a>(rows: impl IntoIterator<Item = &'a [f64]>) -> Vec<[f64; 9]> {
    let mut by: std::collections::BTreeMap<u64, [f64; 9]> = Default::default();
    for r in rows {
        let at = by.entry(r[0] as u64).or_insert_with(|| {
            let mut v = [0.0; 9];
            v[0] = r[0];
            v[5] = f64::NAN;
            v
        });
        for k in [1, 2, 3, 4, 6, 7, 8] {
            at[k] += r[k];
        }
        // The earliest break; `min` ignores a NaN (no break).
        at[5] = at[5].min(r[5]);
    }
    by.into_values()
        .map(|mut r| {
            for d in 0..3 {
                r[6 + d] /= r[1];
            }
            r
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::merge_body_cracks;

    /// A split body's rows from two ranks make one: counts, areas and
    /// energies summed, the earliest break, the centroid over all joints;
    /// another body's row passes through.
    #[test]
    fn crack_rows_of_a_split_body_merge() {
        let nan = f64::NAN;
        let rows = [
            [3.0, 2.0, 1.0, 0.5, 0.25, 4.0, 2.0, 4.0, 6.0],
            [1.0, 1.0, 0.0, 0.0, 0.0, nan, 1.0, 1.0, 1.0],
            [3.0, 2.0, 0.0, 0.0, 0.5, nan, 6.0, 0.0, 2.0],
            [3.0, 4.0, 2.0, 1.0, 0.25, 3.0, 0.0, 4.0, 0.0],
        ];
        let m = merge_body_cracks(rows.iter().map(|r| &r[..]));
        assert_eq!(m.len(), 2);
        assert_eq!(m[0][..5], [1.0, 1.0, 0.0, 0.0, 0.0]);
        assert!(m[0][5].is_nan());
        assert_eq!(m[1], [3.0, 8.0, 3.0, 1.5, 1.0, 3.0, 1.0, 1.0, 1.0]);
    }
}
