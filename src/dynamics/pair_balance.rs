//! The balancing of the penalty pairs over the ranks at a detection
//! (issue 22): each rank's share of the pair work (`pair_shares`), the
//! work it hands to each other rank (`quotas`), and which pairs carry it
//! (`assign_pairs`). Within a step, a pair handed to the rank that
//! evaluated it since the last detection keeps its linearised overlap and
//! touch mark there (`carry`); before, the pairs handed over were picked
//! afresh at every detection, and about a tenth of the touching ones
//! changed rank, each with its model (520 bytes) and without its touch
//! mark. A detection at a step start (where models are dropped, and where
//! a restart starts) shares the pairs by the positions alone, so a
//! restarted run gives each rank the same pairs, hence the same share of
//! the dissipated energy, as the uninterrupted one.

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::candidates::{ReceivedPairs, TetRecord, PAIR_F64S, TET_F64S};
use super::carry::Carried;
use super::force_sum::key_of;
use super::{ExplicitDomain, NONE};
use crate::contact::OwnAndGhosts;
use crate::parallel::exchange::all_to_all;

impl ExplicitDomain {
    /// Collective. Share the work evenly over the ranks. Each rank finds
    /// the pairs of the tets it owns, so the ranks holding the bottom of
    /// a settling column (or its contacts) would do all the contact work
    /// while the others wait. With `weights` the estimated cost of each
    /// found pair, each rank's share of the pair work is what brings its
    /// elements' work up to the mean work (elements and pairs) of the
    /// ranks; the pairs of all ranks, in rank order, are cut into runs of
    /// those shares, and the overlap of this rank's stretch with run r is
    /// the work it hands to rank r (`quotas`). Which pairs fill that is
    /// [`assign_pairs`]: first (within a step) those rank r evaluated since
    /// the last detection (`pairs_given`), so a touching pair keeps its model and
    /// touch mark where they are (`carry`), then hot pairs (the same work
    /// in the fewest pairs, hence the fewest force contributions that
    /// travel back every substep). After a repartition by work the shares
    /// are about what each rank found, and few pairs move. The forces do
    /// not depend on which rank evaluates a pair (they are summed by pair
    /// key). Returns the pairs this rank evaluates.
    #[allow(clippy::type_complexity)]
    pub(super) fn balance_pairs(
        &mut self,
        comm: &SimpleCommunicator,
        og: &OwnAndGhosts,
        kept: &[(u32, u32)],
        weights: &[u64],
        carried: &Carried,
    ) -> (Vec<(u32, u32)>, ReceivedPairs) {
        let size = comm.size() as usize;
        let rank = comm.rank() as usize;
        let mine: u64 = weights.iter().sum();
        self.pair_share = mine as f64;
        if size == 1 {
            return (kept.to_vec(), ReceivedPairs::default());
        }
        let local = [mine as f64, self.element_work];
        let mut all = vec![0.0f64; 2 * size];
        comm.all_gather_into(&local[..], &mut all[..]);
        let found: Vec<f64> = all.iter().step_by(2).copied().collect();
        let total: f64 = found.iter().sum();
        if total == 0.0 {
            return (kept.to_vec(), ReceivedPairs::default());
        }
        let shares = pair_shares(
            &found,
            &all.iter().skip(1).step_by(2).copied().collect::<Vec<_>>(),
        );
        // Run r of the pair sequence: [ends[r], ends[r + 1]).
        let mut ends = vec![0.0f64; size + 1];
        for r in 0..size {
            ends[r + 1] = ends[r] + shares[r];
        }
        self.pair_share = shares[rank];
        let start: f64 = found[..rank].iter().sum();
        let quota = quotas(&ends, start, found[rank]);
        // The rank that evaluated each hot pair at the last detection if
        // not this one (looked up only when this rank hands work over).
        let cold = weights.iter().copied().min().unwrap_or(0);
        let key = |i: usize| key_of(og.gid(kept[i].0), og.gid(kept[i].1));
        let hands_over = quota.iter().enumerate().any(|(d, &q)| d != rank && q > 0.0);
        // Whether this detection may use what earlier ones did: within a
        // step, with linearised models to keep in place (`detect`).
        let sticky = !self.last_detect_fresh;
        let before: Vec<u32> = if sticky && hands_over && !self.pairs_given.is_empty() {
            (0..kept.len())
                .map(|i| match weights[i] > cold {
                    true => self.pairs_given.get(&key(i)).copied().unwrap_or(NONE),
                    false => NONE,
                })
                .collect()
        } else {
            Vec::new()
        };
        let dest = match hands_over {
            // Touch marks are history too: used within a step only (they
            // are dropped at its start, `carry`).
            true => assign_pairs(weights, &quota, rank, &before, |i| {
                sticky && carried.touched_here(key(i))
            }),
            false => vec![rank as u32; kept.len()],
        };
        drop(before);
        self.pairs_given.clear();
        // Per destination: its tets (each once) and its pairs (tet slots,
        // stiffness, reduced mass).
        let mut tets: Vec<Vec<f64>> = vec![Vec::new(); size];
        let mut pairs: Vec<Vec<f64>> = vec![Vec::new(); size];
        let mut slot: Vec<HashMap<u32, u32>> = vec![HashMap::new(); size];
        let mut here = Vec::with_capacity(kept.len());
        for (i, &(a, b)) in kept.iter().enumerate() {
            let d = dest[i] as usize;
            if d == rank {
                here.push((a, b));
                continue;
            }
            if weights[i] > cold && self.linear_tolerance > 0.0 {
                self.pairs_given.insert(key(i), d as u32);
            }
            let (_, _, stiffness, reduced_mass) = self.pair_record_values(og, a, b);
            let mut slot_of = |h: u32| -> f64 {
                let next = slot[d].len() as u32;
                let s = *slot[d].entry(h).or_insert_with(|| {
                    TetRecord::of(og, h).push(&mut tets[d]);
                    next
                });
                f64::from(s)
            };
            let (sa, sb) = (slot_of(a), slot_of(b));
            pairs[d].extend_from_slice(&[sa, sb, stiffness, reduced_mass]);
        }
        drop(slot);
        let out: Vec<Vec<f64>> = tets
            .into_iter()
            .zip(pairs)
            .map(|(mut t, p)| {
                let mut m = Vec::with_capacity(1 + t.len() + p.len());
                m.push((t.len() / TET_F64S) as f64);
                m.append(&mut t);
                m.extend_from_slice(&p);
                m
            })
            .collect();
        let mut received = ReceivedPairs::default();
        for m in all_to_all(comm, out).iter().filter(|m| !m.is_empty()) {
            let nt = m[0] as usize;
            let (t, p) = m[1..].split_at(nt * TET_F64S);
            let base = received.tets.len() as u32;
            received
                .tets
                .extend(t.chunks_exact(TET_F64S).map(TetRecord::read));
            received.pairs.extend(
                p.chunks_exact(PAIR_F64S)
                    .map(|r| (base + r[0] as u32, base + r[1] as u32, r[2], r[3])),
            );
        }
        (here, received)
    }
}

/// Each rank's share of the pair work (`found` per rank, summing to the
/// total): what brings its `elements` work up to the mean of elements
/// and pairs, a rank whose elements alone exceed a share taking none, the
/// shares scaled to the total found.
fn pair_shares(found: &[f64], elements: &[f64]) -> Vec<f64> {
    let pairs: f64 = found.iter().sum();
    // The level L with sum over r of max(0, L - elements_r) = pairs: filled
    // over the ranks sorted by element work.
    let mut e: Vec<f64> = elements.to_vec();
    e.sort_by(f64::total_cmp);
    let (mut sum, mut level) = (0.0, 0.0);
    for k in 0..e.len() {
        sum += e[k];
        level = (sum + pairs) / (k + 1) as f64;
        if k + 1 == e.len() || level <= e[k + 1] {
            break;
        }
    }
    let raw: Vec<f64> = elements.iter().map(|&x| (level - x).max(0.0)).collect();
    let sum: f64 = raw.iter().sum();
    if sum > 0.0 {
        raw.iter().map(|&x| x * pairs / sum).collect()
    } else {
        found.to_vec()
    }
}

/// The work a rank whose stretch of the pair sequence is [`start`,
/// `start` + `found`) hands to each rank: the overlap with that rank's run
/// [`ends[d]`, `ends[d + 1]`) (its own entry is what it keeps).
fn quotas(ends: &[f64], start: f64, found: f64) -> Vec<f64> {
    ends.windows(2)
        .map(|e| (e[1].min(start + found) - e[0].max(start)).max(0.0))
        .collect()
}

/// The rank that evaluates each pair of `weights` found by rank `rank`,
/// which hands `quota[d]` work to rank d (its own entry unused). First
/// each pair goes back to the rank it went to at the last detection
/// (`before`, NONE for none) while that rank has room; then the room
/// left is filled, in the order found, by the hot pairs (above the least
/// weight: the same work in the fewest pairs) that did not touch here
/// (`touched`), then those that did (their models would move), then the
/// cold ones. A pair goes where at least half its weight of room is left
/// (the mid-point rule of a cut sequence), so each rank gets its quota to
/// within half a pair; the rest stay here.
fn assign_pairs(
    weights: &[u64],
    quota: &[f64],
    rank: usize,
    before: &[u32],
    touched: impl Fn(usize) -> bool,
) -> Vec<u32> {
    let me = rank as u32;
    let mut dest = vec![me; weights.len()];
    let mut room = quota.to_vec();
    room[rank] = 0.0;
    let take = |room: &mut [f64], d: usize, w: u64| -> bool {
        let fits = room[d] > 0.0 && room[d] >= 0.5 * w as f64;
        if fits {
            room[d] -= w as f64;
        }
        fits
    };
    for (i, &d) in before.iter().enumerate() {
        if d != NONE && d != me && take(&mut room, d as usize, weights[i]) {
            dest[i] = d;
        }
    }
    let cold = weights.iter().copied().min().unwrap_or(0);
    let open = |room: &[f64]| room.iter().any(|&r| r > 0.0 && r >= 0.5 * cold as f64);
    // Classes: 0 hot and not touching here, 1 hot and touching, 2 cold.
    for class in 0..3u8 {
        if !open(&room) {
            break;
        }
        for (i, &w) in weights.iter().enumerate() {
            let fits = |d: usize| room[d] > 0.0 && room[d] >= 0.5 * w as f64;
            if dest[i] != me || !(0..room.len()).any(fits) {
                continue;
            }
            let c = if w == cold {
                2
            } else if touched(i) {
                1
            } else {
                0
            };
            if c != class {
                continue;
            }
            if let Some(d) = (0..room.len()).find(|&d| take(&mut room, d, w)) {
                dest[i] = d as u32;
                if !open(&room) {
                    break;
                }
            }
        }
    }
    dest
}

#[cfg(test)]
mod shares {
    use super::{assign_pairs, pair_shares, quotas};
    use crate::dynamics::NONE;

    #[test]
    fn pairs_go_back_where_they_were_then_hot_untouched_first() {
        // Rank 0 of 3 hands 40 to rank 1 and 2 to rank 2.
        let w = [1, 32, 1, 32, 32, 1, 32, 1];
        let quota = [0.0, 40.0, 2.0];
        // Pair 3 went to rank 1 last time and pair 6 to rank 2 (which has
        // no room for it now); pair 1 touched here.
        let mut before = vec![NONE; w.len()];
        before[3] = 1;
        before[6] = 2;
        let touched = |i: usize| i == 1;
        let d = assign_pairs(&w, &quota, 0, &before, touched);
        // 3 back to rank 1 (32), then a hot pair would need 16 of the 8
        // left: no; the four cold pairs fill the 8 left of rank 1 (the
        // lower rank first).
        assert_eq!(d, vec![1, 0, 1, 1, 0, 1, 0, 1]);
        // Rank 1 got 32 + 4 = 36: short by 4, yet more than half a hot
        // pair; every quota is met to within half the largest weight.
        for (r, q) in quota.iter().enumerate().skip(1) {
            let got: u64 = (0..w.len())
                .filter(|&i| d[i] == r as u32)
                .map(|i| w[i])
                .sum();
            assert!((got as f64 - q).abs() <= 16.0, "rank {r}: {got} for {q}");
        }
        // No history: the untouched hot pairs first (3 and 4; 6 would
        // need 16 of the 6 left), then the cold ones.
        let d = assign_pairs(&w, &[0.0, 70.0, 0.0], 0, &[NONE; 8], touched);
        assert_eq!(d, vec![1, 0, 1, 1, 1, 1, 0, 1]);
        // Room for every untouched hot pair (96) and then the touched one
        // (30 left >= 16): 128, no room left for the cold ones.
        let d = assign_pairs(&w, &[0.0, 126.0, 0.0], 0, &[NONE; 8], touched);
        assert_eq!(d, vec![0, 1, 0, 1, 1, 0, 1, 0]);
        // Without touch marks, the hot pairs in the order found.
        let d = assign_pairs(&w, &[0.0, 70.0, 0.0], 0, &[NONE; 8], |_| false);
        assert_eq!(d, vec![1, 1, 1, 1, 0, 1, 0, 1]);
        // No room anywhere: everything stays, whatever the history.
        let d = assign_pairs(&w, &[50.0, 0.0, 0.0], 0, &before, touched);
        assert!(d.iter().all(|&r| r == 0));
        // Equal weights, or none.
        assert_eq!(
            assign_pairs(&[1, 1, 1], &[0.0, 2.0], 0, &[NONE; 3], |_| false),
            vec![1, 1, 0]
        );
        assert!(assign_pairs(&[], &[0.0, 1.0], 0, &[], |_| false).is_empty());
    }

    #[test]
    fn quotas_are_the_overlaps_with_the_runs() {
        let ends = [0.0, 10.0, 25.0, 30.0];
        assert_eq!(quotas(&ends, 5.0, 12.0), vec![5.0, 7.0, 0.0]);
        assert_eq!(quotas(&ends, 20.0, 10.0), vec![0.0, 5.0, 5.0]);
        let q = quotas(&ends, 0.0, 30.0);
        assert_eq!(q, vec![10.0, 15.0, 5.0]);
    }

    #[test]
    fn shares_fill_the_ranks_up_to_the_mean_work() {
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        // Equal elements: the pairs evenly.
        assert!(close(&pair_shares(&[10.0, 0.0], &[4.0, 4.0]), &[5.0, 5.0]));
        // A rank with more elements takes fewer pairs: 8 + 1 = 0 + 9.
        assert!(close(&pair_shares(&[10.0, 0.0], &[8.0, 0.0]), &[1.0, 9.0]));
        // Elements alone above the level: no pairs there.
        assert!(close(
            &pair_shares(&[3.0, 3.0, 0.0], &[20.0, 0.0, 0.0]),
            &[0.0, 3.0, 3.0]
        ));
        // Shares always sum to the pairs found.
        let s = pair_shares(&[7.0, 1.0, 0.5], &[3.0, 2.0, 9.0]);
        assert!((s.iter().sum::<f64>() - 8.5).abs() < 1e-12);
        // No pairs: no shares.
        assert!(close(&pair_shares(&[0.0, 0.0], &[1.0, 2.0]), &[0.0, 0.0]));
    }
}
