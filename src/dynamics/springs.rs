//! The tangential springs of Coulomb friction with stick
//! (`mechanics.contact.tangential_stiffness`, issue 22): each touching
//! candidate pair keeps its spring's elastic tangential force F_e
//! ([`crate::contact::penalty::penalty_forces_with`]) from substep to
//! substep, and keeps it across detections, repartitions and restarts,
//! whichever rank evaluates the pair, so the trajectories stay those of
//! one rank bitwise.
//!
//! A detection keeps F_e of the pairs this rank evaluated before and still
//! evaluates. The others meet at a home rank fixed by the pair's global
//! tet numbers: each rank sends there the springs it no longer evaluates
//! (`released`) and the pairs it now evaluates without a spring
//! (`wanted`); the home rank returns each wanted pair's spring, and drops
//! released springs no rank wants (the pair is no longer a candidate, as
//! on one rank). After a repartition or a restart every spring starts as
//! released ([`ExplicitDomain::set_spring_pool`]).

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::ExplicitDomain;
use crate::contact::penalty::Spring;
use crate::parallel::exchange::all_to_all;

/// A pair by the global numbers of its two tets.
pub type PairKey = (u32, u32);

/// Floats per released spring (a, b, F_e) and per wanted pair (a, b).
const RELEASED: usize = 6;
const WANTED: usize = 2;

/// The home rank of a pair among `size`.
fn home(key: PairKey, size: usize) -> usize {
    let h = u64::from(key.0).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ u64::from(key.1);
    (h % size as u64) as usize
}

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
        let size = comm.size() as usize;
        if size == 1 {
            self.drop_springs(held.into_values());
            return;
        }
        // Released springs first, then the wanted pairs, per home rank.
        let mut released: Vec<Vec<f64>> = vec![Vec::new(); size];
        let mut released_keys: Vec<(PairKey, Spring)> = held.into_iter().collect();
        released_keys.sort_unstable_by_key(|e| e.0);
        for ((a, b), x) in released_keys {
            let r = &mut released[home((a, b), size)];
            r.extend_from_slice(&[f64::from(a), f64::from(b), x[0], x[1], x[2], x[3]]);
        }
        let mut asks: Vec<Vec<f64>> = vec![Vec::new(); size];
        for &j in &wanted {
            let c = &self.candidates[j];
            asks[home((c.a, c.b), size)].extend_from_slice(&[f64::from(c.a), f64::from(c.b)]);
        }
        let send: Vec<Vec<f64>> = released
            .into_iter()
            .zip(asks)
            .map(|(r, a)| {
                let mut m = Vec::with_capacity(1 + r.len() + a.len());
                m.push((r.len() / RELEASED) as f64);
                m.extend_from_slice(&r);
                m.extend_from_slice(&a);
                m
            })
            .collect();
        let got = all_to_all(comm, send);
        // At home: the released springs, then each asker's answers in the
        // order of its asks (zero: no rank held one).
        let mut pool: HashMap<PairKey, Spring> = HashMap::new();
        let mut asked: Vec<&[f64]> = Vec::with_capacity(size);
        for m in &got {
            let nr = m[0] as usize;
            let (r, a) = m[1..].split_at(nr * RELEASED);
            for e in r.chunks_exact(RELEASED) {
                pool.insert((e[0] as u32, e[1] as u32), [e[2], e[3], e[4], e[5]]);
            }
            asked.push(a);
        }
        let answers: Vec<Vec<f64>> = asked
            .iter()
            .map(|a| {
                a.chunks_exact(WANTED)
                    .flat_map(|k| pool.remove(&(k[0] as u32, k[1] as u32)).unwrap_or([0.0; 4]))
                    .collect()
            })
            .collect();
        // Springs no rank wants: their pairs are no longer candidates.
        self.drop_springs(pool.into_values());
        let back = all_to_all(comm, answers);
        let mut at = vec![0usize; size];
        for &j in &wanted {
            let c = &self.candidates[j];
            let r = home((c.a, c.b), size);
            let x = &back[r][4 * at[r]..4 * at[r] + 4];
            at[r] += 1;
            self.springs[j] = [x[0], x[1], x[2], x[3]];
        }
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
