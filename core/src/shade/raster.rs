//! The shadow caster's first pass (Purcell 2002 §3.1.4, the hybrid "shadow caster"): a
//! small scan-converting rasterizer that fills a G-buffer with the nearest triangle and
//! its depth at every pixel centre, as a GPU's z-buffer pass would, so that ray tracing
//! only has the shadow rays left to do. Edge functions over the triangle's screen
//! bounding box, depth interpolated perspective-correctly (as 1/z), ties to the lower
//! triangle id. Triangles crossing the near plane are clipped against it first
//! (Sutherland–Hodgman), so the floor under the eye is drawn as ray casting sees it.
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

/// What the rasterizer did with a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// Wholly in front of the near plane: scan-converted as it is.
    Whole,
    /// Crossing the near plane: the part in front of it was scan-converted.
    Clipped,
    /// Wholly behind the near plane (or degenerate): nothing to draw.
    Hidden,
}

/// A vertex of a clipped triangle: its position in the camera's frame and its weights
/// over the original triangle's three vertices, carried through the clip so the
/// G-buffer still gives weights of the original second and third vertex.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    p: Vec3,
    b: [f32; 3],
}

/// Sutherland & Hodgman 1974, against one plane: the polygon of `v` that lies at view
/// depth `z >= near`, into `out` (0, 3 or 4 vertices; returns how many). A new vertex
/// sits exactly on the plane, its position and weights interpolated along the edge.
fn clip_near(v: [ClipVertex; 3], near: f32, out: &mut [ClipVertex; 4]) -> usize {
    let mut n = 0;
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let (p_in, q_in) = (p.p.z >= near, q.p.z >= near);
        if p_in {
            out[n] = p;
            n += 1;
        }
        if p_in != q_in {
            let t = (near - p.p.z) / (q.p.z - p.p.z);
            let mut pos = p.p + (q.p - p.p) * t;
            pos.z = near;
            let b = core::array::from_fn(|k| p.b[k] + (q.b[k] - p.b[k]) * t);
            // A triangle has at most two edges crossing a plane, so `n` stays <= 4.
            if let Some(slot) = out.get_mut(n) {
                *slot = ClipVertex { p: pos, b };
                n += 1;
            }
        }
    }
    n
}

/// Scan-converts triangle `prim` (vertices `v`) into `g` as `eye` sees it, clipped
/// against the near plane at view depth `near > 0` first, as a GPU clips in clip space
/// before the perspective divide: the part in front of the plane is drawn whatever the
/// rest does, so the G-buffer covers what ray casting sees beyond `near`.
///
/// The G-buffer is for eye ray `sample` of each pixel: with several samples per pixel
/// ([`EyeRays::samples`]) the edge functions are evaluated at each pixel's sample
/// position instead of its centre, so each sample's G-buffer holds what its eye ray sees.
pub fn rasterize_triangle(
    eye: &EyeRays,
    v: [Vec3; 3],
    prim: u32,
    near: f32,
    sample: u32,
    g: &mut GBufferMut<'_>,
) -> Coverage {
    let corners: [ClipVertex; 3] = core::array::from_fn(|k| {
        let mut b = [0.0; 3];
        b[k] = 1.0;
        ClipVertex { p: eye.to_view(v[k]), b }
    });
    if !corners.iter().all(|c| c.p.is_finite()) {
        return Coverage::Hidden;
    }
    let mut poly = [corners[0]; 4];
    let n = clip_near(corners, near, &mut poly);
    if n < 3 {
        return Coverage::Hidden;
    }
    // The polygon is convex: a fan from its first vertex.
    for k in 1..n - 1 {
        fill(eye, [poly[0], poly[k], poly[k + 1]], prim, sample, g);
    }
    if corners.iter().all(|c| c.p.z >= near) {
        Coverage::Whole
    } else {
        Coverage::Clipped
    }
}

/// Edge functions over the triangle's screen bounding box, in `f64` (a clipped vertex
/// can project millions of pixels away); depth and the original triangle's weights
/// interpolated perspective-correctly (as attribute / z over 1 / z); ties to the lower
/// triangle id.
fn fill(eye: &EyeRays, t: [ClipVertex; 3], prim: u32, sample: u32, g: &mut GBufferMut<'_>) {
    let (w, h) = (g.width, g.height);
    let s: [(f64, f64, f64); 3] = core::array::from_fn(|k| {
        let (x, y) = eye.view_to_pixel(t[k].p);
        (x, y, t[k].p.z as f64)
    });
    let (a, b, c) = (s[0], s[1], s[2]);
    let edge =
        |p: (f64, f64, f64), q: (f64, f64, f64), x: f64, y: f64| (q.0 - p.0) * (y - p.1) - (q.1 - p.1) * (x - p.0);
    let area = edge(a, b, c.0, c.1);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    // Sample positions stray from pixel centres by up to the filter's radius.
    let r = if eye.samples() > 1 { eye.sampler.filter.radius() as f64 } else { 0.0 };
    let lo_x = libm::ceil(a.0.min(b.0).min(c.0) - r).max(0.0);
    let hi_x = libm::floor(a.0.max(b.0).max(c.0) + r).min(w as f64 - 1.0);
    let lo_y = libm::ceil(a.1.min(b.1).min(c.1) - r).max(0.0);
    let hi_y = libm::floor(a.1.max(b.1).max(c.1) + r).min(h as f64 - 1.0);
    if !(lo_x <= hi_x && lo_y <= hi_y) {
        return;
    }
    for y in lo_y as u32..=hi_y as u32 {
        for x in lo_x as u32..=hi_x as u32 {
            let (dx, dy) = eye.sample_offset(x, y, sample);
            let (fx, fy) = (x as f64 + dx as f64, y as f64 + dy as f64);
            // Weights of a, b, c; the sample position is inside (edges included) when all
            // have the sign of the area.
            let wt = [edge(b, c, fx, fy) / area, edge(c, a, fx, fy) / area, edge(a, b, fx, fy) / area];
            if wt.iter().any(|&x| x < 0.0) {
                continue;
            }
            let over_z: [f64; 3] = core::array::from_fn(|k| wt[k] / s[k].2);
            let z = 1.0 / (over_z[0] + over_z[1] + over_z[2]);
            let weight = |vertex: usize| {
                ((over_z[0] * t[0].b[vertex] as f64 + over_z[1] * t[1].b[vertex] as f64)
                    + over_z[2] * t[2].b[vertex] as f64)
                    * z
            };
            let z = z as f32;
            // In u64: `y * w` overflows u32 past 2^32 pixels (and `usize` on 32-bit targets).
            let i = usize::try_from(y as u64 * w as u64 + x as u64).unwrap_or(usize::MAX);
            let (Some(depth), Some(id), Some(uv)) = (g.depth.get_mut(i), g.prim.get_mut(i), g.uv.get_mut(i)) else {
                continue;
            };
            if z < *depth || (z == *depth && prim < *id) {
                *depth = z;
                *id = prim;
                *uv = (weight(1) as f32, weight(2) as f32);
            }
        }
    }
}

/// The hit a G-buffer pixel — nearest triangle `prim`, view depth `depth`, weights
/// `uv` — gives the eye ray `ray` it was rasterized for: the triangle hit exactly by the
/// intersection kernel where the ray's test agrees (the same bits as ray casting), else
/// — a pixel centre on a triangle's edge that the two tests decide differently — at the
/// rasterizer's depth and weights.
pub fn gbuffer_hit<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    ray: &Ray,
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
        None => Hit { t: depth / eye.depth_per_distance_of(ray), u: uv.0, v: uv.1, prim },
    })
}
