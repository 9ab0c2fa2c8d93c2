//! Weighted ray records and bounded ray queues (Purcell 2002 §3.1.4, after Kajiya 1986):
//! a shading kernel consumes a hit and emits new ray records instead of recursing; each
//! record carries the pixel it contributes to and the weight its radiance is multiplied
//! by, so a driver can trace them in any order and add each contribution when the ray
//! ends.

use glam::Vec3;
use heapless::Deque;

use crate::ray::Ray;
use crate::shade::ray_cone::RayCone;

/// What a ray is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum RayKind {
    /// From the eye.
    Primary = 0,
    /// Toward a light: its weight is added if nothing is in the way (an any-hit query).
    Shadow = 1,
    /// Mirror reflection.
    Reflection = 2,
    /// Refraction into or out of a transparent material.
    Refraction = 3,
    /// A sampled diffuse bounce of a path.
    Path = 4,
    /// A sampled bounce off a glossy lobe (it sees emitters and the sky, as a mirror
    /// ray does: next-event estimation covers only the diffuse part of area lights).
    Glossy = 5,
}

impl RayKind {
    /// Every kind, in a fixed order (for reports).
    pub const ALL: [RayKind; RayKind::COUNT] =
        [RayKind::Primary, RayKind::Shadow, RayKind::Reflection, RayKind::Refraction, RayKind::Path, RayKind::Glossy];

    /// How many kinds there are.
    pub const COUNT: usize = 6;

    /// Lower-case name for reports.
    pub const fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Reflection => "reflection",
            RayKind::Refraction => "refraction",
            RayKind::Path => "path",
            RayKind::Glossy => "glossy",
        }
    }
}

/// A ray with the pixel it contributes to and its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayRecord {
    /// The ray.
    pub ray: Ray,
    /// Pixel index (row-major) the contribution goes to.
    pub pixel: u32,
    /// Linear RGB factor applied to whatever the ray brings back.
    pub weight: Vec3,
    /// What the ray is for.
    pub kind: RayKind,
    /// Bounces from the eye (primary rays: 0).
    pub depth: u8,
    /// Sample number within the pixel (path tracing's random numbers are drawn from
    /// pixel, sample and bounce).
    pub sample: u32,
    /// The cone of space the ray stands for, for texture filtering.
    pub cone: RayCone,
    /// Solid-angle density with which the shader sampled this ray's direction (the
    /// path tracer's diffuse and glossy bounces, for multiple importance sampling);
    /// zero for rays that were not sampled (eye, mirror, glass, shadow rays).
    pub pdf: f32,
    /// The path has left a diffuse or glossy surface: what it brings is indirect light
    /// (the path tracer's clamp applies to that only).
    pub indirect: bool,
}

impl RayRecord {
    /// A primary ray of weight one, of no cone width (textures at their finest level).
    pub fn primary(ray: Ray, pixel: u32) -> RayRecord {
        RayRecord {
            ray,
            pixel,
            weight: Vec3::ONE,
            kind: RayKind::Primary,
            depth: 0,
            sample: 0,
            cone: RayCone::POINT,
            pdf: 0.0,
            indirect: false,
        }
    }

    /// Eye ray `sample` of `samples` through pixel `pixel`, with the eye's `cone`: weight
    /// `1 / samples`, so the pixel's records add up to the mean of its samples.
    pub fn eye_sample(ray: Ray, pixel: u32, sample: u32, samples: u32, cone: RayCone) -> RayRecord {
        RayRecord { weight: Vec3::splat(1.0 / samples.max(1) as f32), sample, cone, ..RayRecord::primary(ray, pixel) }
    }

    /// A record continuing from `self` (same pixel and sample, indirect if `self` is)
    /// with `cone`, not sampled from a density.
    pub fn child(&self, ray: Ray, weight: Vec3, kind: RayKind, depth: u8, cone: RayCone) -> RayRecord {
        let indirect = self.indirect;
        RayRecord { ray, pixel: self.pixel, weight, kind, depth, sample: self.sample, cone, pdf: 0.0, indirect }
    }
}

/// A bounded first-in first-out queue of ray records (fixed capacity, no heap).
pub type RayQueue<const N: usize> = Deque<RayRecord, N>;
