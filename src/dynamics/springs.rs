//! The tangential springs of Coulomb friction with stick
//! (`mechanics.contact.tangential_stiffness`, issue 22): each touching
//! candidate pair keeps its spring's elastic tangential force F_e
//! ([`crate::contact::penalty::penalty_forces_with`]) from substep to
//! substep, and keeps it across detections, repartitions and restarts,
//! whichever rank evaluates the pair, so the trajectories stay those of
//! one rank bitwise.
//!
//! A detection keeps F_e of the pairs this rank evaluated before and still
//! evaluates. The others are handed over (`handover`): the pairs this rank
//! now evaluates without a spring ask for theirs, and released springs no
//! rank wants are dropped (the pair is no longer a candidate, as on one
//! rank). After a repartition or a restart every spring starts as
//! released ([`ExplicitDomain::set_spring_pool`]).

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;

use super::handover::{hand_over, Records};
use super::ExplicitDomain;
use crate::contact::penalty::Spring;

pub use super::handover::PairKey;

impl ExplicitDomain {
    /// Whether pairs carry tangential springs.
    pub fn tangential_springs(&self) -> bool {
        self.has_springs()
    }

    pub(super) fn has_springs(&self) -> bool {
        self.penalty
            .as_ref()
            .is_some_and(|(p, _)| p.tangential_ratio > 0.0)
    }

    /// The springs held before a detection: those of the current
    /// candidates that are not zero, and the pool.
    pub(super) fn springs_before_detection(&mut self) -> HashMap<PairKey, Spring> {
        let mut held: HashMap<PairKey, Spring> =
            std::mem::take(&mut self.spring_pool).into_iter().collect();
        for (c, x) in self.candidates.iter().zip(&self.springs) {
            if *x != [0.0; 4] {
                held.insert((c.a, c.b), *x);
            }
        }
        held
    }

    /// Collective. Give the new candidates their springs from `held`
    /// (this rank's before the detection) and from the other ranks.
    pub(super) fn springs_after_detection(
        &mut self,
        comm: &SimpleCommunicator,
        mut held: HashMap<PairKey, Spring>,
    ) {
        let n = self.candidates.len();
        self.springs = vec![[0.0; 4]; n];
        self.spring_seen = vec![0; n];
        let mut wanted: Vec<usize> = Vec::new();
        for (j, c) in self.candidates.iter().enumerate() {
            match held.remove(&(c.a, c.b)) {
                Some(x) => self.springs[j] = x,
                None => wanted.push(j),
            }
        }
        let mut released = Records::default();
        for (key, x) in held {
            released.push(key, &x);
        }
        let asks: Vec<PairKey> = wanted
            .iter()
            .map(|&j| (self.candidates[j].a, self.candidates[j].b))
            .collect();
        let got = hand_over(comm, 4, released, &asks);
        for (k, &j) in wanted.iter().enumerate() {
            let x = &got.data[4 * k..4 * k + 4];
            self.springs[j] = [x[0], x[1], x[2], x[3]];
        }
        // Springs no rank wants: their pairs are no longer candidates.
        self.drop_springs(
            got.unclaimed
                .data
                .chunks_exact(4)
                .map(|x| [x[0], x[1], x[2], x[3]]),
        );
    }

    /// Zero the springs of the candidates that did not touch at substep
    /// `now` (their contact ended: the next one starts unstressed).
    pub(super) fn release_apart_springs(&mut self, now: u64) {
        let mut lost = 0.0;
        for (x, &seen) in self.springs.iter_mut().zip(&self.spring_seen) {
            if seen != now && *x != [0.0; 4] {
                lost += x[3];
                *x = [0.0; 4];
            }
        }
        self.dissipated += lost;
    }

    /// Springs whose contact ended: the energy they held is dissipated.
    fn drop_springs(&mut self, springs: impl Iterator<Item = Spring>) {
        let mut lost = 0.0;
        for x in springs {
            lost += x[3];
        }
        self.dissipated += lost;
    }

    /// This rank's springs that are not zero (pairs by global tet
    /// numbers, ascending), for a checkpoint or a repartition.
    pub fn held_springs(&self) -> Vec<(PairKey, Spring)> {
        let mut v: Vec<(PairKey, Spring)> = self
            .candidates
            .iter()
            .zip(&self.springs)
            .filter(|(_, x)| **x != [0.0; 4])
            .map(|(c, x)| ((c.a, c.b), *x))
            .chain(self.spring_pool.iter().copied())
            .collect();
        v.sort_unstable_by_key(|e| e.0);
        v
    }

    /// Springs to hand out at the next detection (read from a checkpoint,
    /// or carried over a repartition by any rank).
    pub fn set_spring_pool(&mut self, springs: Vec<(PairKey, Spring)>) {
        self.spring_pool = springs;
    }
}
