//! Where in a pixel each eye ray goes: anti-aliasing by filter importance sampling
//! (pbrt-v4 §8.8, "Filter Sampling"). Instead of splatting every sample into its
//! neighbours with the reconstruction filter's weights, each sample's offset from the
//! pixel centre is drawn with the filter's density, and every sample of a pixel counts
//! the same: the estimate is the filtered image, each pixel is computed alone (tiles and
//! hardware units stay independent), and no weight can be negative or need normalising.
//!
//! The numbers are counter-based ([`crate::shade::rng`]: pixel, sample, a dimension of
//! the camera's own), so a sample lands in the same place whoever traces it. With a
//! square number of samples they are stratified: sample `s` keeps to its cell of a
//! `k × k` grid over the unit square before the filter's warp.

use crate::shade::rng::uniform;

/// The `bounce` counter of the camera's random numbers: no path reaches it, so they
/// never repeat a number the path tracer draws.
pub const CAMERA_STREAM: u32 = u32::MAX;

/// Width of the Gaussian filter's standard deviation, in pixels (pbrt-v4's default).
pub const GAUSSIAN_SIGMA: f32 = 0.5;
/// Radius at which the Gaussian filter is cut off, in pixels (pbrt-v4's default).
pub const GAUSSIAN_RADIUS: f32 = 1.5;

/// A reconstruction filter, separable in x and y.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u8)]
pub enum Filter {
    /// Uniform over the pixel (radius 1/2).
    #[default]
    Box,
    /// The tent `1 - |x|` over radius 1: neighbours' samples overlap, edges soften.
    Tent,
    /// A Gaussian of σ = 1/2 pixel cut off at radius 3/2.
    Gaussian,
}

impl Filter {
    /// Name for reports and the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Filter::Box => "box",
            Filter::Tent => "tent",
            Filter::Gaussian => "gaussian",
        }
    }

    /// Half the filter's support in pixels: no offset is farther from the centre.
    pub const fn radius(self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent => 1.0,
            Filter::Gaussian => GAUSSIAN_RADIUS,
        }
    }

    /// One axis of an offset with the filter's density, from a uniform `u` in `[0, 1)`
    /// (the inverse of the filter's cumulative distribution).
    pub fn warp(self, u: f32) -> f32 {
        match self {
            Filter::Box => u - 0.5,
            Filter::Tent => {
                if u < 0.5 {
                    libm::sqrtf(2.0 * u) - 1.0
                } else {
                    1.0 - libm::sqrtf(2.0 - 2.0 * u)
                }
            }
            Filter::Gaussian => {
                // The truncated normal's inverse CDF: `u` rescaled into [Φ(-r/σ), Φ(r/σ)],
                // then σ √2 erf⁻¹(2u - 1).
                let edge = 0.5 * (1.0 + libm::erff(-GAUSSIAN_RADIUS / (GAUSSIAN_SIGMA * core::f32::consts::SQRT_2)));
                let u = edge + u * (1.0 - 2.0 * edge);
                let x = GAUSSIAN_SIGMA * core::f32::consts::SQRT_2 * erf_inv(2.0 * u - 1.0);
                x.clamp(-GAUSSIAN_RADIUS, GAUSSIAN_RADIUS)
            }
        }
    }
}

/// The inverse error function on `(-1, 1)`, single precision (Giles 2010,
/// "Approximating the erfinv function", GPU Computing Gems: the `float` version, whose
/// relative error is below 4e-7 over the range).
pub fn erf_inv(x: f32) -> f32 {
    let w = -libm::logf((1.0 - x) * (1.0 + x));
    let p = if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_4e-8;
        for c in [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            0.000_218_580_87,
            -0.001_253_725,
            -0.004_177_681_6,
            0.246_640_73,
            1.501_409_4,
        ] {
            p = c + p * w;
        }
        p
    } else {
        let w = libm::sqrtf(w) - 3.0;
        let mut p = -0.000_200_214_26;
        for c in [
            0.000_100_950_56,
            0.001_349_343_2,
            -0.003_673_428_4,
            0.005_739_507_7,
            -0.007_622_461,
            0.009_438_870_5,
            1.001_674,
            2.832_976_8,
        ] {
            p = c + p * w;
        }
        p
    };
    p * x
}

/// How many eye rays each pixel gets and where they go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSampler {
    /// Samples per pixel (at least 1). One sample goes through the pixel centre.
    pub samples: u32,
    /// The reconstruction filter the offsets follow.
    pub filter: Filter,
}

impl Default for PixelSampler {
    fn default() -> Self {
        PixelSampler { samples: 1, filter: Filter::Box }
    }
}

impl PixelSampler {
    /// Offset of sample `s` of pixel number `pixel` from the pixel's centre, in pixels
    /// (`x` right, `y` down): `(0, 0)` for a lone sample, so a one-sample image is the
    /// pixel-centre image.
    #[inline]
    pub fn offset(&self, pixel: u32, s: u32) -> (f32, f32) {
        if self.samples <= 1 {
            return (0.0, 0.0);
        }
        let (u, v) = (uniform(pixel, s, CAMERA_STREAM, 0), uniform(pixel, s, CAMERA_STREAM, 1));
        let k = libm::sqrtf(self.samples as f32) as u32;
        let (u, v) = if k * k == self.samples && s < self.samples {
            // Stratified: one sample per cell of a k × k grid.
            (((s % k) as f32 + u) / k as f32, ((s / k) as f32 + v) / k as f32)
        } else {
            (u, v)
        };
        // `u` can round up to 1 at the grid's last cell; keep it inside.
        let (u, v) = (u.min(1.0 - f32::EPSILON / 2.0), v.min(1.0 - f32::EPSILON / 2.0));
        (self.filter.warp(u), self.filter.warp(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_is_the_pixel_centre() {
        for filter in [Filter::Box, Filter::Tent, Filter::Gaussian] {
            assert_eq!(PixelSampler { samples: 1, filter }.offset(17, 0), (0.0, 0.0));
        }
    }

    #[test]
    fn offsets_stay_within_the_filter_and_follow_its_density() {
        for filter in [Filter::Box, Filter::Tent, Filter::Gaussian] {
            let sampler = PixelSampler { samples: 16, filter };
            let (mut sum, mut sq, mut n) = (0.0f64, 0.0f64, 0.0f64);
            for pixel in 0..2000 {
                for s in 0..16 {
                    let (x, y) = sampler.offset(pixel, s);
                    assert!(x.abs() <= filter.radius() && y.abs() <= filter.radius(), "{filter:?}: {x}, {y}");
                    sum += x as f64;
                    sq += (x * x) as f64;
                    n += 1.0;
                }
            }
            let (mean, var) = (sum / n, sq / n);
            // Variances: box 1/12, tent 1/6, the truncated Gaussian just under σ² = 1/4.
            let expected = match filter {
                Filter::Box => 1.0 / 12.0,
                Filter::Tent => 1.0 / 6.0,
                Filter::Gaussian => 0.2433,
            };
            assert!(mean.abs() < 0.005, "{filter:?} mean {mean}");
            assert!((var - expected).abs() < 0.004, "{filter:?} variance {var}, expected {expected}");
        }
    }

    #[test]
    fn square_counts_are_stratified() {
        let sampler = PixelSampler { samples: 4, filter: Filter::Box };
        for pixel in 0..100 {
            let mut cells = [false; 4];
            for s in 0..4 {
                let (x, y) = sampler.offset(pixel, s);
                cells[(x >= 0.0) as usize + 2 * (y >= 0.0) as usize] = true;
            }
            assert_eq!(cells, [true; 4], "pixel {pixel}");
        }
    }

    #[test]
    fn erf_inv_inverts_erf() {
        for i in -99..100 {
            let x = i as f32 / 100.0;
            assert!((libm::erff(erf_inv(x)) - x).abs() < 2e-6, "{x}");
        }
    }
}
