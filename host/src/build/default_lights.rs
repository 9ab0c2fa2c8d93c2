//! Lights for a scene that brings none of its own, chosen for the camera that renders it.
//!
//! * A point light inside the scene's bounds and visible from the eye: of a fan of
//!   directions above and around the view direction, the one with the longest stretch
//!   of free space inside the bounds; the light sits halfway along that stretch. From
//!   an interior camera (Sponza, the conference room) it lands inside the room, above
//!   and ahead of the eye, never behind a wall; from outside it lands inside the box
//!   between the eye and the model.
//! * Emissive triangles are area lights (the path tracer samples them by power). They
//!   replace the point light only when they carry enough power: when their total
//!   power — luminance of `Ke` times area, summed — spread over all of the scene's
//!   surface area is at least [`STRONG_EMITTERS`]. A Cornell box's ceiling lamp passes;
//!   Lost Empire's lava and the sports car's headlights do not, and those scenes keep
//!   the point light too.
//! * A dim ambient term.

use glam::Vec3;
use raypipe_core::image::{CameraRecord, LightRecord};
use raypipe_core::traverse::boxes::clip::clip_ray;
use raypipe_core::{Intersector, Ray, Watertight};

use crate::build::emitter_sums::EmitterSums;
use crate::input::mesh::Mesh;

/// Emitted power per unit of scene surface area above which the emitters light the
/// scene alone (see the module's rule).
pub const STRONG_EMITTERS: f64 = 0.01;

/// The default lights and one line saying what they are.
pub fn default_lights(mesh: &Mesh, camera: &CameraRecord) -> (Vec<LightRecord>, String) {
    let (lo, hi) = mesh.bounds();
    let sums = EmitterSums::of_mesh(mesh);
    let (mut lights, note) = lights_for(&sums, (lo, hi), camera, |ray| first_hit(mesh, ray));
    // Area lights last: the shaders of the other algorithms read only the lights before
    // them.
    lights.extend(emitters(mesh));
    (lights, note)
}

/// The default lights other than area lights — a point light (for the camera, or
/// standing in for strong emitters) and the ambient term — for a scene of `bounds`
/// whose emitters sum to `sums` and whose nearest hit along a ray `first_hit` gives.
pub fn lights_for(
    sums: &EmitterSums,
    bounds: ([f32; 3], [f32; 3]),
    camera: &CameraRecord,
    first_hit: impl Fn(&Ray) -> Option<f32>,
) -> (Vec<LightRecord>, String) {
    let (lo, hi) = (Vec3::from(bounds.0), Vec3::from(bounds.1));
    let mut lights = Vec::new();
    let note = if sums.strong(STRONG_EMITTERS) {
        let p = sums.centre(lo, hi);
        lights.push(LightRecord {
            position: p.to_array(),
            kind: LightRecord::EMITTERS,
            color: sums.colour().to_array(),
            triangle: 0,
        });
        format!(
            "{} emissive triangles (power {:.3} per unit of surface, at least {STRONG_EMITTERS}): area lights, and a point light at ({:.3}, {:.3}, {:.3}) standing in for them",
            sums.count,
            sums.density(),
            p.x,
            p.y,
            p.z
        )
    } else {
        let p = light_in_view(lo, hi, camera, first_hit);
        lights.push(LightRecord { position: p.to_array(), kind: LightRecord::POINT, color: [0.9; 3], triangle: 0 });
        if sums.count == 0 {
            format!("point light at ({:.3}, {:.3}, {:.3}), chosen for the camera", p.x, p.y, p.z)
        } else {
            format!(
                "point light at ({:.3}, {:.3}, {:.3}), chosen for the camera; {} emissive triangles are area lights too (power {:.4} per unit of surface, below {STRONG_EMITTERS})",
                p.x,
                p.y,
                p.z,
                sums.count,
                sums.density()
            )
        }
    };
    lights.push(LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 });
    (lights, note)
}

/// The mesh's emissive triangles as area lights (those [`is_emitter`] admits).
pub fn emitters(mesh: &Mesh) -> Vec<LightRecord> {
    let mut areas = Vec::new();
    for (i, (t, &m)) in mesh.triangles.iter().zip(&mesh.tri_materials).enumerate() {
        let ke = mesh.materials.get(m as usize).map_or([0.0; 3], |m| m.emission);
        if is_emitter(t.map(|v| mesh.positions[v as usize]), ke) {
            areas.push(LightRecord { position: [0.0; 3], kind: LightRecord::AREA, color: ke, triangle: i as u32 });
        }
    }
    areas
}

/// Whether the triangle `p` of emission `ke` is an area light: it emits, and it has an
/// area (its edges' cross product, in f64, is not zero).
pub fn is_emitter(p: [[f32; 3]; 3], ke: [f32; 3]) -> bool {
    let [a, b, c] = p.map(|v| glam::DVec3::from(v.map(f64::from)));
    Vec3::from(ke).max_element() > 0.0 && (b - a).cross(c - a) != glam::DVec3::ZERO
}

/// A point inside the scene's bounds that the eye sees: halfway along the longest free
/// stretch inside the bounds of a fan of rays from the eye, tilted up from the view
/// direction (light from above and ahead shows shapes and casts visible shadows).
pub fn light_for_camera(mesh: &Mesh, camera: &CameraRecord) -> Vec3 {
    let (lo, hi) = mesh.bounds();
    light_in_view(Vec3::from(lo), Vec3::from(hi), camera, |ray| first_hit(mesh, ray))
}

/// [`light_for_camera`] for a scene of bounds `lo`..`hi` whose nearest hit along a ray
/// `first_hit` gives (a mesh before building, or a built image's structure).
pub fn light_in_view(lo: Vec3, hi: Vec3, camera: &CameraRecord, first_hit: impl Fn(&Ray) -> Option<f32>) -> Vec3 {
    let eye = Vec3::from(camera.eye);
    let forward = (Vec3::from(camera.look_at) - eye).normalize_or_zero();
    let right = forward.cross(Vec3::from(camera.up)).normalize_or_zero();
    let up = right.cross(forward);
    let mut best: Option<(f32, Vec3)> = None;
    for (a, b) in [(0.6, 0.0), (0.6, 0.35), (0.6, -0.35), (0.3, 0.0), (1.2, 0.0), (0.3, 0.5), (0.0, 0.0)] {
        let dir = (forward + up * a + right * b).normalize_or_zero();
        if dir == Vec3::ZERO {
            continue;
        }
        let ray = Ray::new(eye, dir);
        let Some((enter, exit)) = clip_ray(&ray, lo, hi) else { continue };
        let free_end = first_hit(&ray).unwrap_or(f32::INFINITY).min(exit);
        let start = enter.max(0.0);
        if free_end <= start {
            continue;
        }
        // Prefer long free stretches, tilted up a little.
        let score = (free_end - start) * (1.0 + 0.25 * a.min(0.6));
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, ray.at(start + 0.5 * (free_end - start))));
        }
    }
    match best {
        Some((_, p)) => p,
        // Nothing free inside the bounds in front of the eye: the old headlight above it.
        None => eye + up * (eye - (lo + hi) * 0.5).length() * 0.25,
    }
}

/// The nearest triangle along `ray`, by core's watertight test over every triangle (a
/// handful of rays at build time; no structure exists yet).
fn first_hit(mesh: &Mesh, ray: &Ray) -> Option<f32> {
    let mut nearest = NearestHit::new(ray);
    for t in &mesh.triangles {
        nearest.test(t.map(|i| Vec3::from(mesh.positions[i as usize])));
    }
    nearest.t()
}

/// The nearest triangle in front of a ray's origin over triangles handed in one by one
/// (brute force with core's watertight test): the default light's rays, before any
/// structure exists.
pub struct NearestHit {
    prepared: <Watertight as Intersector>::Prepared,
    best: Option<f32>,
}

impl NearestHit {
    /// Nothing hit yet.
    pub fn new(ray: &Ray) -> NearestHit {
        NearestHit { prepared: Watertight::prepare(ray), best: None }
    }

    /// Tests one triangle.
    #[inline]
    pub fn test(&mut self, tri: [Vec3; 3]) {
        if let Some((d, _, _)) = Watertight::intersect(&self.prepared, &tri) {
            if d > 0.0 && self.best.is_none_or(|b| d < b) {
                self.best = Some(d);
            }
        }
    }

    /// The nearest distance found.
    pub fn t(&self) -> Option<f32> {
        self.best
    }
}
