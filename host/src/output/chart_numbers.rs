//! Numbers on charts: SI suffixes (k, M, G) and a few significant figures, one rule for
//! every axis, cell and colour bar.

/// `v` with an SI suffix past ten thousand and about `sig` significant figures (whole
/// numbers shown whole below the suffixes).
pub fn si(v: f64, sig: i32) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    let (x, suffix) = if a >= 1e9 {
        (v / 1e9, "G")
    } else if a >= 1e6 {
        (v / 1e6, "M")
    } else if a >= 1e4 {
        (v / 1e3, "k")
    } else {
        (v, "")
    };
    let whole = suffix.is_empty() && v.fract() == 0.0;
    let before = if x != 0.0 { x.abs().log10().floor() as i32 + 1 } else { 1 };
    let decimals = if whole { 0 } else { (sig - before).clamp(0, 3) as usize };
    format!("{x:.decimals$}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::si;

    #[test]
    fn suffixes_and_figures() {
        assert_eq!(si(0.0, 3), "0");
        assert_eq!(si(0.1234, 3), "0.123");
        assert_eq!(si(12.345, 3), "12.3");
        assert_eq!(si(1500.0, 2), "1500");
        assert_eq!(si(147_059.0, 3), "147k");
        assert_eq!(si(2_500_000.0, 2), "2.5M");
        assert_eq!(si(f64::NAN, 3), "–");
    }
}
