//! The shading kernel (Purcell 2002 §3.1.4, the ray caster's shader): interpolated
//! per-vertex normal, material diffuse colour times vertex colour, Lambert shading from
//! the point lights plus ambient light, plus emission; the background colour on a miss.
//! Shadows and secondary rays come with the later algorithms.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::shade::surface::Surface;

/// The linear RGB radiance seen along `ray`.
pub fn shade<P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    hit: Option<Hit>,
    background: Vec3,
    probe: &mut P,
) -> Vec3 {
    let Some(hit) = hit else { return background };
    let surface = Surface::at(scene, ray, &hit, probe);
    let (n, point) = (surface.normal, surface.point);
    let mut light = Vec3::ZERO;
    for i in 0..scene.light_count() {
        let l = scene.light(i, probe);
        let color = Vec3::from(l.color);
        if l.kind == LightRecord::AMBIENT {
            light += color;
        } else if l.is_point() {
            let to_light = (Vec3::from(l.position) - point).normalize_or_zero();
            light += color * n.dot(to_light).max(0.0);
        }
    }
    Vec3::from(surface.material.diffuse) * surface.tint * light + Vec3::from(surface.material.emission)
}
