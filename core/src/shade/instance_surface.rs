//! The surface at an instanced hit: read in the instance's bottom image along the ray in
//! object space (so texture, vertex data and interpolation are the bottom's own), then
//! carried to world space — the point on the world ray, normals by the inverse
//! transpose (Wald & Slusallek 2001 §8.3), the instance's override material — for the
//! ordinary shaders' `*_surface` forms to light with the globals image.

use glam::Vec3;

use crate::image::instanced::TopLevel;
use crate::image::{SceneView, NULL_INDEX};
use crate::math::affine;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::shade::ray_cone::RayCone;
use crate::shade::surface::Surface;
use crate::traverse::instanced::InstanceHit;

/// The world-space surface at `hit` along the world ray `ray` (whose cone is `cone`);
/// `globals` holds the override materials and the scene's bounds. `None` only for a hit
/// naming an instance or bottom that does not exist.
pub fn instance_surface<P: MemoryProbe>(
    top: &TopLevel<'_>,
    bottoms: &[SceneView<'_>],
    globals: &SceneView<'_>,
    ray: &Ray,
    hit: &InstanceHit,
    cone: RayCone,
    probe: &mut P,
) -> Option<Surface> {
    let inst = top.instances().get(hit.instance as usize)?;
    let view = bottoms.get(inst.bottom as usize)?;
    let object = affine::object_ray(&inst.to_object, ray);
    let s = Surface::at(view, &object, &hit.hit, cone, probe);
    // The object-space normal faced the object ray; an affine map keeps the sign of
    // `n · d` (it is `n_obj · d_obj`), so the world normal faces the world ray.
    let normal = affine::normal(&inst.to_object, s.normal).normalize_or_zero();
    let geometric = affine::normal(&inst.to_object, s.geometric);
    let (material, tint) = match inst.material {
        // An override replaces the colours, vertex tint and texture alike.
        NULL_INDEX => (s.material, s.tint),
        m => (*globals.materials().get(m as usize)?, Vec3::ONE),
    };
    let (lo, hi) = globals.scene_bounds();
    Some(Surface {
        point: ray.at(hit.hit.t),
        normal,
        entering: s.entering,
        geometric,
        material,
        tint,
        scene_extent: (hi - lo).max_element(),
        cone: cone.at_hit(hit.hit.t, ray.dir),
    })
}
