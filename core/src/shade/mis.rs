//! Multiple importance sampling of the path tracer's two ways to reach an emitter
//! (Veach & Guibas 1995, §4 and the power heuristic with β = 2, eq. 9): next-event
//! estimation samples a point on an emitter picked by power; a BSDF bounce may hit one
//! too. Each way weighs what it finds by `p² / (p_light² + p_bsdf²)`, both densities in
//! solid angle, so a sharp lobe reflecting a large emitter comes mostly from the
//! bounce and a small emitter seen by a matte surface mostly from the light sample,
//! without counting either twice.

use glam::Vec3;

use crate::image::SceneView;
use crate::probe::MemoryProbe;
use crate::shade::color::luminance;

/// The power heuristic's weight of a strategy of density `a` against one of density
/// `b` (zero when `a` is zero; one when only `a` could have produced the sample).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    let w = a2 / (a2 + b2);
    if w.is_finite() {
        w
    } else if a > 0.0 {
        1.0
    } else {
        0.0
    }
}

/// Solid-angle density of next-event estimation reaching a point on an emitter that
/// was picked with probability `pick`: area `area` seen at squared distance `d2` under
/// cosine `cos_light` (uniform area sampling turned into solid angle).
#[inline]
pub fn light_density(pick: f32, d2: f32, cos_light: f32, area: f32) -> f32 {
    if cos_light <= 0.0 || area <= 0.0 {
        return 0.0;
    }
    pick * d2 / (cos_light * area)
}

/// Area of the triangle with edge cross product `e` (`(b − a) × (c − a)`).
#[inline]
pub fn area_of(e: Vec3) -> f32 {
    0.5 * e.length()
}

/// The probability that next-event estimation picks the emitting triangle `prim` of
/// radiance `ke`: its power over the emitters' total. The image stores probabilities,
/// not powers, so the total comes from the first area light with a positive
/// probability (power / probability); without an alias table the pick is uniform.
pub fn emitter_pick_probability<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, ke: Vec3, probe: &mut P) -> f32 {
    let n = scene.area_light_count();
    if n == 0 {
        return 0.0;
    }
    let first = scene.shading_light_count();
    let power = |tri: u32, ke: Vec3, probe: &mut P| {
        let [a, b, c] = scene.triangle(tri, probe);
        luminance(ke) * area_of((b - a).cross(c - a))
    };
    for k in 0..n {
        let Some(p) = scene.area_light_probability(k, probe) else { return 1.0 / n as f32 };
        if p <= 0.0 {
            continue;
        }
        let l = scene.light(first + k, probe);
        let reference = power(l.triangle, Vec3::from(l.color), probe);
        if reference > 0.0 {
            let total = reference / p;
            return (power(prim, ke, probe) / total).clamp(0.0, 1.0);
        }
    }
    0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_weights_sum_to_one() {
        for (a, b) in [(1.0f32, 1.0f32), (0.3, 7.0), (1e-20, 1e20), (5.0, 0.0), (0.0, 3.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
    }

    #[test]
    fn light_density_is_the_inverse_solid_angle_of_a_small_patch() {
        // A patch of area 0.01 at distance 2 facing the point: solid angle 0.01/4.
        assert!((light_density(1.0, 4.0, 1.0, 0.01) - 400.0).abs() < 1e-3);
        assert_eq!(light_density(1.0, 4.0, -0.5, 0.01), 0.0);
    }
}
