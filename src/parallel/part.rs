//! This rank's part of the mesh: the elements it owns, their nodes (owned
//! first, then the ghosts its elements touch), each with its global id;
//! the owner and PETSc number of every local node; which faces lie on
//! their body's boundary; and the boundary conditions resolved to these
//! nodes and faces. Every array here is of the size of the part, not of
//! the whole mesh.
//!
//! Numbering (the same on any rank count): elements and nodes keep the
//! global ids of the combined mesh (bodies in order, each contiguous). A
//! node is owned by the lowest rank among the elements that touch it;
//! rank r's owned nodes get the consecutive PETSc numbers [start_r,
//! end_r), in ascending global id.

use crate::mechanics::explicit::VelocityBc;
use crate::mesh::TetMesh;

/// Boundary conditions on the part's nodes and faces (local indices; as
/// [`GlobalBcs`], a whole model's with global ids).
#[derive(Debug, Clone, Default)]
pub struct LocalBcs {
    /// Initial temperature of every local node.
    pub initial_t: Vec<f64>,
    /// Prescribed temperatures of owned nodes (local index, value).
    pub dirichlet: Vec<(u32, f64)>,
    /// Per entry of `dirichlet`: the seconds over which its value is
    /// reached from the node's initial temperature (0: at once). Empty when
    /// nothing ramps (a part made from a whole mesh, in tests).
    pub dirichlet_ramp: Vec<f64>,
    /// Prescribed inward flux on faces of owned elements (local nodes, W/m²).
    pub flux: Vec<([u32; 3], f64)>,
    /// Convection on faces of owned elements (local nodes, h, T_env).
    pub convection: Vec<([u32; 3], f64, f64)>,
    /// Velocity conditions of every local node (mechanics; empty without).
    pub velocity: Vec<VelocityBc>,
    /// Dead-load nodal forces of every owned node (mechanics; empty without).
    pub traction: Vec<[f64; 3]>,
}

/// One rank's part of the mesh.
#[derive(Debug, Clone, Default)]
pub struct Part {
    /// This rank and the number of ranks.
    pub rank: usize,
    pub size: usize,
    /// The owned elements (ascending global id) over the local nodes;
    /// `mesh.body[e]` is the global body id, `mesh.nodes` the reference
    /// coordinates. No named sets (they are resolved into `bc`).
    pub mesh: TetMesh,
    /// Global id of every local element.
    pub elem_gid: Vec<u32>,
    /// Material of every local element.
    pub elem_material: Vec<u32>,
    /// Per element: bit i set when its face opposite node i lies on its
    /// body's boundary (a face on a cut between ranks is not).
    pub face_mask: Vec<u8>,
    /// Per element, when some body is Hex8 and the part was built from the
    /// model's bodies: the Table 1 index in its hex of each of its nodes
    /// (`io::checkpoint_hexes::NO_CORNER` for a Tet4 body's); else empty.
    pub hex_corner: Vec<[u8; 4]>,
    /// Global id of every local node: owned ones ascending, then ghosts ascending.
    pub node_gid: Vec<u32>,
    /// Number of owned nodes (the first ones).
    pub n_owned: usize,
    /// Owning rank of every local node.
    pub node_owner: Vec<u32>,
    /// PETSc number (thermal row) of every local node. The copies of a
    /// node that intact joints tie share one row (issue 19); otherwise
    /// each owned node has its own, in local order.
    pub petsc: Vec<u32>,
    /// First PETSc row of each rank, and the total at the end.
    pub starts: Vec<usize>,
    /// Per local node: whether it lies on its body's boundary.
    pub boundary_node: Vec<bool>,
    /// Boundary conditions resolved to the part.
    pub bc: LocalBcs,
    /// Maps over the whole mesh, present while the model is built on every
    /// rank (the contact stages still look up other ranks' nodes in them).
    pub whole: Option<WholeMaps>,
    /// The bodies this rank holds whole (global ids, ascending): all their
    /// elements and nodes are here and owned here.
    pub whole_bodies: Vec<u32>,
    /// The cohesive joints of the jointed bodies held (issue 19): of a
    /// body held whole, all its joints; of a split body, every joint with
    /// a corner in a tet here (those across the cut, and for a body
    /// jointed on a set those at its continuum nodes whose tets are all
    /// elsewhere; corners in no tet here are ghosts), corners over local
    /// nodes, tets by global id, by body and then in the order of the
    /// body's joints.
    pub joints: Vec<PartJoint>,
    /// Thermal rows of the bonded particles owned here (issue 21): the
    /// last ones of this rank's range, after the nodes' (bodies in
    /// ascending id, each body's owned spheres in its lattice's order).
    /// Zero without heat.
    pub particle_rows: usize,
    /// The bonded particles here (issue 21), per body with any
    /// ([`super::spheres`]): owned and ghost spheres, bonds and links.
    pub spheres: Vec<super::spheres::PartSpheres>,
    /// Whether the copies of a split jointed body tie thermal rows across
    /// the ranks (issue 19; the same on every rank): an owned node's row
    /// may then be another rank's ([`Part::remote_rows`]).
    pub rows_across: bool,
    /// With `rows_across`: the part's own prescribed temperatures (and
    /// ramps), before those of other ranks' copies joined them.
    pub(super) own_dirichlet: Option<OwnDirichlet>,
}

/// A part's own prescribed temperatures (local node, value) and ramps.
pub(super) type OwnDirichlet = (Vec<(u32, f64)>, Vec<f64>);

/// One cohesive joint of a part.
#[derive(Debug, Clone, Copy)]
pub struct PartJoint {
    /// Corners (local nodes), the two tets (global ids) and the area.
    pub faces: crate::fracture::insert::JointFaces,
    /// Fracture material (index into the model's materials).
    pub material: u32,
    /// Broken from the start (an initial crack of the scenario).
    pub broken: bool,
    /// Its body, and its place in the body's joints.
    pub body: u32,
    pub index: u32,
}

/// Per element and node of the whole mesh: its rank and PETSc number.
#[derive(Debug, Clone, Default)]
pub struct WholeMaps {
    /// Rank of every element.
    pub elem_part: Vec<u32>,
    /// Owning rank of every node.
    pub node_owner: Vec<u32>,
    /// PETSc number of every node.
    pub petsc_of: Vec<u32>,
}

impl Part {
    /// Number of owned nodes.
    pub fn num_owned(&self) -> usize {
        self.n_owned
    }

    /// Number of nodes over all ranks.
    pub fn num_global(&self) -> usize {
        *self.starts.last().unwrap_or(&0)
    }

    /// This rank's PETSc rows [start, end).
    pub fn owned_range(&self) -> (usize, usize) {
        (self.starts[self.rank], self.starts[self.rank + 1])
    }

    /// Number of this rank's PETSc rows: its owned nodes, less the copies
    /// that share a row with a node tied to them by intact joints, plus
    /// its particles' rows.
    pub fn owned_rows(&self) -> usize {
        self.starts[self.rank + 1] - self.starts[self.rank]
    }

    /// This rank's first particle row (PETSc numbering): its particle
    /// rows are [first, end of the owned range).
    pub fn first_particle_row(&self) -> usize {
        self.starts[self.rank + 1] - self.particle_rows
    }

    /// A value per owned node from a value per owned PETSc row (particle
    /// rows left out). Every owned node's row must be this rank's (not so
    /// with [`Part::rows_across`]: `thermal::node_rows` gathers the others).
    pub fn rows_to_nodes(&self, rows: &[f64]) -> Vec<f64> {
        if rows.len() == self.n_owned && self.particle_rows == 0 {
            return rows.to_vec();
        }
        let lo = self.starts[self.rank];
        self.petsc[..self.n_owned]
            .iter()
            .map(|&p| rows[p as usize - lo])
            .collect()
    }

    /// A value per owned PETSc row from a value per owned node (the copies
    /// sharing a row hold the same value; the last one's is taken; particle
    /// rows are zero). Copies whose row another rank owns are left out:
    /// that rank owns the row's lowest copy.
    pub fn nodes_to_rows(&self, nodes: &[f64]) -> Vec<f64> {
        let n = self.owned_rows();
        if n == self.n_owned && self.particle_rows == 0 {
            return nodes[..n].to_vec();
        }
        let lo = self.starts[self.rank];
        let mut rows = vec![0.0; n];
        for (&p, &v) in self.petsc[..self.n_owned].iter().zip(nodes) {
            if let Some(r) = rows.get_mut((p as usize).wrapping_sub(lo)) {
                *r = v;
            }
        }
        rows
    }

    /// Number of local elements.
    pub fn num_elements(&self) -> usize {
        self.elem_gid.len()
    }

    /// Local index of a node by global id, if it is local.
    pub fn local_node(&self, gid: u32) -> Option<u32> {
        let (owned, ghosts) = self.node_gid.split_at(self.n_owned);
        if let Ok(i) = owned.binary_search(&gid) {
            return Some(i as u32);
        }
        ghosts
            .binary_search(&gid)
            .ok()
            .map(|i| (self.n_owned + i) as u32)
    }

    /// Local index of an element by global id, if this rank owns it.
    pub fn local_element(&self, gid: u32) -> Option<u32> {
        self.elem_gid.binary_search(&gid).ok().map(|i| i as u32)
    }

    /// Global ids of the owned nodes (ascending).
    pub fn owned_gids(&self) -> &[u32] {
        &self.node_gid[..self.n_owned]
    }

    /// Collective. The halo of the part's ghost nodes (those its elements
    /// touch) with their owners.
    pub fn node_halo<C: mpi::traits::Communicator>(&self, comm: &C) -> Result<super::Halo, String> {
        let ghosts: Vec<(u32, u32, u32)> = (self.n_owned..self.node_gid.len())
            .map(|l| (self.node_gid[l], self.node_owner[l], l as u32))
            .collect();
        let owned = &self.node_gid[..self.n_owned];
        super::Halo::new(comm, &ghosts, |g| {
            owned.binary_search(&g).ok().map(|i| i as u32)
        })
    }

    /// Collective. Per owned node, the sum over all its elements (on any
    /// rank) of `share(e)` for each local element e touching it.
    pub fn sum_to_owned<C: mpi::traits::Communicator>(
        &self,
        comm: &C,
        halo: &super::Halo,
        share: impl Fn(usize) -> f64,
    ) -> Vec<f64> {
        let mut w = vec![0.0; self.node_gid.len()];
        for e in 0..self.num_elements() {
            let x = share(e);
            for &l in &self.mesh.tets[e] {
                w[l as usize] += x;
            }
        }
        halo.reverse_add(comm, &mut w, 1, |_| {});
        w.truncate(self.n_owned);
        w
    }

    /// Collective. Per owned node, the sum over all its elements (on any
    /// rank) of `share(e)`, added in ascending element id: the same bits on
    /// any number of ranks. Shares of ghost nodes travel to their owners
    /// one by one, not pre-summed.
    pub fn sum_to_owned_in_order<C: mpi::traits::Communicator>(
        &self,
        comm: &C,
        share: impl Fn(usize) -> f64,
    ) -> Vec<f64> {
        self.sum_corners_to_owned_in_order(comm, |e| [share(e); 4])
    }

    /// Collective. As [`Part::sum_to_owned_in_order`], element `e` giving
    /// `share(e)[c]` to its corner `c`.
    pub fn sum_corners_to_owned_in_order<C: mpi::traits::Communicator>(
        &self,
        comm: &C,
        share: impl Fn(usize) -> [f64; 4],
    ) -> Vec<f64> {
        let mut w = vec![0.0; self.n_owned];
        // Local elements ascend by id, so each owned node's local shares
        // arrive in id order; remote ones are merged in below.
        let mut ghost_terms: Vec<Vec<f64>> = vec![Vec::new(); self.size];
        let mut local_terms: Vec<(u32, u32, f64)> = Vec::new();
        let shared = self.shared_owned(comm);
        for e in 0..self.num_elements() {
            let xs = share(e);
            for (&l, &x) in self.mesh.tets[e].iter().zip(&xs) {
                let l = l as usize;
                if l >= self.n_owned {
                    let o = self.node_owner[l] as usize;
                    ghost_terms[o].extend_from_slice(&[
                        f64::from(self.node_gid[l]),
                        f64::from(self.elem_gid[e]),
                        x,
                    ]);
                } else if shared[l] {
                    local_terms.push((l as u32, self.elem_gid[e], x));
                } else {
                    w[l] += x;
                }
            }
        }
        let received = super::exchange::all_to_all(comm, ghost_terms);
        for rec in received.iter().flat_map(|r| r.chunks_exact(3)) {
            let l = self
                .local_node(rec[0] as u32)
                .expect("a ghost's owner holds it");
            local_terms.push((l, rec[1] as u32, rec[2]));
        }
        local_terms.sort_by_key(|&(l, e, _)| (l, e));
        for (l, _, x) in local_terms {
            w[l as usize] += x;
        }
        w
    }

    /// Collective. Per owned node, whether another rank ghosts it.
    fn shared_owned<C: mpi::traits::Communicator>(&self, comm: &C) -> Vec<bool> {
        let mut ask: Vec<Vec<u32>> = vec![Vec::new(); self.size];
        for l in self.n_owned..self.node_gid.len() {
            ask[self.node_owner[l] as usize].push(self.node_gid[l]);
        }
        let asked = super::exchange::all_to_all(comm, ask);
        let mut shared = vec![false; self.n_owned];
        for &g in asked.iter().flatten() {
            if let Some(l) = self.local_node(g) {
                shared[l as usize] = true;
            }
        }
        shared
    }

    /// The part's tets as the contact search reads them, with the local
    /// nodes at positions `x` (the reference ones when `None`).
    pub fn contact_tets(&self, x: Option<&[[f64; 3]]>) -> crate::contact::ContactTets {
        crate::contact::ContactTets {
            gid: self.elem_gid.clone(),
            body: self.mesh.body.clone(),
            material: self.elem_material.clone(),
            mask: self.face_mask.clone(),
            volume0: (0..self.num_elements())
                .map(|e| self.mesh.element_volume(e))
                .collect(),
            tets: self.mesh.tets.clone(),
            node_gid: self.node_gid.clone(),
            node_owner: self.node_owner.clone(),
            node_petsc: self.petsc.clone(),
            node_boundary: self.boundary_node.clone(),
            x: x.map_or_else(|| self.mesh.nodes.clone(), <[[f64; 3]]>::to_vec),
        }
    }

    /// The boundary tets of the part from the face masks: local element
    /// indices, their masks, and the boundary nodes.
    pub fn boundary_tets(&self) -> crate::contact::BoundaryTets {
        crate::contact::BoundaryTets::from_masks(&self.face_mask, self.boundary_node.clone())
    }

    /// Rank `rank`'s part (of `size`) of a model's bodies all made on this
    /// process ([`crate::model::Model::whole_mesh`]), for the element
    /// partition `elem_part` (tests).
    pub fn from_whole(
        w: &crate::model::WholeMesh,
        elem_part: &[u32],
        rank: usize,
        size: usize,
    ) -> Part {
        let bcs = GlobalBcs {
            initial_t: w.initial_t.clone(),
            dirichlet: w.dirichlet.clone(),
            dirichlet_ramp: Vec::new(),
            flux: w.flux.clone(),
            convection: w.convection.clone(),
            velocity: w.velocity.clone(),
            traction: w.traction.clone(),
        };
        let mut p = Part::from_global(&w.mesh, &w.material, elem_part, rank, size, &bcs);
        p.whole = None;
        p
    }

    /// Build rank `rank`'s part (of `size`) from the whole mesh and an
    /// element partition `elem_part`, with the boundary conditions of
    /// `bcs` given per global node and face. Used where the whole mesh
    /// exists (a model built on every rank, tests).
    pub fn from_global(
        mesh: &TetMesh,
        elem_material: &[u32],
        elem_part: &[u32],
        rank: usize,
        size: usize,
        bcs: &GlobalBcs,
    ) -> Part {
        let nn = mesh.nodes.len();
        let mut owner = vec![u32::MAX; nn];
        for (e, t) in mesh.tets.iter().enumerate() {
            for &n in t {
                owner[n as usize] = owner[n as usize].min(elem_part[e]);
            }
        }
        // Nodes used by no element (refused by the mesh checks) go to rank 0.
        owner
            .iter_mut()
            .filter(|o| **o == u32::MAX)
            .for_each(|o| *o = 0);
        let mut counts = vec![0usize; size];
        for &o in &owner {
            counts[o as usize] += 1;
        }
        let mut starts = vec![0usize; size + 1];
        for r in 0..size {
            starts[r + 1] = starts[r] + counts[r];
        }
        let mut next = starts.clone();
        let mut petsc_of = vec![0u32; nn];
        for (n, &o) in owner.iter().enumerate() {
            petsc_of[n] = next[o as usize] as u32;
            next[o as usize] += 1;
        }
        let rank32 = rank as u32;
        let elems: Vec<u32> = (0..mesh.tets.len() as u32)
            .filter(|&e| elem_part[e as usize] == rank32)
            .collect();
        let mut ghosts: Vec<u32> = elems
            .iter()
            .flat_map(|&e| mesh.tets[e as usize])
            .filter(|&n| owner[n as usize] != rank32)
            .collect();
        ghosts.sort_unstable();
        ghosts.dedup();
        let mut node_gid: Vec<u32> = (0..nn as u32)
            .filter(|&n| owner[n as usize] == rank32)
            .collect();
        let n_owned = node_gid.len();
        node_gid.extend_from_slice(&ghosts);
        let mut local = std::collections::HashMap::with_capacity(node_gid.len());
        for (i, &g) in node_gid.iter().enumerate() {
            local.insert(g, i as u32);
        }
        let bt = crate::contact::BoundaryTets::new(mesh);
        let l = |g: u32| local[&g];
        let part_mesh = TetMesh {
            nodes: node_gid.iter().map(|&g| mesh.nodes[g as usize]).collect(),
            tets: elems
                .iter()
                .map(|&e| mesh.tets[e as usize].map(l))
                .collect(),
            body: elems.iter().map(|&e| mesh.body[e as usize]).collect(),
            ..Default::default()
        };
        // A face goes to the rank that owns an element holding all three
        // of its nodes (on a body's boundary there is one such element).
        let sorted = |mut f: [u32; 3]| {
            f.sort_unstable();
            f
        };
        let owned_faces: std::collections::HashSet<[u32; 3]> = elems
            .iter()
            .flat_map(|&e| {
                let t = mesh.tets[e as usize];
                (0..4).map(move |k| crate::mesh::sorted_face(&t, k))
            })
            .collect();
        let here = |f: &[u32; 3]| owned_faces.contains(&sorted(*f));
        let flux: Vec<([u32; 3], f64)> = bcs
            .flux
            .iter()
            .filter(|(f, _)| here(f))
            .map(|(f, q)| (f.map(l), *q))
            .collect();
        let convection: Vec<([u32; 3], f64, f64)> = bcs
            .convection
            .iter()
            .filter(|(f, _, _)| here(f))
            .map(|(f, h, t)| (f.map(l), *h, *t))
            .collect();
        let bc = LocalBcs {
            initial_t: node_gid
                .iter()
                .map(|&g| bcs.initial_t[g as usize])
                .collect(),
            dirichlet: bcs
                .dirichlet
                .iter()
                .filter(|(g, _)| owner[*g as usize] == rank32)
                .map(|&(g, v)| (l(g), v))
                .collect(),
            dirichlet_ramp: Vec::new(),
            flux,
            convection,
            velocity: if bcs.velocity.is_empty() {
                Vec::new()
            } else {
                node_gid.iter().map(|&g| bcs.velocity[g as usize]).collect()
            },
            traction: if bcs.traction.is_empty() {
                Vec::new()
            } else {
                node_gid[..n_owned]
                    .iter()
                    .map(|&g| bcs.traction[g as usize])
                    .collect()
            },
        };
        Part {
            rank,
            size,
            face_mask: elems.iter().map(|&e| bt.mask[e as usize]).collect(),
            hex_corner: Vec::new(),
            boundary_node: node_gid
                .iter()
                .map(|&g| bt.boundary_node[g as usize])
                .collect(),
            elem_material: elems.iter().map(|&e| elem_material[e as usize]).collect(),
            mesh: part_mesh,
            elem_gid: elems,
            node_owner: node_gid.iter().map(|&g| owner[g as usize]).collect(),
            petsc: node_gid.iter().map(|&g| petsc_of[g as usize]).collect(),
            node_gid,
            n_owned,
            starts,
            bc,
            whole: Some(WholeMaps {
                elem_part: elem_part.to_vec(),
                node_owner: owner,
                petsc_of,
            }),
            whole_bodies: Vec::new(),
            joints: Vec::new(),
            spheres: Vec::new(),
            particle_rows: 0,
            rows_across: false,
            own_dirichlet: None,
        }
    }

    /// The whole-mesh maps (a model built on every rank has them).
    pub fn whole(&self) -> &WholeMaps {
        self.whole
            .as_ref()
            .expect("whole-mesh maps exist while the model is replicated")
    }
}

/// Boundary conditions per global node and face, as a model built on every
/// rank holds them ([`Part::from_global`]): the fields of [`LocalBcs`] with
/// global node ids, every node and face.
pub type GlobalBcs = LocalBcs;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    fn parts(mesh: &TetMesh, size: usize) -> Vec<Part> {
        let elem_part = crate::parallel::partition_elements(mesh, size).unwrap();
        let bcs = GlobalBcs {
            initial_t: vec![0.0; mesh.nodes.len()],
            flux: mesh.face_sets["xmin"].iter().map(|&f| (f, 1.0)).collect(),
            ..Default::default()
        };
        (0..size)
            .map(|r| Part::from_global(mesh, &vec![0; mesh.tets.len()], &elem_part, r, size, &bcs))
            .collect()
    }

    #[test]
    fn parts_number_every_node_once_and_split_the_faces() {
        let mesh = box_mesh([0.0; 3], [1.0, 0.5, 0.5], 0.25).unwrap();
        let ps = parts(&mesh, 3);
        let mut seen = vec![false; mesh.nodes.len()];
        for p in &ps {
            let (lo, hi) = p.owned_range();
            assert_eq!(hi - lo, p.num_owned());
            for l in 0..p.node_gid.len() {
                let (g, pe) = (p.node_gid[l], p.petsc[l] as usize);
                assert_eq!(p.local_node(g), Some(l as u32));
                if l < p.n_owned {
                    assert!(pe >= lo && pe < hi);
                    assert!(!seen[pe], "PETSc number {pe} twice");
                    seen[pe] = true;
                } else {
                    // A ghost's owner numbers it the same way.
                    let o = &ps[p.node_owner[l] as usize];
                    let lo_ = o.local_node(g).unwrap() as usize;
                    assert!(lo_ < o.n_owned);
                    assert_eq!(o.petsc[lo_] as usize, pe);
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
        let elems: usize = ps.iter().map(Part::num_elements).sum();
        assert_eq!(elems, mesh.tets.len());
        // Each flux face on exactly one rank.
        let faces: usize = ps.iter().map(|p| p.bc.flux.len()).sum();
        assert_eq!(faces, mesh.face_sets["xmin"].len());
        // Face masks: the body's boundary, not the cuts.
        let bt = crate::contact::BoundaryTets::new(&mesh);
        for p in &ps {
            for (e, &g) in p.elem_gid.iter().enumerate() {
                assert_eq!(p.face_mask[e], bt.mask[g as usize]);
            }
        }
    }
}
