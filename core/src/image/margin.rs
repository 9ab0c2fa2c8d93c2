//! The margin every box around the scene keeps, as the builders grow theirs.

use glam::Vec3;

/// The scene bounds grown by a margin (1e-5 of the extent plus a few ulps of the
/// coordinates), as the builders grow their boxes: a box that a kernel's rounding cannot
/// make a hit fall outside of.
pub(in crate::image) fn grow_bounds(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let pad = 1e-5 * (hi - lo).max_element() + 8.0 * f32::EPSILON * lo.abs().max(hi.abs()).max_element();
    (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
}
