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

use glam::{DVec3, Vec3};
use raypipe_core::image::{CameraRecord, LightRecord};
use raypipe_core::traverse::boxes::clip::clip_ray;
use raypipe_core::{Intersector, Ray, Watertight};

use crate::build::light_distribution::{area_light_power, luminance};
use crate::input::mesh::Mesh;

/// Emitted power per unit of scene surface area above which the emitters light the
/// scene alone (see the module's rule).
pub const STRONG_EMITTERS: f64 = 0.01;

/// The default lights and one line saying what they are.
pub fn default_lights(mesh: &Mesh, camera: &CameraRecord) -> (Vec<LightRecord>, String) {
    let mut lights = Vec::new();
    let (power, areas) = emitters(mesh);
    let surface: f64 = mesh.triangles.iter().map(|&t| triangle_area(mesh, t)).sum();
    let strong = !areas.is_empty() && power >= STRONG_EMITTERS * surface;
    let note = if strong {
        let p = emitters_centre(mesh, &areas);
        let brightest = areas.iter().map(|l| Vec3::from(l.color)).fold(Vec3::ZERO, Vec3::max);
        lights.push(LightRecord {
            position: p.to_array(),
            kind: LightRecord::EMITTERS,
            color: (brightest / brightest.max_element()).to_array(),
            triangle: 0,
        });
        format!(
            "{} emissive triangles (power {:.3} per unit of surface, at least {STRONG_EMITTERS}): area lights, and a point light at ({:.3}, {:.3}, {:.3}) standing in for them",
            areas.len(),
            power / surface.max(f64::MIN_POSITIVE),
            p.x,
            p.y,
            p.z
        )
    } else {
        let p = light_for_camera(mesh, camera);
        lights.push(LightRecord { position: p.to_array(), kind: LightRecord::POINT, color: [0.9; 3], triangle: 0 });
        if areas.is_empty() {
            format!("point light at ({:.3}, {:.3}, {:.3}), chosen for the camera", p.x, p.y, p.z)
        } else {
            format!(
                "point light at ({:.3}, {:.3}, {:.3}), chosen for the camera; {} emissive triangles are area lights too (power {:.4} per unit of surface, below {STRONG_EMITTERS})",
                p.x,
                p.y,
                p.z,
                areas.len(),
                power / surface.max(f64::MIN_POSITIVE)
            )
        }
    };
    lights.push(LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 });
    // Area lights last: the shaders of the other algorithms read only the lights before
    // them.
    lights.extend(areas);
    (lights, note)
}

/// The mesh's emissive triangles as area lights, and their total power.
pub fn emitters(mesh: &Mesh) -> (f64, Vec<LightRecord>) {
    let mut areas = Vec::new();
    for (i, (t, &m)) in mesh.triangles.iter().zip(&mesh.tri_materials).enumerate() {
        let ke = mesh.materials.get(m as usize).map_or([0.0; 3], |m| m.emission);
        if Vec3::from(ke).max_element() > 0.0 && !mesh.is_degenerate(*t) {
            areas.push(LightRecord { position: [0.0; 3], kind: LightRecord::AREA, color: ke, triangle: i as u32 });
        }
    }
    let power = areas.iter().map(|l| area_light_power(mesh, l)).sum();
    (power, areas)
}

fn triangle_area(mesh: &Mesh, t: [u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| Vec3::from(mesh.positions[i as usize]));
    crate::build::light_distribution::triangle_area(a, b, c)
}

/// The emitters' power-weighted centre, nudged off them towards the middle of the scene.
fn emitters_centre(mesh: &Mesh, areas: &[LightRecord]) -> Vec3 {
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let centre = (lo + hi) * 0.5;
    let mut sum = DVec3::ZERO;
    let mut weight = 0.0;
    for l in areas {
        let t = mesh.triangles[l.triangle as usize];
        let [a, b, c] = t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
        let w = triangle_area(mesh, t) * luminance(l.color).max(1e-12);
        sum += (a + b + c) / 3.0 * w;
        weight += w;
    }
    let p = (sum / weight.max(f64::MIN_POSITIVE)).as_vec3();
    p + (centre - p).normalize_or_zero() * (hi - lo).length() * 0.01
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
