//! The host's driver of the ray-emitting shaders (Purcell 2002 §3.1.4): a tile's rays
//! are records in one first-in first-out stream. Primary hits are shaded in pixel order
//! (one record per sample); every record a shader emits joins the stream; shadow rays
//! take core's any-hit query, the others its closest-hit query and the shader again. A
//! record's contribution is added to its pixel when it ends, as an exact fixed-point sum
//! ([`RadianceSum`]), so the image depends neither on the order rays end in nor on
//! threads, tiles, packet sizes — or on being traced by the hardware model instead.

use std::collections::VecDeque;

use raypipe_core::camera::EyeRays;
use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::traverse::occlusion::{occluded, occluded_cached};
use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;
use raypipe_core::{Hit, Intersector, MemoryProbe, Ray, RayCounters, SceneView, Vec3};

use crate::render::ray_log::TileRayLog;
use crate::render::tracer::trace;

/// What a tile's ray stream cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamCounts {
    /// Rays by kind (indexed by `RayKind as usize`; primary rays are the caller's).
    pub rays: [u64; RayKind::COUNT],
    /// Traversal steps (nodes or voxels) of the secondary and shadow rays.
    pub steps: u64,
    /// Their ray–triangle tests.
    pub tests: u64,
    /// Hits shaded.
    pub shades: u64,
}

impl StreamCounts {
    /// Adds another tile's counts.
    pub fn add(&mut self, o: &StreamCounts) {
        for (a, b) in self.rays.iter_mut().zip(o.rays) {
            *a += b;
        }
        self.steps += o.steps;
        self.tests += o.tests;
        self.shades += o.shades;
    }
}

/// A tile of the image: its corner, its width, and the image's width. Records carry
/// image-wide pixel numbers (path tracing draws its random numbers from them).
#[derive(Clone, Copy, Debug)]
pub struct TileGeometry {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Tile width.
    pub width: u32,
    /// Image width.
    pub image_width: u32,
}

impl TileGeometry {
    fn global(&self, local: usize) -> u32 {
        let (x, y) = self.xy(local);
        y * self.image_width + x
    }

    /// Image coordinates of the tile's pixel `local` (row-major in the tile).
    pub fn xy(&self, local: usize) -> (u32, u32) {
        (self.x0 + local as u32 % self.width, self.y0 + local as u32 / self.width)
    }

    fn local(&self, global: u32) -> usize {
        let (x, y) = (global % self.image_width, global / self.image_width);
        ((y.wrapping_sub(self.y0)) * self.width + x.wrapping_sub(self.x0)) as usize
    }
}

/// How a tile is shaded: the ray-emitting shader, the background, eye rays per pixel and
/// the camera's eye rays (their cone filters textures; an eye ray that misses the
/// scene's box still sees the sky along its direction).
#[derive(Clone, Copy, Debug)]
pub struct TileShading<'s> {
    /// The shader.
    pub shader: &'s Shader,
    /// What a ray that misses sees.
    pub background: Vec3,
    /// Eye rays per pixel.
    pub samples: u32,
    /// The camera's eye rays.
    pub eye: &'s EyeRays,
}

/// Radiance of a tile's pixels (row-major in the tile) from their eye rays and hits:
/// `samples` per pixel, sample-major (`primaries[s * pixels + p]`); a `None` ray missed
/// the scene's bounds and brings the background. `log`, if given, receives every emitted
/// ray as it is traced.
pub fn shade_tile<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    shading: &TileShading<'_>,
    tile: TileGeometry,
    primaries: &[(Option<Ray>, Option<Hit>)],
    probe: &mut P,
    counts: &mut StreamCounts,
    mut log: Option<&mut TileRayLog>,
) -> Vec<Vec3> {
    let TileShading { shader, background, samples, eye } = *shading;
    let cone = eye.cone();
    let samples = samples.max(1);
    let pixels = primaries.len() / samples as usize;
    let mut radiance = vec![RadianceSum::default(); pixels];
    let mut stream: VecDeque<RayRecord> = VecDeque::new();
    let share = 1.0 / samples as f32;
    for (i, (ray, hit)) in primaries.iter().enumerate() {
        let (s, p) = ((i / pixels.max(1)) as u32, i % pixels.max(1));
        match ray {
            None => {
                let (x, y) = tile.xy(p);
                radiance[p].add(eye_escaped(scene, eye, (x, y, s), background, probe) * share);
            }
            Some(ray) => {
                counts.shades += hit.is_some() as u64;
                shader.shade_primary(
                    scene,
                    RayRecord::eye_sample(*ray, tile.global(p), s, samples, cone),
                    *hit,
                    &mut radiance[p],
                    probe,
                    &mut |r| stream.push_back(r),
                );
            }
        }
    }
    // One shadow cache for the tile's shadow rays from its eye rays' hits, which are
    // neighbours; those from later bounces scatter, and skip it (the cache's first form,
    // tested before every such ray, took the conference room's path-traced frame from
    // 2.45 s to 2.51 on one core).
    let mut cache = LastOccluder::default();
    while let Some(rec) = stream.pop_front() {
        counts.rays[rec.kind as usize] += 1;
        if let Some(log) = log.as_deref_mut() {
            log.push(rec.kind, rec.ray);
        }
        let Some(slot) = radiance.get_mut(tile.local(rec.pixel)) else { continue };
        let mut c = RayCounters::default();
        if rec.kind == RayKind::Shadow {
            let blocked = if rec.depth == 0 {
                occluded_cached::<I, _>(scene, &rec.ray, &mut cache, probe, &mut c)
            } else {
                occluded::<I, _>(scene, &rec.ray, probe, &mut c)
            };
            if !blocked {
                slot.add(rec.weight);
            }
        } else {
            let hit = trace::<I, _>(scene, &rec.ray, probe, &mut c);
            counts.shades += hit.is_some() as u64;
            slot.add(shader.shade(scene, &rec, hit, probe, &mut |r| stream.push_back(r)));
        }
        counts.steps += c.nodes as u64;
        counts.tests += c.tri_tests as u64;
    }
    radiance.iter().map(RadianceSum::value).collect()
}
