//! What a contact pair keeps across a detection within a step (issue 22):
//! its linearised overlap (`contact::penalty::LinearizedOverlap`), which
//! stays valid while the pair's nodes move within the tolerance whether or
//! not the candidates were rebuilt meanwhile, and the mark that it touched
//! at its last evaluation, so it goes to the clipping at once instead of
//! first trying the 44 separating axes. Before this, every detection (about
//! one in ten substeps in a deposition) dropped both: a quarter of the
//! exact clippings and two thirds of the separating-axis work of a settled
//! bed were spent finding again what the pairs knew.
//!
//! A pair evaluated by another rank after the detection gets its model by
//! the hand-over (`handover`), so the trajectories stay those of one rank
//! bitwise; the touch mark is a cost only (a clipping of tets that do not
//! overlap finds nothing) and stays where it was. Models are dropped at
//! the start of every step (`ExplicitDomain::advance`), where a restart
//! starts.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::candidates::Candidate;
use super::force_sum::pair_key;
use super::handover::{hand_over, PairKey, Records};
use super::substep::{OVERLAPPED, UNSEEN};
use super::{ExplicitDomain, NONE};
use crate::contact::penalty::LinearizedOverlap;

/// The contact state of the pairs before a detection, in key order (the
/// candidates are kept in key order: [`in_key_order`]).
pub(super) struct Carried {
    /// Pairs that touched at their last evaluation, by key, and the slot
    /// of their model in `models` (NONE: none).
    touched: Vec<(u64, u32)>,
    models: Vec<LinearizedOverlap>,
    /// With several ranks, the keys of every pair evaluated here (a pair
    /// new here may bring its model from another rank).
    evaluated: Vec<u64>,
}

/// Sort `candidates` by pair key (`force_sum::pair_key`): a radix sort of
/// the keys (a comparison sort of the pairs took a fifth of a detection).
pub(super) fn in_key_order(candidates: &mut Vec<Candidate>) {
    let mut keys: Vec<(u64, u32)> = candidates
        .iter()
        .enumerate()
        .map(|(i, c)| (pair_key(c), i as u32))
        .collect();
    // Digits of 11 bits (a table that stays in the L1 cache), up to the
    // highest bit in which the keys differ.
    const BITS: u32 = 11;
    let (lo, hi) = keys
        .iter()
        .fold((u64::MAX, 0), |(lo, hi), &(k, _)| (lo.min(k), hi.max(k)));
    let top = 64 - (lo ^ hi).leading_zeros();
    let mut buf = vec![(0u64, 0u32); keys.len()];
    for shift in (0..top).step_by(BITS as usize) {
        let digit = |k: u64| ((k >> shift) & ((1 << BITS) - 1)) as usize;
        let mut start = [0usize; (1 << BITS) + 1];
        for &(k, _) in &keys {
            start[digit(k) + 1] += 1;
        }
        if start.contains(&keys.len()) {
            continue; // every key has this digit
        }
        for d in 0..1 << BITS {
            start[d + 1] += start[d];
        }
        for &e in &keys {
            let at = &mut start[digit(e.0)];
            buf[*at] = e;
            *at += 1;
        }
        std::mem::swap(&mut keys, &mut buf);
    }
    drop(buf);
    *candidates = keys.iter().map(|&(_, i)| candidates[i as usize]).collect();
}

/// The pair of `key` (`force_sum::pair_key`).
fn pair_of(key: u64) -> PairKey {
    (
        ((key >> 31) & 0xffff_ffff) as u32,
        (key & 0x7fff_ffff) as u32,
    )
}

impl Carried {
    /// Whether the pair of `key` touched here at its last evaluation.
    pub(super) fn touched_here(&self, key: u64) -> bool {
        self.touched.binary_search_by_key(&key, |e| e.0).is_ok()
    }
}

impl ExplicitDomain {
    /// Drop every linearised overlap and every touch mark or separating
    /// axis (the state a restart starts from: which rank evaluates a pair
    /// within the step depends on the touch marks, `pair_balance`).
    pub(super) fn drop_models(&mut self) {
        self.linearized.clear();
        self.lin_of.fill(NONE);
        self.witness.fill(UNSEEN);
    }

    /// Take the touching pairs' state before the candidates are rebuilt.
    pub(super) fn contacts_before_detection(&mut self, ranks: usize) -> Carried {
        let models = std::mem::take(&mut self.linearized);
        let mut touched: Vec<(u64, u32)> = self
            .candidates
            .iter()
            .zip(&self.witness)
            .zip(&self.lin_of)
            .filter(|((_, &w), _)| w == OVERLAPPED)
            .map(|((c, _), &slot)| {
                let slot = if (slot as usize) < models.len() {
                    slot
                } else {
                    NONE
                };
                (pair_key(c), slot)
            })
            .collect();
        // Already in order (linear time then), but a merge needs it.
        touched.sort_unstable();
        let mut evaluated: Vec<u64> = if ranks > 1 {
            self.candidates.iter().map(pair_key).collect()
        } else {
            Vec::new()
        };
        evaluated.sort_unstable();
        Carried {
            touched,
            models,
            evaluated,
        }
    }

    /// Collective (with several ranks). Give the new candidates (in key
    /// order) the state they had before the detection, here or on another
    /// rank; the others start unseen.
    pub(super) fn contacts_after_detection(&mut self, comm: &SimpleCommunicator, carried: Carried) {
        let n = self.candidates.len();
        self.lin_of = vec![NONE; n];
        self.witness = vec![UNSEEN; n];
        if self.penalty.is_none() {
            // Thermal contact only (on every rank): nothing to carry.
            return;
        }
        let Carried {
            touched,
            mut models,
            evaluated,
        } = carried;
        let several = comm.size() > 1;
        let (mut t, mut e) = (0usize, 0usize);
        let mut kept = vec![false; touched.len()];
        let mut asks: Vec<PairKey> = Vec::new();
        let mut asked: Vec<usize> = Vec::new();
        for (j, c) in self.candidates.iter().enumerate() {
            let key = pair_key(c);
            while t < touched.len() && touched[t].0 < key {
                t += 1;
            }
            if t < touched.len() && touched[t].0 == key {
                // Touching here before: its model stays in its slot.
                kept[t] = true;
                self.witness[j] = OVERLAPPED;
                self.lin_of[j] = touched[t].1;
                continue;
            }
            if several {
                while e < evaluated.len() && evaluated[e] < key {
                    e += 1;
                }
                if e == evaluated.len() || evaluated[e] != key {
                    asks.push((c.a, c.b));
                    asked.push(j);
                }
            }
        }
        // Models can change rank only if some rank releases one (not after
        // a step start, which drops them, nor at the first detection).
        let mine = touched.iter().zip(&kept).any(|(e, k)| !*k && e.1 != NONE);
        let mut any = false;
        if several {
            comm.all_reduce_into(&mine, &mut any, SystemOperation::logical_or());
        }
        if any {
            drop(evaluated);
            // The models of pairs this rank no longer evaluates, by key.
            let mut released = Records::default();
            for (&(key, slot), _) in touched
                .iter()
                .zip(&kept)
                .filter(|(e, k)| !**k && e.1 != NONE)
            {
                released.push(pair_of(key), &models[slot as usize].to_record());
            }
            let got = hand_over(comm, LinearizedOverlap::RECORD, released, &asks);
            let w = LinearizedOverlap::RECORD;
            for (k, &j) in asked.iter().enumerate() {
                if got.found[k] {
                    self.witness[j] = OVERLAPPED;
                    self.lin_of[j] = models.len() as u32;
                    models.push(LinearizedOverlap::from_record(
                        &got.data[w * k..w * (k + 1)],
                    ));
                }
            }
        }
        // Slots of pairs gone stay unused until the step's end.
        self.linearized = models;
    }
}
