//! The ray of the fixed-point datapath: what a fixed-point box test and triangle test
//! (`crate::traverse::boxes::fixed_slab`, `crate::intersect::fixed_watertight`) agree to
//! trace. An `f32` ray is rounded once, at the datapath's input, to
//!
//! * an origin on the format's grid (each coordinate to the nearest raw value), and
//! * a direction with a major axis `kz` (the largest component, as in the watertight
//!   test) and two slopes `sx = d[kx] / d[kz]`, `sy = d[ky] / d[kz]`, each in `[−1, 1]`,
//!   rounded to the nearest with `BITS − 2` fraction bits (one `BITS`-bit register each).
//!
//! Distances along it are `τ`: the distance travelled along the major axis, in the
//! format's raw units. A point at `τ` is `origin + τ · (e_x, e_y, ±1)` in the ray's axis
//! order, with `e = ±slope` by the sign of `d[kz]`. `τ` converts back to the `f32` ray's
//! parameter as `t = τ · 2^−FRAC / |d[kz]|` (`tau_to_t`, monotone), which is how a
//! fixed-point hit takes its place in the `f32` walks: their comparisons of distances
//! keep working, and the box test rounds the walk's `f32` bounds outward into `τ`
//! (`tau_floor`, `tau_ceil`) so that no comparison can drop a hit.
//!
//! Heinly et al., "Integer Ray Tracing" (JGT 14(4), 2009) and Hanika & Keller, "Towards
//! Hardware Ray Tracing using Fixed Point Arithmetic" (IEEE RT 2007) take the same
//! route: quantize the scene and the ray once, then compute in integers.

use crate::math::fixed_point::{pow2, ratio_nearest, scaled, QFormat, Round};
use crate::ray::Ray;

/// An `f32` ray rounded into the format `Q(BITS − FRAC).FRAC` (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FixedRay<const BITS: u32, const FRAC: u32> {
    /// Origin, raw, per world axis.
    pub origin: [i64; 3],
    /// The axes in the ray's order: `[kx, ky, kz]`, `kz` the major one (`kx`, `ky`
    /// swapped when `d[kz] < 0`, as the watertight test does to keep the winding).
    pub k: [u8; 3],
    /// `d[kz] < 0`: the ray runs toward −`kz`.
    pub negative: bool,
    /// `d[kx] / d[kz]` and `d[ky] / d[kz]`, raw with [`FixedRay::SLOPE_FRAC`] fraction bits.
    pub slope: [i64; 2],
    /// `|d[kz]|`, to turn `τ` back into `t`.
    pub dz: f32,
    /// The `f32` ray was valid ([`Ray::is_valid`]); an invalid one hits nothing.
    pub valid: bool,
}

impl<const BITS: u32, const FRAC: u32> FixedRay<BITS, FRAC> {
    /// The coordinate format.
    pub const FORMAT: QFormat = {
        let f = QFormat { bits: BITS, frac: FRAC };
        assert!(f.is_supported(), "fixed-point formats have 8 to 32 bits and at least one integer bit");
        f
    };
    /// Fraction bits of the slopes: a slope lies in `[−1, 1]`, so a `BITS`-bit register
    /// holds it with two bits above the point (sign and one).
    pub const SLOPE_FRAC: u32 = BITS - 2;

    /// Rounds `ray` into the datapath.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let fmt = Self::FORMAT;
        let d = ray.dir.to_array();
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let negative = d[kz] < 0.0;
        if negative {
            core::mem::swap(&mut kx, &mut ky);
        }
        let o = ray.origin.to_array().map(|v| fmt.from_f32(v, Round::Nearest));
        FixedRay {
            origin: o,
            k: [kx as u8, ky as u8, kz as u8],
            negative,
            slope: [ratio_nearest(d[kx], d[kz], Self::SLOPE_FRAC), ratio_nearest(d[ky], d[kz], Self::SLOPE_FRAC)],
            dz: a[kz],
            valid: ray.is_valid(),
        }
    }

    /// The `f32` parameter `t` of the distance `τ` (raw): `τ · 2^−FRAC / |d[kz]|`, monotone
    /// (non-decreasing) in `τ`.
    #[inline]
    pub fn tau_to_t(&self, tau: i64) -> f32 {
        Self::FORMAT.to_f32(tau) / self.dz
    }

    /// A `τ` no larger than any `τ` whose [`FixedRay::tau_to_t`] is at least `t` (`t ≥ 0`):
    /// the walk's lower bound, rounded outward. The margin `2^−20` covers the three
    /// roundings of `t · |d[kz]|` and of `tau_to_t` (each at most `2^−24` relative), the
    /// last unit the rounding of `τ` itself.
    #[inline]
    pub fn tau_floor(&self, t: f32) -> i64 {
        let x = t * self.dz;
        let x = if x >= 0.0 { x * (1.0 - pow2(-20)) } else { x * (1.0 + pow2(-20)) };
        scaled(x, FRAC as i32, Round::Floor).saturating_sub(1)
    }

    /// A `τ` no smaller than any `τ` whose [`FixedRay::tau_to_t`] is at most `t`: the
    /// walk's upper bound (the best hit so far, or the ray's end), rounded outward.
    #[inline]
    pub fn tau_ceil(&self, t: f32) -> i64 {
        let x = t * self.dz;
        let x = if x >= 0.0 { x * (1.0 + pow2(-20)) } else { x * (1.0 - pow2(-20)) };
        scaled(x, FRAC as i32, Round::Ceil).saturating_add(1)
    }

    /// The direction along world axis `axis` as a ratio to the major component's
    /// magnitude: `(sign, magnitude raw with SLOPE_FRAC bits)`; the major axis is exactly 1.
    #[inline]
    pub fn direction(&self, axis: usize) -> (bool, i64) {
        let one = 1i64 << Self::SLOPE_FRAC;
        let [kx, ky, _] = self.k.map(usize::from);
        let s = if axis == kx {
            self.slope[0]
        } else if axis == ky {
            self.slope[1]
        } else {
            return (self.negative, one);
        };
        // e = slope · sign(d[kz]).
        ((s < 0) != self.negative, s.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    type R = FixedRay<32, 16>;

    #[test]
    fn distance_bounds_enclose_every_tau_of_their_t() {
        let mut g = Lcg(11);
        for _ in 0..20_000 {
            let dir = Vec3::new(g.range(-3.0, 3.0), g.range(-3.0, 3.0), g.range(-3.0, 3.0));
            let r = R::new(&Ray::new(Vec3::ZERO, dir));
            if !r.valid {
                continue;
            }
            let tau = (g.next() >> 44) as i64 - (1 << 19);
            let t = r.tau_to_t(tau);
            assert!(r.tau_floor(t) <= tau && tau <= r.tau_ceil(t), "{tau} {t}");
            // Monotone.
            assert!(r.tau_to_t(tau + 1) >= t);
        }
        let r = R::new(&Ray::new(Vec3::ZERO, Vec3::X));
        assert!(r.tau_ceil(f32::INFINITY) > 1 << 60);
    }

    #[test]
    fn slopes_and_axes_follow_the_watertight_choice() {
        let r = R::new(&Ray::new(Vec3::new(1.5, 0.0, -2.0), Vec3::new(0.5, -4.0, 1.0)));
        assert_eq!(r.k, [0, 2, 1]);
        assert!(r.negative);
        assert_eq!(r.slope, [-(1 << 30) / 8, -(1 << 30) / 4]);
        assert_eq!(r.origin, [3 << 15, 0, -2 << 16]);
        assert_eq!(r.direction(1), (true, 1 << 30));
        assert_eq!(r.direction(0), (false, (1 << 30) / 8));
        assert_eq!(r.dz, 4.0);
    }
}
