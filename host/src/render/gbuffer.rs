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
    /// The eye ray of each pixel it is for.
    pub sample: u32,
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

/// Rasterizes every triangle of `scene` as eye ray `sample` of each pixel sees it (core's
/// kernel, triangle by triangle, into storage allocated here).
pub fn rasterize(scene: &SceneView<'_>, eye: &EyeRays, sample: u32) -> GBuffer {
    let (w, h) = (eye.width, eye.height);
    let n = (w * h) as usize;
    let mut g = GBuffer {
        width: w,
        height: h,
        prim: vec![NULL_INDEX; n],
        depth: vec![f32::INFINITY; n],
        uv: vec![(0.0, 0.0); n],
        clipped: 0,
        sample,
    };
    let mut target = GBufferMut { width: w, height: h, prim: &mut g.prim, depth: &mut g.depth, uv: &mut g.uv };
    let near = near_plane(scene);
    let mut clipped = 0;
    for prim in 0..scene.triangle_count() {
        if rasterize_triangle(eye, scene.triangle(prim, &mut NoProbe), prim, near, sample, &mut target)
            == Coverage::Clipped
        {
            clipped += 1;
        }
    }
    g.clipped = clipped;
    g
}

/// The eye ray of pixel `(x, y)` the G-buffer is for, and the hit it gives it (core's
/// [`raypipe_core::shade::raster::gbuffer_hit`]).
pub fn gbuffer_hit<I: raypipe_core::Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    g: &GBuffer,
    x: u32,
    y: u32,
) -> (Option<raypipe_core::Ray>, Option<raypipe_core::Hit>) {
    let i = (y * g.width + x) as usize;
    let ray = eye.sample_ray(x, y, g.sample);
    let hit = raster::gbuffer_hit::<I>(scene, eye, &ray, g.prim[i], g.depth[i], g.uv[i]);
    (Some(ray), hit)
}

/// Every pixel's `(ray, hit)` for eye ray `sample` from a rasterized G-buffer, row-major:
/// the shadow caster's visibility pass, for the drivers that take visibility instead of
/// tracing eye rays.
pub fn gbuffer_visibility<I: raypipe_core::Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    sample: u32,
) -> Vec<(Option<raypipe_core::Ray>, Option<raypipe_core::Hit>)> {
    let g = rasterize(scene, eye, sample);
    (0..eye.height)
        .flat_map(|y| (0..eye.width).map(move |x| (x, y)))
        .map(|(x, y)| gbuffer_hit::<I>(scene, eye, &g, x, y))
        .collect()
}
