//! Stable hashing for trial seeds, run keys and plan hashes.
//!
//! std's `DefaultHasher` is randomized per process and may change between Rust releases, so
//! seeds derived from it would not be reproducible. This is FNV-1a (64 bit) over the bytes,
//! finished with the SplitMix64 mixer; it never changes.

/// FNV-1a of the parts, each terminated by a 0xFF separator byte, mixed by SplitMix64.
pub fn stable_hash(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in p.iter().chain(std::iter::once(&0xFFu8)) {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    splitmix64(h)
}

/// The SplitMix64 finaliser.
pub fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The seed of a trial: a function of (master seed, instance id, solver id, replicate) only.
pub fn trial_seed(master: u64, instance: &str, solver: &str, replicate: u32) -> u64 {
    stable_hash(&[
        &master.to_le_bytes(),
        instance.as_bytes(),
        solver.as_bytes(),
        &replicate.to_le_bytes(),
    ])
}

/// 16 lowercase hex digits.
pub fn hex(h: u64) -> String {
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values_never_change() {
        // FNV-1a of the empty string is the offset basis; pin the mixed value so any change
        // to the hash (which would silently change every seed) fails here.
        assert_eq!(stable_hash(&[]), splitmix64(0xcbf2_9ce4_8422_2325));
        // computed independently (a Python re-implementation of FNV-1a + SplitMix64)
        assert_eq!(trial_seed(1, "a", "greedy", 0), 0x6111_7f33_21dd_fab4);
        assert_ne!(
            trial_seed(1, "a", "greedy", 0),
            trial_seed(1, "a", "greedy", 1)
        );
        assert_ne!(trial_seed(1, "ab", "c", 0), trial_seed(1, "a", "bc", 0));
        assert_eq!(hex(trial_seed(1, "a", "greedy", 0)).len(), 16);
    }
}
