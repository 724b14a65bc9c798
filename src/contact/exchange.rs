//! Contact pairs as flat `f64` records, for gathering them over the ranks
//! in one `f64` collective.

use super::{ContactPair, ContactSurface};

/// `f64`s per pair: target, contactor, S_tar, S_con, then the four
/// weights w_tar, w_con, v_tar, v_con (four each).
pub const PAIR_F64S: usize = 20;

impl ContactPair {
    /// Append this pair's [`PAIR_F64S`] values to `out` (element ids are
    /// exact in an `f64`).
    pub fn push_f64s(&self, out: &mut Vec<f64>) {
        let s = &self.surface;
        out.extend_from_slice(&[
            self.target as f64,
            self.contactor as f64,
            s.s_target,
            s.s_contactor,
        ]);
        out.extend_from_slice(&s.w_target);
        out.extend_from_slice(&s.w_contactor);
        out.extend_from_slice(&s.v_target);
        out.extend_from_slice(&s.v_contactor);
    }

    /// The pair written by [`ContactPair::push_f64s`] (`c` holds [`PAIR_F64S`] values).
    pub fn from_f64s(c: &[f64]) -> ContactPair {
        ContactPair {
            target: c[0] as u32,
            contactor: c[1] as u32,
            surface: ContactSurface {
                s_target: c[2],
                s_contactor: c[3],
                w_target: [c[4], c[5], c[6], c[7]],
                w_contactor: [c[8], c[9], c[10], c[11]],
                v_target: [c[12], c[13], c[14], c[15]],
                v_contactor: [c[16], c[17], c[18], c[19]],
            },
        }
    }
}

/// Pairs packed into [`PAIR_F64S`] values each.
pub fn pairs_to_f64s(pairs: &[ContactPair]) -> Vec<f64> {
    let mut flat = Vec::with_capacity(pairs.len() * PAIR_F64S);
    for p in pairs {
        p.push_f64s(&mut flat);
    }
    flat
}

/// Pairs unpacked from [`pairs_to_f64s`]'s values (concatenated over ranks).
pub fn pairs_from_f64s(flat: &[f64]) -> Vec<ContactPair> {
    flat.chunks_exact(PAIR_F64S)
        .map(ContactPair::from_f64s)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(k: u32) -> ContactPair {
        let x = |i: usize| k as f64 + 0.01 * i as f64 + 1.0 / 3.0;
        ContactPair {
            target: k,
            contactor: 4_000_000_000 - k,
            surface: ContactSurface {
                s_target: x(0),
                s_contactor: -x(1),
                w_target: [x(2), x(3), x(4), x(5)],
                w_contactor: [x(6), x(7), x(8), x(9)],
                v_target: [x(10), x(11), x(12), x(13)],
                v_contactor: [x(14), x(15), x(16), f64::MIN_POSITIVE],
            },
        }
    }

    #[test]
    fn pairs_round_trip_bitwise() {
        let pairs: Vec<ContactPair> = (0..5).map(pair).collect();
        let flat = pairs_to_f64s(&pairs);
        assert_eq!(flat.len(), 5 * PAIR_F64S);
        let back = pairs_from_f64s(&flat);
        assert_eq!(back, pairs);
        // Every field in its own slot: the packing of one pair is injective.
        assert_eq!(flat[1], 4_000_000_000.0);
        assert_eq!(flat[PAIR_F64S - 1], f64::MIN_POSITIVE);
        assert!(pairs_from_f64s(&[]).is_empty());
    }
}
