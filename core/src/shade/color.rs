//! Linear colour to 8-bit sRGB and back, shared by every driver so images agree bit for
//! bit.

/// Encodes one linear channel as 8-bit sRGB (IEC 61966-2-1), clamping to `[0, 1]`;
/// NaN becomes 0.
#[inline]
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * libm::powf(c, 1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Encodes an RGB triple.
#[inline]
pub fn rgb8(c: glam::Vec3) -> [u8; 3] {
    [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z)]
}

/// 8-bit sRGB to linear (IEC 61966-2-1), for texels.
#[inline]
pub fn srgb8_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.040_45 {
        c / 12.92
    } else {
        libm::powf((c + 0.055) / 1.055, 2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding_matches_the_encoder() {
        for c in [0u8, 1, 10, 100, 128, 200, 255] {
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
