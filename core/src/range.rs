//! The guaranteed range: the scenes and rays for which "one hit whatever the path"
//! ([design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md)) holds — every structure, packet size and driver returns the brute-force
//! hit bit for bit, with the watertight test. Outside it the kernels stay bounded and
//! panic-free, but hits may differ between paths (far origins, where
//! the rounding of the ray itself outgrows the structures' margins; tiny direction
//! components, whose reciprocals the box tests clamp; scenes so large or small that the
//! watertight test's products overflow or underflow). Drivers check rays and scenes here
//! and flag those outside ([`check_ray`], [`check_scene`]); `tests/tests/range.rs` checks
//! the hits at the edges of the range.
//!
//! * Scene: the extent (largest side of the bounds) within `[2^-20, 2^20]` (about 1e-6
//!   to 1e6 in the scene's units).
//! * Ray: valid ([`Ray::is_valid`]); the origin at most [`ORIGIN_EXTENTS`] extents
//!   outside the scene's bounds on each axis; the direction's largest component within
//!   `[2^-20, 2^20]` and every other component 0 or at least `2^-40` times the largest.
//! * Without the `f64-fallback` feature (the default embedded build): the scene lies
//!   within [`EMBEDDED_ORIGIN_EXTENTS`] extents of the origin. An edge function that
//!   rounds to exactly 0 then counts as inside without its true sign (no double
//!   precision to ask), and far from the origin, where coordinates carry few bits below
//!   the scene's size, that happens at points outside the triangle's true bounds, where
//!   brute force takes the triangle and a structure, whose box is not on the ray there,
//!   does not. Measured: none in 10⁶ vertex-aimed rays up to 3·10⁴ extents, 73 in 2·10⁵
//!   at 10⁵; the bound keeps an eightfold margin below the first.
//! * Intersector: [`crate::Watertight`]. Möller–Trumbore and Wald's test are not
//!   watertight: near an edge (within an ulp or so) they may report different triangles
//!   on different structures, whose leaves hand them the same triangle with different
//!   intervals.

use crate::image::SceneView;
use crate::ray::Ray;
use crate::Vec3;

/// How far outside the scene's bounds an origin may lie, in scene extents.
pub const ORIGIN_EXTENTS: f32 = 16.0;
/// Smallest and largest scene extent, and smallest and largest largest direction
/// component.
pub const MIN_SCALE: f32 = 1.0 / 1_048_576.0;
/// See [`MIN_SCALE`].
pub const MAX_SCALE: f32 = 1_048_576.0;
/// Smallest nonzero direction component, relative to the largest.
pub const MIN_COMPONENT_RATIO: f32 = 1.0 / 1_099_511_627_776.0;
/// Without `f64-fallback`: how far from the origin the scene may lie, in scene extents
/// (its bounds' largest coordinate magnitude over its extent).
pub const EMBEDDED_ORIGIN_EXTENTS: f32 = 4096.0;
/// Whether this build has the `f64-fallback` feature (and so no
/// [`EMBEDDED_ORIGIN_EXTENTS`] limit).
pub const F64_FALLBACK: bool = cfg!(feature = "f64-fallback");

/// Why a scene or ray lies outside the guaranteed range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutOfRange {
    /// The ray is not valid (no hit at all).
    InvalidRay,
    /// The origin lies more than [`ORIGIN_EXTENTS`] extents outside the scene.
    FarOrigin,
    /// The direction's largest component is outside `[2^-20, 2^20]`.
    DirectionScale,
    /// A nonzero direction component is below `2^-40` times the largest.
    TinyComponent,
    /// The scene's extent is outside `[2^-20, 2^20]`.
    SceneScale,
    /// Without `f64-fallback`: the scene lies more than [`EMBEDDED_ORIGIN_EXTENTS`]
    /// extents from the origin.
    FarFromOrigin,
}

impl core::fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            OutOfRange::InvalidRay => "the ray is invalid (NaN, zero direction or t_min outside [0, t_max])",
            OutOfRange::FarOrigin => "the ray starts more than 16 scene extents outside the scene",
            OutOfRange::DirectionScale => "the direction's largest component is outside [2^-20, 2^20]",
            OutOfRange::TinyComponent => "a direction component is nonzero but below 2^-40 of the largest",
            OutOfRange::SceneScale => "the scene's extent is outside [2^-20, 2^20]",
            OutOfRange::FarFromOrigin => {
                "the scene lies more than 4096 extents from the origin (the build without f64-fallback)"
            }
        })
    }
}

/// The scene's extent: its bounds' largest side.
fn extent(view: &SceneView<'_>) -> f32 {
    let (lo, hi) = view.bounds();
    (hi - lo).max_element()
}

/// Whether the scene lies in the guaranteed range.
pub fn check_scene(view: &SceneView<'_>) -> Result<(), OutOfRange> {
    let (lo, hi) = view.bounds();
    check_bounds(lo, hi)
}

/// Whether a scene with bounds `lo`..`hi` lies in the guaranteed range of this build.
pub fn check_bounds(lo: Vec3, hi: Vec3) -> Result<(), OutOfRange> {
    let e = (hi - lo).max_element();
    if !(MIN_SCALE..=MAX_SCALE).contains(&e) {
        return Err(OutOfRange::SceneScale);
    }
    let far = lo.abs().max(hi.abs()).max_element();
    if !F64_FALLBACK && far > EMBEDDED_ORIGIN_EXTENTS * e {
        return Err(OutOfRange::FarFromOrigin);
    }
    Ok(())
}

/// Whether `ray` lies in the guaranteed range of `view`'s scene (the scene's own range
/// is [`check_scene`]'s).
pub fn check_ray(view: &SceneView<'_>, ray: &Ray) -> Result<(), OutOfRange> {
    if !ray.is_valid() {
        return Err(OutOfRange::InvalidRay);
    }
    let (lo, hi) = view.bounds();
    // A flat or point scene still has room around it: at least the smallest extent.
    let reach = extent(view).max(MIN_SCALE) * ORIGIN_EXTENTS;
    let outside = (lo - ray.origin).max(ray.origin - hi).max_element();
    if outside > reach {
        return Err(OutOfRange::FarOrigin);
    }
    let d = ray.dir.abs();
    let largest = d.max_element();
    if !(MIN_SCALE..=MAX_SCALE).contains(&largest) {
        return Err(OutOfRange::DirectionScale);
    }
    let floor = largest * MIN_COMPONENT_RATIO;
    if d.to_array().iter().any(|&c| c != 0.0 && c < floor) {
        return Err(OutOfRange::TinyComponent);
    }
    Ok(())
}
