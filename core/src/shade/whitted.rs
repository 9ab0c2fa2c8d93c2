//! Whitted ray tracing as a stream kernel (Whitted 1980; Purcell 2002 §3.1.4 and Fig. 3):
//! the shader consumes the hit of a primary, reflected or refracted ray and, instead of
//! recursing, returns the radiance it can add at once (emission, ambient light) and emits
//! weighted ray records — one shadow ray per point light, whose weight is that light's
//! Lambert contribution and is added only if nothing blocks it, a mirror ray and a
//! refracted ray (Fresnel, total internal reflection) while the depth allows.
//!
//! Mirrors and glass follow the MTL illumination models ([`crate::shade::specular`]); the
//! diffuse part keeps the fraction `d` of a dissolved material. A glossy material (`illum
//! 2` with `Ks`) adds each point light's Blinn–Phong highlight to its shadow ray's weight
//! ([`crate::shade::blinn_phong`]).

use glam::Vec3;

use crate::hit::Hit;
use crate::image::SceneView;
use crate::probe::MemoryProbe;
use crate::shade::escaped::escaped;
use crate::shade::ray_record::RayRecord;
use crate::shade::specular::specular_rays;
use crate::shade::surface::Surface;

/// Settings of the Whitted shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhittedOptions {
    /// Largest number of reflection/refraction bounces.
    pub max_depth: u8,
    /// Radiance of rays that hit nothing when the scene has no sky.
    pub background: Vec3,
}

/// Shades the end of `rec`: returns the radiance added now (already times the record's
/// weight) and passes new records to `emit`.
pub fn shade_whitted<P: MemoryProbe>(
    scene: &SceneView<'_>,
    rec: &RayRecord,
    hit: Option<Hit>,
    opts: &WhittedOptions,
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) -> Vec3 {
    let surface = hit.map(|hit| Surface::at(scene, &rec.ray, &hit, rec.cone, probe));
    shade_whitted_surface(scene, rec, surface, opts, probe, emit)
}

/// [`shade_whitted`] on a surface read already (an instance's, carried to world space):
/// `lights` is the image whose lights and sky shade it.
pub fn shade_whitted_surface<P: MemoryProbe>(
    lights: &SceneView<'_>,
    rec: &RayRecord,
    surface: Option<Surface>,
    opts: &WhittedOptions,
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) -> Vec3 {
    let scene = lights;
    let Some(s) = surface else { return rec.weight * escaped(scene, rec.ray.dir, opts.background, probe) };
    let m = s.material;
    let (diffuse, glossy) = s.lobes();
    let mut now = Vec3::from(m.emission);
    let n = s.normal;
    // The lights before the area lights (Whitted's shader reads no emitter records).
    for i in 0..scene.shading_light_count() {
        let l = scene.light(i, probe);
        now += s.unshadowed(&l, diffuse);
        if Surface::casts_shadows(&l) {
            if let Some(shadow) = s.point_light_shadow(rec, &l, diffuse, glossy.as_ref()) {
                emit(shadow);
            }
        }
    }
    if rec.depth < opts.max_depth && n != Vec3::ZERO {
        let d = rec.ray.dir.normalize_or_zero();
        specular_rays(&m, d, n, s.entering, |dir, factor, kind| {
            if factor.max_element() > 0.0 && dir != Vec3::ZERO {
                emit(rec.child(s.ray_along(dir), rec.weight * factor, kind, rec.depth + 1, s.cone));
            }
        });
    }
    rec.weight * now
}
