//! The shading kernel (Purcell 2002 §3.1.4, the ray caster's shader): interpolated
//! per-vertex normal, material diffuse colour times vertex colour, Lambert shading from
//! the point and directional lights plus ambient light (an environment's mean counts
//! as ambient), plus emission; on a miss the sky or the background ([`crate::shade::escaped`]).
//! Shadows and secondary rays come with the later algorithms.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::shade::escaped::escaped;
use crate::shade::ray_cone::RayCone;
use crate::shade::surface::Surface;

/// The linear RGB radiance seen along `ray`, whose cone is `cone` (it filters textures).
pub fn shade<P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    cone: RayCone,
    hit: Option<Hit>,
    background: Vec3,
    probe: &mut P,
) -> Vec3 {
    let surface = hit.map(|hit| Surface::at(scene, ray, &hit, cone, probe));
    shade_surface(scene, ray, surface, background, probe)
}

/// [`shade`] on a surface read already (an instance's, carried to world space): `lights`
/// is the image whose lights and sky shade it.
pub fn shade_surface<P: MemoryProbe>(
    lights: &SceneView<'_>,
    ray: &Ray,
    surface: Option<Surface>,
    background: Vec3,
    probe: &mut P,
) -> Vec3 {
    let scene = lights;
    let Some(surface) = surface else { return escaped(scene, ray.dir, background, probe) };
    let (n, point) = (surface.normal, surface.point);
    let mut light = Vec3::ZERO;
    // The lights before the area lights: an image's emitters cost this kernel nothing.
    for i in 0..scene.shading_light_count() {
        let l = scene.light(i, probe);
        let color = Vec3::from(l.color);
        match l.kind {
            LightRecord::AMBIENT => light += color,
            LightRecord::ENVIRONMENT => light += l.sky_mean(),
            LightRecord::DIRECTIONAL => light += color * n.dot(Vec3::from(l.position).normalize_or_zero()).max(0.0),
            _ if l.is_point() => {
                let to_light = (Vec3::from(l.position) - point).normalize_or_zero();
                light += color * n.dot(to_light).max(0.0);
            }
            _ => {}
        }
    }
    Vec3::from(surface.material.diffuse) * surface.tint * light + Vec3::from(surface.material.emission)
}
