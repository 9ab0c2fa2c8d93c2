//! The shadow caster's first pass (Purcell 2002 §3.1.4, the hybrid "shadow caster"): a
//! small scan-converting rasterizer that fills a G-buffer with the nearest triangle and
//! its depth at every pixel centre, as a GPU's z-buffer pass would, so that ray tracing
//! only has the shadow rays left to do. Edge functions over the triangle's screen
//! bounding box, depth interpolated perspective-correctly (as 1/z), ties to the lower
//! triangle id. Triangles reaching behind the eye are not clipped but left out (counted).

use raypipe_core::camera::EyeRays;
use raypipe_core::image::NULL_INDEX;
use raypipe_core::{NoProbe, SceneView};

/// Nearest triangle per pixel.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Triangle id per pixel, row-major (`NULL_INDEX`: none).
    pub prim: Vec<u32>,
    /// View depth per pixel (`f32::INFINITY`: none).
    pub depth: Vec<f32>,
    /// Screen-space barycentric weights `(u, v)` of the second and third vertex.
    pub uv: Vec<(f32, f32)>,
    /// Triangles left out because they reach behind the eye.
    pub skipped: u32,
}

/// Rasterizes every triangle of `scene` as `eye` sees it.
pub fn rasterize(scene: &SceneView<'_>, eye: &EyeRays) -> GBuffer {
    let (w, h) = (eye.width, eye.height);
    let n = (w * h) as usize;
    let mut g = GBuffer {
        width: w,
        height: h,
        prim: vec![NULL_INDEX; n],
        depth: vec![f32::INFINITY; n],
        uv: vec![(0.0, 0.0); n],
        skipped: 0,
    };
    for prim in 0..scene.triangle_count() {
        let [p0, p1, p2] = scene.triangle(prim, &mut NoProbe);
        let (Some(a), Some(b), Some(c)) = (eye.project(p0), eye.project(p1), eye.project(p2)) else {
            g.skipped += 1;
            continue;
        };
        let edge =
            |p: (f32, f32, f32), q: (f32, f32, f32), x: f32, y: f32| (q.0 - p.0) * (y - p.1) - (q.1 - p.1) * (x - p.0);
        let area = edge(a, b, c.0, c.1);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        let lo_x = a.0.min(b.0).min(c.0).ceil().max(0.0);
        let hi_x = a.0.max(b.0).max(c.0).floor().min(w as f32 - 1.0);
        let lo_y = a.1.min(b.1).min(c.1).ceil().max(0.0);
        let hi_y = a.1.max(b.1).max(c.1).floor().min(h as f32 - 1.0);
        if !(lo_x <= hi_x && lo_y <= hi_y) {
            continue;
        }
        for y in lo_y as u32..=hi_y as u32 {
            for x in lo_x as u32..=hi_x as u32 {
                let (fx, fy) = (x as f32, y as f32);
                // Weights of a, b, c; the pixel centre is inside (edges included) when
                // all have the sign of the area.
                let (w0, w1, w2) = (edge(b, c, fx, fy) / area, edge(c, a, fx, fy) / area, edge(a, b, fx, fy) / area);
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let inv_z = w0 / a.2 + w1 / b.2 + w2 / c.2;
                let z = 1.0 / inv_z;
                let i = (y * w + x) as usize;
                if z < g.depth[i] || (z == g.depth[i] && prim < g.prim[i]) {
                    g.depth[i] = z;
                    g.prim[i] = prim;
                    // Perspective-correct weights of the second and third vertex.
                    g.uv[i] = (w1 / b.2 * z, w2 / c.2 * z);
                }
            }
        }
    }
    g
}

/// The primary ray of pixel `(x, y)` and the hit the G-buffer gives it: the triangle the
/// rasterizer found, hit exactly by the intersection kernel where the ray's test agrees
/// (the same bits as ray casting), else — a pixel centre on a triangle's edge that the
/// two tests decide differently — at the rasterizer's depth and weights.
pub fn gbuffer_hit<I: raypipe_core::Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    g: &GBuffer,
    x: u32,
    y: u32,
) -> (Option<raypipe_core::Ray>, Option<raypipe_core::Hit>) {
    let i = (y * g.width + x) as usize;
    let ray = eye.ray(x, y);
    let prim = g.prim[i];
    if prim == NULL_INDEX {
        return (Some(ray), None);
    }
    let tri = I::fetch(scene, prim, &mut NoProbe);
    let hit = match I::intersect(&I::prepare(&ray), &tri) {
        Some((t, u, v)) => raypipe_core::Hit { t, u, v, prim },
        None => {
            let (u, v) = g.uv[i];
            raypipe_core::Hit { t: g.depth[i] / eye.depth_per_distance(x, y), u, v, prim }
        }
    };
    (Some(ray), Some(hit))
}
