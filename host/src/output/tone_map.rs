//! From linear radiance to display pixels: exposure, a tone-mapping operator, then the
//! sRGB encoding (core's `rgb8`). HDR outputs (OpenEXR, PFM) skip all of it and keep
//! the linear values.

use glam::Vec3;
use raypipe_core::shade::color::rgb8;

/// How highlights are brought into the displayable range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ToneMap {
    /// None: values above 1 clip to white (the golden images and host = model checks).
    #[default]
    Clamp,
    /// Reinhard et al. 2002, the global operator on luminance, `L / (1 + L)`: every
    /// value stays below white and hue is kept.
    Reinhard,
    /// The ACES filmic curve as fitted by Narkowicz 2015 ("ACES Filmic Tone Mapping
    /// Curve"), per channel: a toe, a shoulder and slight desaturation of highlights.
    Aces,
}

/// The display transform of an 8-bit output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Display {
    /// Exposure in stops: radiance is multiplied by `2^exposure` first.
    pub exposure: f32,
    /// The tone-mapping operator.
    pub tone_map: ToneMap,
}

impl Display {
    /// Whether this is the identity before encoding (no exposure, clamping).
    pub fn is_identity(&self) -> bool {
        self.exposure == 0.0 && self.tone_map == ToneMap::Clamp
    }

    /// Linear radiance `c` as an 8-bit sRGB pixel.
    pub fn pixel(&self, c: Vec3) -> [u8; 3] {
        let c = c * self.exposure.exp2();
        rgb8(match self.tone_map {
            ToneMap::Clamp => c,
            ToneMap::Reinhard => {
                // Rec. 709 luminance.
                let l = c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
                if l > 0.0 {
                    c * (1.0 / (1.0 + l))
                } else {
                    Vec3::ZERO
                }
            }
            ToneMap::Aces => {
                let (a, b, cc, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
                let c = c.max(Vec3::ZERO);
                ((c * (c * a + b)) / (c * (c * cc + d) + e)).clamp(Vec3::ZERO, Vec3::ONE)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operators_keep_order_and_stay_in_range() {
        for op in [ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces] {
            let d = Display { exposure: 0.0, tone_map: op };
            let mut last = 0;
            for i in 0..200 {
                let v = i as f32 * 0.05;
                let [r, g, b] = d.pixel(Vec3::splat(v));
                assert!(r == g && g == b);
                assert!(r >= last, "{op:?} decreases at {v}");
                last = r;
            }
            assert_eq!(d.pixel(Vec3::ZERO), [0; 3]);
        }
        // Reinhard never reaches white; clamping does at 1.
        assert!(Display { tone_map: ToneMap::Reinhard, ..Default::default() }.pixel(Vec3::splat(9.0))[0] < 255);
        assert_eq!(Display::default().pixel(Vec3::ONE), [255; 3]);
        // One stop up doubles the radiance.
        let up = Display { exposure: 1.0, ..Default::default() };
        assert_eq!(up.pixel(Vec3::splat(0.25)), Display::default().pixel(Vec3::splat(0.5)));
    }
}
