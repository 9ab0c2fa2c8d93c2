//! Counter-based random numbers: a number is a hash of where it is used — pixel, sample,
//! bounce and dimension — not the next state of a generator, so an image comes out the
//! same whatever order, thread or hardware unit traces its rays ([design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md),
//! "determinism"). The mixer is the lowbias32 integer hash (C. Wellons, "Prospecting for
//! hash functions", 2018), applied over the four counters.

/// A well-mixed 32-bit hash of one word.
#[inline]
pub fn mix(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// The random word for `(pixel, sample, bounce, dimension)`.
#[inline]
pub fn hash4(pixel: u32, sample: u32, bounce: u32, dimension: u32) -> u32 {
    let mut h = mix(pixel ^ 0x9e37_79b9);
    h = mix(h ^ sample.wrapping_mul(0x85eb_ca6b));
    h = mix(h ^ bounce.wrapping_mul(0xc2b2_ae35));
    mix(h ^ dimension.wrapping_mul(0x27d4_eb2f))
}

/// A uniform number in `[0, 1)` for `(pixel, sample, bounce, dimension)` (24 bits).
#[inline]
pub fn uniform(pixel: u32, sample: u32, bounce: u32, dimension: u32) -> f32 {
    (hash4(pixel, sample, bounce, dimension) >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_numbers_fill_the_unit_interval_evenly() {
        let mut bins = [0u32; 16];
        let n = 64_000u32;
        for i in 0..n {
            let u = uniform(i % 4000, i / 4000, 1, 0);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 16.0) as usize] += 1;
        }
        for b in bins {
            // 4000 expected per bin; 5 standard deviations is about ±300.
            assert!((3700..4300).contains(&b), "{bins:?}");
        }
        // Each counter matters.
        assert_ne!(hash4(1, 2, 3, 4), hash4(1, 2, 3, 5));
        assert_ne!(hash4(1, 2, 3, 4), hash4(1, 2, 4, 4));
        assert_ne!(hash4(1, 2, 3, 4), hash4(1, 3, 3, 4));
        assert_ne!(hash4(1, 2, 3, 4), hash4(2, 2, 3, 4));
    }
}
