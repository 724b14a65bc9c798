//! The free spheres in checkpoints (issue 21): what a rank saves of its
//! slab (`io::checkpoint_spheres`) and how a restart on any number of
//! ranks puts it back. Each rank reads a block of sphere numbers and a
//! block of each spring list; the springs go to the ranks whose block
//! holds their spheres, and then every sphere, with its springs, goes to
//! the owner of its slab by the same exchange the substeps use, which
//! also makes the ghosts. So the restored slabs hold what the run's slabs
//! held at the checkpoint, on any number of ranks. With heat, each
//! sphere's temperature travels with it and the heat account goes back as
//! the energy account does.

use std::collections::HashSet;

use mpi::topology::SimpleCommunicator;

use crate::error::Result;
use crate::io::checkpoint_particles::GlobalRows;
use crate::io::checkpoint_spheres::{
    SavedSpheres, SphereCheckpoint, SAVED_SPHERE, SAVED_SPHERE_FACE, SAVED_SPHERE_PAIR,
};
use crate::io::checkpoint_springs::sorted_by_key;
use crate::mechanics::sphere_contacts::Histories;
use crate::parallel::exchange::{all_to_all, block_owner};

use super::{v3, DomainSpheres, SphereReport, V3};

/// Tags of the springs' records on their way to the block ranks.
const PAIR: f64 = 0.0;
const FACE: f64 = 1.0;

impl DomainSpheres {
    /// Collective. This rank's share of a checkpoint: its owned spheres,
    /// the springs of the pairs whose lower number it owns and of its
    /// owned spheres' face contacts (both lists sorted over the ranks),
    /// and its account.
    pub(in crate::dynamics) fn saved(&self, comm: &SimpleCommunicator) -> SphereCheckpoint {
        let no = self.n_owned;
        let mut values = Vec::with_capacity(no * SAVED_SPHERE);
        for i in 0..no {
            values.push(f64::from(self.set[i]));
            for a in [&self.x0[i], &self.x[i], &self.v[i], &self.w[i]] {
                values.extend_from_slice(a.as_slice());
            }
        }
        let owned: HashSet<u64> = self.gid[..no].iter().copied().collect();
        let mut pairs = Vec::new();
        for (&(a, b), xi) in &self.history.pair {
            if owned.contains(&a) {
                pairs.extend_from_slice(&[a as f64, b as f64, xi.x, xi.y, xi.z]);
            }
        }
        let mut faces = Vec::new();
        for &g in &self.gid[..no] {
            for (k, (body, n, xi)) in self.history.face.get(&g).into_iter().flatten().enumerate() {
                faces.extend_from_slice(&[g as f64, k as f64, f64::from(*body)]);
                faces.extend_from_slice(n.as_slice());
                faces.extend_from_slice(xi.as_slice());
            }
        }
        let sorted = |flat: &[f64], width: usize| {
            let (gid, values, total) = sorted_by_key(comm, flat, width);
            GlobalRows { gid, values, total }
        };
        let gid: Vec<u32> = self.gid[..no].iter().map(|&g| g as u32).collect();
        // With heat: the temperatures and the heat account; the FE's side
        // is the thermal system's (`run::checkpoint::save_checkpoint`).
        let heat = self.heat.is_some().then(|| {
            let t = GlobalRows {
                gid: gid.clone(),
                values: self.t[..no].to_vec(),
                total: self.total,
            };
            (t, [self.report.face_heat_in, self.report.fourier], [0.0; 2])
        });
        SphereCheckpoint {
            state: GlobalRows {
                gid,
                values,
                total: self.total,
            },
            pairs: sorted(&pairs, SAVED_SPHERE_PAIR),
            faces: sorted(&faces, SAVED_SPHERE_FACE),
            account: [self.report.gravity_work, self.report.damped],
            heat,
        }
    }

    /// Collective. Replace this rank's spheres by the checkpoint's: `s` is
    /// this rank's block of each list (`CheckpointFile::sphere_rows`).
    pub(in crate::dynamics) fn restore(
        &mut self,
        comm: &SimpleCommunicator,
        s: &SavedSpheres,
    ) -> Result<()> {
        let (rank, size, total) = (self.rank, self.size, self.total);
        // The springs to the ranks whose block of numbers holds their spheres.
        let mut send = vec![Vec::new(); size];
        for r in &s.pairs {
            let (ra, rb) = (
                block_owner(r[0] as u64, total, size),
                block_owner(r[1] as u64, total, size),
            );
            for to in if ra == rb { vec![ra] } else { vec![ra, rb] } {
                send[to].push(PAIR);
                send[to].extend_from_slice(r);
            }
        }
        for r in &s.faces {
            let to = block_owner(r[0] as u64, total, size);
            send[to].push(FACE);
            send[to].extend_from_slice(r);
        }
        let got = all_to_all(comm, send);
        let mut history = Histories::default();
        let mut faces: Vec<&[f64]> = Vec::new();
        for list in got.iter() {
            let mut at = 0;
            while at < list.len() {
                if list[at] == PAIR {
                    let r = &list[at + 1..at + 1 + SAVED_SPHERE_PAIR];
                    history.pair.insert((r[0] as u64, r[1] as u64), v3(&r[2..]));
                    at += 1 + SAVED_SPHERE_PAIR;
                } else {
                    faces.push(&list[at + 1..at + 1 + SAVED_SPHERE_FACE]);
                    at += 1 + SAVED_SPHERE_FACE;
                }
            }
        }
        faces.sort_unstable_by_key(|r| (r[0] as u64, r[1] as u64));
        for r in faces {
            history.face.entry(r[0] as u64).or_default().push((
                r[2] as u32,
                v3(&r[3..]),
                v3(&r[6..]),
            ));
        }
        self.history = history;
        // The block's spheres, owned here for a moment.
        self.n_owned = s.ids.len();
        self.gid = s.ids.iter().map(|&g| u64::from(g)).collect();
        self.set = s.state.iter().map(|r| r[0] as u32).collect();
        let col = |c: usize| -> Vec<V3> { s.state.iter().map(|r| v3(&r[c..])).collect() };
        (self.x0, self.x, self.v, self.w) = (col(1), col(4), col(7), col(10));
        // The saved temperatures (a thermal run), else the sets' initial ones.
        self.t = match &s.heat {
            Some(h) => h.temperature.clone(),
            None => self
                .set
                .iter()
                .map(|&k| self.initial_temperature(k))
                .collect(),
        };
        // The energies so far: each rank its own on as many ranks. On
        // another number, rank 0 takes the gravity work's sum; the damped
        // energy is then in the checkpoint's total of the dissipated
        // energy, which rank 0's domain takes whole (`restore`).
        let mine = match s.accounts.len() {
            n if n == size => s.accounts[rank],
            _ if rank == 0 => [s.accounts.iter().map(|r| r[0]).sum(), 0.0],
            _ => [0.0; 2],
        };
        // The heat from the faces and the largest Fourier number likewise:
        // each rank its own on as many ranks, else rank 0 the sum and max.
        let heat = match s.heat.as_ref().map(|h| &h.accounts[..]) {
            Some(a) if a.len() == size => a[rank],
            Some(a) if rank == 0 => [
                a.iter().map(|r| r[0]).sum(),
                a.iter().map(|r| r[1]).fold(0.0, f64::max),
            ],
            _ => [0.0; 2],
        };
        self.report = SphereReport {
            gravity_work: mine[0],
            damped: mine[1],
            face_heat_in: heat[0],
            fourier: heat[1],
            ..SphereReport::default()
        };
        // Every sphere to its slab's owner with its springs; the ghosts.
        let leaving: Vec<usize> = (0..self.n_owned)
            .filter(|&i| self.slabs.owner(&self.x[i].into()) != rank)
            .collect();
        self.exchange(comm, leaving);
        let owned: HashSet<u64> = self.gid[..self.n_owned].iter().copied().collect();
        self.history
            .pair
            .retain(|(a, b), _| owned.contains(a) || owned.contains(b));
        self.history.face.retain(|g, _| owned.contains(g));
        Ok(())
    }
}

impl crate::dynamics::ExplicitDomain {
    /// Collective. This rank's free spheres for a checkpoint (None without).
    pub fn saved_spheres(&self, comm: &SimpleCommunicator) -> Option<SphereCheckpoint> {
        self.spheres.as_ref().map(|s| s.saved(comm))
    }

    /// The number of free spheres and of their sets, and whether they
    /// carry heat (None without).
    pub fn sphere_totals(&self) -> Option<(u64, usize, bool)> {
        self.spheres
            .as_ref()
            .map(|s| (s.total, s.sets.len(), s.has_heat()))
    }

    /// Collective. Replace the free spheres by a checkpoint's blocks `s`.
    pub fn restore_spheres(&mut self, comm: &SimpleCommunicator, s: &SavedSpheres) -> Result<()> {
        match self.spheres.as_mut() {
            Some(d) => d.restore(comm, s),
            None => Ok(()),
        }
    }
}
