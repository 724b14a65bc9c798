//! Records that follow their contact pairs across a detection, whichever
//! rank evaluates each pair afterwards: the tangential springs
//! (`springs`) and the linearised overlaps (`models`). A pair's record
//! meets its new rank at a home rank fixed by the pair's global tet
//! numbers: each rank sends there the records it holds but no longer
//! evaluates (`released`) and the pairs it now evaluates without a record
//! (`asks`); the home rank answers each ask, and keeps the released
//! records nobody asked for (their pairs are no longer candidates).

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::parallel::exchange::all_to_all;

/// A pair by the global numbers of its two tets.
pub type PairKey = (u32, u32);

/// The home rank of a pair among `size`.
fn home(key: PairKey, size: usize) -> usize {
    let h = u64::from(key.0).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ u64::from(key.1);
    (h % size as u64) as usize
}

/// Records of `width` floats each, by pair.
#[derive(Default)]
pub(super) struct Records {
    pub(super) keys: Vec<PairKey>,
    pub(super) data: Vec<f64>,
}

impl Records {
    pub(super) fn push(&mut self, key: PairKey, record: &[f64]) {
        self.keys.push(key);
        self.data.extend_from_slice(record);
    }
}

/// What a hand-over gives a rank.
pub(super) struct HandOver {
    /// Per ask, whether some rank released its record.
    pub(super) found: Vec<bool>,
    /// Per ask, the record (`width` floats; zeros when not found).
    pub(super) data: Vec<f64>,
    /// The released records homed here that no rank asked for, by key.
    pub(super) unclaimed: Records,
}

/// Collective. Hand the `released` records (`width` floats each) to the
/// ranks that `asks` for their pairs. On one rank nothing is elsewhere:
/// no ask is answered and every released record is unclaimed.
pub(super) fn hand_over(
    comm: &SimpleCommunicator,
    width: usize,
    released: Records,
    asks: &[PairKey],
) -> HandOver {
    let size = comm.size() as usize;
    let mut order: Vec<usize> = (0..released.keys.len()).collect();
    order.sort_unstable_by_key(|&i| released.keys[i]);
    let record = |i: usize| &released.data[width * i..width * (i + 1)];
    if size == 1 {
        let mut unclaimed = Records::default();
        for &i in &order {
            unclaimed.push(released.keys[i], record(i));
        }
        return HandOver {
            found: vec![false; asks.len()],
            data: vec![0.0; width * asks.len()],
            unclaimed,
        };
    }
    // Per home rank: the number released, the released (a, b, record),
    // then the asked pairs (a, b).
    let mut send: Vec<Vec<f64>> = vec![vec![0.0]; size];
    for &i in &order {
        let (a, b) = released.keys[i];
        let m = &mut send[home((a, b), size)];
        m[0] += 1.0;
        m.extend_from_slice(&[f64::from(a), f64::from(b)]);
        m.extend_from_slice(record(i));
    }
    drop(released);
    for &(a, b) in asks {
        send[home((a, b), size)].extend_from_slice(&[f64::from(a), f64::from(b)]);
    }
    let got = all_to_all(comm, send);
    // At home: the pool of released records (where they are in `got`),
    // then each asker's answers in the order of its asks: a flag, then
    // the record.
    let stride = 2 + width;
    let mut pool: HashMap<PairKey, &[f64]> = HashMap::new();
    let mut asked: Vec<&[f64]> = Vec::with_capacity(size);
    for m in &got {
        let nr = m[0] as usize;
        let (r, a) = m[1..].split_at(nr * stride);
        for e in r.chunks_exact(stride) {
            pool.insert((e[0] as u32, e[1] as u32), &e[2..]);
        }
        asked.push(a);
    }
    let answers: Vec<Vec<f64>> = asked
        .iter()
        .map(|a| {
            let mut out = Vec::with_capacity(a.len() / 2 * (1 + width));
            for k in a.chunks_exact(2) {
                match pool.remove(&(k[0] as u32, k[1] as u32)) {
                    Some(x) => {
                        out.push(1.0);
                        out.extend_from_slice(x);
                    }
                    None => out.extend(std::iter::repeat_n(0.0, 1 + width)),
                }
            }
            out
        })
        .collect();
    let mut left: Vec<(PairKey, &[f64])> = pool.into_iter().collect();
    left.sort_unstable_by_key(|e| e.0);
    let mut unclaimed = Records::default();
    for (k, x) in left {
        unclaimed.push(k, x);
    }
    let back = all_to_all(comm, answers);
    let mut at = vec![0usize; size];
    let mut found = Vec::with_capacity(asks.len());
    let mut data = Vec::with_capacity(width * asks.len());
    for &key in asks {
        let r = home(key, size);
        let x = &back[r][(1 + width) * at[r]..(1 + width) * (at[r] + 1)];
        at[r] += 1;
        found.push(x[0] != 0.0);
        data.extend_from_slice(&x[1..]);
    }
    HandOver {
        found,
        data,
        unclaimed,
    }
}
