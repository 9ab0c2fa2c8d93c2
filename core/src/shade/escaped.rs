//! What a ray that leaves the scene sees. Every algorithm and every driver asks this one
//! function — the shaders for rays that hit nothing, the drivers for eye rays that miss
//! the scene's box and are never traced — so a sky (an environment light) fills the
//! whole frame, not only the box's silhouette, and every path shows the same background.

use glam::Vec3;

use crate::camera::EyeRays;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;

/// The scene's sky light, if it has one (the first environment record).
pub fn sky_light<P: MemoryProbe>(scene: &SceneView<'_>, probe: &mut P) -> Option<LightRecord> {
    (0..scene.shading_light_count()).map(|i| scene.light(i, probe)).find(|l| l.kind == LightRecord::ENVIRONMENT)
}

/// Radiance arriving along a ray of direction `dir` that hit nothing: the sky's if the
/// scene has one, else the camera's `background`.
#[inline]
pub fn escaped<P: MemoryProbe>(scene: &SceneView<'_>, dir: Vec3, background: Vec3, probe: &mut P) -> Vec3 {
    match sky_light(scene, probe) {
        Some(sky) => sky.sky(dir.normalize_or_zero()),
        None => background,
    }
}

/// What eye ray `s` of pixel `(x, y)` sees when it misses the scene's box: drivers do not
/// trace it, but it sees the sky along its own direction.
#[inline]
pub fn eye_escaped<P: MemoryProbe>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    (x, y, s): (u32, u32, u32),
    background: Vec3,
    probe: &mut P,
) -> Vec3 {
    escaped(scene, eye.sample_ray(x, y, s).dir, background, probe)
}
