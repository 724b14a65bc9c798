//! The node copies and joints of a mesh made discontinuous
//! ([`super::insert::make_discontinuous`]), numbered without making them:
//! a tet's copies from a prefix count over the tets, a joint's number from
//! a prefix count over the continuous mesh's nodes (the joints whose
//! lowest corner is each node). The numbers are those of the whole-body
//! build, so any list of tets (a rank's part) gets its copies and the
//! joints at them, numbered as every rank numbers them, from the
//! continuous mesh and arrays of ints of its size (no array of all the
//! copies or joints). Free of MPI and PETSc.

use super::insert::{joint_faces, JointFaces, FACES};

/// Copy and joint numbers of a mesh made discontinuous on a set of tets.
#[derive(Debug, Clone)]
pub struct Numbering {
    /// Per tet: the number of its first new copy (the copies the tets
    /// before it made).
    start: Vec<u32>,
    /// Per node: the first tet outside the set at it (`u32::MAX`: none),
    /// the tet that makes its shared copy.
    first_plain: Vec<u32>,
    /// Per node, and one past the last: the joints whose faces' lowest
    /// corner is a lower node.
    joints_before: Vec<u32>,
    /// Node → tets at it (compressed rows).
    at_offsets: Vec<u32>,
    at_tets: Vec<u32>,
}

/// A shared face (sorted corners) with its two tets (lower first) and the
/// local face in the lower.
type Shared = ([u32; 3], (u32, usize), u32);

impl Numbering {
    /// The numbering of `tets` (over `nodes` nodes) made discontinuous on
    /// the tets of `in_set`.
    pub fn new(nodes: usize, tets: &[[u32; 4]], in_set: &[bool]) -> Numbering {
        assert_eq!(tets.len(), in_set.len());
        let mut first_plain = vec![u32::MAX; nodes];
        let mut at_offsets = vec![0u32; nodes + 1];
        for (t, tet) in tets.iter().enumerate() {
            for &g in tet {
                at_offsets[g as usize + 1] += 1;
                if !in_set[t] && first_plain[g as usize] == u32::MAX {
                    first_plain[g as usize] = t as u32;
                }
            }
        }
        for n in 0..nodes {
            at_offsets[n + 1] += at_offsets[n];
        }
        let mut fill = at_offsets.clone();
        let mut at_tets = vec![0u32; 4 * tets.len()];
        for (t, tet) in tets.iter().enumerate() {
            for &g in tet {
                at_tets[fill[g as usize] as usize] = t as u32;
                fill[g as usize] += 1;
            }
        }
        let mut start = Vec::with_capacity(tets.len());
        let mut next = 0u32;
        for (t, tet) in tets.iter().enumerate() {
            start.push(next);
            next += if in_set[t] {
                4
            } else {
                tet.iter()
                    .filter(|&&g| first_plain[g as usize] == t as u32)
                    .count() as u32
            };
        }
        let mut num = Numbering {
            start,
            first_plain,
            joints_before: vec![0; nodes + 1],
            at_offsets,
            at_tets,
        };
        for n in 0..nodes {
            num.joints_before[n + 1] =
                num.joints_before[n] + num.shared_at(n as u32, tets, in_set).len() as u32;
        }
        num
    }

    /// Bytes of its arrays: about 20 per tet and 12 per node of the
    /// continuous mesh.
    pub fn heap_bytes(&self) -> usize {
        4 * (self.start.len()
            + self.first_plain.len()
            + self.joints_before.len()
            + self.at_offsets.len()
            + self.at_tets.len())
    }

    /// The tets at node `n`.
    pub fn tets_at(&self, n: u32) -> &[u32] {
        let n = n as usize;
        &self.at_tets[self.at_offsets[n] as usize..self.at_offsets[n + 1] as usize]
    }

    /// The joints' faces whose lowest corner is node `n`, in their order.
    fn shared_at(&self, n: u32, tets: &[[u32; 4]], in_set: &[bool]) -> Vec<Shared> {
        let mut faces: Vec<([u32; 3], u32, usize)> = Vec::new();
        for &t in self.tets_at(n) {
            for (f, loc) in FACES.iter().enumerate() {
                let mut key = loc.map(|l| tets[t as usize][l]);
                key.sort_unstable();
                if key[0] == n {
                    faces.push((key, t, f));
                }
            }
        }
        faces.sort_unstable();
        let mut out = Vec::new();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            let (p, q) = (faces[i], faces[i + 1..j].first().copied());
            if let (2, Some(q)) = (j - i, q) {
                if in_set[p.1 as usize] || in_set[q.1 as usize] {
                    out.push((p.0, (p.1, p.2), q.1));
                }
            }
            i = j;
        }
        out
    }

    /// How many copies and joints the whole mesh has.
    pub fn totals(&self, tets: &[[u32; 4]], in_set: &[bool]) -> (u32, u32) {
        let copies = match tets.len() {
            0 => 0,
            n => self.start[n - 1] + self.made(n - 1, tets, in_set),
        };
        (copies, *self.joints_before.last().unwrap_or(&0))
    }

    /// How many new copies tet `t` makes.
    fn made(&self, t: usize, tets: &[[u32; 4]], in_set: &[bool]) -> u32 {
        if in_set[t] {
            4
        } else {
            tets[t]
                .iter()
                .filter(|&&g| self.first_plain[g as usize] == t as u32)
                .count() as u32
        }
    }

    /// The copies of tet `t`'s corners.
    pub fn tet_copies(&self, t: u32, tets: &[[u32; 4]], in_set: &[bool]) -> [u32; 4] {
        let tu = t as usize;
        if in_set[tu] {
            return std::array::from_fn(|k| self.start[tu] + k as u32);
        }
        tets[tu].map(|g| {
            let first = self.first_plain[g as usize];
            let made_before = tets[first as usize]
                .iter()
                .take_while(|&&c| c != g)
                .filter(|&&c| self.first_plain[c as usize] == first)
                .count() as u32;
            self.start[first as usize] + made_before
        })
    }

    /// The node of the continuous mesh copy `c` is a copy of.
    pub fn origin(&self, c: u32, tets: &[[u32; 4]], in_set: &[bool]) -> u32 {
        // The tet that made it: the last whose first copy is at most c (a
        // tet that made none shares its start with the next).
        let t = self.start.partition_point(|&s| s <= c) - 1;
        let k = (c - self.start[t]) as usize;
        if in_set[t] {
            return tets[t][k];
        }
        tets[t]
            .iter()
            .copied()
            .filter(|&g| self.first_plain[g as usize] == t as u32)
            .nth(k)
            .unwrap_or_else(|| unreachable!("copy {c} is made by tet {t}"))
    }

    /// How many copies node `n` of the continuous mesh has.
    pub fn copies_of(&self, n: u32, in_set: &[bool]) -> u32 {
        let set = self
            .tets_at(n)
            .iter()
            .filter(|&&t| in_set[t as usize])
            .count() as u32;
        set + u32::from(self.first_plain[n as usize] != u32::MAX)
    }

    /// Every joint with a corner at one of the nodes `vertices` of the
    /// continuous mesh (ascending number): (number, faces).
    pub fn joints_at(
        &self,
        nodes: &[[f64; 3]],
        tets: &[[u32; 4]],
        in_set: &[bool],
        vertices: impl IntoIterator<Item = u32>,
    ) -> Vec<(u32, JointFaces)> {
        let mut at: Vec<u32> = vertices.into_iter().collect();
        at.sort_unstable();
        at.dedup();
        // A face at a vertex has its lowest corner among the nodes of the
        // tets at that vertex.
        let mut lowest: Vec<u32> = Vec::new();
        for &g in &at {
            for &t in self.tets_at(g) {
                for loc in FACES {
                    let face = loc.map(|l| tets[t as usize][l]);
                    if face.contains(&g) {
                        lowest.push(*face.iter().min().unwrap_or(&g));
                    }
                }
            }
        }
        lowest.sort_unstable();
        lowest.dedup();
        let mut joints = Vec::new();
        for n in lowest {
            for (k, (corners, a, tb)) in self.shared_at(n, tets, in_set).into_iter().enumerate() {
                if corners.iter().any(|c| at.binary_search(c).is_ok()) {
                    let ca = self.tet_copies(a.0, tets, in_set);
                    let cb = self.tet_copies(tb, tets, in_set);
                    let j = joint_faces(nodes, tets, a, tb, ca, cb);
                    joints.push((self.joints_before[n as usize] + k as u32, j));
                }
            }
        }
        joints.sort_unstable_by_key(|j| j.0);
        joints
    }

    /// Every joint, in number order: (number, sorted corners in the
    /// continuous mesh), made one lowest corner at a time.
    pub fn for_each_joint(
        &self,
        tets: &[[u32; 4]],
        in_set: &[bool],
        mut f: impl FnMut(u32, [u32; 3]),
    ) {
        for n in 0..self.first_plain.len() as u32 {
            for (k, (corners, _, _)) in self.shared_at(n, tets, in_set).into_iter().enumerate() {
                f(self.joints_before[n as usize] + k as u32, corners);
            }
        }
    }

    /// The copies the tets `held` (ascending) need and the joints at
    /// them, numbered as in the whole-body build: the copies of their
    /// corners, and every joint one of whose corners is among those
    /// copies (with its global number).
    pub fn part(
        &self,
        nodes: &[[f64; 3]],
        tets: &[[u32; 4]],
        in_set: &[bool],
        held: &[u32],
    ) -> PartJointed {
        let mut copies: Vec<(u32, u32)> = held
            .iter()
            .flat_map(|&t| {
                let c = self.tet_copies(t, tets, in_set);
                (0..4).map(move |k| (c[k], tets[t as usize][k]))
            })
            .collect();
        copies.sort_unstable();
        copies.dedup();
        let used = |c: u32| copies.binary_search_by_key(&c, |&(n, _)| n).is_ok();
        // The joints at a used copy have its vertex as a corner.
        let mut joints = self.joints_at(nodes, tets, in_set, copies.iter().map(|&(_, g)| g));
        joints.retain(|(_, j)| j.a.iter().chain(&j.b).any(|&c| used(c)));
        PartJointed { copies, joints }
    }
}

/// What a part of a mesh made discontinuous holds.
#[derive(Debug, Clone, PartialEq)]
pub struct PartJointed {
    /// The copies its tets need (ascending): (copy, node of the continuous mesh).
    pub copies: Vec<(u32, u32)>,
    /// The joints at those copies (ascending number): (number, faces).
    pub joints: Vec<(u32, JointFaces)>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fracture::insert::make_discontinuous;
    use crate::mesh::generate::box_mesh;

    /// Every part of a box, jointed on all its tets and on a set, holds
    /// the copies and joints of the whole-body build with their numbers,
    /// vertices and faces, and (cut into 3) fewer of them than the whole.
    #[test]
    fn parts_number_their_copies_and_joints_as_the_whole_body() {
        let m = box_mesh([0.0; 3], [1.0, 0.5, 0.25], 0.125).unwrap();
        let all = vec![true; m.tets.len()];
        let some: Vec<bool> = (0..m.tets.len()).map(|t| t % 3 != 1).collect();
        for in_set in [all, some] {
            let whole = make_discontinuous(&m.nodes, &m.tets, &in_set);
            let num = Numbering::new(m.nodes.len(), &m.tets, &in_set);
            assert_eq!(
                num.totals(&m.tets, &in_set),
                (whole.nodes.len() as u32, whole.joints.len() as u32)
            );
            for t in 0..m.tets.len() {
                assert_eq!(num.tet_copies(t as u32, &m.tets, &in_set), whole.tets[t]);
            }
            let n = m.tets.len() as u32;
            let mut seen = vec![false; whole.joints.len()];
            for (lo, hi) in [(0, n / 3), (n / 3, 2 * n / 3), (2 * n / 3, n)] {
                let held: Vec<u32> = (lo..hi).collect();
                let p = num.part(&m.nodes, &m.tets, &in_set, &held);
                for &(c, g) in &p.copies {
                    assert_eq!(whole.origin[c as usize], g);
                }
                // The whole build's joints at a copy here, and only they.
                let mut want: Vec<u32> = Vec::new();
                for (k, j) in whole.joints.iter().enumerate() {
                    let here = |c: &u32| p.copies.binary_search_by_key(c, |&(x, _)| x).is_ok();
                    if j.a.iter().chain(&j.b).any(here) {
                        want.push(k as u32);
                    }
                }
                let got: Vec<u32> = p.joints.iter().map(|j| j.0).collect();
                assert_eq!(got, want);
                for (k, j) in &p.joints {
                    assert_eq!(*j, whole.joints[*k as usize]);
                    seen[*k as usize] = true;
                }
                assert!(p.joints.len() < whole.joints.len());
                assert!(p.copies.len() < whole.nodes.len());
            }
            assert!(seen.iter().all(|&s| s), "every joint is in some part");
        }
    }

    /// Each copy's node, each node's copy count, the joints at a few
    /// nodes and the walk over every joint agree with the whole-body build.
    #[test]
    fn origins_and_joints_at_nodes_are_the_whole_bodys() {
        let m = box_mesh([0.0; 3], [1.0, 0.5, 0.25], 0.125).unwrap();
        let some: Vec<bool> = (0..m.tets.len()).map(|t| t % 4 != 1).collect();
        let whole = make_discontinuous(&m.nodes, &m.tets, &some);
        let num = Numbering::new(m.nodes.len(), &m.tets, &some);
        let mut count = vec![0u32; m.nodes.len()];
        for (c, &g) in whole.origin.iter().enumerate() {
            assert_eq!(num.origin(c as u32, &m.tets, &some), g);
            count[g as usize] += 1;
        }
        for (n, &k) in count.iter().enumerate() {
            assert_eq!(num.copies_of(n as u32, &some), k);
        }
        let vertices = [0u32, 7, 20, 33];
        let got = num.joints_at(&m.nodes, &m.tets, &some, vertices);
        let want: Vec<(u32, JointFaces)> = whole
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| {
                j.a.iter()
                    .any(|&c| vertices.contains(&whole.origin[c as usize]))
            })
            .map(|(k, j)| (k as u32, *j))
            .collect();
        assert!(!want.is_empty());
        assert_eq!(got, want);
        let mut walked = Vec::new();
        num.for_each_joint(&m.tets, &some, |k, corners| walked.push((k, corners)));
        assert_eq!(walked.len(), whole.joints.len());
        for (i, (k, corners)) in walked.iter().enumerate() {
            assert_eq!(*k, i as u32);
            let mut g = whole.joints[i].a.map(|c| whole.origin[c as usize]);
            g.sort_unstable();
            assert_eq!(*corners, g);
        }
    }

    /// The fully jointed 97,500-tet box of scenarios/bench-jointed-box.toml
    /// cut into 2 and 4 slabs of tets: each holds its share of the 390,000
    /// copies and of the 190,550 joints at most 10 % more (the joints on
    /// its one or two cuts: 1.4 % and 6.8 % measured), and the numbering
    /// 20 B per tet and 12 per node.
    #[test]
    fn a_part_of_the_jointed_box_holds_its_share() {
        let m = box_mesh([0.0; 3], [0.2, 0.1, 0.05], 0.004).unwrap();
        let n = m.tets.len() as u32;
        assert_eq!(n, 97_500);
        let in_set = vec![true; m.tets.len()];
        let num = Numbering::new(m.nodes.len(), &m.tets, &in_set);
        let (copies, joints) = num.totals(&m.tets, &in_set);
        assert_eq!((copies, joints), (390_000, 190_550));
        let bytes = num.heap_bytes();
        assert!(
            bytes <= 20 * m.tets.len() + 12 * m.nodes.len() + 16,
            "{bytes} B"
        );
        for p in [2u32, 4] {
            for k in 0..p {
                let held: Vec<u32> = (k * n / p..(k + 1) * n / p).collect();
                let part = num.part(&m.nodes, &m.tets, &in_set, &held);
                let share = |x: usize, whole: u32| x as f64 / (f64::from(whole) / f64::from(p));
                let (c, j) = (
                    share(part.copies.len(), copies),
                    share(part.joints.len(), joints),
                );
                eprintln!(
                    "{p} parts, part {k}: {} copies, {} joints ({c:.3}, {j:.3} of a share); \
                     numbering {bytes} B",
                    part.copies.len(),
                    part.joints.len()
                );
                assert!(c <= 1.0 + 1e-12 && j <= 1.1, "part {k} of {p}: {c}, {j}");
            }
        }
    }

    /// A part of nothing holds nothing; a tetless mesh has no copies.
    #[test]
    fn an_empty_part_holds_nothing() {
        let m = box_mesh([0.0; 3], [1.0, 1.0, 1.0], 0.5).unwrap();
        let in_set = vec![true; m.tets.len()];
        let num = Numbering::new(m.nodes.len(), &m.tets, &in_set);
        let p = num.part(&m.nodes, &m.tets, &in_set, &[]);
        assert!(p.copies.is_empty() && p.joints.is_empty());
        let none = Numbering::new(0, &[], &[]);
        assert_eq!(none.totals(&[], &[]), (0, 0));
    }
}
