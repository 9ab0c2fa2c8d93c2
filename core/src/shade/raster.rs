//! The shadow caster's first pass (Purcell 2002 §3.1.4, the hybrid "shadow caster"): a
//! small scan-converting rasterizer that fills a G-buffer with the nearest triangle and
//! its depth at every pixel centre, as a GPU's z-buffer pass would, so that ray tracing
//! only has the shadow rays left to do. Edge functions over the triangle's screen
//! bounding box, depth interpolated perspective-correctly (as 1/z), ties to the lower
//! triangle id. Triangles reaching behind the eye are not clipped but left out.
//!
//! The caller owns the G-buffer's storage ([`GBufferMut`]): core allocates nothing.

use glam::Vec3;

use crate::camera::EyeRays;
use crate::hit::Hit;
use crate::image::{SceneView, NULL_INDEX};
use crate::intersect::triangle::Intersector;
use crate::probe::NoProbe;
use crate::ray::Ray;

/// A G-buffer in caller-owned storage: per pixel, row-major, the nearest triangle
/// (`NULL_INDEX`: none; start with it), its view depth (start with `f32::INFINITY`) and
/// the screen-space weights `(u, v)` of its second and third vertex.
#[derive(Debug)]
pub struct GBufferMut<'a> {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Triangle id per pixel.
    pub prim: &'a mut [u32],
    /// View depth per pixel.
    pub depth: &'a mut [f32],
    /// Weights of the second and third vertex per pixel.
    pub uv: &'a mut [(f32, f32)],
}

/// Scan-converts triangle `prim` (vertices `v`) into `g` as `eye` sees it. Returns false
/// if the triangle reaches behind the eye and is left out.
pub fn rasterize_triangle(eye: &EyeRays, v: [Vec3; 3], prim: u32, g: &mut GBufferMut<'_>) -> bool {
    let (w, h) = (g.width, g.height);
    let (Some(a), Some(b), Some(c)) = (eye.project(v[0]), eye.project(v[1]), eye.project(v[2])) else {
        return false;
    };
    let edge =
        |p: (f32, f32, f32), q: (f32, f32, f32), x: f32, y: f32| (q.0 - p.0) * (y - p.1) - (q.1 - p.1) * (x - p.0);
    let area = edge(a, b, c.0, c.1);
    if area == 0.0 || !area.is_finite() {
        return true;
    }
    let lo_x = libm::ceilf(a.0.min(b.0).min(c.0)).max(0.0);
    let hi_x = libm::floorf(a.0.max(b.0).max(c.0)).min(w as f32 - 1.0);
    let lo_y = libm::ceilf(a.1.min(b.1).min(c.1)).max(0.0);
    let hi_y = libm::floorf(a.1.max(b.1).max(c.1)).min(h as f32 - 1.0);
    if !(lo_x <= hi_x && lo_y <= hi_y) {
        return true;
    }
    for y in lo_y as u32..=hi_y as u32 {
        for x in lo_x as u32..=hi_x as u32 {
            let (fx, fy) = (x as f32, y as f32);
            // Weights of a, b, c; the pixel centre is inside (edges included) when all
            // have the sign of the area.
            let (w0, w1, w2) = (edge(b, c, fx, fy) / area, edge(c, a, fx, fy) / area, edge(a, b, fx, fy) / area);
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let inv_z = w0 / a.2 + w1 / b.2 + w2 / c.2;
            let z = 1.0 / inv_z;
            // In u64: `y * w` overflows u32 past 2^32 pixels (and `usize` on 32-bit targets).
            let i = usize::try_from(y as u64 * w as u64 + x as u64).unwrap_or(usize::MAX);
            let (Some(depth), Some(id), Some(uv)) = (g.depth.get_mut(i), g.prim.get_mut(i), g.uv.get_mut(i)) else {
                continue;
            };
            if z < *depth || (z == *depth && prim < *id) {
                *depth = z;
                *id = prim;
                // Perspective-correct weights of the second and third vertex.
                *uv = (w1 / b.2 * z, w2 / c.2 * z);
            }
        }
    }
    true
}

/// The hit a G-buffer pixel `(x, y)` — nearest triangle `prim`, view depth `depth`,
/// weights `uv` — gives the pixel's primary ray `ray`: the triangle hit exactly by the
/// intersection kernel where the ray's test agrees (the same bits as ray casting), else
/// — a pixel centre on a triangle's edge that the two tests decide differently — at the
/// rasterizer's depth and weights.
pub fn gbuffer_hit<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    ray: &Ray,
    (x, y): (u32, u32),
    prim: u32,
    depth: f32,
    uv: (f32, f32),
) -> Option<Hit> {
    if prim == NULL_INDEX {
        return None;
    }
    let tri = I::fetch(scene, prim, &mut NoProbe);
    Some(match I::intersect(&I::prepare(ray), &tri) {
        Some((t, u, v)) => Hit { t, u, v, prim },
        None => Hit { t: depth / eye.depth_per_distance(x, y), u: uv.0, v: uv.1, prim },
    })
}
