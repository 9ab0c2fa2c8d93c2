//! An order-independent sum of radiance contributions: each contribution is rounded once
//! to fixed point (2^-32 steps) and added as an integer, so a pixel's value is the same
//! whichever order its rays end in — on the host, where a tile's stream orders them, and
//! in the hardware model, where packets come back as the units finish them.

use glam::Vec3;

/// Fixed-point scale: 2^32 steps per unit of radiance. Scaling by a power of two is
/// exact in f32 (short of overflow, which saturates as a wider type would), so no f64
/// is needed.
const SCALE: f32 = 4_294_967_296.0;

/// A pixel's radiance, summed exactly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RadianceSum([u64; 3]);

impl RadianceSum {
    /// Adds a contribution (negative, NaN or infinite components count as zero or
    /// saturate: radiance is never negative).
    #[inline]
    pub fn add(&mut self, c: Vec3) {
        for (acc, v) in self.0.iter_mut().zip(c.to_array()) {
            let fixed = if v.is_nan() || v <= 0.0 { 0 } else { (v * SCALE) as u64 };
            *acc = acc.saturating_add(fixed);
        }
    }

    /// The sum as linear RGB (each component rounded once, to the nearest f32).
    pub fn value(&self) -> Vec3 {
        let [r, g, b] = self.0.map(|v| v as f32 / SCALE);
        Vec3::new(r, g, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_order_of_contributions_does_not_matter() {
        let parts = [Vec3::new(0.1, 0.2, 0.3), Vec3::new(1e-7, 5.0, 0.0), Vec3::new(0.333, -1.0, f32::NAN)];
        let mut a = RadianceSum::default();
        let mut b = RadianceSum::default();
        for p in parts {
            a.add(p);
        }
        for p in parts.iter().rev() {
            b.add(*p);
        }
        assert_eq!(a, b);
        let v = a.value();
        assert!((v.x - 0.4330001).abs() < 1e-6 && (v.y - 5.2).abs() < 1e-5 && (v.z - 0.3).abs() < 1e-6, "{v:?}");
    }

    /// The f32 arithmetic gives the fixed-point steps and the value that exact (f64)
    /// arithmetic gives, for contributions across f32's whole range.
    #[test]
    fn single_precision_scaling_is_exact() {
        let mut g = crate::test_lcg::Lcg(3);
        for _ in 0..100_000 {
            let v = f32::from_bits((g.next() >> 33) as u32 & 0x7FFF_FFFF);
            let mut sum = RadianceSum::default();
            sum.add(Vec3::splat(v));
            let exact = if v.is_nan() || v <= 0.0 { 0 } else { (v as f64 * 4_294_967_296.0) as u64 };
            assert_eq!(sum.0[0], exact, "{v:e}");
            // Below 2^53 steps the f64 conversion is exact, so both round once.
            if exact < 1 << 53 {
                assert_eq!(sum.value().x.to_bits(), ((exact as f64 / 4_294_967_296.0) as f32).to_bits(), "{v:e}");
            }
        }
    }
}
