//! Ray–box clipping with the robust slab test (Ize 2013, "Robust BVH ray traversal";
//! pbrt-v4 `Bounds3::IntersectP`): the far distance is enlarged by `1 + 2·gamma(3)` so
//! that rounding never rejects a box the ray touches.

use glam::Vec3;

use crate::ray::Ray;

/// `1 + 2·gamma(3)` with `gamma(n) = n·u / (1 − n·u)`, `u = 2^-24` (pbrt-v4 §6.8).
pub const SLAB_GROWTH: f32 = 1.0 + 2.0 * (3.0 * 5.960_464_5e-8 / (1.0 - 3.0 * 5.960_464_5e-8));

/// The parameter interval in which `ray` is inside the box `[min, max]`, intersected with
/// the ray's own `[t_min, t_max]`; `None` when the ray misses it. Axes along which the
/// direction is zero are handled explicitly (no `0 · ∞`).
#[inline]
pub fn clip_ray(ray: &Ray, min: Vec3, max: Vec3) -> Option<(f32, f32)> {
    let mut t0 = ray.t_min;
    let mut t1 = ray.t_max;
    for a in 0..3 {
        let (o, d) = (ray.origin[a], ray.dir[a]);
        if d == 0.0 {
            if o < min[a] || o > max[a] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d;
        let mut near = (min[a] - o) * inv;
        let mut far = (max[a] - o) * inv;
        if near > far {
            core::mem::swap(&mut near, &mut far);
        }
        far *= SLAB_GROWTH;
        // Written so that a NaN (from overflow) never shrinks the interval.
        if near > t0 {
            t0 = near;
        }
        if far < t1 {
            t1 = far;
        }
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_parallel_ray_on_the_face_is_inside() {
        let r = Ray::new(Vec3::new(0.0, 1.0, -5.0), Vec3::new(0.0, 0.0, 1.0));
        let (t0, t1) = clip_ray(&r, Vec3::ZERO, Vec3::ONE).expect("touches the face y = 1");
        assert_eq!(t0, 5.0);
        assert!(t1 >= 6.0);
    }

    #[test]
    fn ray_beside_the_box_misses() {
        let r = Ray::new(Vec3::new(2.0, 0.5, -5.0), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(clip_ray(&r, Vec3::ZERO, Vec3::ONE), None);
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!(clip_ray(&r, Vec3::ZERO, Vec3::ONE), None);
    }
}
