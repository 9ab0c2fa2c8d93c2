//! From linear radiance to display pixels: exposure, a tone-mapping operator, then the
//! sRGB encoding (core's `rgb8`). HDR outputs (OpenEXR, PFM) skip all of it and keep
//! the linear values.

use glam::Vec3;
use raypipe_core::shade::color::{luminance, rgb8};

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

/// The exposure asked for: a number of stops, or chosen from the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// Radiance times `2^EV`.
    Stops(f32),
    /// Chosen per frame by [`auto_exposure`].
    Auto,
}

/// The middle grey the log-average luminance is mapped to (Reinhard et al. 2002, §3,
/// the "key" of a normal scene).
pub const KEY: f32 = 0.18;

/// The share of pixels automatic exposure lets clip to white at most.
pub const CLIP_SHARE: f64 = 0.01;

/// What automatic exposure chose for a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoExposure {
    /// The exposure, in stops.
    pub ev: f32,
    /// The frame's log-average luminance (Reinhard's `L̄w`).
    pub log_average: f32,
    /// The share of pixels whose largest component is still above 1 after exposure.
    pub clipped: f64,
}

/// Exposure for a frame of linear radiance: the log-average luminance to [`KEY`]
/// (Reinhard et al. 2002, eq. 1–2), lowered where needed so that no more than
/// [`CLIP_SHARE`] of the pixels clip. A black frame gets 0 EV.
pub fn auto_exposure(radiance: &[[f32; 3]]) -> AutoExposure {
    let luminance = |c: &[f32; 3]| luminance(Vec3::from(*c));
    let finite: Vec<&[f32; 3]> = radiance.iter().filter(|c| c.iter().all(|v| v.is_finite() && *v >= 0.0)).collect();
    let lit: Vec<f32> = finite.iter().map(|c| luminance(c)).filter(|&l| l > 0.0).collect();
    if lit.is_empty() {
        return AutoExposure { ev: 0.0, log_average: 0.0, clipped: 0.0 };
    }
    // Over every pixel, the black ones counted at a small floor (Reinhard's δ).
    let delta = 1e-4f64;
    let log_sum: f64 = finite.iter().map(|c| (luminance(c) as f64 + delta).ln()).sum();
    let log_average = (log_sum / finite.len() as f64).exp() as f32;
    let mut ev = (KEY / log_average).log2();
    // The brightest component of the pixel at the clip quantile must stay at or below 1.
    let mut peaks: Vec<f32> = finite.iter().map(|c| c[0].max(c[1]).max(c[2])).collect();
    let k = ((peaks.len() as f64 * (1.0 - CLIP_SHARE)).floor() as usize).min(peaks.len() - 1);
    let (_, &mut peak, _) = peaks.select_nth_unstable_by(k, f32::total_cmp);
    if peak > 0.0 {
        ev = ev.min((1.0 / peak).log2());
    }
    let ev = ev.clamp(-32.0, 32.0);
    let scale = ev.exp2();
    // (Within rounding: the pixel at the quantile lands on 1 itself.)
    let clipped =
        finite.iter().filter(|c| c.iter().any(|v| v * scale > 1.0 + 1e-5)).count() as f64 / radiance.len() as f64;
    AutoExposure { ev, log_average, clipped }
}

/// The display transform asked for, before a frame fixes an automatic exposure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayChoice {
    /// Stops, or automatic.
    pub exposure: Exposure,
    /// The tone-mapping operator.
    pub tone_map: ToneMap,
}

impl DisplayChoice {
    /// The choice with an automatic exposure fixed by one frame (a walkthrough's first,
    /// so that its frames do not flicker), and what was chosen.
    pub fn fixed_by(&self, radiance: &[[f32; 3]]) -> (DisplayChoice, Option<AutoExposure>) {
        let (d, auto) = self.for_frame(radiance);
        (DisplayChoice { exposure: Exposure::Stops(d.exposure), tone_map: self.tone_map }, auto)
    }

    /// The transform for a frame of linear radiance, and what automatic exposure chose
    /// if it was asked for.
    pub fn for_frame(&self, radiance: &[[f32; 3]]) -> (Display, Option<AutoExposure>) {
        match self.exposure {
            Exposure::Stops(ev) => (Display { exposure: ev, tone_map: self.tone_map }, None),
            Exposure::Auto => {
                let auto = auto_exposure(radiance);
                (Display { exposure: auto.ev, tone_map: self.tone_map }, Some(auto))
            }
        }
    }
}

impl AutoExposure {
    /// One line for the terminal.
    pub fn describe(&self) -> String {
        format!(
            "auto {:+.2} EV (log-average luminance {:.3} to {KEY}; {:.1}% of pixels clip; --exposure EV to fix it)",
            self.ev,
            self.log_average,
            self.clipped * 100.0
        )
    }
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
                let l = luminance(c);
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
    }

    /// A lit interior exposed automatically: its log-average goes to the key unless
    /// that would clip more than the allowed share, and a black frame is left alone.
    #[test]
    fn auto_exposure_finds_the_key_and_bounds_clipping() {
        // A uniform frame at luminance 2: one stop of 0.18/2 → log2(0.09).
        let flat = vec![[2.0f32; 3]; 100];
        let a = auto_exposure(&flat);
        assert!((a.ev - (KEY / 2.0).log2()).abs() < 1e-3, "{a:?}");
        assert_eq!(a.clipped, 0.0);
        // A dim frame with 5% very bright pixels: the key alone would clip them all.
        let mut spotty = vec![[0.01f32; 3]; 95];
        spotty.extend(vec![[50.0f32; 3]; 5]);
        let a = auto_exposure(&spotty);
        assert!(a.clipped <= CLIP_SHARE, "{a:?}");
        assert_eq!(auto_exposure(&[[0.0; 3]; 10]).ev, 0.0);
        assert_eq!(auto_exposure(&[[f32::NAN; 3]; 10]).ev, 0.0);
        // One stop up doubles the radiance.
        let up = Display { exposure: 1.0, ..Default::default() };
        assert_eq!(up.pixel(Vec3::splat(0.25)), Display::default().pixel(Vec3::splat(0.5)));
    }
}
