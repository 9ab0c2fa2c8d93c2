//! Signed fixed-point numbers `Q(BITS − FRAC).FRAC`, the number format of the fixed-point
//! datapath (`crate::fixed_ray`, the box test `crate::traverse::boxes::fixed_slab`, the
//! triangle test `crate::intersect::fixed_watertight`): a value is a `BITS`-bit two's
//! complement integer `raw` standing for `raw · 2^−FRAC` scene units.
//!
//! Conversions from `f32` are exact and directed (floor, ceiling, nearest with ties away
//! from zero): an `f32` is `±m · 2^e` with a 24-bit `m`, so its scaled value is an integer
//! shift of `m`, and the rounding is decided on the bits shifted out. No `f64` and no
//! float rounding stands between a scene's coordinates and their fixed-point values,
//! which is what lets the box test round its boxes outward with certainty.

/// A fixed-point format: `bits` in all (sign included), `frac` of them below the point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QFormat {
    /// Total width, 8 to 32.
    pub bits: u32,
    /// Fraction bits, below `bits`.
    pub frac: u32,
}

/// How a conversion rounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Round {
    /// Toward −∞ (a box's lower corner).
    Floor,
    /// Toward +∞ (a box's upper corner).
    Ceil,
    /// To the nearest, ties away from zero (vertices, ray origins, slopes).
    Nearest,
}

/// Largest magnitude of an unbounded intermediate (`scaled`): far beyond any format, and
/// far from overflowing the products the datapath forms with it.
pub const SATURATE: i64 = 1 << 62;

impl QFormat {
    /// Q16.16: 32 bits, 16 of them fraction.
    pub const Q16_16: QFormat = QFormat { bits: 32, frac: 16 };
    /// Q12.12: the 24-bit variant.
    pub const Q12_12: QFormat = QFormat { bits: 24, frac: 12 };

    /// True for a format the datapath supports: 8 to 32 bits, at least one integer bit
    /// besides the sign (`frac ≤ bits − 2`).
    pub const fn is_supported(self) -> bool {
        self.bits >= 8 && self.bits <= 32 && self.frac + 2 <= self.bits
    }

    /// Largest raw value.
    pub const fn max_raw(self) -> i64 {
        (1i64 << (self.bits.saturating_sub(1) & 63)) - 1
    }

    /// Smallest raw value.
    pub const fn min_raw(self) -> i64 {
        -(1i64 << (self.bits.saturating_sub(1) & 63))
    }

    /// Largest value, in scene units.
    pub fn max_value(self) -> f32 {
        self.to_f32(self.max_raw())
    }

    /// One unit in the last place, in scene units.
    pub fn ulp(self) -> f32 {
        self.to_f32(1)
    }

    /// `x` in this format, rounded as asked and saturated to the format's range (NaN
    /// gives 0: the datapath has no NaN, and the image validation rejects them).
    #[inline]
    pub fn from_f32(self, x: f32, round: Round) -> i64 {
        scaled(x, self.frac as i32, round).clamp(self.min_raw(), self.max_raw())
    }

    /// True if `x` is inside the format's range (so that converting it does not saturate).
    pub fn holds(self, x: f32) -> bool {
        let v = scaled(x, self.frac as i32, Round::Nearest);
        !x.is_nan() && v >= self.min_raw() && v <= self.max_raw()
    }

    /// The value of `raw`, in scene units (rounded to the nearest `f32`).
    #[inline]
    pub fn to_f32(self, raw: i64) -> f32 {
        raw as f32 * pow2(-(self.frac as i32))
    }
}

impl core::fmt::Display for QFormat {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Q{}.{}", self.bits - self.frac, self.frac)
    }
}

/// `2^e` as an `f32`, for `−126 ≤ e ≤ 127` (clamped there).
#[inline]
pub fn pow2(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// `x` as `(negative, m, e)` with `|x| = m · 2^e` exactly and `m < 2^24`; `None` for a NaN.
/// Infinities come back as `m = 1, e = 1000` (beyond every saturation).
#[inline]
pub fn decompose(x: f32) -> Option<(bool, u64, i32)> {
    if x.is_nan() {
        return None;
    }
    let bits = x.to_bits();
    let neg = bits >> 31 != 0;
    let exp = ((bits >> 23) & 0xFF) as i32;
    let frac = (bits & 0x7F_FFFF) as u64;
    Some(match exp {
        0xFF => (neg, 1, 1000),
        // Subnormals: no implicit bit, the smallest exponent.
        0 => (neg, frac, -149),
        _ => (neg, frac | 0x80_0000, exp - 150),
    })
}

/// `x · 2^shift` rounded as asked, saturated to `±SATURATE` (NaN: 0). Exact: the only
/// rounding is the one asked for.
#[inline]
pub fn scaled(x: f32, shift: i32, round: Round) -> i64 {
    let Some((neg, m, e)) = decompose(x) else { return 0 };
    if m == 0 {
        return 0;
    }
    let total = e.saturating_add(shift);
    if total >= 0 {
        // `m < 2^24`: up to 38 more bits stay below 2^62.
        let mag = if total > 38 { SATURATE } else { ((m << total) as i64).min(SATURATE) };
        return if neg { -mag } else { mag };
    }
    let s = total.unsigned_abs();
    // `q`: the magnitude truncated; `rem` / `half`: what was shifted out.
    let (q, inexact, at_least_half) = if s > 40 {
        (0, true, false)
    } else {
        let rem = m & ((1u64 << s) - 1);
        (m >> s, rem != 0, rem >= 1u64 << (s - 1))
    };
    let q = q as i64;
    let up = |mag_up: bool| if mag_up { q + 1 } else { q };
    match (round, neg) {
        (Round::Floor, false) | (Round::Ceil, true) => {
            if neg {
                -q
            } else {
                q
            }
        }
        (Round::Floor, true) => -up(inexact),
        (Round::Ceil, false) => up(inexact),
        (Round::Nearest, _) => {
            let mag = up(at_least_half);
            if neg {
                -mag
            } else {
                mag
            }
        }
    }
}

/// `num / den · 2^frac` rounded to the nearest (ties away from zero), for `|num| ≤ |den|`
/// and `den ≠ 0` (otherwise 0): a slope of the fixed-point ray, exact but for the one
/// rounding.
pub fn ratio_nearest(num: f32, den: f32, frac: u32) -> i64 {
    let (Some((nn, mn, en)), Some((nd, md, ed))) = (decompose(num), decompose(den)) else { return 0 };
    if mn == 0 || md == 0 || num.abs() > den.abs() || ed >= 1000 {
        return 0;
    }
    // |num / den| · 2^frac = mn / md · 2^sh, at most 2^frac.
    let sh = en - ed + frac as i32;
    let (top, bottom) = if sh >= 0 {
        if sh > 100 {
            return 0;
        }
        ((mn as u128) << sh, md as u128)
    } else {
        let s = sh.unsigned_abs();
        if s > 100 {
            return 0;
        }
        (mn as u128, (md as u128) << s)
    };
    let q = ((2 * top + bottom) / (2 * bottom)) as i64;
    if nn != nd {
        -q
    } else {
        q
    }
}

/// `x / 2^s` rounded to the nearest, ties away from zero (`s` < 127).
#[inline]
pub fn shift_nearest(x: i128, s: u32) -> i128 {
    if s == 0 {
        return x;
    }
    let half = 1i128 << (s - 1);
    if x >= 0 {
        (x + half) >> s
    } else {
        -((half - x) >> s)
    }
}

/// `a / b` rounded to the nearest, ties away from zero; 0 for `b = 0`. (No overflow: the
/// datapath's operands stay far below `i128`'s range.)
#[inline]
pub fn div_nearest(a: i128, b: i128) -> i128 {
    if b == 0 {
        return 0;
    }
    let (ua, ub) = (a.unsigned_abs(), b.unsigned_abs());
    let q = ((ua + ub / 2) / ub) as i128;
    if (a < 0) != (b < 0) {
        -q
    } else {
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;

    /// Against f64, where `x · 2^shift` is exact (f64 holds every f32 scaled by a power
    /// of two in range).
    #[test]
    fn conversions_round_as_asked_exactly() {
        let mut g = Lcg(3);
        for i in 0..200_000 {
            let x = match i % 4 {
                0 => (g.unit() - 0.5) * 100.0,
                1 => f32::from_bits((g.next() >> 32) as u32),
                2 => (g.unit() - 0.5) * 1e-3,
                _ => (((g.next() >> 32) as u32 % 2000) as f32 - 1000.0) / 8.0,
            };
            if x.is_nan() {
                continue;
            }
            let shift = ((g.next() >> 32) as u32 % 40) as i32 - 8;
            let exact = x as f64 * 2f64.powi(shift);
            let lim = SATURATE as f64;
            let want = |v: f64| {
                if v >= lim {
                    SATURATE
                } else if v <= -lim {
                    -SATURATE
                } else {
                    v as i64
                }
            };
            assert_eq!(scaled(x, shift, Round::Floor), want(exact.floor()), "floor {x} {shift}");
            assert_eq!(scaled(x, shift, Round::Ceil), want(exact.ceil()), "ceil {x} {shift}");
            let near = if exact >= 0.0 { (exact + 0.5).floor() } else { -((-exact + 0.5).floor()) };
            assert_eq!(scaled(x, shift, Round::Nearest), want(near), "nearest {x} {shift}");
        }
        assert_eq!(scaled(f32::NAN, 4, Round::Floor), 0);
        assert_eq!(scaled(f32::INFINITY, 4, Round::Floor), SATURATE);
        assert_eq!(scaled(f32::NEG_INFINITY, 4, Round::Ceil), -SATURATE);
        assert_eq!(scaled(-0.0, 4, Round::Ceil), 0);
    }

    #[test]
    fn ratios_round_to_the_nearest() {
        let mut g = Lcg(5);
        for _ in 0..100_000 {
            let den = (g.unit() - 0.5) * 8.0;
            let num = den * (g.unit() * 2.0 - 1.0);
            if den == 0.0 {
                continue;
            }
            let frac = 8 + (g.next() >> 32) as u32 % 24;
            let exact = num as f64 / den as f64 * 2f64.powi(frac as i32);
            let got = ratio_nearest(num, den, frac) as f64;
            // f64's own rounding of the quotient is far below half a unit here.
            assert!((got - exact).abs() <= 0.5 + 1e-6, "{num}/{den} at {frac}: {got} vs {exact}");
        }
        assert_eq!(ratio_nearest(1.0, 0.0, 16), 0);
        assert_eq!(ratio_nearest(-1.0, 1.0, 16), -65536);
    }

    #[test]
    fn formats_saturate_and_name_themselves() {
        let q = QFormat::Q16_16;
        assert_eq!(q.from_f32(40000.0, Round::Nearest), q.max_raw());
        assert_eq!(q.from_f32(-1e30, Round::Floor), q.min_raw());
        assert_eq!(q.from_f32(1.5, Round::Floor), 3 << 15);
        assert!(q.holds(32767.0) && !q.holds(32768.0) && !q.holds(f32::NAN));
        assert_eq!(QFormat::Q12_12.ulp(), 1.0 / 4096.0);
        extern crate std;
        assert_eq!(std::format!("{}", QFormat::Q12_12), "Q12.12");
        assert!(QFormat::Q16_16.is_supported() && !QFormat { bits: 33, frac: 8 }.is_supported());
        assert_eq!((shift_nearest(-3, 1), shift_nearest(3, 1), shift_nearest(-5, 2)), (-2, 2, -1));
        assert_eq!((div_nearest(7, -2), div_nearest(-7, -2), div_nearest(1, 0)), (-4, 4, 0));
    }
}
