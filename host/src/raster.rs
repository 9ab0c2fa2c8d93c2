//! The shadow caster's G-buffer (Purcell 2002 §3.1.4): storage for the frame, filled by
//! core's rasterizer kernel (`raypipe_core::shade::raster`) triangle by triangle.

use raypipe_core::camera::EyeRays;
use raypipe_core::image::NULL_INDEX;
use raypipe_core::shade::raster::{self, rasterize_triangle, Coverage, GBufferMut};
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
    /// Triangles crossing the near plane, drawn clipped.
    pub clipped: u32,
}

/// The near plane's view depth: a millionth of the scene's diagonal, so only what lies
/// closer to the eye than that (which ray casting would see as a wall filling the
/// screen) is lost, while the edge functions in `f64` stay exact to a small fraction of
/// a pixel for vertices projected from just beyond it.
pub fn near_plane(scene: &SceneView<'_>) -> f32 {
    let (lo, hi) = scene.bounds();
    let diagonal = (hi - lo).length();
    if diagonal.is_finite() && diagonal > 0.0 {
        (diagonal * 1e-6).max(f32::MIN_POSITIVE)
    } else {
        1e-6
    }
}

/// Rasterizes every triangle of `scene` as `eye` sees it (core's kernel, triangle by
/// triangle, into storage allocated here).
pub fn rasterize(scene: &SceneView<'_>, eye: &EyeRays) -> GBuffer {
    let (w, h) = (eye.width, eye.height);
    let n = (w * h) as usize;
    let mut g = GBuffer {
        width: w,
        height: h,
        prim: vec![NULL_INDEX; n],
        depth: vec![f32::INFINITY; n],
        uv: vec![(0.0, 0.0); n],
        clipped: 0,
    };
    let mut target = GBufferMut { width: w, height: h, prim: &mut g.prim, depth: &mut g.depth, uv: &mut g.uv };
    let near = near_plane(scene);
    let mut clipped = 0;
    for prim in 0..scene.triangle_count() {
        if rasterize_triangle(eye, scene.triangle(prim, &mut NoProbe), prim, near, &mut target) == Coverage::Clipped {
            clipped += 1;
        }
    }
    g.clipped = clipped;
    g
}

/// The primary ray of pixel `(x, y)` and the hit the G-buffer gives it (core's
/// [`raypipe_core::shade::raster::gbuffer_hit`]).
pub fn gbuffer_hit<I: raypipe_core::Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    g: &GBuffer,
    x: u32,
    y: u32,
) -> (Option<raypipe_core::Ray>, Option<raypipe_core::Hit>) {
    let i = (y * g.width + x) as usize;
    let ray = eye.ray(x, y);
    let hit = raster::gbuffer_hit::<I>(scene, eye, &ray, (x, y), g.prim[i], g.depth[i], g.uv[i]);
    (Some(ray), hit)
}

/// Every pixel's `(ray, hit)` from a rasterized G-buffer, row-major: the shadow caster's
/// visibility pass, for the drivers that take visibility instead of tracing eye rays.
pub fn gbuffer_visibility<I: raypipe_core::Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
) -> Vec<(Option<raypipe_core::Ray>, Option<raypipe_core::Hit>)> {
    let g = rasterize(scene, eye);
    (0..eye.height)
        .flat_map(|y| (0..eye.width).map(move |x| (x, y)))
        .map(|(x, y)| gbuffer_hit::<I>(scene, eye, &g, x, y))
        .collect()
}
