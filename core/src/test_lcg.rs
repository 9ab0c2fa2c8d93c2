//! The deterministic generator of core's unit tests (core has no dependencies to draw
//! one from): Knuth's MMIX linear congruential generator, the same cases on every run.

/// The generator; its state is public so a test can use it as raw random bits.
pub(crate) struct Lcg(pub u64);

impl Lcg {
    /// The next state.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }

    /// A uniform number in `[0, 1)` (24 bits).
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A uniform number in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// One of nine lattice values in `[-1, 1]` (steps of 0.25): the intersection tests'
    /// inputs, so that edge functions are often exactly zero (the lanes a SIMD form
    /// leaves to the one-ray test), components tie, and triangles are often hit.
    pub fn lattice(&mut self) -> f32 {
        ((self.next() >> 33) % 9) as f32 * 0.25 - 1.0
    }
}

/// The distance in ulps between an f32 and the true value (f64), for the tests of the
/// single-precision maths ([`crate::math::trig`], [`crate::math::exp_log`]).
pub(crate) fn ulps(got: f32, want: f64) -> f64 {
    let w = want as f32;
    let ulp = (w.abs().next_up() - w.abs()) as f64;
    (got as f64 - want).abs() / ulp
}
