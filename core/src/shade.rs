//! The shading kernel (Purcell 2002 §3.1.4, the ray caster's shader): interpolated
//! per-vertex normal, material diffuse colour times vertex colour, Lambert shading from
//! the point lights plus ambient light, plus emission; the background colour on a miss.
//! Shadows and secondary rays come with the later algorithms.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// The linear RGB radiance seen along `ray`.
pub fn shade<P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    hit: Option<Hit>,
    background: Vec3,
    probe: &mut P,
) -> Vec3 {
    let Some(hit) = hit else { return background };
    let material = scene.material_of(hit.prim, probe);
    let [p0, p1, p2] = scene.triangle(hit.prim, probe);
    let geometric = (p1 - p0).cross(p2 - p0);
    let (w0, w1, w2) = (1.0 - hit.u - hit.v, hit.u, hit.v);

    let idx = scene.triangle_indices(hit.prim);
    let (mut normal, mut tint) = (geometric, Vec3::ONE);
    if let (Some(a), Some(b), Some(c)) =
        (scene.shading_vertex(idx[0], probe), scene.shading_vertex(idx[1], probe), scene.shading_vertex(idx[2], probe))
    {
        let n = Vec3::from(a.normal) * w0 + Vec3::from(b.normal) * w1 + Vec3::from(c.normal) * w2;
        if n.length_squared() > 0.0 && n.is_finite() {
            normal = n;
        }
        tint = Vec3::from(a.color) * w0 + Vec3::from(b.color) * w1 + Vec3::from(c.color) * w2;
    }
    let mut n = normal.normalize_or_zero();
    // Face the viewer: both sides of a triangle are lit alike.
    if n.dot(ray.dir) > 0.0 {
        n = -n;
    }
    let point = ray.at(hit.t);
    let mut light = Vec3::ZERO;
    for i in 0..scene.light_count() {
        let l = scene.light(i, probe);
        let color = Vec3::from(l.color);
        if l.kind == LightRecord::AMBIENT {
            light += color;
        } else {
            let to_light = (Vec3::from(l.position) - point).normalize_or_zero();
            light += color * n.dot(to_light).max(0.0);
        }
    }
    Vec3::from(material.diffuse) * tint * light + Vec3::from(material.emission)
}
