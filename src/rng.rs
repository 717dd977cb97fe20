//! Seeded randomness that does not depend on the order work is done in.
//!
//! Every random draw is a hash of the seed and of *where* it is drawn (level,
//! pass, pixel, slot), not the next value of a shared stream, so results are
//! the same bytes whatever the number of threads and whatever order they run
//! in. Written here rather than taken from `rand`: its generators are
//! sequential streams, and their output is not promised stable across
//! versions, while organtex promises the same bytes for the same seed.

/// SplitMix64's finaliser (Steele, Lea, Flood 2014): a bijective mix with
/// good avalanche, enough for sampling (not for cryptography).
#[inline]
pub fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A random 64-bit value for `key` (any tuple of coordinates) under `seed`.
#[inline]
pub fn hash(seed: u64, key: &[u64]) -> u64 {
    key.iter().fold(mix(seed), |h, &k| mix(h ^ k))
}

/// A random number in [0, 1] for `key` under `seed`.
#[inline]
pub fn unit(seed: u64, key: &[u64]) -> f64 {
    hash(seed, key) as f64 / u64::MAX as f64
}

/// A standard normal number for `key` under `seed` (Box-Muller on two
/// keyed uniforms).
#[inline]
pub fn normal(seed: u64, key: &[u64]) -> f64 {
    let u = unit(seed, key).max(1e-300);
    let v = hash(seed ^ 0x6a09_e667_f3bc_c909, key) as f64 / u64::MAX as f64;
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A random index in `0..n` for `key` under `seed` (n > 0).
#[inline]
pub fn below(seed: u64, key: &[u64], n: usize) -> usize {
    // Multiply-shift: unbiased enough for n far below 2^64.
    ((hash(seed, key) as u128 * n as u128) >> 64) as usize
}

/// A permutation of `0..n` for `key` under `seed` (Fisher-Yates driven by
/// keyed hashes).
pub fn permutation(seed: u64, key: &[u64], n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut k = key.to_vec();
    k.push(0);
    for i in (1..n).rev() {
        *k.last_mut().expect("pushed above") = i as u64;
        order.swap(i, below(seed, &k, i + 1));
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_spread_and_keyed() {
        let n = 10;
        let mut counts = [0usize; 10];
        for i in 0..100_000u64 {
            counts[below(7, &[i], n)] += 1;
        }
        assert!(
            counts.iter().all(|&c| (9_000..11_000).contains(&c)),
            "{counts:?}"
        );
        assert_ne!(hash(1, &[1, 2]), hash(1, &[2, 1]));
        assert_ne!(hash(1, &[1]), hash(2, &[1]));
        let p = permutation(3, &[4], 100);
        let mut sorted = p.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..100).collect::<Vec<_>>());
        assert_eq!(p, permutation(3, &[4], 100));
    }
}
