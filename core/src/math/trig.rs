//! Sine, cosine and tangent in single precision only. `libm`'s `sinf`, `cosf` and
//! `tanf` (musl's) compute in f64, which the firmware targets emulate in software; these
//! keep to f32 so that the default embedded build has no f64 code, and every target (the
//! host too) gets the same bits. Cephes' single-precision forms (Moshier, `sinf.c`,
//! `tanf.c`): reduction by π/4 in three parts (exact for |x| ≤ 8192), then a minimax
//! polynomial on [−π/4, π/4]. Measured against f64 in the tests: sine and cosine within
//! 2 ulp, the tangent within 2.4 ulp over every field of view a camera may have.

/// 4/π.
const FOUR_OVER_PI: f32 = 1.273_239_5;
// π/4 in three parts, each exact in f32 with trailing zeros, so that `y · DP1` and
// `y · DP2` are exact for the integers `y` of the reduction.
const DP1: f32 = 0.785_156_25;
const DP2: f32 = 2.418_756_5e-4;
const DP3: f32 = 3.774_895e-8;
/// Largest |x| the reduction is exact for.
const LOSSLESS: f32 = 8192.0;

/// `x` reduced: the octant `j` (even, 0..8) and the remainder `z` in [−π/4, π/4].
#[inline]
fn reduce(x: f32) -> (u32, f32) {
    let x = x.clamp(0.0, LOSSLESS);
    let mut j = (FOUR_OVER_PI * x) as u32;
    // Odd octants map to the next even one, so that `z` lies in [−π/4, π/4].
    j += j & 1;
    let y = j as f32;
    (j & 7, ((x - y * DP1) - y * DP2) - y * DP3)
}

/// sin(z) for |z| ≤ π/4.
#[inline]
fn sin_poly(z: f32) -> f32 {
    let zz = z * z;
    ((-1.951_529_6e-4 * zz + 8.332_161e-3) * zz - 1.666_665_5e-1) * zz * z + z
}

/// cos(z) for |z| ≤ π/4.
#[inline]
fn cos_poly(z: f32) -> f32 {
    let zz = z * z;
    ((2.443_315_7e-5 * zz - 1.388_731_6e-3) * zz + 4.166_664_6e-2) * zz * zz - 0.5 * zz + 1.0
}

/// `(sin x, cos x)`. Exact reduction for |x| ≤ 8192; beyond it the result is still
/// within [−1, 1], but not the sine and cosine of `x`. NaN gives NaN.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let (j, z) = reduce(x.abs());
    let (s, c) = (sin_poly(z), cos_poly(z));
    // Octants 0, 2, 4, 6: (s, c), (c, −s), (−s, −c), (−c, s).
    let (sin, cos) = match j {
        0 => (s, c),
        2 => (c, -s),
        4 => (-s, -c),
        _ => (-c, s),
    };
    (if x < 0.0 { -sin } else { sin }, cos)
}

/// tan x for |x| < π/2 (a camera's half field of view); exact reduction as [`sin_cos`].
#[inline]
pub fn tan(x: f32) -> f32 {
    let (j, z) = reduce(x.abs());
    let zz = z * z;
    let t = if z.abs() > 1e-4 {
        (((((9.385_402e-3 * zz + 3.119_922_3e-3) * zz + 2.443_013_5e-2) * zz + 5.341_128e-2) * zz + 1.333_879_9e-1)
            * zz
            + 3.333_315_7e-1)
            * zz
            * z
            + z
    } else {
        z
    };
    // Octants 2 and 6: tan(z + π/2) = −1/tan z.
    let t = if j & 2 != 0 { -1.0 / t } else { t };
    if x < 0.0 {
        -t
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;

    use crate::test_lcg::ulps;

    #[test]
    fn sine_and_cosine_are_within_two_ulps() {
        let mut worst: f64 = 0.0;
        let mut g = crate::test_lcg::Lcg(1);
        for k in 0..200_000 {
            // Path sampling's range (2π·u), then wider.
            let x = if k % 2 == 0 { g.range(0.0, core::f32::consts::TAU) } else { g.range(-100.0, 100.0) };
            let (s, c) = sin_cos(x);
            let (ws, wc) = ((x as f64).sin(), (x as f64).cos());
            // Near a zero of the function, ulps of the result mean nothing: compare
            // absolutely there (f32's resolution at 1).
            for (got, want) in [(s, ws), (c, wc)] {
                if want.abs() < 1e-3 {
                    assert!((got as f64 - want).abs() < 2e-7, "{x}: {got} vs {want}");
                } else {
                    worst = worst.max(ulps(got, want));
                }
            }
        }
        assert!(worst <= 2.0, "worst {worst} ulps");
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for x in [1e30, -1e30, f32::MAX, f32::INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.abs() <= 1.0 && c.abs() <= 1.0, "{x}: {s} {c}");
        }
        assert!(sin_cos(f32::NAN).0.is_nan());
    }

    #[test]
    fn tangent_is_within_two_ulps_over_every_field_of_view() {
        let mut worst: f64 = 0.0;
        for k in 1..179_000 {
            // Half of a field of view from 0.001° to 178.999°, as the camera computes it.
            let x = (k as f32 * 0.001).to_radians() * 0.5;
            worst = worst.max(ulps(tan(x), (x as f64).tan()));
            assert_eq!(tan(-x), -tan(x));
        }
        assert!(worst <= 2.4, "worst {worst} ulps");
    }
}
