//! Linear colour to 8-bit sRGB and back, shared by every driver so images agree bit for
//! bit. Both directions read tables (`shade/srgb_tables.rs`) made from the
//! IEC 61966-2-1 formulas, so no power function (and no f64) runs on a firmware target;
//! the results are the formulas' bit for bit.

use crate::shade::srgb_tables::{DECODE, ENCODE_FROM};

/// Encodes one linear channel as 8-bit sRGB (IEC 61966-2-1), clamping to `[0, 1]`;
/// NaN becomes 0. The code is the number of codes whose smallest linear value is at or
/// below `c`: read from the bucket of `c`'s upper bits (a table), then one or
/// two table steps within the bucket. (A binary search of eight dependent steps cost a
/// 2048² frame 0.1 s of its 0.56 s on Sponza.)
#[inline]
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    // Non-negative floats order as their bits (`+ 0.0` turns −0 into +0).
    let bits = (c + 0.0).to_bits();
    let mut code = ENCODE_START.get((bits >> BUCKET_SHIFT) as usize).copied().unwrap_or(255) as usize;
    while ENCODE_FROM.get(code).is_some_and(|&from| from <= bits) {
        code += 1;
    }
    code as u8
}

/// Floats of one bucket share their bits above this one.
const BUCKET_SHIFT: u32 = 16;

/// Buckets of the floats in `[0, 1]`.
const BUCKETS: usize = (1f32.to_bits() >> BUCKET_SHIFT) as usize + 1;

/// `ENCODE_START[b]`: the code of the smallest float of bucket `b` (those whose bits
/// shifted by [`BUCKET_SHIFT`] are `b`). Buckets follow the float's exponent, so they are
/// finest where sRGB's codes are densest; no bucket spans more than three codes (checked
/// in the tests), so the encoding takes at most three more steps.
const ENCODE_START: [u8; BUCKETS] = {
    let mut table = [0u8; BUCKETS];
    let (mut b, mut code) = (0, 0);
    while b < BUCKETS {
        let bits = (b as u32) << BUCKET_SHIFT;
        while code < ENCODE_FROM.len() && ENCODE_FROM[code] <= bits {
            code += 1;
        }
        table[b] = code as u8;
        b += 1;
    }
    table
};

/// Encodes an RGB triple.
#[inline]
pub fn rgb8(c: glam::Vec3) -> [u8; 3] {
    [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z)]
}

/// 8-bit sRGB to linear (IEC 61966-2-1), for texels.
#[inline]
pub fn srgb8_to_linear(c: u8) -> f32 {
    f32::from_bits(DECODE[c as usize])
}

/// Rec. 709 luminance of a linear RGB colour (the power measure of the image's alias
/// table, up to the constant π of a Lambertian emitter; what exposure is set by).
#[inline]
pub fn luminance(c: glam::Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;

    /// The encoding formula, as the table was made from.
    fn encode_formula(c: f32) -> u8 {
        let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * libm::powf(c, 1.0 / 2.4) - 0.055 };
        (s * 255.0 + 0.5) as u8
    }

    /// The decoding formula.
    fn decode_formula(c: u8) -> f32 {
        let c = c as f32 / 255.0;
        if c <= 0.040_45 {
            c / 12.92
        } else {
            libm::powf((c + 0.055) / 1.055, 2.4)
        }
    }

    /// The tables give the formulas' results: every code decodes to the formula's value;
    /// at each code's first value and the float just below it, and at random values and
    /// beyond [0, 1], the encoding is the formula's. (An exhaustive run over every f32 in
    /// [0, 1] found the formula monotone, which makes the table exact everywhere.)
    #[test]
    fn the_tables_are_the_formulas() {
        for c in 0..=255u8 {
            assert_eq!(srgb8_to_linear(c).to_bits(), decode_formula(c).to_bits(), "code {c}");
        }
        for &from in &ENCODE_FROM {
            for bits in [from - 1, from, from + 1] {
                let v = f32::from_bits(bits);
                assert_eq!(linear_to_srgb8(v), encode_formula(v), "{v:e}");
            }
        }
        let mut g = Lcg(7);
        for _ in 0..100_000 {
            let v = g.range(-0.1, 1.1);
            assert_eq!(linear_to_srgb8(v), encode_formula(v), "{v:e}");
        }
        for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, f32::MIN_POSITIVE, 1e-45] {
            assert_eq!(linear_to_srgb8(v), encode_formula(v), "{v:e}");
        }
    }

    /// The bucketed encoding is the count of table entries at or below the value (what
    /// the binary search gave) at every bucket's first float and the one before it, and
    /// on a stride through all floats in [0, 1]; no bucket needs more than two steps.
    #[test]
    fn buckets_give_the_searchs_code() {
        let search = |bits: u32| ENCODE_FROM.partition_point(|&from| from <= bits) as u8;
        for b in 0..BUCKETS as u32 {
            let first = b << BUCKET_SHIFT;
            for bits in [first.saturating_sub(1), first, first + (1 << BUCKET_SHIFT) - 1] {
                let v = f32::from_bits(bits);
                assert_eq!(linear_to_srgb8(v), search(bits.min(1f32.to_bits())), "{v:e}");
            }
            let next = ENCODE_START.get(b as usize + 1).copied().unwrap_or(255);
            let last = search((first + (1 << BUCKET_SHIFT) - 1).min(1f32.to_bits()));
            assert!(last - ENCODE_START[b as usize] <= 2 && next >= last, "bucket {b}");
        }
        for bits in (0..=1f32.to_bits()).step_by(997) {
            assert_eq!(linear_to_srgb8(f32::from_bits(bits)), search(bits), "{bits:#x}");
        }
    }

    #[test]
    fn srgb_decoding_matches_the_encoder() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
        }
    }

    #[test]
    fn endpoints_and_clamping() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(7.0), 255);
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        // Mid grey: linear 0.2158 is sRGB 128.
        assert_eq!(linear_to_srgb8(0.2158), 128);
    }
}
