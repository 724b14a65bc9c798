//! The thermal rows of a jointed body split over the ranks (issue 19):
//! the copies of one vertex of the continuous mesh tied by intact joints
//! share one row, as in a body held whole, but they live on several
//! ranks. Each copy is named by its class (the lowest copy tied to it,
//! union-find over the body's intact joints in the model, the same on
//! every rank); the rank owning that lowest copy numbers the row, and the
//! other copies' ranks learn it through a rendezvous on the class at rank
//! class mod P. An owned node's row may then be another rank's: the
//! values of such rows are gathered ([`Part::remote_rows`]), and a
//! prescribed temperature on a copy goes to its row's owner
//! ([`Part::share_dirichlet`]).

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::exchange::all_to_all;
use super::Part;
use crate::fracture::insert::JointFaces;

/// The joints of a jointed source mesh `j` (over the continuous mesh's
/// `nodes`) at the vertices of the copies `copies`: every joint
/// with a corner at one of their vertices, so every tie between two
/// copies of such a vertex. Made from the numbering, only what is asked.
pub(super) fn joints_at(
    j: &crate::model::SourceJoints,
    nodes: &[[f64; 3]],
    copies: &[u32],
) -> Vec<(u32, JointFaces)> {
    j.joints_at(nodes, copies.iter().map(|&c| j.origin(c)))
}

/// The class (lowest copy tied to it by the intact joints among `at`,
/// those for which `intact` holds) of each copy of `nodes`, when `at`
/// holds every joint at their vertices ([`joints_at`]): the copies of
/// one vertex are tied only by joints at it. Local: no union-find over
/// the whole body.
pub(super) fn local_classes(
    nodes: &[u32],
    at: &[(u32, JointFaces)],
    intact: impl Fn(u32, &JointFaces) -> bool,
) -> HashMap<u32, u32> {
    let tied = crate::fracture::vertices::id_classes(
        at.iter()
            .filter(|(k, f)| intact(*k, f))
            .flat_map(|(_, f)| f.a.iter().copied().zip(f.b.iter().copied())),
    );
    nodes
        .iter()
        .map(|&n| (n, tied.get(&n).copied().unwrap_or(n)))
        .collect()
}

/// Collective. Which of the joints `asked` (each by its two tets' global
/// ids) are broken, from the ranks that hold them and offer their broken
/// joints `offered`: a rendezvous at rank (lower tet) mod P, so each rank
/// sends and receives only the joints at its own nodes.
fn broken_elsewhere(
    comm: &SimpleCommunicator,
    asked: &[[u32; 2]],
    offered: impl Iterator<Item = [u32; 2]>,
) -> std::collections::HashSet<[u32; 2]> {
    let size = comm.size() as usize;
    let at = |t: &[u32; 2]| t[0].min(t[1]) as usize % size;
    // Records [kind, tet, tet]: 0 asks, 1 offers.
    let mut send: Vec<Vec<u32>> = vec![Vec::new(); size];
    for t in asked {
        send[at(t)].extend_from_slice(&[0, t[0], t[1]]);
    }
    for t in offered {
        send[at(&t)].extend_from_slice(&[1, t[0], t[1]]);
    }
    let got = all_to_all(comm, send);
    let known: std::collections::HashSet<[u32; 2]> = got
        .iter()
        .flat_map(|v| v.chunks_exact(3))
        .filter(|r| r[0] == 1)
        .map(|r| [r[1], r[2]])
        .collect();
    let reply: Vec<Vec<u32>> = got
        .iter()
        .map(|v| {
            v.chunks_exact(3)
                .filter(|r| r[0] == 0 && known.contains(&[r[1], r[2]]))
                .flat_map(|r| [r[1], r[2]])
                .collect()
        })
        .collect();
    all_to_all(comm, reply)
        .iter()
        .flat_map(|v| v.chunks_exact(2))
        .map(|r| [r[0], r[1]])
        .collect()
}

/// Collective. The rows of the classes `wanted` (global ids of the lowest
/// copies, numbered on other ranks), from the ranks that own them and
/// offer them in `offered` (class, row): a rendezvous at rank class mod P.
pub(super) fn fetch_class_rows(
    comm: &SimpleCommunicator,
    wanted: &[u32],
    offered: &[(u32, u32)],
) -> HashMap<u32, u32> {
    let size = comm.size() as usize;
    // Records [kind, class, row]: 0 asks, 1 offers.
    let mut send: Vec<Vec<u32>> = vec![Vec::new(); size];
    for &c in wanted {
        send[c as usize % size].extend_from_slice(&[0, c, 0]);
    }
    for &(c, r) in offered {
        send[c as usize % size].extend_from_slice(&[1, c, r]);
    }
    let got = all_to_all(comm, send);
    let row_at: HashMap<u32, u32> = got
        .iter()
        .flat_map(|v| v.chunks_exact(3))
        .filter(|r| r[0] == 1)
        .map(|r| (r[1], r[2]))
        .collect();
    let reply: Vec<Vec<u32>> = got
        .iter()
        .map(|v| {
            v.chunks_exact(3)
                .filter(|r| r[0] == 0)
                .flat_map(|r| [r[1], row_at[&r[1]]])
                .collect()
        })
        .collect();
    all_to_all(comm, reply)
        .iter()
        .flat_map(|v| v.chunks_exact(2))
        .map(|r| (r[0], r[1]))
        .collect()
}

/// Collective. The rows of the owned nodes `elsewhere` (node, class) whose
/// class (lowest tied copy) another rank owns, put in `row_of` (the rows
/// of this rank's owned nodes, each class's lowest copy among them).
pub(super) fn fill_elsewhere(
    comm: &SimpleCommunicator,
    class_of: &HashMap<u32, u32>,
    row_of: &mut HashMap<u32, u32>,
    elsewhere: Vec<(u32, u32)>,
) {
    let mut wanted: Vec<u32> = elsewhere.iter().map(|&(_, c)| c).collect();
    wanted.sort_unstable();
    wanted.dedup();
    let offered: Vec<(u32, u32)> = class_of
        .iter()
        .filter(|(g, c)| g == c)
        .filter_map(|(&g, _)| row_of.get(&g).map(|&r| (g, r)))
        .collect();
    let rows = fetch_class_rows(comm, &wanted, &offered);
    for (g, c) in elsewhere {
        row_of.insert(g, rows[&c]);
    }
}

impl Part {
    /// Collective when [`Part::rows_across`]. The class of every local
    /// node of the split jointed bodies here (global ids), over their
    /// joints that are intact: not broken at the start, nor in `broken`
    /// (this rank's broken joints by their tets' global ids), nor broken
    /// on another rank. Each rank looks only at the joints at its nodes'
    /// vertices ([`joints_at`]) and learns the state of those it does not
    /// hold from the ranks that do ([`broken_elsewhere`]). Empty without
    /// `rows_across`.
    pub(super) fn split_classes(
        &self,
        comm: &SimpleCommunicator,
        model: &crate::model::Model,
        broken: &std::collections::HashSet<[u32; 2]>,
    ) -> HashMap<u32, u32> {
        let mut class_of = HashMap::new();
        if !self.rows_across {
            return class_of;
        }
        let mut bodies: Vec<u32> = self
            .mesh
            .body
            .iter()
            .copied()
            .filter(|b| self.whole_bodies.binary_search(b).is_err())
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        // Per split jointed body here: its joints at the nodes here, and
        // those of them this rank does not hold (by their tets).
        let mut found = Vec::new();
        let mut asked: Vec<[u32; 2]> = Vec::new();
        for b in bodies {
            let body = &model.bodies[b as usize];
            let crate::model::BodySource::Mesh { mesh, .. } = body.source else {
                continue;
            };
            let src = &model.meshes[mesh as usize];
            let Some(j) = &src.joints else {
                continue;
            };
            let (n0, e0) = (body.node_range.0, body.elem_range.0);
            let nodes: Vec<u32> = self
                .node_gid
                .iter()
                .filter(|&&g| (n0..body.node_range.1).contains(&g))
                .map(|&g| g - n0)
                .collect();
            let at = joints_at(j, &src.mesh.nodes, &nodes);
            let held: std::collections::HashSet<u32> = self
                .joints
                .iter()
                .filter(|pj| pj.body == b)
                .map(|pj| pj.index)
                .collect();
            asked.extend(
                at.iter()
                    .filter(|(k, _)| !held.contains(k) && !j.broken_at_start(*k))
                    .map(|(_, f)| f.tets.map(|e| e0 + e)),
            );
            found.push((j, n0, e0, nodes, at));
        }
        let elsewhere = broken_elsewhere(comm, &asked, broken.iter().copied());
        for (j, n0, e0, nodes, at) in found {
            let intact = |k: u32, f: &JointFaces| {
                let t = f.tets.map(|e| e0 + e);
                !j.broken_at_start(k) && !broken.contains(&t) && !elsewhere.contains(&t)
            };
            for (n, c) in local_classes(&nodes, &at, intact) {
                class_of.insert(n0 + n, n0 + c);
            }
        }
        class_of
    }

    /// The rows of owned nodes that another rank owns (a copy tied to a
    /// lower copy there), ascending and distinct.
    pub fn remote_rows(&self) -> Vec<i32> {
        let (lo, hi) = self.owned_range();
        let mut r: Vec<i32> = self.petsc[..self.n_owned]
            .iter()
            .filter(|&&p| !(lo..hi).contains(&(p as usize)))
            .map(|&p| p as i32)
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    }

    /// A value per owned node from the owned rows `rows` and the values
    /// `remote` of [`Self::remote_rows`] (in its order).
    pub fn rows_to_nodes_with(&self, rows: &[f64], remote: &[f64]) -> Vec<f64> {
        let (lo, hi) = self.owned_range();
        let far = self.remote_rows();
        self.petsc[..self.n_owned]
            .iter()
            .map(|&p| {
                if (lo..hi).contains(&(p as usize)) {
                    rows[p as usize - lo]
                } else {
                    remote[far.binary_search(&(p as i32)).expect("a remote row")]
                }
            })
            .collect()
    }

    /// Collective. The prescribed temperatures of owned copies whose row
    /// another rank owns, given to that rank: it prescribes its row
    /// through one of its own copies (the lowest), unless one already is.
    /// Nothing moves unless [`Part::rows_across`].
    pub(super) fn share_dirichlet(&mut self, comm: &SimpleCommunicator) {
        if !self.rows_across {
            return;
        }
        // Start again from the part's own conditions (the rows move when
        // joints break).
        let own = self
            .own_dirichlet
            .get_or_insert_with(|| (self.bc.dirichlet.clone(), self.bc.dirichlet_ramp.clone()));
        (self.bc.dirichlet, self.bc.dirichlet_ramp) = own.clone();
        let (lo, hi) = self.owned_range();
        let owner = |p: usize| self.starts.partition_point(|&s| s <= p) - 1;
        let mut send: Vec<Vec<f64>> = vec![Vec::new(); self.size];
        for (k, &(l, v)) in self.bc.dirichlet.iter().enumerate() {
            let p = self.petsc[l as usize] as usize;
            if !(lo..hi).contains(&p) {
                let ramp = self.bc.dirichlet_ramp.get(k).copied().unwrap_or(0.0);
                send[owner(p)].extend_from_slice(&[p as f64, v, ramp]);
            }
        }
        let got = super::exchange::all_to_all(comm, send);
        let mut prescribed: std::collections::HashSet<u32> = self
            .bc
            .dirichlet
            .iter()
            .map(|&(l, _)| self.petsc[l as usize])
            .collect();
        let mut first: HashMap<u32, u32> = HashMap::new();
        for l in (0..self.n_owned as u32).rev() {
            first.insert(self.petsc[l as usize], l);
        }
        // One ramp per condition (none only in parts made from a whole mesh).
        let ramps = self.bc.dirichlet_ramp.len() == self.bc.dirichlet.len();
        for r in got.iter().flat_map(|v| v.chunks_exact(3)) {
            let p = r[0] as u32;
            if prescribed.insert(p) {
                self.bc.dirichlet.push((first[&p], r[1]));
                if ramps {
                    self.bc.dirichlet_ramp.push(r[2]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The classes a rank finds from the joints at its nodes' vertices are
    /// those of the union-find over every intact joint of the body, for
    /// any subset of the nodes, with joints broken here and there.
    #[test]
    fn local_classes_are_the_whole_bodys() {
        let m = crate::mesh::generate::box_mesh([0.0; 3], [1.0, 0.5, 0.5], 0.25).unwrap();
        let mut in_set = vec![false; m.tets.len()];
        for (t, s) in in_set.iter_mut().enumerate() {
            *s = t % 3 != 0;
        }
        let whole_build = crate::fracture::make_discontinuous(&m.nodes, &m.tets, &in_set);
        let src = crate::model::SourceMesh::jointed(m, vec![0; in_set.len()], &in_set, 0);
        let j = src.joints.as_ref().unwrap();
        let n = j.copies as usize;
        let intact = |k: u32| k % 5 != 2;
        let whole = crate::fracture::vertices::vertex_classes(
            n,
            (0..whole_build.joints.len() as u32)
                .filter(|&k| intact(k))
                .flat_map(|k| {
                    let f = &whole_build.joints[k as usize];
                    f.a.iter().copied().zip(f.b.iter().copied())
                }),
        );
        for stride in [1usize, 3, 7, 11] {
            let nodes: Vec<u32> = (0..n as u32)
                .filter(|v| (*v as usize).is_multiple_of(stride))
                .collect();
            let at = joints_at(j, &src.mesh.nodes, &nodes);
            let local = local_classes(&nodes, &at, |k, _| intact(k));
            assert_eq!(local.len(), nodes.len());
            for &v in &nodes {
                assert_eq!(local[&v], whole[v as usize], "node {v}, every {stride}");
            }
        }
    }
}
