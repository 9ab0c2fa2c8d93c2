//! Mipmaps for the scene image (Williams 1983, "Pyramidal parametrics"): each level
//! halves the one above, every texel the box average of the 2 × 2 texels it covers,
//! averaged in linear colour (texels are 8-bit sRGB) so a black-and-white pattern fades
//! to its true mean grey, not to a darker one. A side of odd length drops its last
//! row or column at the next level (a slight bias, invisible beside the filtering).

use raypipe_core::image::TextureRecord;
use raypipe_core::shade::color::{linear_to_srgb8, srgb8_to_linear};

use crate::input::texture::TextureImage;

/// The texels of every level of `t`, level 0 first, as little-endian RGBA words: the
/// complete chain down to 1 × 1.
pub fn chain(t: &TextureImage) -> Vec<u32> {
    let levels = TextureRecord::full_chain(t.width, t.height);
    let mut out: Vec<u32> = t.rgba.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    let (mut w, mut h, mut start) = (t.width, t.height, 0usize);
    for k in 1..levels {
        let (nw, nh) = TextureRecord::level_size(t.width, t.height, k);
        let above = start;
        start = out.len();
        for y in 0..nh {
            for x in 0..nw {
                let mut sum = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                    let c = out[above + (sy * w + sx) as usize].to_le_bytes();
                    for i in 0..3 {
                        sum[i] += srgb8_to_linear(c[i]);
                    }
                    sum[3] += c[3] as f32;
                }
                let rgb = [0, 1, 2].map(|i| linear_to_srgb8(sum[i] * 0.25));
                let a = (sum[3] * 0.25).round() as u8;
                out.push(u32::from_le_bytes([rgb[0], rgb[1], rgb[2], a]));
            }
        }
        (w, h) = (nw, nh);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> TextureImage {
        let texel = &texel;
        let rgba = (0..height).flat_map(|y| (0..width).flat_map(move |x| texel(x, y))).collect::<Vec<u8>>();
        TextureImage { width, height, rgba, wrap: TextureRecord::REPEAT }
    }

    /// A black-and-white checkerboard fades to the sRGB code of linear 0.5 (188), not
    /// to 128, and the chain has every level down to 1 × 1.
    #[test]
    fn a_checkerboard_fades_to_its_linear_mean() {
        let t = texture(8, 4, |x, y| if (x + y) % 2 == 0 { [255; 4] } else { [0, 0, 0, 255] });
        let texels = chain(&t);
        assert_eq!(TextureRecord::full_chain(8, 4), 4);
        assert_eq!(texels.len() as u64, TextureRecord::chain_texels(8, 4, 4));
        assert_eq!(texels.len(), 32 + 8 + 2 + 1);
        for &c in &texels[32..] {
            assert_eq!(c.to_le_bytes(), [188, 188, 188, 255]);
        }
    }

    /// Odd sides: a 5 × 3 texture has levels 2 × 1 and 1 × 1, each texel the mean of the
    /// texels it covers.
    #[test]
    fn odd_sides_halve_downwards() {
        let t = texture(5, 3, |x, _| if x < 2 { [255, 0, 0, 255] } else { [0, 0, 255, 255] });
        let texels = chain(&t);
        assert_eq!(texels.len(), 15 + 2 + 1);
        assert_eq!(texels[15].to_le_bytes(), [255, 0, 0, 255]);
        assert_eq!(texels[16].to_le_bytes(), [0, 0, 255, 255]);
        assert_eq!(texels[17].to_le_bytes(), [188, 0, 188, 255]);
    }
}
