//! Path tracing as a stream kernel (Kajiya 1986; Purcell 2002 §3.1.4 and Fig. 3): at each
//! hit the shader adds what it can at once (emission seen along a camera or specular
//! path), estimates direct light by next-event estimation — one shadow ray per point
//! light, weighted by its Lambert term — and continues the path with a cosine-weighted
//! diffuse bounce (whose weight is just the diffuse colour: cosine and density cancel)
//! and, for mirrors and glass, the specular bounce, until the configured number of
//! bounces. Random numbers come from [`crate::shade::rng`]: pixel, sample and bounce, so the
//! image does not depend on the order rays are traced in.
//!
//! A glossy material (`illum 2` with `Ks`) adds its Blinn–Phong lobe: the point lights'
//! shadow rays carry its highlight, and the bounce picks the diffuse or the glossy lobe
//! in proportion to their reflectance, the glossy one sampled by its half-vector
//! distribution ([`crate::shade::blinn_phong`]). A glossy bounce sees the sky
//! as a mirror ray does, since next-event estimation samples it for the diffuse lobe
//! only.
//!
//! Emissive triangles are area lights, reached two ways: next-event estimation picks one
//! by power (the image's alias table, [`SceneView::pick_area_light`]) and samples a point
//! on it, and a diffuse or glossy bounce may hit one. Each way's contribution is weighed
//! by the power heuristic ([`crate::shade::mis`], Veach & Guibas 1995), so neither
//! counts the light twice and each covers what the other samples badly (a sharp lobe
//! toward a large emitter, a small emitter seen by a matte wall). The point light that
//! stands in for the emitters in the other algorithms is not used. A sky (environment
//! light) is sampled along a cosine-distributed shadow ray, and a diffuse bounce that
//! escapes adds nothing. Ambient light records are ignored: the bounces replace them.
//!
//! An optional clamp bounds what any one path vertex adds to its pixel (rare paths that
//! find a bright light through a small density, "fireflies"): biased toward darker, but
//! it trades a speckle for a bounded error.

use glam::Vec3;

use crate::hit::Hit;
use crate::image::{LightRecord, SceneView};
use crate::probe::MemoryProbe;
use crate::shade::blinn_phong::BlinnPhong;
use crate::shade::escaped::sky_light;
use crate::shade::hemisphere::cosine_direction;
use crate::shade::mis::{area_of, emitter_pick_probability, light_density, power_heuristic};
use crate::shade::ray_record::{RayKind, RayRecord};
use crate::shade::rng::uniform;
use crate::shade::specular::specular_rays;
use crate::shade::surface::Surface;

/// Settings of the path tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptions {
    /// Bounces after the first hit (Purcell used 2).
    pub bounces: u8,
    /// End paths at random after the first bounce, reweighting the survivors (unbiased,
    /// but a surviving path's weight can grow).
    pub roulette: bool,
    /// Radiance of rays that hit nothing when the scene has no sky.
    pub background: Vec3,
    /// Largest contribution of one path vertex, in the units of a record's weight (a
    /// driver divides a per-sample radiance limit by the samples per pixel);
    /// contributions above it are scaled down, hue kept. Infinity: no clamp.
    pub clamp: f32,
}

impl PathOptions {
    /// The options without a clamp.
    pub const fn new(bounces: u8, roulette: bool, background: Vec3) -> PathOptions {
        PathOptions { bounces, roulette, background, clamp: f32::INFINITY }
    }
}

/// `c` scaled down so that its largest component is at most `limit`.
#[inline]
fn clamped(c: Vec3, limit: f32) -> Vec3 {
    let m = c.max_element();
    if m > limit {
        c * (limit / m)
    } else {
        c
    }
}

/// Shades the end of `rec`: returns the radiance added now (times the record's weight)
/// and passes new records to `emit`.
pub fn shade_path<P: MemoryProbe>(
    scene: &SceneView<'_>,
    rec: &RayRecord,
    hit: Option<Hit>,
    opts: &PathOptions,
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) -> Vec3 {
    // Only indirect light is clamped: what the eye sees directly or through mirrors and
    // glass, and the direct light of the surfaces it sees, stay exact.
    let clamp = if rec.indirect { opts.clamp } else { f32::INFINITY };
    let Some(hit) = hit else {
        // The sky: seen directly along camera and specular paths; after a diffuse bounce
        // next-event estimation has counted it already.
        return clamped(
            match sky_light(scene, probe) {
                Some(_) if rec.kind == RayKind::Path => Vec3::ZERO,
                Some(sky) => rec.weight * sky.sky(rec.ray.dir.normalize_or_zero()),
                None => rec.weight * opts.background,
            },
            clamp,
        );
    };
    let s = Surface::at(scene, &rec.ray, &hit, rec.cone, probe);
    let m = s.material;
    let n = s.normal;
    let ke = Vec3::from(m.emission);
    let mut now = Vec3::ZERO;
    if ke.max_element() > 0.0 {
        now = clamped(rec.weight * ke * emission_weight(scene, rec, &hit, ke, probe), clamp);
    }
    if n == Vec3::ZERO {
        return now;
    }
    let (diffuse, glossy) = s.lobes();
    let depth = rec.depth as u32;
    let u = |dim: u32| uniform(rec.pixel, rec.sample, depth, dim);
    let to_eye = -rec.ray.dir.normalize_or_zero();
    // The lobe mixture the bounce draws from: its density weighs both the light sample
    // and a bounce that hits an emitter (the power heuristic).
    let lobes = Lobes { diffuse, glossy, glossy_share: glossy_share(diffuse, glossy) };
    if diffuse.max_element() > 0.0 || glossy.is_some() {
        // Without a bounce to follow, the light sample is the only way to an emitter.
        next_event(scene, rec, &s, (&lobes, rec.depth < opts.bounces), clamp, probe, emit);
    }
    if rec.depth >= opts.bounces {
        return now;
    }
    let mut bounce = |dir: Vec3, weight: Vec3, kind: RayKind| {
        if weight.max_element() > 0.0 && dir != Vec3::ZERO && weight.is_finite() {
            let child = rec.child(s.ray_along(dir), weight, kind, rec.depth + 1, s.cone);
            emit(if matches!(kind, RayKind::Path | RayKind::Glossy) {
                RayRecord { pdf: lobes.pdf(n, dir, to_eye), indirect: true, ..child }
            } else {
                child
            });
        }
    };
    // One bounce off the diffuse or the glossy lobe, picked in proportion to their
    // reflectance and reweighted by that probability.
    let roulette = |factor: Vec3| {
        if opts.roulette && rec.depth >= 1 {
            factor.max_element().clamp(0.05, 0.95)
        } else {
            1.0
        }
    };
    let glossy_share = lobes.glossy_share;
    match glossy {
        Some(g) if u(9) < glossy_share => {
            if let Some((dir, factor)) = g.sample(n, to_eye, u(0), u(1)) {
                let factor = factor / glossy_share;
                let survive = roulette(factor);
                if u(2) < survive {
                    bounce(dir, rec.weight * factor / survive, RayKind::Glossy);
                }
            }
        }
        _ if diffuse.max_element() > 0.0 => {
            let factor = if glossy.is_some() { diffuse / (1.0 - glossy_share) } else { diffuse };
            let survive = roulette(factor);
            if u(2) < survive {
                bounce(cosine_direction(n, u(0), u(1)), rec.weight * factor / survive, RayKind::Path);
            }
        }
        _ => {}
    }
    // Mirrors and glass, as in Whitted's shader.
    let d = rec.ray.dir.normalize_or_zero();
    specular_rays(&m, d, n, s.entering, |dir, factor, kind| bounce(dir, rec.weight * factor, kind));
    now
}

/// Next-event estimation through both lobes: the point and directional lights and one
/// point on one emitting triangle picked by power. The sky through the diffuse lobe
/// only (its cosine-distributed direction rarely falls in a narrow glossy lobe): the
/// glossy bounce sees the sky itself.
#[inline(always)]
fn next_event<P: MemoryProbe>(
    scene: &SceneView<'_>,
    rec: &RayRecord,
    s: &Surface,
    (lobes, bounce_follows): (&Lobes, bool),
    clamp: f32,
    probe: &mut P,
    emit: &mut impl FnMut(RayRecord),
) {
    let n = s.normal;
    let (diffuse, glossy) = (lobes.diffuse, lobes.glossy);
    let mut emit = |r: RayRecord| emit(RayRecord { weight: clamped(r.weight, clamp), ..r });
    let depth = rec.depth as u32;
    let u = |dim: u32| uniform(rec.pixel, rec.sample, depth, dim);
    let to_eye = -rec.ray.dir.normalize_or_zero();
    for i in 0..scene.shading_light_count() {
        let l = scene.light(i, probe);
        match l.kind {
            LightRecord::POINT | LightRecord::DIRECTIONAL => {
                if let Some(shadow) = s.point_light_shadow(rec, &l, diffuse, glossy.as_ref()) {
                    emit(shadow);
                }
            }
            LightRecord::ENVIRONMENT if diffuse.max_element() > 0.0 => {
                // A cosine-distributed direction: the Lambert BRDF, the cosine and
                // the density cancel to diffuse × sky radiance.
                let dir = cosine_direction(n, u(3), u(4));
                let weight = rec.weight * diffuse * l.sky(dir);
                if weight.max_element() > 0.0 && weight.is_finite() && dir != Vec3::ZERO {
                    emit(rec.child(s.ray_along(dir), weight, RayKind::Shadow, rec.depth, s.cone));
                }
            }
            _ => {}
        }
    }
    if let Some((k, pdf)) = scene.pick_area_light(u(5), u(6), probe) {
        let l = scene.light(scene.shading_light_count() + k, probe);
        let [a, b, c] = scene.triangle(l.triangle, probe);
        let (r1, r2) = (libm::sqrtf(u(7)), u(8));
        let q = a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2);
        let e = (b - a).cross(c - a);
        let to = q - s.point;
        let d2 = to.length_squared();
        let dir = to.normalize_or_zero();
        // Radiance Ke toward the side the triangle faces (its winding), area |e|/2,
        // BRDF (kd + the glossy lobe's π f)/π; divided by the probability of picking
        // this light.
        let cos_l = -e.normalize_or_zero().dot(dir);
        let g = n.dot(dir).max(0.0) * cos_l.max(0.0) * area_of(e) / (core::f32::consts::PI * d2);
        let reflectance = match glossy {
            Some(gl) => diffuse + gl.eval_pi(n, dir, to_eye),
            None => diffuse,
        };
        // The power heuristic against the bounce that could have found the same point.
        let mis = if bounce_follows {
            power_heuristic(light_density(pdf, d2, cos_l, area_of(e)), lobes.pdf(n, dir, to_eye))
        } else {
            1.0
        };
        let weight = rec.weight * reflectance * Vec3::from(l.color) * (g / pdf * mis);
        if pdf > 0.0 && weight.max_element() > 0.0 && weight.is_finite() {
            // The sample lies on its triangle: stop just short of it.
            emit(rec.child(s.ray_toward(q, 1.0 - 1e-4), weight, RayKind::Shadow, rec.depth, s.cone));
        }
    }
}

/// The surface's two lobes and the share of bounces the glossy one gets.
struct Lobes {
    diffuse: Vec3,
    glossy: Option<BlinnPhong>,
    glossy_share: f32,
}

impl Lobes {
    /// Solid-angle density of a bounce toward unit `dir`: the mixture of the cosine
    /// density and the glossy lobe's, in their shares.
    fn pdf(&self, n: Vec3, dir: Vec3, to_eye: Vec3) -> f32 {
        let cosine = n.dot(dir).max(0.0) * core::f32::consts::FRAC_1_PI;
        let diffuse = if self.diffuse.max_element() > 0.0 { cosine } else { 0.0 };
        match &self.glossy {
            Some(g) => (1.0 - self.glossy_share) * diffuse + self.glossy_share * g.pdf(n, dir, to_eye),
            None => diffuse,
        }
    }
}

/// The share of bounces off the glossy lobe: its reflectance over both lobes'.
fn glossy_share(diffuse: Vec3, glossy: Option<BlinnPhong>) -> f32 {
    glossy.map_or(0.0, |g| {
        let (kd, ks) = (diffuse.element_sum(), g.ks.element_sum());
        if kd + ks > 0.0 {
            ks / (kd + ks)
        } else {
            0.0
        }
    })
}

/// The weight of the emission a ray finds at `hit`: whole along camera and specular
/// paths and in scenes whose emitters are not sampled as area lights; after a diffuse or
/// glossy bounce the power heuristic's share against next-event estimation, which could
/// have sampled the same point (zero from an emitter's back, which it never samples).
fn emission_weight<P: MemoryProbe>(scene: &SceneView<'_>, rec: &RayRecord, hit: &Hit, ke: Vec3, probe: &mut P) -> f32 {
    if !matches!(rec.kind, RayKind::Path | RayKind::Glossy) || scene.area_light_count() == 0 {
        return 1.0;
    }
    let [a, b, c] = scene.triangle(hit.prim, probe);
    let e = (b - a).cross(c - a);
    let len = rec.ray.dir.length();
    let dir = rec.ray.dir / len;
    let cos_l = -e.normalize_or_zero().dot(dir);
    if cos_l <= 0.0 {
        return 0.0;
    }
    let d = hit.t * len;
    let pick = emitter_pick_probability(scene, hit.prim, ke, probe);
    power_heuristic(rec.pdf, light_density(pick, d * d, cos_l, area_of(e)))
}
