//! Whitted ray tracing as a stream kernel (Whitted 1980; Purcell 2002 §3.1.4 and Fig. 3):
//! the shader consumes the hit of a primary, reflected or refracted ray and, instead of
//! recursing, returns the radiance it can add at once (emission, ambient light) and emits
//! weighted ray records — one shadow ray per point light, whose weight is that light's
//! Lambert contribution and is added only if nothing blocks it, a mirror ray and a
//! refracted ray (Fresnel, total internal reflection) while the depth allows.
//!
//! Materials follow the MTL illumination models: `illum` 3 reflects with weight `Ks`, 5
//! with Schlick's Fresnel term from `Ks` (a conductor), 7 with `Ks` times the dielectric
//! Fresnel term of `Ni`; `illum` 4, 6, 7 and 9, or a dissolve `d` below 1, refract with the
//! index `Ni` (the diffuse part then keeps the fraction `d`).

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::ray_record::{RayKind, RayRecord};
use crate::surface::Surface;

/// Settings of the Whitted shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhittedOptions {
    /// Largest number of reflection/refraction bounces.
    pub max_depth: u8,
    /// Radiance of rays that hit nothing.
    pub background: Vec3,
}

/// Fresnel reflectance of an unpolarised ray meeting a dielectric interface at incidence
/// cosine `cos_i`, from index `eta_i` into `eta_t`; 1 under total internal reflection.
pub fn fresnel(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = eta_i / eta_t * libm::sqrtf((1.0 - cos_i * cos_i).max(0.0));
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = libm::sqrtf((1.0 - sin_t * sin_t).max(0.0));
    let rs = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    let rp = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let r = 0.5 * (rs * rs + rp * rp);
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// The mirror direction of unit `d` about unit normal `n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// The refracted direction of unit `d` through unit normal `n` facing it, with relative
/// index `eta` (incident over transmitted); `None` under total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    if eta == 1.0 {
        // Equal indices: no bending (exactly, not up to the rounding of the formula).
        return Some(d);
    }
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        return None;
    }
    Some(d * eta + n * (eta * cos_i - libm::sqrtf(k)))
}

fn clamp01(v: Vec3) -> Vec3 {
    v.clamp(Vec3::ZERO, Vec3::ONE)
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
    let Some(hit) = hit else { return rec.weight * opts.background };
    let s = Surface::at(scene, &rec.ray, &hit, probe);
    let m = s.material;
    let (lo, hi) = scene.bounds();
    let extent = (hi - lo).max_element();
    let transparent = m.dissolve < 1.0 || matches!(m.illum, 4 | 6 | 7 | 9);
    let opacity = if m.dissolve < 1.0 { m.dissolve.clamp(0.0, 1.0) } else { 1.0 };
    let diffuse = clamp01(Vec3::from(m.diffuse) * s.tint) * opacity;
    let mut now = Vec3::from(m.emission);
    let n = s.normal;
    for i in 0..scene.light_count() {
        let l = scene.light(i, probe);
        let color = Vec3::from(l.color);
        if l.kind == LightRecord::AMBIENT {
            now += diffuse * color;
            continue;
        }
        if !l.is_point() {
            continue;
        }
        let to_light = Vec3::from(l.position) - s.point;
        let cos = n.dot(to_light.normalize_or_zero());
        let weight = rec.weight * diffuse * color * cos;
        if cos > 0.0 && weight.max_element() > 0.0 {
            let origin = s.offset_point(to_light, extent);
            // The light sits at t = 1: only what lies before it can block it.
            let ray = Ray { origin, dir: Vec3::from(l.position) - origin, t_min: 0.0, t_max: 1.0 };
            emit(rec.child(ray, weight, RayKind::Shadow, rec.depth));
        }
    }
    if rec.depth < opts.max_depth && n != Vec3::ZERO {
        let d = rec.ray.dir.normalize_or_zero();
        let ior = if m.ior > 0.0 && m.ior.is_finite() { m.ior } else { 1.0 };
        let (eta_i, eta_t) = if s.entering { (1.0, ior) } else { (ior, 1.0) };
        let kr = fresnel(-d.dot(n), eta_i, eta_t);
        let mut bounce = |dir: Vec3, weight: Vec3, kind: RayKind| {
            if weight.max_element() > 0.0 && dir != Vec3::ZERO {
                let origin = s.offset_point(dir, extent);
                let ray = Ray::new(origin, dir);
                emit(rec.child(ray, rec.weight * weight, kind, rec.depth + 1));
            }
        };
        let ks = clamp01(Vec3::from(m.specular));
        match m.illum {
            3 => bounce(reflect(d, n), ks, RayKind::Reflection),
            // Fresnel on a conductor: Schlick's approximation with `Ks` at normal incidence.
            5 => {
                let c = (1.0 + d.dot(n)).clamp(0.0, 1.0);
                let schlick = ks + (Vec3::ONE - ks) * (c * c * c * c * c);
                bounce(reflect(d, n), schlick, RayKind::Reflection)
            }
            7 => bounce(reflect(d, n), ks * kr, RayKind::Reflection),
            _ => {}
        }
        if transparent {
            // A dissolved material lets through what it does not scatter; glass all of it.
            let transmitted = if m.dissolve < 1.0 { 1.0 - opacity } else { 1.0 };
            match refract(d, n, eta_i / eta_t) {
                Some(t) => bounce(t, Vec3::splat((1.0 - kr) * transmitted), RayKind::Refraction),
                // Total internal reflection: what would have been transmitted reflects.
                None => bounce(reflect(d, n), Vec3::splat(transmitted), RayKind::Reflection),
            }
        }
    }
    rec.weight * now
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_indices_refract_straight_through_and_reflect_nothing() {
        let d = Vec3::new(0.3, -0.8, 0.2).normalize();
        let n = Vec3::Y;
        assert_eq!(refract(d, n, 1.0), Some(d));
        assert_eq!(fresnel(-d.dot(n), 1.5, 1.5), 0.0);
    }

    #[test]
    fn total_internal_reflection_and_normal_incidence() {
        // From glass into air beyond the critical angle (41.8°): everything reflects.
        let d = Vec3::new(0.9, -0.1, 0.0).normalize();
        assert_eq!(refract(d, Vec3::Y, 1.5), None);
        assert_eq!(fresnel(-d.dot(Vec3::Y), 1.5, 1.0), 1.0);
        // Normal incidence on glass: ((1.5 - 1) / (1.5 + 1))^2 = 0.04.
        assert!((fresnel(1.0, 1.0, 1.5) - 0.04).abs() < 1e-6);
        let r = reflect(Vec3::new(1.0, -1.0, 0.0), Vec3::Y);
        assert_eq!(r, Vec3::new(1.0, 1.0, 0.0));
    }
}
