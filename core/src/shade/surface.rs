//! What a shader knows about a hit point: its position, the interpolated normal (turned
//! to face the incoming ray) and the material's colours times the vertex colour. Shared
//! by every shading kernel so they agree on the surface bit for bit.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, MaterialRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::shade::blinn_phong::{lobes, BlinnPhong};
use crate::shade::ray_cone::RayCone;
use crate::shade::ray_record::{RayKind, RayRecord};
use crate::shade::texture;

/// The shading data at a hit.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// The hit point, `ray.at(t)`.
    pub point: Vec3,
    /// Unit shading normal facing the incoming ray (zero for a degenerate triangle).
    pub normal: Vec3,
    /// True if the ray arrived on the side the normal points to (it is entering the
    /// surface from outside, for refraction).
    pub entering: bool,
    /// Geometric normal (unnormalised, winding order), for offsetting new rays.
    pub geometric: Vec3,
    /// The triangle's material.
    pub material: MaterialRecord,
    /// Interpolated vertex colour (white without shading vertices).
    pub tint: Vec3,
    /// The scene's largest extent (new rays start off the surface in proportion to it).
    pub scene_extent: f32,
    /// The arriving ray's cone at the hit: what rays leaving the surface continue.
    pub cone: RayCone,
}

impl Surface {
    /// Reads the shading data of `hit` along `ray`, whose cone is `cone` (it filters the
    /// texture).
    pub fn at<P: MemoryProbe>(scene: &SceneView<'_>, ray: &Ray, hit: &Hit, cone: RayCone, probe: &mut P) -> Surface {
        let material = scene.material_of(hit.prim, probe);
        let [p0, p1, p2] = scene.triangle(hit.prim, probe);
        let geometric = (p1 - p0).cross(p2 - p0);
        let (w0, w1, w2) = (1.0 - hit.u - hit.v, hit.u, hit.v);
        let idx = scene.triangle_indices(hit.prim);
        let (mut normal, mut tint) = (geometric, Vec3::ONE);
        if let (Some(a), Some(b), Some(c)) = (
            scene.shading_vertex(idx[0], probe),
            scene.shading_vertex(idx[1], probe),
            scene.shading_vertex(idx[2], probe),
        ) {
            let n = Vec3::from(a.normal) * w0 + Vec3::from(b.normal) * w1 + Vec3::from(c.normal) * w2;
            if n.length_squared() > 0.0 && n.is_finite() {
                normal = n;
            }
            tint = Vec3::from(a.color) * w0 + Vec3::from(b.color) * w1 + Vec3::from(c.color) * w2;
            if let Some(t) = texture::surface_texture(scene, &material) {
                let uv = [a.uv[0] * w0 + b.uv[0] * w1 + c.uv[0] * w2, a.uv[1] * w0 + b.uv[1] * w1 + c.uv[1] * w2];
                // The footprint's mipmap level: the triangle's texels per unit of area,
                // the cone's width at the hit and the incidence.
                let (e1, e2) = ([b.uv[0] - a.uv[0], b.uv[1] - a.uv[1]], [c.uv[0] - a.uv[0], c.uv[1] - a.uv[1]]);
                let texel_area = (e1[0] * e2[1] - e1[1] * e2[0]).abs() * t.width as f32 * t.height as f32;
                let cos = geometric.normalize_or_zero().dot(ray.dir.normalize_or_zero());
                let level = RayCone::level(cone.width_at(hit.t, ray.dir), cos, texel_area, geometric.length());
                if let Some(t) = texture::sample(scene, &t, uv, level, probe) {
                    tint *= t;
                }
            }
        }
        let mut n = normal.normalize_or_zero();
        // Face the viewer: both sides of a triangle are lit alike.
        // "Not facing away", NaN included: the ray caster's shading turned the normal
        // exactly when the dot product was positive.
        let facing_away = n.dot(ray.dir) > 0.0;
        let entering = !facing_away;
        if !entering {
            n = -n;
        }
        let (lo, hi) = scene.scene_bounds();
        let scene_extent = (hi - lo).max_element();
        let cone = cone.at_hit(hit.t, ray.dir);
        Surface { point: ray.at(hit.t), normal: n, entering, geometric, material, tint, scene_extent, cone }
    }

    /// The diffuse reflectance: `Kd` times the vertex colour (and texture), clamped to
    /// `[0, 1]`, times the opacity of a dissolved material.
    pub fn diffuse(&self) -> Vec3 {
        (Vec3::from(self.material.diffuse) * self.tint).clamp(Vec3::ZERO, Vec3::ONE)
            * crate::shade::specular::opacity(&self.material)
    }

    /// The diffuse reflectance and the glossy lobe, scaled together to conserve energy
    /// ([`crate::shade::blinn_phong::lobes`]).
    pub fn lobes(&self) -> (Vec3, Option<BlinnPhong>) {
        lobes(&self.material, self.diffuse())
    }

    /// A point just off the surface on the side `dir` leaves toward, so that a new ray
    /// from it does not hit this triangle again: the offset grows with the coordinates'
    /// magnitude (their rounding) and the scene's size.
    pub fn offset_point(&self, dir: Vec3) -> Vec3 {
        let g = self.geometric.normalize_or_zero();
        let g = if g.dot(dir) < 0.0 { -g } else { g };
        let scale =
            1e-4 * self.scene_extent.max(f32::MIN_POSITIVE) + 64.0 * f32::EPSILON * self.point.abs().max_element();
        self.point + g * scale
    }

    /// A new ray from just off the surface along `dir`.
    pub fn ray_along(&self, dir: Vec3) -> Ray {
        Ray::new(self.offset_point(dir), dir)
    }

    /// A shadow ray from just off the surface to `target`, which lies at `t = 1`; only
    /// what lies before `t_max` can block it.
    pub fn ray_toward(&self, target: Vec3, t_max: f32) -> Ray {
        let origin = self.offset_point(target - self.point);
        Ray { origin, dir: target - origin, t_min: 0.0, t_max }
    }

    /// The shadow ray of a point light (Lambert, no fall-off: the ray caster's light)
    /// continuing `rec`, weighted by `diffuse` and the `glossy` lobe's highlight seen along
    /// `rec`'s ray — `None` if the light is behind the surface or the weight is nothing.
    pub fn point_light_shadow(
        &self,
        rec: &RayRecord,
        light: &LightRecord,
        diffuse: Vec3,
        glossy: Option<&BlinnPhong>,
    ) -> Option<RayRecord> {
        let (to_light, ray) = if light.kind == LightRecord::DIRECTIONAL {
            // A light at infinity: anything along the direction blocks it.
            let d = Vec3::from(light.position).normalize_or_zero();
            (d, self.ray_along(d))
        } else {
            let position = Vec3::from(light.position);
            ((position - self.point).normalize_or_zero(), self.ray_toward(position, 1.0))
        };
        let cos = self.normal.dot(to_light);
        let reflectance = match glossy {
            Some(g) => diffuse + g.eval_pi(self.normal, to_light, -rec.ray.dir.normalize_or_zero()),
            None => diffuse,
        };
        let weight = rec.weight * reflectance * Vec3::from(light.color) * cos;
        (cos > 0.0 && weight.max_element() > 0.0 && weight.is_finite())
            .then(|| rec.child(ray, weight, RayKind::Shadow, rec.depth, self.cone))
    }

    /// What a light adds without a shadow ray (ambient; an environment's mean), times
    /// `diffuse`; zero for the lights that cast shadows.
    pub fn unshadowed(&self, light: &LightRecord, diffuse: Vec3) -> Vec3 {
        match light.kind {
            LightRecord::AMBIENT => diffuse * Vec3::from(light.color),
            LightRecord::ENVIRONMENT => diffuse * light.sky_mean(),
            _ => Vec3::ZERO,
        }
    }

    /// Whether `light` is reached by a shadow ray (point, stand-in, directional).
    pub fn casts_shadows(light: &LightRecord) -> bool {
        light.is_point() || light.kind == LightRecord::DIRECTIONAL
    }
}
