//! A look at a view before it is rendered: a grid of its eye rays traced, the hits
//! grouped by the plane they land on. A view that is mostly one surface (a camera
//! outside the scene facing its outer wall, or one pressed against a foreground
//! object) or that sees almost nothing gets a one-line hint, so a first render that
//! misses the scene says why instead of leaving the user to guess.

use glam::Vec3;
use raypipe_core::image::CameraRecord;
use raypipe_core::{NoProbe, RayCounters, SceneView, Watertight};

use crate::render::eye_rays;
use crate::render::tracer::trace;

/// Eye rays per side of the probe grid.
const GRID: u32 = 24;
/// A plane holding at least this share of the probe rays' hits makes the view "one
/// surface" (Sponza from outside: 74% of what it sees is its outer wall).
pub const ONE_SURFACE: f64 = 0.6;
/// A plane this close to the eye (as a share of the scene's size) covering at least
/// [`BLOCKING`] of the frame is a foreground surface in the way.
pub const NEAR: f32 = 0.15;
/// See [`NEAR`].
pub const BLOCKING: f64 = 0.3;
/// A wall seen from outside faces the eye about head-on (a floor under an object, seen
/// from above at an angle, is a view of the object, not a wall).
pub const FACING: f32 = 0.9;
/// Below this share of hits the view "sees almost nothing".
pub const ALMOST_NOTHING: f64 = 0.03;

/// A plane's quantized normal and offset.
type PlaneKey = (i32, i32, i32, i32);

/// What the probe saw.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSummary {
    /// Share of the probe rays that hit anything.
    pub hit_share: f64,
    /// Share of all probe rays on the most-hit plane.
    pub dominant_share: f64,
    /// Median distance from the eye to that plane's hits.
    pub dominant_distance: f32,
    /// The diagonal of the scene's bounds.
    pub scene_size: f32,
    /// |cos| of the angle between that plane's normal and the view direction (1: seen
    /// head-on).
    pub facing: f32,
    /// The eye is outside the scene's bounds.
    pub outside: bool,
    /// The scene is flat (one plane is all there is to see).
    pub flat: bool,
}

/// Traces the probe grid of `cam` through `view`.
pub fn summarize(view: &SceneView<'_>, cam: &CameraRecord) -> Option<ViewSummary> {
    let eye = eye_rays(&CameraRecord { width: GRID, height: GRID, ..*cam }, "camera").ok()?;
    let (lo, hi) = view.test_bounds();
    let scale = (hi - lo).length().max(1e-6);
    // Planes by their unit normal (sign-folded: both sides of a wall are one surface)
    // and their offset, each quantized to about 2% (of the scene's size for the offset).
    let mut planes: Vec<(PlaneKey, Vec<f32>, Vec3)> = Vec::new();
    let mut hits = 0usize;
    for y in 0..GRID {
        for x in 0..GRID {
            let ray = eye.ray(x, y);
            let Some(hit) = trace::<Watertight, _>(view, &ray, &mut NoProbe, &mut RayCounters::default()) else {
                continue;
            };
            hits += 1;
            let [a, b, c] = view.triangle(hit.prim, &mut NoProbe);
            let mut n = (b - a).cross(c - a).normalize_or_zero();
            let first = if n.x != 0.0 {
                n.x
            } else if n.y != 0.0 {
                n.y
            } else {
                n.z
            };
            if first < 0.0 {
                n = -n;
            }
            let offset = n.dot(a) / scale;
            let q = |v: f32| (v * 50.0).round() as i32;
            let key = (q(n.x), q(n.y), q(n.z), q(offset));
            let dist = hit.t * ray.dir.length();
            match planes.iter_mut().find(|(k, _, _)| *k == key) {
                Some((_, d, _)) => d.push(dist),
                None => planes.push((key, vec![dist], n)),
            }
        }
    }
    let all = (GRID * GRID) as f64;
    let e = Vec3::from(cam.eye);
    let outside = e.cmplt(lo).any() || e.cmpgt(hi).any();
    let flat = (hi - lo).min_element() <= 0.01 * scale;
    let view_dir = (Vec3::from(cam.look_at) - e).normalize_or_zero();
    let Some((_, dists, normal)) = planes.iter_mut().max_by_key(|(_, d, _)| d.len()) else {
        let nothing = ViewSummary {
            hit_share: 0.0,
            dominant_share: 0.0,
            dominant_distance: 0.0,
            scene_size: scale,
            facing: 0.0,
            outside,
            flat,
        };
        return Some(nothing);
    };
    dists.sort_by(f32::total_cmp);
    Some(ViewSummary {
        hit_share: hits as f64 / all,
        dominant_share: dists.len() as f64 / all,
        dominant_distance: dists.get(dists.len() / 2).copied().unwrap_or(0.0),
        scene_size: scale,
        facing: normal.dot(view_dir).abs(),
        outside,
        flat,
    })
}

/// The hint for a view, if it needs one.
pub fn hint(view: &SceneView<'_>, cam: &CameraRecord) -> Option<String> {
    hint_for(&summarize(view, cam)?, Vec3::from(cam.eye))
}

/// The hint for what a probe saw from `eye`.
pub fn hint_for(s: &ViewSummary, eye: Vec3) -> Option<String> {
    let advice = "give a camera file (--camera) or --eye and --look-at";
    let of_hits = s.dominant_share / s.hit_share.max(1e-9);
    if s.hit_share < ALMOST_NOTHING {
        Some(format!(
            "the view from ({:.3}, {:.3}, {:.3}) sees almost nothing of the scene ({:.0}% of the frame); {advice}",
            eye.x,
            eye.y,
            eye.z,
            100.0 * s.hit_share
        ))
    } else if s.dominant_share >= BLOCKING && s.dominant_distance < NEAR * s.scene_size {
        Some(format!(
            "a surface {:.3} units from the eye covers {:.0}% of the frame: something in the foreground blocks the \
             view; {advice}",
            s.dominant_distance,
            100.0 * s.dominant_share
        ))
    } else if of_hits >= ONE_SURFACE && s.outside && s.facing >= FACING && !s.flat {
        Some(format!(
            "the view is mostly one surface ({:.0}% of what it sees, {:.3} units from the eye): the camera may be \
             outside the scene facing a wall; {advice}",
            100.0 * of_hits,
            s.dominant_distance
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(hit_share: f64, dominant_share: f64, dominant_distance: f32) -> Option<String> {
        let s = ViewSummary {
            hit_share,
            dominant_share,
            dominant_distance,
            scene_size: 100.0,
            facing: 1.0,
            outside: true,
            flat: false,
        };
        hint_for(&s, Vec3::ZERO)
    }

    /// The figures of the views the audit found wrong get a hint; good ones none.
    #[test]
    fn blocked_and_single_surface_views_get_a_hint() {
        // Sponza from outside: a quarter of the frame, three quarters of it one wall.
        assert!(seen(0.35, 0.26, 50.0).unwrap().contains("mostly one surface"));
        // A foreground surface over 37% of the frame, close to the eye.
        assert!(seen(1.0, 0.37, 10.0).unwrap().contains("blocks the view"));
        assert!(seen(0.01, 0.01, 10.0).unwrap().contains("almost nothing"));
        // An interior with many surfaces, a far wall behind a table: no hint.
        assert_eq!(seen(1.0, 0.25, 10.0), None);
        assert_eq!(seen(1.0, 0.4, 60.0), None);
        // A floor under an object, seen at an angle from above it: no hint.
        let floor = ViewSummary {
            hit_share: 0.9,
            dominant_share: 0.7,
            dominant_distance: 3.0,
            scene_size: 5.0,
            facing: 0.6,
            outside: true,
            flat: false,
        };
        assert_eq!(hint_for(&floor, Vec3::ZERO), None);
    }
}
