//! Mirrors and glass: the specular rays a material sends on, by its MTL illumination
//! model — `illum` 3 reflects with weight `Ks`, 5 with Schlick's Fresnel term from `Ks`
//! (a conductor), 7 with `Ks` times the dielectric Fresnel term of `Ni`; `illum` 4, 6, 7
//! and 9, or a dissolve `d` below 1, refract with index `Ni` (Fresnel, total internal
//! reflection). Whitted's shader and the path tracer share it.

use glam::Vec3;

use crate::image::MaterialRecord;
use crate::shade::ray_record::RayKind;

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

/// True if the material lets light through (refraction).
pub fn is_transparent(m: &MaterialRecord) -> bool {
    m.dissolve < 1.0 || matches!(m.illum, 4 | 6 | 7 | 9)
}

/// The fraction of light the material scatters diffusely (`d`, clamped; 1 unless `d` < 1).
pub fn opacity(m: &MaterialRecord) -> f32 {
    if m.dissolve < 1.0 {
        m.dissolve.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// Calls `send(direction, weight factor, kind)` for each specular ray (at most two) that
/// a ray of unit direction `d` sends on from a surface of material `m` with unit normal
/// `n` facing it; `entering`: the ray arrives from outside (for the index ratio).
pub fn specular_rays(m: &MaterialRecord, d: Vec3, n: Vec3, entering: bool, mut send: impl FnMut(Vec3, Vec3, RayKind)) {
    let ior = if m.ior > 0.0 && m.ior.is_finite() { m.ior } else { 1.0 };
    let (eta_i, eta_t) = if entering { (1.0, ior) } else { (ior, 1.0) };
    let kr = fresnel(-d.dot(n), eta_i, eta_t);
    let ks = Vec3::from(m.specular).clamp(Vec3::ZERO, Vec3::ONE);
    match m.illum {
        3 => send(reflect(d, n), ks, RayKind::Reflection),
        // Fresnel on a conductor: Schlick's approximation with `Ks` at normal incidence.
        5 => {
            let c = (1.0 + d.dot(n)).clamp(0.0, 1.0);
            let schlick = ks + (Vec3::ONE - ks) * (c * c * c * c * c);
            send(reflect(d, n), schlick, RayKind::Reflection)
        }
        7 => send(reflect(d, n), ks * kr, RayKind::Reflection),
        _ => {}
    }
    if is_transparent(m) {
        // A dissolved material lets through what it does not scatter; glass all of it.
        let transmitted = if m.dissolve < 1.0 { 1.0 - opacity(m) } else { 1.0 };
        match refract(d, n, eta_i / eta_t) {
            Some(t) => send(t, Vec3::splat((1.0 - kr) * transmitted), RayKind::Refraction),
            // Total internal reflection: what would have been transmitted reflects.
            None => send(reflect(d, n), Vec3::splat(transmitted), RayKind::Reflection),
        }
    }
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
