//! The bonded particles of a body split over the ranks (issue 21): which
//! spheres a rank owns, which it holds as ghosts, and which bonds, links
//! and heat links it evaluates.
//!
//! A sphere is owned by the rank the recursive coordinate bisection gives
//! its centre (cut together with the body's elements, [`super::build`]),
//! or by the rank holding the body whole. A rank evaluates every bond with
//! an owned end and every link whose sphere it owns or whose element
//! point has a node of an element held here (so each owned node and
//! sphere receives all its bond and link forces in the body's fixed
//! order, as a joint lives on every rank holding a tet at one of its
//! corners, `dynamics::joints`); it assembles the heat links of the
//! elements it holds. The other ends are ghost spheres, whose motion and
//! temperature their owners forward every substep, and the links' element
//! nodes that no element here has are ghost nodes. Selecting them scans
//! the body's lattice, which the model holds as it holds the source mesh.

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::exchange::all_to_all;
use super::Part;
use crate::mesh::particle_region::ParticleRegion;
use crate::model::Model;

/// What one rank holds of one body's particles (indices into the body's
/// [`ParticleRegion`] lists, each ascending).
#[derive(Debug, Clone, Default)]
pub struct PartSpheres {
    /// The body (global id).
    pub body: u32,
    /// The spheres owned here.
    pub owned: Vec<u32>,
    /// The ghost spheres: other ends of the bonds and links here.
    pub ghosts: Vec<u32>,
    /// Per ghost: its owner rank, and its thermal row counted back from
    /// the end of the owner's range (rows move when joints renumber them,
    /// but the particles' rows stay the last of each range).
    pub ghost_owner: Vec<u32>,
    pub ghost_row_from_end: Vec<u32>,
    /// Bonds with an owned end.
    pub bonds: Vec<u32>,
    /// Links of an owned sphere or at an element point with a node of an
    /// element held here.
    pub links: Vec<u32>,
    /// Heat links whose element is held here.
    pub heat_links: Vec<u32>,
}

impl PartSpheres {
    /// What a rank owning the spheres `owned` and holding the elements
    /// `held` (per element of the body's mesh) with the nodes `used` (per
    /// node) evaluates of `region`; `tets` are the body mesh's elements.
    /// Returns it and the nodes the links need beyond `used`.
    pub(super) fn select(
        body: u32,
        region: &ParticleRegion,
        owned: Vec<u32>,
        held: &[bool],
        used: &[bool],
        tets: &[[u32; 4]],
    ) -> (PartSpheres, Vec<u32>) {
        let mut is_owned = vec![false; region.centres.len()];
        owned.iter().for_each(|&s| is_owned[s as usize] = true);
        let mut ghost = vec![false; region.centres.len()];
        let mut bonds = Vec::new();
        for (k, b) in region.bonds.iter().enumerate() {
            let (i, j) = (b.i as usize, b.j as usize);
            if is_owned[i] || is_owned[j] {
                bonds.push(k as u32);
                ghost[i] |= !is_owned[i];
                ghost[j] |= !is_owned[j];
            }
        }
        let mut links = Vec::new();
        let mut wanted = Vec::new();
        for (k, l) in region.links.iter().enumerate() {
            let point = tets[l.point_elem as usize];
            if is_owned[l.sphere as usize] || point.iter().any(|&n| used[n as usize]) {
                links.push(k as u32);
                ghost[l.sphere as usize] |= !is_owned[l.sphere as usize];
                for n in point.iter().chain(&tets[l.ghost_elem as usize]) {
                    if !used[*n as usize] {
                        wanted.push(*n);
                    }
                }
            }
        }
        let mut heat_links = Vec::new();
        for (k, l) in region.heat_links.iter().enumerate() {
            if held[l.point_elem as usize] {
                heat_links.push(k as u32);
                ghost[l.sphere as usize] |= !is_owned[l.sphere as usize];
            }
        }
        wanted.sort_unstable();
        wanted.dedup();
        let ghosts: Vec<u32> = (0..ghost.len() as u32)
            .filter(|&s| ghost[s as usize])
            .collect();
        let n = ghosts.len();
        let spheres = PartSpheres {
            body,
            owned,
            ghosts,
            ghost_owner: vec![0; n],
            ghost_row_from_end: vec![0; n],
            bonds,
            links,
            heat_links,
        };
        (spheres, wanted)
    }

    /// Whether nothing of the body is here.
    pub fn is_empty(&self) -> bool {
        self.owned.is_empty() && self.ghosts.is_empty()
    }
}

impl Part {
    /// The number of spheres owned here (over all bodies).
    pub fn owned_spheres(&self) -> usize {
        self.spheres.iter().map(|s| s.owned.len()).sum()
    }

    /// Collective. The owners of this rank's ghost spheres and their
    /// thermal rows, through a rendezvous on the global particle numbers
    /// (rank gid % size); the owned spheres' rows are this rank's last,
    /// bodies ascending, each body's spheres ascending.
    pub(super) fn locate_ghost_spheres(&mut self, comm: &SimpleCommunicator, model: &Model) {
        let size = comm.size() as usize;
        let (offsets, _) = model.particle_offsets();
        let total_owned = self.owned_spheres() as u32;
        // Records [kind, gid, value]: kind 0 an owner (value: row from the end), 1 a question.
        let mut send: Vec<Vec<u32>> = vec![Vec::new(); size];
        let mut k = 0u32;
        for s in &self.spheres {
            let first = offsets[s.body as usize] as u32;
            for &o in &s.owned {
                let g = first + o;
                send[g as usize % size].extend_from_slice(&[0, g, total_owned - k]);
                k += 1;
            }
            for &o in &s.ghosts {
                let g = first + o;
                send[g as usize % size].extend_from_slice(&[1, g, 0]);
            }
        }
        let got = all_to_all(comm, send);
        let mut owner_of: std::collections::HashMap<u32, [u32; 2]> = Default::default();
        for (r, list) in got.iter().enumerate() {
            for rec in list.chunks_exact(3).filter(|rec| rec[0] == 0) {
                owner_of.insert(rec[1], [r as u32, rec[2]]);
            }
        }
        let mut reply: Vec<Vec<u32>> = vec![Vec::new(); size];
        for (r, list) in got.iter().enumerate() {
            for rec in list.chunks_exact(3).filter(|rec| rec[0] == 1) {
                let [o, from_end] = owner_of[&rec[1]];
                reply[r].extend_from_slice(&[rec[1], o, from_end]);
            }
        }
        let answers: std::collections::HashMap<u32, [u32; 2]> = all_to_all(comm, reply)
            .iter()
            .flat_map(|v| v.chunks_exact(3))
            .map(|rec| (rec[0], [rec[1], rec[2]]))
            .collect();
        for s in &mut self.spheres {
            let first = offsets[s.body as usize] as u32;
            for (k, &o) in s.ghosts.iter().enumerate() {
                let [owner, from_end] = answers[&(first + o)];
                s.ghost_owner[k] = owner;
                s.ghost_row_from_end[k] = from_end;
            }
        }
        tracing::debug!(
            target: "particles",
            rank = comm.rank(),
            owned = total_owned,
            ghosts = self.spheres.iter().map(|s| s.ghosts.len()).sum::<usize>(),
            "spheres here"
        );
    }

    /// The thermal row of body sphere list `s`'s ghost number `k`.
    pub fn ghost_sphere_row(&self, s: &PartSpheres, k: usize) -> usize {
        self.starts[s.ghost_owner[k] as usize + 1] - s.ghost_row_from_end[k] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bar 0..12r × 0..4r × 0..4r of elements of side r, x in [4r, 8r]
    /// particles (2 × 2 × 2 spheres of radius r), cut at x = 6r for the
    /// spheres and at x = 3r for the elements: the rank owns the left
    /// spheres and holds the elements left of the cut, not the interface's.
    #[test]
    fn a_rank_left_of_the_cut_gets_the_bonds_links_and_nodes_it_needs() {
        let r = 1e-3;
        let (_, fe, region) = crate::mesh::particle_region::tests::bar(r);
        assert_eq!(region.centres.len(), 8);
        let left = |s: u32| region.centres[s as usize][0] < 6.0 * r;
        let owned: Vec<u32> = (0..8).filter(|&s| left(s)).collect();
        assert_eq!(owned.len(), 4);
        let centroid_x = |e: usize| {
            fe.tets[e]
                .iter()
                .map(|&n| fe.nodes[n as usize][0])
                .sum::<f64>()
                / 4.0
        };
        let held: Vec<bool> = (0..fe.tets.len())
            .map(|e| centroid_x(e) < 3.0 * r)
            .collect();
        let mut used = vec![false; fe.nodes.len()];
        for (_, t) in fe.tets.iter().enumerate().filter(|(e, _)| held[*e]) {
            t.iter().for_each(|&n| used[n as usize] = true);
        }
        let (s, wanted) = PartSpheres::select(0, &region, owned.clone(), &held, &used, &fe.tets);
        // The bonds with an end left of the cut, in the body's order.
        let with_left: Vec<u32> = (0..region.bonds.len() as u32)
            .filter(|&k| {
                let b = &region.bonds[k as usize];
                left(b.i) || left(b.j)
            })
            .collect();
        assert!(with_left.len() < region.bonds.len());
        assert_eq!(s.bonds, with_left);
        // The right spheres are ghosts (each bonded to a left one).
        let right: Vec<u32> = (0..8).filter(|&s| !left(s)).collect();
        assert_eq!(s.ghosts, right);
        // The links here are those of the owned spheres (the right
        // interface's elements have no node here).
        let mine: Vec<u32> = (0..region.links.len() as u32)
            .filter(|&k| left(region.links[k as usize].sphere))
            .collect();
        assert!(!mine.is_empty());
        assert_eq!(s.links, mine);
        // Their elements' nodes are here or wanted, and some are wanted (x = 4r).
        assert!(!wanted.is_empty());
        assert!(wanted.iter().all(|&n| !used[n as usize]));
        for &k in &s.links {
            let l = &region.links[k as usize];
            for n in fe.tets[l.point_elem as usize]
                .iter()
                .chain(&fe.tets[l.ghost_elem as usize])
            {
                assert!(used[*n as usize] || wanted.binary_search(n).is_ok());
            }
        }
        // No element at the interface is held: no heat link is assembled here.
        assert!(s.heat_links.is_empty());
    }
}
