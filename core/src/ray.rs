//! The ray record.

use glam::{Vec3, Vec3A};

/// A ray `origin + t * dir` restricted to `t_min <= t <= t_max`.
///
/// The direction need not be normalised; `t` is measured in units of `dir`.
///
/// `repr(C)`: eight `f32` in the order origin, direction, `t_min`, `t_max`, which a
/// packet's AVX fill loads as one 32-byte row.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (not necessarily unit length, never all zero for a useful ray).
    pub dir: Vec3,
    /// Smallest accepted hit distance.
    pub t_min: f32,
    /// Largest accepted hit distance.
    pub t_max: f32,
}

const _: () = assert!(core::mem::size_of::<Ray>() == 32 && core::mem::align_of::<Ray>() == 4);

impl Ray {
    /// A ray over `[0, +inf]`.
    pub fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray { origin, dir, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// Origin and direction x, as a packet's transpose reads them.
    #[inline(always)]
    pub(crate) fn head(&self) -> [f32; 4] {
        [self.origin.x, self.origin.y, self.origin.z, self.dir.x]
    }

    /// Direction y and z, and the interval.
    #[inline(always)]
    pub(crate) fn tail(&self) -> [f32; 4] {
        [self.dir.y, self.dir.z, self.t_min, self.t_max]
    }

    /// True when every component is finite (or `t_max` is `+inf`), the direction is not
    /// zero and `0 <= t_min <= t_max`; kernels return "miss" for any other ray rather than
    /// misbehave.
    ///
    /// A ray starts at its origin: a negative `t_min` (the part behind the origin) is not
    /// a ray every structure can trace alike. The kd-tree's split rule and the robust box
    /// tests' rounding margins are exact for `t >= 0` only, and the kd-tree returned a
    /// different hit from every other structure on 6–52% of such rays, so
    /// every structure rejects them (one rule, documented in the README).
    #[inline]
    pub fn is_valid(&self) -> bool {
        // `x − x` is 0 for a finite `x` and NaN otherwise: one test for all six
        // components, without a branch per component. The comparisons fail for a NaN.
        let (o, d) = (Vec3A::from(self.origin), Vec3A::from(self.dir));
        #[allow(clippy::eq_op)]
        let finite = ((o - o) + (d - d)).cmpeq(Vec3A::ZERO).all();
        finite & d.cmpne(Vec3A::ZERO).any() & (self.t_min >= 0.0) & (self.t_min <= self.t_max)
    }
}
