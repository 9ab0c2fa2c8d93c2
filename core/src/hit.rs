//! The hit record and the one ordering every tracer obeys.

/// A ray–triangle hit: four 32-bit values, like tinybvh's `Intersection`; shading data is
/// fetched later from `prim`, `u` and `v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit point.
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
    /// Triangle index in the scene image (the input's face order after triangulation).
    pub prim: u32,
}

impl Hit {
    /// [design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md), "one hit, whatever the path": the closest hit is the one with the smallest
    /// `(t, prim)`, compared lexicographically. Returns true if `self` beats `other`.
    #[inline]
    pub fn is_closer_than(&self, other: &Hit) -> bool {
        self.t < other.t || (self.t == other.t && self.prim < other.prim)
    }

    /// Bit-exact equality (distinguishes `-0.0` from `0.0`), as the property tests demand.
    pub fn bits_eq(&self, other: &Hit) -> bool {
        self.t.to_bits() == other.t.to_bits()
            && self.u.to_bits() == other.u.to_bits()
            && self.v.to_bits() == other.v.to_bits()
            && self.prim == other.prim
    }
}

/// Keeps the closer of `best` and `candidate` under the `(t, prim)` order.
#[inline]
pub fn keep_closest(best: &mut Option<Hit>, candidate: Hit) {
    match best {
        Some(b) if !candidate.is_closer_than(b) => {}
        _ => *best = Some(candidate),
    }
}
