//! The fixed-point ray–box test: the slab test on the fixed-point ray
//! ([`crate::fixed_ray::FixedRay`]) in integers, rounded outward at every step so that
//! it never rejects a box the ray touches, nor a box holding a triangle that the
//! fixed-point triangle test ([`crate::intersect::fixed_watertight`]) hits.
//!
//! * A box's corners are rounded outward into the format (floor, ceiling).
//! * It grows by one unit on every axis. A box need not hold its triangles' vertices — a
//!   BVH with spatial splits (Stich et al. 2009) gives each leaf the part of a triangle
//!   inside its box — but the triangle's points lie in the union of its leaves' boxes.
//!   The triangle test finds its hit on the triangle with rounded vertices (each moved at
//!   most half a unit per axis), through a shear rounded to the nearest unit across the
//!   ray: the hit point lies within one unit, on every axis, of the point with the same
//!   barycentric weights on the exact triangle, which some leaf's box holds. (Where the
//!   scene does not fit the format, coordinates saturate, vertices move further and no
//!   margin is enough: the datapath is exact only for scenes it holds.)
//! * Per ray, the reciprocal of each minor axis' direction ratio is held as an interval
//!   `[floor, ceil]` with `BITS / 2` fraction bits in an unsigned `BITS`-bit register
//!   (Keely 2014, "Reduced Precision for Hardware Ray Tracing in GPUs", tests boxes with
//!   such reduced-precision, outward-rounded reciprocals); where it does not fit, the
//!   register saturates and the far plane's distance becomes +∞ (the near plane's is
//!   still bounded from below by the saturated value). The major axis' ratio is exactly 1.
//! * Each plane's distance takes the end of the interval that keeps it conservative: the
//!   lower bound for a near plane, the upper for a far one, each rounded outward.
//! * The walk's `f32` interval `[t0, t1]` is rounded outward into `τ`
//!   ([`FixedRay::tau_floor`], [`FixedRay::tau_ceil`]); the entry distance returned is the
//!   `τ` lower bound turned back into `t`, no larger than the `t` of any hit inside.
//!
//! Vaidyanathan, Akenine-Möller & Salvi, "Watertight Ray Traversal with Reduced
//! Precision" (HPG 2016) make the same argument for boxes tested in reduced precision.

use glam::Vec3A;

use crate::fixed_ray::FixedRay;
use crate::math::fixed_point::{Round, SATURATE};
use crate::ray::Ray;
use crate::traverse::boxes::box_test::{BoxTest, WideRay};
use crate::traverse::boxes::wide_slab::WideSlab;

/// Per-ray constants of the fixed-point slab test.
#[derive(Clone, Copy, Debug, Default)]
pub struct FixedRayBox<const BITS: u32, const FRAC: u32> {
    /// The ray.
    pub ray: FixedRay<BITS, FRAC>,
    /// Per world axis, `1 / |e|` rounded down (raw, [`FixedRayBox::RECIP_FRAC`] bits).
    recip_lo: [i64; 3],
    /// Rounded up; [`UNBOUNDED`] where the register saturates.
    recip_hi: [i64; 3],
    /// Per axis, the direction is negative (the axis is mirrored).
    negative: [bool; 3],
    /// Per axis, the direction is zero (the ray runs inside the slab or misses it).
    zero: [bool; 3],
}

/// A reciprocal beyond its register: +∞.
const UNBOUNDED: i64 = i64::MAX;

/// How far a box grows on every axis, in raw units (see the module docs).
const MARGIN: i64 = 1;

impl<const BITS: u32, const FRAC: u32> FixedRayBox<BITS, FRAC> {
    /// Fraction bits of the reciprocals.
    pub const RECIP_FRAC: u32 = BITS / 2;
    /// Largest reciprocal register value (raw, unsigned `BITS` bits).
    pub const RECIP_MAX: i64 = (1i64 << BITS) - 1;

    /// Rounds `ray` and precomputes its reciprocals.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let r = FixedRay::<BITS, FRAC>::new(ray);
        let s = FixedRay::<BITS, FRAC>::SLOPE_FRAC;
        let mut b = FixedRayBox { ray: r, ..Default::default() };
        for axis in 0..3 {
            let (negative, mag) = r.direction(axis);
            b.negative[axis] = negative;
            b.zero[axis] = mag == 0;
            if mag == 0 {
                continue;
            }
            // 1 / (mag · 2^−s) with RECIP_FRAC bits: 2^(s + RECIP_FRAC) / mag, both ways.
            let num = 1u128 << (s + Self::RECIP_FRAC);
            let (q, rem) = (num / mag as u128, num % mag as u128);
            let lo = q.min(Self::RECIP_MAX as u128) as i64;
            let hi = q + u128::from(rem != 0);
            b.recip_lo[axis] = lo;
            b.recip_hi[axis] = if hi > Self::RECIP_MAX as u128 { UNBOUNDED } else { hi as i64 };
        }
        b
    }

    /// Entry distance (as `t`) of the ray into the box `[lo, hi]` within `[t0, t1]`, or
    /// `None`; never `None` for a box the ray touches in that interval (see the module).
    #[inline]
    pub fn entry(&self, lo: Vec3A, hi: Vec3A, t0: f32, t1: f32) -> Option<f32> {
        let (near, far) = self.interval(t0, t1);
        self.entry_tau(lo, hi, near, far).map(|tau| self.ray.tau_to_t(tau).max(t0))
    }

    /// The walk's `f32` interval `[t0, t1]` rounded outward into `τ` (once per node: it is
    /// the same for every box of a wide node).
    #[inline]
    fn interval(&self, t0: f32, t1: f32) -> (i64, i64) {
        (self.ray.tau_floor(t0), self.ray.tau_ceil(t1))
    }

    /// [`FixedRayBox::entry`] within the `τ` interval `[near, far]`: the entry's `τ` lower
    /// bound, or `None`.
    #[inline]
    fn entry_tau(&self, lo: Vec3A, hi: Vec3A, mut near: i64, mut far: i64) -> Option<i64> {
        if !self.ray.valid {
            return None;
        }
        let fmt = FixedRay::<BITS, FRAC>::FORMAT;
        for axis in 0..3 {
            let l = fmt.from_f32(lo[axis], Round::Floor) - MARGIN;
            let h = fmt.from_f32(hi[axis], Round::Ceil) + MARGIN;
            let o = self.ray.origin[axis];
            // Mirrored so that the ray runs toward +axis: the lower plane is the near one.
            let (dl, dh) = if self.negative[axis] { (o - h, o - l) } else { (l - o, h - o) };
            if self.zero[axis] {
                if dl > 0 || dh < 0 {
                    return None;
                }
                continue;
            }
            near = near.max(self.lower(dl, axis));
            far = far.min(self.upper(dh, axis));
        }
        (near <= far).then_some(near)
    }

    /// A lower bound of `x · (1 / |e|)` (raw `τ`), for the near plane at raw offset `x`.
    #[inline]
    fn lower(&self, x: i64, axis: usize) -> i64 {
        let r = if x >= 0 { self.recip_lo[axis] } else { self.recip_hi[axis] };
        if r == UNBOUNDED {
            return -SATURATE;
        }
        // An arithmetic shift rounds toward −∞.
        clamp((x as i128 * r as i128) >> Self::RECIP_FRAC)
    }

    /// An upper bound of `x · (1 / |e|)`, for the far plane at raw offset `x`.
    #[inline]
    fn upper(&self, x: i64, axis: usize) -> i64 {
        let r = if x >= 0 { self.recip_hi[axis] } else { self.recip_lo[axis] };
        if r == UNBOUNDED {
            return if x == 0 { 0 } else { SATURATE };
        }
        // Ceiling: the floor of the negation, negated.
        clamp(-((-(x as i128) * r as i128) >> Self::RECIP_FRAC))
    }
}

/// Back into the range of `τ` registers.
#[inline]
fn clamp(x: i128) -> i64 {
    x.clamp(-(SATURATE as i128), SATURATE as i128) as i64
}

impl<const BITS: u32, const FRAC: u32> BoxTest for FixedRayBox<BITS, FRAC> {
    #[inline]
    fn for_ray(ray: &Ray) -> Self {
        FixedRayBox::new(ray)
    }

    #[inline]
    fn entry(&self, lo: Vec3A, hi: Vec3A, t0: f32, t1: f32) -> Option<f32> {
        FixedRayBox::entry(self, lo, hi, t0, t1)
    }
}

impl<N: WideSlab, const BITS: u32, const FRAC: u32> WideRay<N> for FixedRayBox<BITS, FRAC> {
    #[inline]
    fn for_ray(ray: &Ray) -> Self {
        FixedRayBox::new(ray)
    }

    /// Slot by slot: a hardware unit would test them side by side, with the same result.
    #[inline]
    fn slab(&self, node: &N, t0: f32, t1: f32, tn: &mut N::Dist) -> u32 {
        let (near, far) = self.interval(t0, t1);
        let mut mask = 0;
        for k in 0..N::WIDTH {
            let (lo, hi, _, _) = node.slot(k);
            // An empty slot (inverted box, or NaN) is never entered, as in the f32 tests.
            if lo[0].partial_cmp(&hi[0]).is_none_or(|o| o.is_gt()) {
                continue;
            }
            if let Some(tau) = self.entry_tau(Vec3A::from_array(lo), Vec3A::from_array(hi), near, far) {
                tn[k] = self.ray.tau_to_t(tau).max(t0);
                mask |= 1 << k;
            }
        }
        mask
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::fixed_point::QFormat;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// A point exactly on the fixed-point ray at `τ` (raw, rational: `num / 2^s`), per
    /// world axis.
    fn point_on<const B: u32, const F: u32>(r: &FixedRay<B, F>, tau: i64) -> [i128; 3] {
        let s = FixedRay::<B, F>::SLOPE_FRAC;
        core::array::from_fn(|axis| {
            let (neg, mag) = r.direction(axis);
            let step = tau as i128 * mag as i128;
            (r.origin[axis] as i128) * (1 << s) + if neg { -step } else { step }
        })
    }

    /// Boxes made around an exact point of the ray (within `[t0, t1]`) are always entered,
    /// whatever the format, direction and box size; and at an entry no later than the point.
    fn touched_boxes_are_entered<const B: u32, const F: u32>() {
        let fmt = QFormat { bits: B, frac: F };
        let s = FixedRay::<B, F>::SLOPE_FRAC;
        let mut g = Lcg(B as u64 * 131 + F as u64);
        // Small enough that the boxes' raw corners are exact in f32 (below 2^24).
        let span = (fmt.max_value() / 8.0).min(crate::math::fixed_point::pow2(21 - F as i32));
        for case in 0..40_000 {
            let origin = Vec3::new(g.range(-span, span), g.range(-span, span), g.range(-span, span));
            let mut dir = Vec3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(-1.0, 1.0));
            // Axis-parallel and nearly parallel directions too.
            match case % 5 {
                0 => dir.x = 0.0,
                1 => dir.y *= 1e-6,
                _ => {}
            }
            let ray = Ray::new(origin, dir);
            let b = FixedRayBox::<B, F>::new(&ray);
            if !b.ray.valid {
                continue;
            }
            let tau = (g.unit() * span * (1 << F) as f32) as i64;
            let p = point_on(&b.ray, tau);
            // The box's raw corners around the point, converted to f32 exactly (small
            // enough integers), `ext` raw units on each side.
            let ext = (g.next() >> 60) as i128 * (g.next() >> 61) as i128;
            let corner = |up: bool| -> Vec3A {
                Vec3A::from_array(core::array::from_fn(|a| {
                    let v = p[a] >> s; // floor
                    let raw = if up { v + 1 + ext } else { v - ext };
                    fmt.to_f32(raw as i64)
                }))
            };
            let (lo, hi) = (corner(false), corner(true));
            let t_point = b.ray.tau_to_t(tau);
            let (t0, t1) = match case % 3 {
                0 => (0.0, f32::INFINITY),
                1 => (t_point, t_point),
                _ => (0.0, t_point),
            };
            let got = b.entry(lo, hi, t0, t1);
            assert!(got.is_some_and(|t| t <= t_point), "{ray:?} τ={tau} box {lo:?}–{hi:?} [{t0}, {t1}]");
        }
    }

    #[test]
    fn touched_boxes_are_entered_q16_16() {
        touched_boxes_are_entered::<32, 16>();
    }

    #[test]
    fn touched_boxes_are_entered_q12_12() {
        touched_boxes_are_entered::<24, 12>();
    }

    #[test]
    fn touched_boxes_are_entered_q8_16() {
        touched_boxes_are_entered::<24, 16>();
    }

    #[test]
    fn boxes_far_off_the_ray_or_behind_it_are_rejected() {
        let b = FixedRayBox::<32, 16>::new(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z));
        let (lo, hi) = (Vec3A::splat(-1.0), Vec3A::splat(1.0));
        assert!(b.entry(lo, hi, 0.0, f32::INFINITY).is_some_and(|t| t <= 4.0 && t > 3.99));
        assert_eq!(b.entry(lo + Vec3A::X * 3.0, hi + Vec3A::X * 3.0, 0.0, f32::INFINITY), None);
        assert_eq!(b.entry(lo - Vec3A::Z * 10.0, hi - Vec3A::Z * 10.0, 0.0, f32::INFINITY), None);
        assert_eq!(b.entry(lo, hi, 0.0, 3.9), None);
        let invalid = FixedRayBox::<32, 16>::new(&Ray::new(Vec3::ZERO, Vec3::ZERO));
        assert_eq!(invalid.entry(lo, hi, 0.0, f32::INFINITY), None);
    }
}
