//! Linear colour to 8-bit sRGB and back, shared by every driver so images agree bit for
//! bit. Both directions read tables (`shade/srgb_tables.rs`) made from the
//! IEC 61966-2-1 formulas, so no power function (and no f64) runs on a firmware target;
//! the results are the formulas' bit for bit.

use crate::shade::srgb_tables::{DECODE, ENCODE_FROM};

/// Encodes one linear channel as 8-bit sRGB (IEC 61966-2-1), clamping to `[0, 1]`;
/// NaN becomes 0. The code is the number of codes whose smallest linear value is at or
/// below `c` (a binary search of eight steps).
#[inline]
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    // Non-negative floats order as their bits (`+ 0.0` turns −0 into +0).
    let bits = (c + 0.0).to_bits();
    ENCODE_FROM.partition_point(|&from| from <= bits) as u8
}

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
