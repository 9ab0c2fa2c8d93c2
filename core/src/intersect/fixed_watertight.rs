//! The watertight ray–triangle test in fixed point: Woop, Benthin & Wald 2013 (JCGT
//! 2(1), Fig. 1) on integers, for FPGA datapaths without floating point.
//!
//! The ray is the fixed-point ray ([`FixedRay`]); vertices are rounded to the nearest
//! raw value of the format `Q(BITS − FRAC).FRAC`, then made relative to the origin
//! (exact). The shear is the only rounding of the test: each vertex's `x − sx · z` is
//! rounded to the nearest unit (`z` is not rounded at all). The edge functions, the
//! determinant and the scaled distance are then exact integer products, so:
//!
//! * the test is **watertight without a fallback**: an edge shared by two triangles has
//!   the same sheared endpoints in both (they depend on the vertex and the ray only), so
//!   its edge function is the same integer with opposite signs, and a zero is a true
//!   zero — the `f32` test's double-precision recount (§3.3) has nothing to do here;
//! * the hit distance `τ = T / det` is rounded once (to the nearest unit) and lies within
//!   the triangle's extent along the major axis.
//!
//! Widths a hardware datapath needs for these results to be exact, for `W = BITS`:
//! relative coordinates `W + 1` bits, slopes `W`, sheared coordinates `W + 2`, edge
//! functions and determinant `2W + 6`, the scaled distance `T` `3W + 9`, the quotient
//! `W + 2`. The model computes them in `i64` / `i128`, where none can overflow.
//!
//! `t` is `τ` turned back into the `f32` ray's parameter ([`FixedRay::tau_to_t`]);
//! `u`, `v` (for shading only) are `V / det` and `W / det` in `f32`. The BVH walks test
//! boxes with the matching fixed-point box test ([`FixedNodes`]).

use glam::Vec3;

use crate::fixed_ray::FixedRay;
use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::math::fixed_point::{div_nearest, shift_nearest, Round};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::FixedNodes;

/// The fixed-point watertight test in the format `Q(BITS − FRAC).FRAC`.
#[derive(Clone, Copy, Debug, Default)]
pub struct FixedWatertight<const BITS: u32, const FRAC: u32>;

/// Q16.16: 32-bit coordinates, 16 fraction bits.
pub type Q16_16 = FixedWatertight<32, 16>;
/// Q12.12: the 24-bit variant.
pub type Q12_12 = FixedWatertight<24, 12>;

impl<const BITS: u32, const FRAC: u32> FixedWatertight<BITS, FRAC> {
    /// The exact edge functions `[U, V, W]`, the determinant and `T` of the triangle `v`
    /// for the ray `r`, or `None` where the ray misses (an edge function of each sign,
    /// or a zero determinant).
    #[inline]
    pub fn edges(r: &FixedRay<BITS, FRAC>, v: &[Vec3; 3]) -> Option<([i128; 3], i128, i128)> {
        if !r.valid {
            return None;
        }
        let fmt = FixedRay::<BITS, FRAC>::FORMAT;
        let s = FixedRay::<BITS, FRAC>::SLOPE_FRAC;
        let k = r.k.map(|a| usize::from(a) % 3);
        let [sx, sy] = r.slope.map(i128::from);
        // Sheared 2D coordinates and the coordinate along the ray (sign-corrected so
        // that it grows along the ray), per vertex.
        let shear = |p: Vec3| -> [i128; 3] {
            let p = p.to_array();
            let rel = k.map(|a| i128::from(fmt.from_f32(p[a], Round::Nearest) - r.origin[a]));
            let z = rel[2];
            [rel[0] - shift_nearest(sx * z, s), rel[1] - shift_nearest(sy * z, s), if r.negative { -z } else { z }]
        };
        let [a, b, c] = v.map(shear);
        let u = c[0] * b[1] - c[1] * b[0];
        let w_v = a[0] * c[1] - a[1] * c[0];
        let w = b[0] * a[1] - b[1] * a[0];
        if (u < 0 || w_v < 0 || w < 0) && (u > 0 || w_v > 0 || w > 0) {
            return None;
        }
        let det = u + w_v + w;
        if det == 0 {
            return None;
        }
        Some(([u, w_v, w], det, u * a[2] + w_v * b[2] + w * c[2]))
    }

    /// The hit distance `τ` (raw) of a hit found by [`FixedWatertight::edges`].
    #[inline]
    pub fn tau(det: i128, t_scaled: i128) -> i64 {
        let q = div_nearest(t_scaled, det);
        q.clamp(i64::MIN as i128, i64::MAX as i128) as i64
    }
}

impl<const BITS: u32, const FRAC: u32> Intersector for FixedWatertight<BITS, FRAC> {
    type Prepared = FixedRay<BITS, FRAC>;
    type Triangle = [Vec3; 3];
    const NAME: &'static str = "fixed-watertight";
    type Nodes = FixedNodes<BITS, FRAC>;
    type Prepared4 = ();
    type Prepared16 = ();

    #[inline]
    fn prepare(ray: &Ray) -> FixedRay<BITS, FRAC> {
        FixedRay::new(ray)
    }

    #[inline(always)]
    fn fetch<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, probe: &mut P) -> [Vec3; 3] {
        scene.triangle(prim, probe)
    }

    #[inline]
    fn intersect(r: &FixedRay<BITS, FRAC>, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let ([_, ev, ew], det, t_scaled) = Self::edges(r, v)?;
        let t = r.tau_to_t(Self::tau(det, t_scaled));
        let d = det as f32;
        Some((t, ev as f32 / d, ew as f32 / d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intersect::watertight::Watertight;
    use crate::test_lcg::Lcg;

    /// Rays through a shared edge or vertex of a fan of triangles hit at least one of
    /// them: never a gap, with no fallback (rays aimed exactly at the grid's edges).
    #[test]
    fn shared_edges_leave_no_gap() {
        let mut g = Lcg(17);
        let mut checked = 0;
        for _ in 0..4000 {
            // A fan around a centre, vertices on the format's grid.
            let q = |x: f32| (x * 4096.0).round() / 4096.0;
            let c = Vec3::new(q(g.range(-2.0, 2.0)), q(g.range(-2.0, 2.0)), q(g.range(-1.0, 1.0)));
            let n = 3 + (g.next() >> 62) as usize * 2;
            let ring: [Vec3; 9] = core::array::from_fn(|i| {
                let a = i as f32 / n as f32 * core::f32::consts::TAU;
                c + Vec3::new(
                    q(crate::math::trig::sin_cos(a).1 * 1.5),
                    q(crate::math::trig::sin_cos(a).0 * 1.5),
                    q(g.range(-0.3, 0.3)),
                )
            });
            let tris: [[Vec3; 3]; 9] = core::array::from_fn(|i| [c, ring[i % n], ring[(i + 1) % n]]);
            // Aim at a point on a shared edge (centre to ring vertex), or at the centre.
            let i = (g.next() >> 40) as usize % n;
            let f = if g.unit() < 0.2 { 0.0 } else { g.unit() };
            let target = c + (ring[i] - c) * f;
            let origin = Vec3::new(g.range(-3.0, 3.0), g.range(-3.0, 3.0), g.range(4.0, 8.0));
            let ray = Ray::new(origin, target - origin);
            let r = <Q12_12 as Intersector>::prepare(&ray);
            let hit = tris[..n].iter().any(|t| Q12_12::intersect(&r, t).is_some());
            assert!(hit, "gap at {target:?} from {origin:?}");
            checked += 1;
        }
        assert_eq!(checked, 4000);
    }

    /// On triangles and rays well inside the format, the hit agrees with the f32 test
    /// (same verdict away from edges, distance within a few units of the format).
    #[test]
    fn agrees_with_the_f32_test_away_from_edges() {
        let mut g = Lcg(23);
        let (mut both, mut compared) = (0, 0);
        for _ in 0..20_000 {
            let v: [Vec3; 3] =
                core::array::from_fn(|_| Vec3::new(g.range(-4.0, 4.0), g.range(-4.0, 4.0), g.range(-4.0, 4.0)));
            let origin = Vec3::new(g.range(-8.0, 8.0), g.range(-8.0, 8.0), g.range(-8.0, 8.0));
            let w = [g.unit(), g.unit(), g.unit()];
            let s = w[0] + w[1] + w[2];
            let target = (v[0] * w[0] + v[1] * w[1] + v[2] * w[2]) / s;
            let ray = Ray::new(origin, target - origin);
            let f = Watertight::intersect(&Watertight::prepare(&ray), &v);
            let x = Q16_16::intersect(&<Q16_16 as Intersector>::prepare(&ray), &v);
            // Away from edges: every barycentric weight above 2%.
            if w.iter().all(|&x| x / s > 0.02) {
                compared += 1;
                let (Some(f), Some(x)) = (f, x) else { panic!("verdicts differ: {f:?} {x:?} {ray:?} {v:?}") };
                // |Δτ| ≤ a few units of 2^-16 along the major axis, more as the ray
                // grazes the triangle (a sideways error of the rounded vertices moves
                // the plane along the ray by it over the cosine).
                let dz = ray.dir.abs().max_element();
                let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                let cos = n.dot(ray.dir.normalize()).abs();
                let tol = 4.0 / 65536.0 / cos + f.0 * dz * 1e-6;
                assert!(((f.0 - x.0) * dz).abs() <= tol, "{f:?} {x:?} cos {cos}");
                assert!((f.1 - x.1).abs() < 1e-3 / cos && (f.2 - x.2).abs() < 1e-3 / cos);
                both += 1;
            }
        }
        assert_eq!(both, compared);
        assert!(compared > 10_000);
    }

    #[test]
    fn invalid_rays_and_degenerate_triangles_miss() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let r = <Q16_16 as Intersector>::prepare(&Ray::new(Vec3::ZERO, Vec3::ZERO));
        assert_eq!(Q16_16::intersect(&r, &v), None);
        let r = <Q16_16 as Intersector>::prepare(&Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z));
        let (t, u, w) = Q16_16::intersect(&r, &v).expect("hits");
        assert_eq!((t, u, w), (1.0, 0.25, 0.25));
        assert_eq!(Q16_16::intersect(&r, &[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]), None);
        // Below the format's resolution the triangle collapses: no hit, no NaN.
        let tiny = [Vec3::ZERO, Vec3::X * 1e-6, Vec3::Y * 1e-6];
        assert_eq!(Q16_16::intersect(&r, &tiny), None);
    }
}
