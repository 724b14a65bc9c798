//! Fingerprints of a rank's rows: a cheap test of whether what a
//! collective structure (a gather, a status grid) was made for has
//! changed since, so it is made again only then.

/// A 64-bit fingerprint of `words` and their count (rotate, xor and an odd
/// multiply a word, the SplitMix64 finaliser at the end; not
/// cryptographic). Equal rows give equal fingerprints; different rows the
/// same one with a chance of about 2⁻⁶⁴.
pub fn fingerprint(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut h = 0x243F_6A88_85A3_08D3u64;
    let mut n = 0u64;
    for w in words {
        h = (h.rotate_left(23) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        n += 1;
    }
    let mut z = h ^ n;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::fingerprint;

    #[test]
    fn rows_that_differ_in_one_word_order_or_length_differ() {
        let a: Vec<u64> = (0..1000).collect();
        let base = fingerprint(a.iter().copied());
        assert_eq!(base, fingerprint(a.iter().copied()));
        let mut b = a.clone();
        b[500] ^= 1;
        assert_ne!(base, fingerprint(b));
        let mut c = a.clone();
        c.swap(3, 4);
        assert_ne!(base, fingerprint(c));
        assert_ne!(base, fingerprint(a.iter().copied().chain([0])));
        assert_ne!(fingerprint([]), fingerprint([0]));
    }
}
