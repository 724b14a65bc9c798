//! Ownership and global numbering of nodes; local element lists; exact
//! preallocation counts for PETSc AIJ matrices.

use mpi::traits::*;

use crate::mesh::TetMesh;

/// How the mesh is distributed over the ranks.
#[derive(Debug, Clone)]
pub struct Layout {
    /// This rank.
    pub rank: usize,
    /// Number of ranks.
    pub size: usize,
    /// Part (rank) of every element.
    pub elem_part: Vec<u32>,
    /// Elements this rank assembles (original ids, ascending).
    pub owned_elems: Vec<u32>,
    /// Owning rank of every node.
    pub node_owner: Vec<u32>,
    /// PETSc global number of every original node.
    pub global_of: Vec<u32>,
    /// Original ids of this rank's owned nodes, in PETSc order.
    pub owned_nodes: Vec<u32>,
    /// First PETSc global number owned by each rank, plus the total at the end.
    pub starts: Vec<usize>,
}

impl Layout {
    /// Collective. Partition on rank 0 with METIS, broadcast, and number.
    pub fn new<C: Communicator>(comm: &C, mesh: &TetMesh) -> Result<Layout, String> {
        Self::new_weighted(comm, mesh, None, |_| Vec::new())
    }

    /// Collective. As [`Layout::new`], balancing per-element work
    /// `weights`, with the element pairs `links(mesh)` (computed on rank 0
    /// only) joined in the graph as well: touching bodies' boundary tets,
    /// so a packing is not cut through every contact.
    pub fn new_weighted<C: Communicator>(
        comm: &C,
        mesh: &TetMesh,
        weights: Option<&[i32]>,
        links: impl Fn(&TetMesh) -> Vec<(u32, u32)>,
    ) -> Result<Layout, String> {
        let size = comm.size() as usize;
        let rank = comm.rank() as usize;
        let ne = mesh.tets.len();
        let mut part: Vec<u32> = vec![0; ne];
        let mut status: i32 = 0;
        let links = |mesh: &TetMesh| {
            if size > 1 {
                links(mesh)
            } else {
                Vec::new()
            }
        };
        if rank == 0 {
            match super::partition_elements_weighted(mesh, size, weights, &links(mesh)) {
                Ok(p) => part = p,
                Err(_) => status = 1,
            }
        }
        comm.process_at_rank(0).broadcast_into(&mut status);
        if status != 0 {
            // Recompute on every rank to get the same message everywhere.
            return Err(
                super::partition_elements_weighted(mesh, size, weights, &links(mesh))
                    .err()
                    .unwrap_or_else(|| "partitioning failed".into()),
            );
        }
        if size > 1 {
            comm.process_at_rank(0).broadcast_into(&mut part[..]);
        }
        Ok(Self::from_partition(mesh, part, rank, size))
    }

    /// Build the numbering from a given element partition (pure; also used
    /// by tests to emulate any rank of any rank count).
    pub fn from_partition(mesh: &TetMesh, elem_part: Vec<u32>, rank: usize, size: usize) -> Layout {
        let nn = mesh.nodes.len();
        let mut node_owner = vec![u32::MAX; nn];
        for (e, t) in mesh.tets.iter().enumerate() {
            for &n in t {
                let o = &mut node_owner[n as usize];
                *o = (*o).min(elem_part[e]);
            }
        }
        // Nodes used by no element (should not happen after mesh checks) go to rank 0.
        for o in node_owner.iter_mut() {
            if *o == u32::MAX {
                *o = 0;
            }
        }
        let mut counts = vec![0usize; size];
        for &o in &node_owner {
            counts[o as usize] += 1;
        }
        let mut starts = vec![0usize; size + 1];
        for r in 0..size {
            starts[r + 1] = starts[r] + counts[r];
        }
        let mut next = starts.clone();
        let mut global_of = vec![0u32; nn];
        for (n, &o) in node_owner.iter().enumerate() {
            global_of[n] = next[o as usize] as u32;
            next[o as usize] += 1;
        }
        let owned_nodes: Vec<u32> = (0..nn as u32)
            .filter(|&n| node_owner[n as usize] as usize == rank)
            .collect();
        let owned_elems: Vec<u32> = (0..mesh.tets.len() as u32)
            .filter(|&e| elem_part[e as usize] as usize == rank)
            .collect();
        Layout {
            rank,
            size,
            elem_part,
            owned_elems,
            node_owner,
            global_of,
            owned_nodes,
            starts,
        }
    }

    /// Number of nodes this rank owns.
    pub fn num_owned(&self) -> usize {
        self.owned_nodes.len()
    }

    /// Total number of nodes.
    pub fn num_global(&self) -> usize {
        *self.starts.last().unwrap_or(&0)
    }

    /// This rank's range of PETSc global numbers.
    pub fn owned_range(&self) -> (usize, usize) {
        (self.starts[self.rank], self.starts[self.rank + 1])
    }

    /// Whether an original node is owned here.
    pub fn owns(&self, node: u32) -> bool {
        self.node_owner[node as usize] as usize == self.rank
    }

    /// Exact AIJ preallocation for the owned rows of the node-coupling
    /// matrix of `mesh` (nodes coupled when they share an element), plus
    /// any extra couplings `extra` (pairs of original node ids, both
    /// directions added): (diagonal-block, off-diagonal-block) counts.
    pub fn preallocation(&self, mesh: &TetMesh, extra: &[(u32, u32)]) -> (Vec<i32>, Vec<i32>) {
        let (lo, _hi) = self.owned_range();
        let n_owned = self.num_owned();
        // Owned-row incidence: row -> list of coupled global columns.
        let mut cols: Vec<Vec<u32>> = vec![Vec::new(); n_owned];
        for t in &mesh.tets {
            for &a in t {
                if self.owns(a) {
                    let r = self.global_of[a as usize] as usize - lo;
                    cols[r].extend(t.iter().map(|&b| self.global_of[b as usize]));
                }
            }
        }
        for &(a, b) in extra {
            for (x, y) in [(a, b), (b, a)] {
                if self.owns(x) {
                    let r = self.global_of[x as usize] as usize - lo;
                    cols[r].push(self.global_of[y as usize]);
                    cols[r].push(self.global_of[x as usize]);
                }
            }
        }
        let (glo, ghi) = (lo as u32, (lo + n_owned) as u32);
        let mut d = vec![0i32; n_owned];
        let mut o = vec![0i32; n_owned];
        for (r, c) in cols.iter_mut().enumerate() {
            c.sort_unstable();
            c.dedup();
            for &g in c.iter() {
                if g >= glo && g < ghi {
                    d[r] += 1;
                } else {
                    o[r] += 1;
                }
            }
            if c.is_empty() {
                d[r] = 1; // isolated node: keep a diagonal
            }
        }
        (d, o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    #[test]
    fn numbering_is_a_permutation_matching_ranges() {
        let mesh = box_mesh([0.0; 3], [1.0, 0.5, 0.5], 0.25).unwrap();
        let part = super::super::partition_elements(&mesh, 2).unwrap();
        let l0 = Layout::from_partition(&mesh, part.clone(), 0, 2);
        let l1 = Layout::from_partition(&mesh, part, 1, 2);
        let mut seen = vec![false; mesh.nodes.len()];
        for &g in &l0.global_of {
            assert!(!seen[g as usize]);
            seen[g as usize] = true;
        }
        assert_eq!(l0.num_owned() + l1.num_owned(), mesh.nodes.len());
        for &n in &l1.owned_nodes {
            let g = l1.global_of[n as usize] as usize;
            assert!(g >= l1.owned_range().0 && g < l1.owned_range().1);
        }
        assert_eq!(l0.owned_elems.len() + l1.owned_elems.len(), mesh.tets.len());
        assert!(!l0.owned_elems.is_empty() && !l1.owned_elems.is_empty());
    }

    #[test]
    fn preallocation_counts_node_neighbours() {
        let mesh = box_mesh([0.0; 3], [1.0, 1.0, 1.0], 1.0).unwrap();
        let l = Layout::from_partition(&mesh, vec![0; mesh.tets.len()], 0, 1);
        let (d, o) = l.preallocation(&mesh, &[]);
        assert!(o.iter().all(|&x| x == 0));
        // In a Kuhn-split cube the two diagonal corners touch all 8 nodes.
        assert_eq!(*d.iter().max().unwrap(), 8);
        assert!(d.iter().all(|&x| x >= 4));
    }
}
