//! Path tracing as a stream kernel (Kajiya 1986; Purcell 2002 §3.1.4 and Fig. 3): at each
//! hit the shader adds what it can at once (emission seen along a camera or specular
//! path), estimates direct light by next-event estimation — one shadow ray per point
//! light, weighted by its Lambert term — and continues the path with a cosine-weighted
//! diffuse bounce (whose weight is just the diffuse colour: cosine and density cancel)
//! and, for mirrors and glass, the specular bounce, until the configured number of
//! bounces. Random numbers come from [`crate::shade::rng`]: pixel, sample and bounce, so the
//! image does not depend on the order rays are traced in.
//!
//! A glossy material (`illum 2` with `Ks`) adds its Blinn–Phong lobe: the point lights'
//! shadow rays carry its highlight, and the bounce picks the diffuse or the glossy lobe
//! in proportion to their reflectance, the glossy one sampled by its half-vector
//! distribution ([`crate::shade::blinn_phong`]). A glossy bounce sees the sky
//! as a mirror ray does, since next-event estimation samples it for the diffuse lobe
//! only; emitters it leaves to next-event estimation, which covers both lobes (no
//! multiple importance sampling: a sharp lobe reflecting a large emitter converges
//! slowly).
//!
//! Emissive triangles are area lights: next-event estimation picks one by power (the
//! image's alias table, [`SceneView::pick_area_light`]) and samples a point on it, so a
//! diffuse bounce that reaches one adds nothing, or its light would be counted twice; the
//! point light that stands in for them in the other algorithms is not used. A sky
//! (environment light) is sampled the same way, along a cosine-distributed shadow ray,
//! and a diffuse bounce that escapes adds nothing. Ambient light records are ignored:
//! the bounces replace them.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::shade::blinn_phong::BlinnPhong;
use crate::shade::escaped::sky_light;
use crate::shade::hemisphere::cosine_direction;
use crate::shade::ray_record::{RayKind, RayRecord};
use crate::shade::rng::uniform;
use crate::shade::specular::specular_rays;
use crate::shade::surface::Surface;

/// Settings of the path tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptions {
    /// Bounces after the first hit (Purcell used 2).
    pub bounces: u8,
    /// End paths at random after the first bounce, reweighting the survivors (unbiased,
    /// but a surviving path's weight can grow).
    pub roulette: bool,
    /// Radiance of rays that hit nothing when the scene has no sky.
    pub background: Vec3,
}

/// Shades the end of `rec`: returns the radiance added now (times the record's weight)
/// and passes new records to `emit`.
pub fn shade_path<P: MemoryProbe>(
    scene: &SceneView<'_>,
    rec: &RayRecord,
    hit: Option<Hit>,
    opts: &PathOptions,
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) -> Vec3 {
    let Some(hit) = hit else {
        // The sky: seen directly along camera and specular paths; after a diffuse bounce
        // next-event estimation has counted it already.
        return match sky_light(scene, probe) {
            Some(_) if rec.kind == RayKind::Path => Vec3::ZERO,
            Some(sky) => rec.weight * sky.sky(rec.ray.dir.normalize_or_zero()),
            None => rec.weight * opts.background,
        };
    };
    let s = Surface::at(scene, &rec.ray, &hit, rec.cone, probe);
    let m = s.material;
    let n = s.normal;
    let areas = scene.area_light_count();
    let mut now = Vec3::ZERO;
    // Emission seen along a camera or specular path; after a diffuse or glossy bounce
    // only when no area light samples the emitters already.
    if !matches!(rec.kind, RayKind::Path | RayKind::Glossy) || areas == 0 {
        now += rec.weight * Vec3::from(m.emission);
    }
    if n == Vec3::ZERO {
        return now;
    }
    let (diffuse, glossy) = s.lobes();
    let depth = rec.depth as u32;
    let u = |dim: u32| uniform(rec.pixel, rec.sample, depth, dim);
    let to_eye = -rec.ray.dir.normalize_or_zero();
    if diffuse.max_element() > 0.0 || glossy.is_some() {
        next_event(scene, rec, &s, (diffuse, glossy), probe, emit);
    }
    if rec.depth >= opts.bounces {
        return now;
    }
    let mut bounce = |dir: Vec3, weight: Vec3, kind: RayKind| {
        if weight.max_element() > 0.0 && dir != Vec3::ZERO && weight.is_finite() {
            emit(rec.child(s.ray_along(dir), weight, kind, rec.depth + 1, s.cone));
        }
    };
    // One bounce off the diffuse or the glossy lobe, picked in proportion to their
    // reflectance and reweighted by that probability.
    let roulette = |factor: Vec3| {
        if opts.roulette && rec.depth >= 1 {
            factor.max_element().clamp(0.05, 0.95)
        } else {
            1.0
        }
    };
    let glossy_share = glossy.map_or(0.0, |g| {
        let (kd, ks) = (diffuse.element_sum(), g.ks.element_sum());
        if kd + ks > 0.0 {
            ks / (kd + ks)
        } else {
            0.0
        }
    });
    match glossy {
        Some(g) if u(9) < glossy_share => {
            if let Some((dir, factor)) = g.sample(n, to_eye, u(0), u(1)) {
                let factor = factor / glossy_share;
                let survive = roulette(factor);
                if u(2) < survive {
                    bounce(dir, rec.weight * factor / survive, RayKind::Glossy);
                }
            }
        }
        _ if diffuse.max_element() > 0.0 => {
            let factor = if glossy.is_some() { diffuse / (1.0 - glossy_share) } else { diffuse };
            let survive = roulette(factor);
            if u(2) < survive {
                bounce(cosine_direction(n, u(0), u(1)), rec.weight * factor / survive, RayKind::Path);
            }
        }
        _ => {}
    }
    // Mirrors and glass, as in Whitted's shader.
    let d = rec.ray.dir.normalize_or_zero();
    specular_rays(&m, d, n, s.entering, |dir, factor, kind| bounce(dir, rec.weight * factor, kind));
    now
}

/// Next-event estimation through both lobes: the point and directional lights and one
/// point on one emitting triangle picked by power. The sky through the diffuse lobe
/// only (its cosine-distributed direction rarely falls in a narrow glossy lobe): the
/// glossy bounce sees the sky itself.
#[inline(always)]
fn next_event<P: MemoryProbe>(
    scene: &SceneView<'_>,
    rec: &RayRecord,
    s: &Surface,
    (diffuse, glossy): (Vec3, Option<BlinnPhong>),
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) {
    let n = s.normal;
    let depth = rec.depth as u32;
    let u = |dim: u32| uniform(rec.pixel, rec.sample, depth, dim);
    let to_eye = -rec.ray.dir.normalize_or_zero();
    for i in 0..scene.shading_light_count() {
        let l = scene.light(i, probe);
        match l.kind {
            LightRecord::POINT | LightRecord::DIRECTIONAL => {
                if let Some(shadow) = s.point_light_shadow(rec, &l, diffuse, glossy.as_ref()) {
                    emit(shadow);
                }
            }
            LightRecord::ENVIRONMENT if diffuse.max_element() > 0.0 => {
                // A cosine-distributed direction: the Lambert BRDF, the cosine and
                // the density cancel to diffuse × sky radiance.
                let dir = cosine_direction(n, u(3), u(4));
                let weight = rec.weight * diffuse * l.sky(dir);
                if weight.max_element() > 0.0 && weight.is_finite() && dir != Vec3::ZERO {
                    emit(rec.child(s.ray_along(dir), weight, RayKind::Shadow, rec.depth, s.cone));
                }
            }
            _ => {}
        }
    }
    if let Some((k, pdf)) = scene.pick_area_light(u(5), u(6), probe) {
        let l = scene.light(scene.shading_light_count() + k, probe);
        let [a, b, c] = scene.triangle(l.triangle, probe);
        let (r1, r2) = (libm::sqrtf(u(7)), u(8));
        let q = a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2);
        let e = (b - a).cross(c - a);
        let to = q - s.point;
        let d2 = to.length_squared();
        let dir = to.normalize_or_zero();
        // Radiance Ke toward the side the triangle faces (its winding), area |e|/2,
        // BRDF (kd + the glossy lobe's π f)/π; divided by the probability of picking
        // this light.
        let cos_l = -e.normalize_or_zero().dot(dir);
        let g = n.dot(dir).max(0.0) * cos_l.max(0.0) * 0.5 * e.length() / (core::f32::consts::PI * d2);
        let reflectance = match glossy {
            Some(gl) => diffuse + gl.eval_pi(n, dir, to_eye),
            None => diffuse,
        };
        let weight = rec.weight * reflectance * Vec3::from(l.color) * (g / pdf);
        if pdf > 0.0 && weight.max_element() > 0.0 && weight.is_finite() {
            // The sample lies on its triangle: stop just short of it.
            emit(rec.child(s.ray_toward(q, 1.0 - 1e-4), weight, RayKind::Shadow, rec.depth, s.cone));
        }
    }
}
