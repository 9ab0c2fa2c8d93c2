//! Ray–box clipping with the robust slab test (Ize 2013, "Robust BVH ray traversal";
//! pbrt-v4 `Bounds3::IntersectP`): the far distance is enlarged by `1 + 2·gamma(3)` so
//! that rounding never rejects a box the ray touches.

use glam::{Vec3, Vec4};

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

/// [`clip_ray`] for four rays of one origin at once (directions `dir`, one lane per ray,
/// intervals `[t_min, t_max]`): bit `k` set where lane `k`'s ray would get `Some`. Lane by
/// lane the same operations; a ray's interval only narrows from axis to axis, so testing
/// it for emptiness once at the end decides as the early returns do.
#[inline]
pub fn clip_rays4(origin: Vec3, dir: [Vec4; 3], t_min: Vec4, t_max: Vec4, min: Vec3, max: Vec3) -> u32 {
    let (mut t0, mut t1) = (t_min, t_max);
    let mut outside = 0u32;
    for a in 0..3 {
        let (o, d) = (origin[a], dir[a]);
        let zero = d.cmpeq(Vec4::ZERO);
        if o < min[a] || o > max[a] {
            outside |= zero.bitmask();
        }
        let inv = Vec4::ONE / d;
        let n = Vec4::splat(min[a] - o) * inv;
        let f = Vec4::splat(max[a] - o) * inv;
        let swap = n.cmpgt(f);
        let (near, far) = (Vec4::select(swap, f, n), Vec4::select(swap, n, f) * SLAB_GROWTH);
        // Zero-direction lanes keep their interval (the scalar test skips their axis).
        t0 = Vec4::select(near.cmpgt(t0) & !zero, near, t0);
        t1 = Vec4::select(far.cmplt(t1) & !zero, far, t1);
    }
    !t0.cmpgt(t1).bitmask() & !outside & 0xF
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

    /// Four rays at once decide as the one-ray clip does, lane by lane: rays of every
    /// octant, with zero direction components, from inside, outside and on the faces of
    /// boxes, flat boxes included.
    #[test]
    fn four_rays_clip_as_one_ray_does() {
        let mut g = crate::test_lcg::Lcg(5);
        let q = |g: &mut crate::test_lcg::Lcg| ((g.next() >> 33) % 9) as f32 * 0.5 - 2.0;
        let (mut seen, mut missed) = (0, 0);
        for case in 0..20_000 {
            let min = Vec3::new(q(&mut g), q(&mut g), q(&mut g));
            let ext = Vec3::new(q(&mut g), q(&mut g), q(&mut g)).abs() * if case % 7 == 0 { 0.0 } else { 1.0 };
            let max = min + ext;
            let origin = Vec3::new(q(&mut g), q(&mut g), q(&mut g)) * 1.5;
            let dirs: [Vec3; 4] = core::array::from_fn(|k| {
                // Half the lanes aimed at a point of the box (often hitting it).
                let d = Vec3::new(q(&mut g), q(&mut g), q(&mut g));
                let d = if (case + k) % 2 == 0 { d } else { min + ext * 0.5 + d * 0.25 - origin };
                if d == Vec3::ZERO {
                    Vec3::X
                } else {
                    d
                }
            });
            let (t_min, t_max) = if case % 3 == 0 { (0.5, 3.0) } else { (0.0, f32::INFINITY) };
            let lanes = |a: usize| Vec4::from_array(dirs.map(|d| d[a]));
            let got =
                clip_rays4(origin, [lanes(0), lanes(1), lanes(2)], Vec4::splat(t_min), Vec4::splat(t_max), min, max);
            for (k, d) in dirs.iter().enumerate() {
                let one = clip_ray(&Ray { origin, dir: *d, t_min, t_max }, min, max).is_some();
                assert_eq!(got >> k & 1 != 0, one, "case {case} lane {k}");
                if one {
                    seen += 1;
                } else {
                    missed += 1;
                }
            }
        }
        assert!(seen > 15_000 && missed > 15_000, "{seen} in, {missed} out");
    }
}
