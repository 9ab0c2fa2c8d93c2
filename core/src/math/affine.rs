//! Affine maps as the instance records store them: a 3×4 matrix in row-major order
//! `[m00 m01 m02 t0, m10 m11 m12 t1, m20 m21 m22 t2]`, mapping `p` to `M p + t`.
//!
//! A ray enters an instance through the world-to-object map without renormalising its
//! direction, so a hit's parameter `t` means the same point in both spaces and hits of
//! different instances compare by `t` directly (Wald & Slusallek 2001 §8.3's two-level
//! scheme; Wald, Benthin & Slusallek 2003 for the transformation unit). Every product is
//! written out in one fixed order, so each driver (host, packet, hardware model)
//! computes the same object-space ray bit for bit.

use glam::Vec3;

use crate::ray::Ray;

/// A 3×4 affine map, row-major.
pub type Affine34 = [f32; 12];

/// The identity map.
pub const IDENTITY: Affine34 = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// `M p + t`.
#[inline]
pub fn point(m: &Affine34, p: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
        m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
        m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11],
    )
}

/// `M v` (a direction: no translation).
#[inline]
pub fn vector(m: &Affine34, v: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * v.x + m[1] * v.y + m[2] * v.z,
        m[4] * v.x + m[5] * v.y + m[6] * v.z,
        m[8] * v.x + m[9] * v.y + m[10] * v.z,
    )
}

/// A normal of object space carried to world space: `to_object`'s transpose times `n`
/// (the inverse transpose of `to_world`), unnormalised.
#[inline]
pub fn normal(to_object: &Affine34, n: Vec3) -> Vec3 {
    let m = to_object;
    Vec3::new(
        m[0] * n.x + m[4] * n.y + m[8] * n.z,
        m[1] * n.x + m[5] * n.y + m[9] * n.z,
        m[2] * n.x + m[6] * n.y + m[10] * n.z,
    )
}

/// The world ray `ray` in the object space of an instance whose world-to-object map is
/// `to_object`: the same interval, so the same `t` names the same point.
#[inline]
pub fn object_ray(to_object: &Affine34, ray: &Ray) -> Ray {
    Ray { origin: point(to_object, ray.origin), dir: vector(to_object, ray.dir), t_min: ray.t_min, t_max: ray.t_max }
}

/// True when every entry is finite.
pub fn is_finite(m: &Affine34) -> bool {
    m.iter().all(|x| x.is_finite())
}

/// The determinant of the linear part.
pub fn determinant(m: &Affine34) -> f32 {
    m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) + m[2] * (m[4] * m[9] - m[5] * m[8])
}

/// `a ∘ b` (first `b`, then `a`).
pub fn compose(a: &Affine34, b: &Affine34) -> Affine34 {
    let rows = [Vec3::new(a[0], a[1], a[2]), Vec3::new(a[4], a[5], a[6]), Vec3::new(a[8], a[9], a[10])];
    let cols = [Vec3::new(b[0], b[4], b[8]), Vec3::new(b[1], b[5], b[9]), Vec3::new(b[2], b[6], b[10])];
    let t = Vec3::new(b[3], b[7], b[11]);
    let [r0, r1, r2] = rows;
    let [c0, c1, c2] = cols;
    [
        r0.dot(c0),
        r0.dot(c1),
        r0.dot(c2),
        r0.dot(t) + a[3],
        r1.dot(c0),
        r1.dot(c1),
        r1.dot(c2),
        r1.dot(t) + a[7],
        r2.dot(c0),
        r2.dot(c1),
        r2.dot(c2),
        r2.dot(t) + a[11],
    ]
}

/// Whether `inverse` undoes `forward`: both finite and `inverse ∘ forward` within
/// `1e-3` of the identity in every entry, the translation measured against the
/// coordinates' size. Accepts maps whose condition number is below about 10⁴; a
/// singular map has no inverse to pass.
pub fn is_inverse_pair(forward: &Affine34, inverse: &Affine34) -> bool {
    if !is_finite(forward) || !is_finite(inverse) {
        return false;
    }
    let r = compose(inverse, forward);
    let scale = 1.0 + forward[3].abs().max(forward[7].abs()).max(forward[11].abs());
    let identity_error = (Vec3::new(r[0], r[5], r[10]) - Vec3::ONE)
        .abs()
        .max_element()
        .max(Vec3::new(r[1], r[2], r[4]).abs().max_element())
        .max(Vec3::new(r[6], r[8], r[9]).abs().max_element());
    let shift = Vec3::new(r[3], r[7], r[11]).abs().max_element();
    is_finite(&r) && identity_error <= 1e-3 && shift <= 1e-3 * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_and_its_inverse_pass_and_a_singular_one_does_not() {
        // Rotate 90° about z, scale 2, translate.
        let fwd = [0.0, -2.0, 0.0, 5.0, 2.0, 0.0, 0.0, -1.0, 0.0, 0.0, 2.0, 3.0];
        let inv = [0.0, 0.5, 0.0, 0.5, -0.5, 0.0, 0.0, 2.5, 0.0, 0.0, 0.5, -1.5];
        assert!(is_inverse_pair(&fwd, &inv));
        let p = Vec3::new(0.3, -0.7, 1.1);
        assert!((point(&inv, point(&fwd, p)) - p).abs().max_element() < 1e-6);
        assert!((determinant(&fwd) - 8.0).abs() < 1e-6);
        let flat = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert!(!is_inverse_pair(&flat, &IDENTITY));
        assert!(!is_inverse_pair(&fwd, &IDENTITY));
        let mut nan = inv;
        nan[5] = f32::NAN;
        assert!(!is_inverse_pair(&fwd, &nan));
    }

    #[test]
    fn normals_stay_perpendicular_to_mapped_surfaces() {
        // A shear: a normal carried by the inverse transpose stays perpendicular.
        let fwd = [1.0, 0.7, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.0];
        let inv = [1.0, -0.7, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0 / 3.0, 0.0];
        let (e1, e2) = (Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.0, 0.5, 1.0));
        let n = e1.cross(e2);
        let nw = normal(&inv, n);
        assert!(nw.dot(vector(&fwd, e1)).abs() < 1e-5);
        assert!(nw.dot(vector(&fwd, e2)).abs() < 1e-5);
    }
}
