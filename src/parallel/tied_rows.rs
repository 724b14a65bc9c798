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

/// The class of each of the `n` nodes of a jointed source mesh with
/// joints `j` (its lowest copy tied to it by intact joints; node numbers
/// of the mesh).
pub(super) fn mesh_classes(n: usize, j: &crate::model::SourceJoints) -> Vec<u32> {
    let ties = j
        .faces
        .iter()
        .zip(&j.broken)
        .filter(|(_, &b)| !b)
        .flat_map(|(f, _)| f.a.iter().copied().zip(f.b.iter().copied()));
    crate::fracture::vertices::vertex_classes(n, ties)
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
    /// (this rank's broken joints by their tets' global ids; merged over
    /// the ranks here). Empty without `rows_across`.
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
        let mine: Vec<u32> = broken.iter().flatten().copied().collect();
        let all: std::collections::HashSet<[u32; 2]> = super::exchange::all_gather(comm, &mine)
            .chunks_exact(2)
            .map(|t| [t[0], t[1]])
            .collect();
        let mut bodies: Vec<u32> = self
            .joints
            .iter()
            .map(|j| j.body)
            .filter(|b| self.whole_bodies.binary_search(b).is_err())
            .collect();
        bodies.dedup();
        for b in bodies {
            let body = &model.bodies[b as usize];
            let crate::model::BodySource::Mesh { mesh, .. } = body.source else {
                continue;
            };
            let src = &model.meshes[mesh as usize];
            let Some(j) = &src.joints else { continue };
            let (n0, e0) = (body.node_range.0, body.elem_range.0);
            let ties = j
                .faces
                .iter()
                .zip(&j.broken)
                .filter(|(f, &b)| !b && !all.contains(&f.tets.map(|e| e0 + e)))
                .flat_map(|(f, _)| f.a.iter().copied().zip(f.b.iter().copied()));
            let classes = crate::fracture::vertices::vertex_classes(src.mesh.nodes.len(), ties);
            for &g in &self.node_gid {
                if (n0..body.node_range.1).contains(&g) {
                    class_of.insert(g, n0 + classes[(g - n0) as usize]);
                }
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
