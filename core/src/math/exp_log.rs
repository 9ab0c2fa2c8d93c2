//! Base-2 exponential, logarithm and power in single precision only: `libm`'s `exp2f`,
//! `log2f` and `powf` (musl's) compute in f64, which the firmware targets emulate in
//! software (see [`crate::math::trig`]); these keep to f32 so the default embedded build has
//! no f64 code and every target gets the same bits. The logarithm splits off the
//! exponent and takes the mantissa `m` in [√½, √2) through the series of
//! `2 atanh((m − 1)/(m + 1))`; the exponential splits off the integer part and takes the
//! rest by Taylor's series about ½. Measured against f64 in the tests: within 4 ulp.

/// 1 / ln 2.
const INV_LN2: f32 = core::f32::consts::LOG2_E;
const LN2: f32 = core::f32::consts::LN_2;

/// log₂ `x`: −∞ at 0, NaN below 0 or for NaN, +∞ at +∞.
pub fn log2(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 {
        return f32::NEG_INFINITY;
    }
    if x == f32::INFINITY {
        return f32::INFINITY;
    }
    // Subnormals: scale into the normal range first.
    let (x, bias) = if x < f32::MIN_POSITIVE { (x * 8_388_608.0, -23) } else { (x, 0) };
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127 + bias;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    // |t| ≤ 0.1716: the term t¹¹/11 is below 4e-10.
    let series = t * (1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0)))));
    e as f32 + 2.0 * INV_LN2 * series
}

/// 2^`x`: 0 far below, +∞ far above, NaN for NaN.
pub fn exp2(x: f32) -> f32 {
    if x.is_nan() {
        return f32::NAN;
    }
    if x >= 128.0 {
        return f32::INFINITY;
    }
    if x < -150.0 {
        return 0.0;
    }
    let i = libm::floorf(x);
    // Whole powers exactly (1 = 2^0 above all: a power of 1 stays 1).
    let r = if x == i { 1.0 } else { two_to_fraction(x - i) };
    // Times 2^i in two exact steps, so that subnormal results come out right.
    let i = i as i32;
    let (a, b) = if i < -126 { (i + 64, -64) } else { (i, 0) };
    r * pow2i(a) * pow2i(b)
}

/// 2^`f` for `f` in [0, 1).
fn two_to_fraction(f: f32) -> f32 {
    // 2^f for f in [0, 1) as √2 · e^((f − ½) ln 2), |(f − ½) ln 2| ≤ 0.347: the Taylor
    // series to the 7th power leaves under 1e-8.
    let g = (f - 0.5) * LN2;
    let p = 1.0
        + g * (1.0
            + g * (1.0 / 2.0
                + g * (1.0 / 6.0 + g * (1.0 / 24.0 + g * (1.0 / 120.0 + g * (1.0 / 720.0 + g * (1.0 / 5040.0)))))));
    core::f32::consts::SQRT_2 * p
}

/// 2^`i` for `i` in −126..=127, exactly.
fn pow2i(i: i32) -> f32 {
    f32::from_bits(((i.clamp(-126, 127) + 127) as u32) << 23)
}

/// `x`^`y` for `x` ≥ 0 (what shading needs: cosines and uniform numbers raised to an
/// exponent); `x`^0 is 1, 0^`y` is 0 for `y` > 0; NaN for a negative or NaN `x`.
pub fn pow(x: f32, y: f32) -> f32 {
    if y == 0.0 {
        return 1.0;
    }
    if x == 0.0 && y > 0.0 {
        return 0.0;
    }
    exp2(y * log2(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_lcg::ulps;

    #[test]
    fn log2_and_exp2_are_within_four_ulp_of_f64() {
        let mut g = crate::test_lcg::Lcg(5);
        for _ in 0..200_000 {
            let x = f32::from_bits((g.next() >> 33) as u32 & 0x7f7f_ffff);
            if x > 0.0 {
                let want = libm::log2(x as f64);
                // Near 1 the result is tiny: measure the error against the result's
                // scale there in absolute terms.
                let err = if want.abs() < 1e-3 { (log2(x) as f64 - want).abs() / 1.2e-10 } else { ulps(log2(x), want) };
                assert!(err <= 4.0, "log2({x}) = {} vs {want}", log2(x));
            }
            let y = g.range(-149.0, 127.9);
            let want = libm::exp2(y as f64);
            if want >= f32::MIN_POSITIVE as f64 {
                assert!(ulps(exp2(y), want) <= 4.0, "exp2({y}) = {} vs {want}", exp2(y));
            } else {
                assert!((exp2(y) as f64 - want).abs() <= 6e-45, "exp2({y}) = {} vs {want}", exp2(y));
            }
        }
        for x in [1.0f32, 2.0, 0.5, 1024.0] {
            assert_eq!(log2(x), libm::log2(x as f64) as f32);
            assert_eq!(exp2(log2(x)), x);
        }
        assert!(log2(-1.0).is_nan() && log2(f32::NAN).is_nan() && exp2(f32::NAN).is_nan());
        assert_eq!((log2(0.0), log2(f32::INFINITY)), (f32::NEG_INFINITY, f32::INFINITY));
        assert_eq!((exp2(200.0), exp2(-200.0), exp2(f32::NEG_INFINITY)), (f32::INFINITY, 0.0, 0.0));
        assert_eq!((log2(1e-45), log2(3e-45)), (-149.0, -148.0));
    }

    #[test]
    fn pow_of_shading_arguments() {
        let mut g = crate::test_lcg::Lcg(6);
        for _ in 0..100_000 {
            let (x, y) = (g.range(0.0, 1.0), g.range(0.0, 1000.0));
            let want = libm::pow(x as f64, y as f64);
            let got = pow(x, y);
            // log2 x carries a relative error; y · log2 x magnifies it by up to ~100 in
            // absolute terms, so compare relatively where the value is representable.
            if want > 1e-30 {
                assert!(((got as f64 - want) / want).abs() < 2e-5, "{x}^{y} = {got} vs {want}");
            } else {
                assert!(got < 1e-29, "{x}^{y} = {got} vs {want}");
            }
        }
        assert_eq!((pow(0.0, 0.0), pow(0.0, 3.0), pow(0.7, 0.0), pow(1.0, 500.0)), (1.0, 0.0, 1.0, 1.0));
    }
}
