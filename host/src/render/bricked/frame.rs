//! A frame of a bricked scene. Tiles are taken a few at a time by each worker, whose
//! tracer holds all their rays at once, so that while one brick loads the others' rays
//! go on (Wald & Slusallek 2001, §6.3). Shading is deferred until a wave of rays is
//! traced and done brick by brick, from the brick each hit lies in; rays that miss are
//! shaded from the globals image. Every pixel's sum is exact ([`RadianceSum`]), so the
//! image is bit-identical to the flat scene's, whatever the cache size, threads or the
//! order bricks arrive in.

use anyhow::{bail, Result};
use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::traverse::two_level::BrickHit;
use raypipe_core::{Intersector, NoProbe, Ray, SceneView, Vec3};

use super::brick_cache::BrickCache;
use super::brick_tracer::{BrickTracer, TraceStats};
use crate::input::bricked::BrickedScene;
use crate::output::progress;
use crate::render::{eye_rays, in_pool, tiles_in, Algorithm, Frame, RayTotals, RenderOptions};
use crate::with_intersector;

/// Tiles one worker's tracer holds at once.
pub const TILES_PER_WORKER: usize = 4;

/// What a bricked frame did.
#[derive(Clone, Debug, Default)]
pub struct BrickedFrame {
    /// Rays traced.
    pub rays: RayTotals,
    /// The tracers' counts.
    pub trace: TraceStats,
    /// Seconds from the frame's start until its first tile was done.
    pub first_tile_seconds: f64,
    /// The bricks its rays needed, sorted, each once.
    pub touched: Vec<u32>,
}

/// Checks that `opts` can render a bricked scene: ray casting and Whitted shade from one
/// brick at a time; the shadow caster rasterizes every triangle and path tracing samples
/// the whole scene's emitters.
pub fn check_algorithm(opts: &RenderOptions) -> Result<()> {
    match opts.algo {
        Algorithm::Cast | Algorithm::Whitted => Ok(()),
        Algorithm::Shadow => {
            bail!("--algo shadow rasterizes every triangle at once: render a bricked scene with --algo cast or whitted")
        }
        Algorithm::Path => bail!(
            "--algo path samples the emitters of the whole scene: render a bricked scene with --algo cast or whitted"
        ),
    }
}

/// Renders the bricked scene as `camera` sees it, loading bricks through `cache`.
pub fn render_bricked(
    scene: &BrickedScene,
    cache: &BrickCache<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<(Frame, BrickedFrame)> {
    let (w, h) = (camera.width, camera.height);
    let (radiance, stats) = in_pool(opts.threads, || render_bricked_rect(scene, cache, camera, opts, (0, 0, w, h)))??;
    Ok((Frame::from_radiance(w, h, radiance), stats))
}

/// The pixels of `rect` (`x0, y0, x1, y1`, row by row) of the frame `camera` sees: each
/// pixel's colour is the whole frame's, bit for bit, so that ranks of a distributed run
/// can render the rectangles of one frame. Runs on the current thread pool.
pub fn render_bricked_rect(
    scene: &BrickedScene,
    cache: &BrickCache<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
    rect: (u32, u32, u32, u32),
) -> Result<(Vec<Vec3>, BrickedFrame)> {
    check_algorithm(opts)?;
    let eye = eye_rays(camera, "camera")?.with_sampler(opts.sampler());
    let background = Vec3::from(camera.background);
    with_intersector!(opts.intersector, I => frame_with::<I>(scene, cache, &eye, background, opts, rect))
}

/// A worker's tiles and their pixels' final radiance.
type TileColors = (Vec<(u32, u32, u32, u32)>, Vec<Vec<Vec3>>);

/// A worker's tiles: their corners and pixels' radiance.
struct Chunk {
    tiles: Vec<(u32, u32, u32, u32)>,
    radiance: Vec<Vec<RadianceSum>>,
}

impl Chunk {
    fn slot(&mut self, pixel: u32, width: u32) -> Option<&mut RadianceSum> {
        let (x, y) = (pixel % width, pixel / width);
        // A chunk holds a few tiles: a scan finds the pixel's.
        let k = self.tiles.iter().position(|&(x0, y0, x1, y1)| (x0..x1).contains(&x) && (y0..y1).contains(&y))?;
        let (x0, y0, x1, _) = self.tiles[k];
        self.radiance[k].get_mut(((y - y0) * (x1 - x0) + (x - x0)) as usize)
    }
}

fn frame_with<I: Intersector>(
    scene: &BrickedScene,
    cache: &BrickCache<'_>,
    eye: &EyeRays,
    background: Vec3,
    opts: &RenderOptions,
    rect: (u32, u32, u32, u32),
) -> Result<(Vec<Vec3>, BrickedFrame)> {
    let index = scene.view();
    let globals = index.globals();
    let all = tiles_in(rect);
    let chunks: Vec<&[(u32, u32, u32, u32)]> = all.chunks(TILES_PER_WORKER).collect();
    let bar = progress::bar(all.len() as u64, "render", opts.progress);
    let shader = opts.shader(background);
    let start = std::time::Instant::now();
    let first = std::sync::OnceLock::new();
    let done: Vec<Result<(TileColors, BrickedFrame)>> = chunks
        .par_iter()
        .map(|tiles| {
            let mut tracer = BrickTracer::new(cache, index, opts.packet);
            let r = render_chunk::<I>(&mut tracer, globals, eye, background, shader.as_ref(), tiles);
            bar.inc(tiles.len() as u64);
            first.get_or_init(|| start.elapsed().as_secs_f64());
            let touched = tracer.touched();
            r.map(|(chunk, rays)| (chunk, BrickedFrame { rays, trace: tracer.stats, first_tile_seconds: 0.0, touched }))
        })
        .collect();
    bar.finish_and_clear();
    let w = rect.2 - rect.0;
    let mut radiance = vec![Vec3::ZERO; (w * (rect.3 - rect.1)) as usize];
    let mut stats = BrickedFrame { first_tile_seconds: first.get().copied().unwrap_or(0.0), ..Default::default() };
    for r in done {
        let (chunk, s) = r?;
        stats.rays.primary += s.rays.primary;
        stats.rays.secondary += s.rays.secondary;
        stats.trace.add(&s.trace);
        stats.touched.extend(s.touched);
        for (&(x0, y0, x1, y1), tile) in chunk.0.iter().zip(&chunk.1) {
            let local = (x0 - rect.0, y0 - rect.1, x1 - rect.0, y1 - rect.1);
            crate::render::place_tile(&mut radiance, w, local, tile);
        }
    }
    stats.touched.sort_unstable();
    stats.touched.dedup();
    Ok((radiance, stats))
}

/// One primary ray: its tile, pixel in the tile, sample and ray (`None`: it missed the
/// scene's box).
struct Primary {
    tile: usize,
    local: usize,
    sample: u32,
    ray: Option<Ray>,
}

/// What a worker's tiles share while they are shaded: the globals image, the camera's
/// eye rays and the background.
#[derive(Clone, Copy)]
struct ShadeContext<'a> {
    globals: &'a SceneView<'a>,
    eye: &'a EyeRays,
    background: Vec3,
}

fn render_chunk<I: Intersector>(
    tracer: &mut BrickTracer<'_, '_>,
    globals: &SceneView<'_>,
    eye: &EyeRays,
    background: Vec3,
    shader: Option<&Shader>,
    tiles: &[(u32, u32, u32, u32)],
) -> Result<(TileColors, RayTotals)> {
    let mut chunk = Chunk {
        tiles: tiles.to_vec(),
        radiance: tiles
            .iter()
            .map(|&(x0, y0, x1, y1)| vec![RadianceSum::default(); ((x1 - x0) * (y1 - y0)) as usize])
            .collect(),
    };
    let primaries = primaries(eye, globals.test_bounds(), tiles);
    let traced: Vec<usize> = (0..primaries.len()).filter(|&i| primaries[i].ray.is_some()).collect();
    let rays: Vec<Ray> = traced.iter().filter_map(|&i| primaries[i].ray).collect();
    let mut totals = RayTotals { primary: rays.len() as u64, secondary: 0 };
    let found = tracer.trace_batch::<I>(&rays, &vec![false; rays.len()])?;
    let mut hits: Vec<Option<BrickHit>> = vec![None; primaries.len()];
    for (&i, h) in traced.iter().zip(found) {
        hits[i] = h;
    }
    let scene = ShadeContext { globals, eye, background };
    match shader {
        None => {
            let colors = cast(tracer, scene, &primaries, &hits, tiles)?;
            if eye.samples() <= 1 {
                // One sample is its colour as it is (a sum of one would round it).
                let mut out: Vec<Vec<Vec3>> = chunk.radiance.iter().map(|t| vec![Vec3::ZERO; t.len()]).collect();
                for (p, c) in primaries.iter().zip(colors) {
                    out[p.tile][p.local] = c;
                }
                return Ok(((chunk.tiles, out), totals));
            }
            let share = 1.0 / eye.samples() as f32;
            for (p, c) in primaries.iter().zip(colors) {
                chunk.radiance[p.tile][p.local].add(c * share);
            }
        }
        Some(shader) => {
            let records = shade_primaries(tracer, scene, shader, &primaries, &hits, &mut chunk)?;
            totals.secondary = secondary_waves::<I>(tracer, globals, shader, &mut chunk, eye.width, records)?;
        }
    }
    let colors = chunk.radiance.iter().map(|t| t.iter().map(RadianceSum::value).collect()).collect();
    Ok(((chunk.tiles, colors), totals))
}

/// Every eye ray of the tiles, tile by tile, sample-major within a tile, rays that miss
/// the scene's box `(lo, hi)` as `None` (Purcell's test).
fn primaries(eye: &EyeRays, (lo, hi): (Vec3, Vec3), tiles: &[(u32, u32, u32, u32)]) -> Vec<Primary> {
    let mut out = Vec::new();
    for (k, &(x0, y0, x1, y1)) in tiles.iter().enumerate() {
        for s in 0..eye.samples() {
            for y in y0..y1 {
                for x in x0..x1 {
                    let local = ((y - y0) * (x1 - x0) + (x - x0)) as usize;
                    out.push(Primary { tile: k, local, sample: s, ray: eye.sample_ray_in_scene(x, y, s, lo, hi) });
                }
            }
        }
    }
    out
}

/// The image position of a primary ray's pixel.
fn pixel_of(p: &Primary, tiles: &[(u32, u32, u32, u32)]) -> (u32, u32) {
    let (x0, y0, x1, _) = tiles[p.tile];
    (x0 + p.local as u32 % (x1 - x0), y0 + p.local as u32 / (x1 - x0))
}

/// Ray casting: each eye ray's colour, hits shaded from their bricks, brick by brick.
fn cast(
    tracer: &mut BrickTracer<'_, '_>,
    scene: ShadeContext<'_>,
    primaries: &[Primary],
    hits: &[Option<BrickHit>],
    tiles: &[(u32, u32, u32, u32)],
) -> Result<Vec<Vec3>> {
    let ShadeContext { globals, eye, background } = scene;
    let cone = eye.cone();
    let mut colors = vec![Vec3::ZERO; primaries.len()];
    let mut work = Vec::new();
    for (i, p) in primaries.iter().enumerate() {
        match (p.ray, hits[i]) {
            (None, _) => {
                let (x, y) = pixel_of(p, tiles);
                colors[i] = eye_escaped(globals, eye, (x, y, p.sample), background, &mut NoProbe);
            }
            (Some(ray), None) => colors[i] = shade(globals, &ray, cone, None, background, &mut NoProbe),
            (Some(_), Some(h)) => work.push((h.brick, i)),
        }
    }
    tracer.grouped(work, |_, view, items, _| {
        for i in items {
            if let (Some(ray), Some(h)) = (primaries[i].ray, hits[i]) {
                colors[i] = shade(view, &ray, cone, Some(h.local_hit()), background, &mut NoProbe);
            }
        }
    })?;
    Ok(colors)
}

/// The ray-emitting shader on the eye rays' hits (brick by brick) and misses; returns the
/// records they emitted.
fn shade_primaries(
    tracer: &mut BrickTracer<'_, '_>,
    scene: ShadeContext<'_>,
    shader: &Shader,
    primaries: &[Primary],
    hits: &[Option<BrickHit>],
    chunk: &mut Chunk,
) -> Result<Vec<RayRecord>> {
    let ShadeContext { globals, eye, background } = scene;
    let (samples, cone) = (eye.samples(), eye.cone());
    let share = 1.0 / samples as f32;
    let mut records = Vec::new();
    let mut work = Vec::new();
    for (i, p) in primaries.iter().enumerate() {
        let (x, y) = pixel_of(p, &chunk.tiles);
        let sum = &mut chunk.radiance[p.tile][p.local];
        match p.ray {
            None => sum.add(eye_escaped(globals, eye, (x, y, p.sample), background, &mut NoProbe) * share),
            Some(ray) => {
                let rec = RayRecord::eye_sample(ray, y * eye.width + x, p.sample, samples, cone);
                match hits[i] {
                    None => shader.shade_primary(globals, rec, None, sum, &mut NoProbe, &mut |r| records.push(r)),
                    Some(h) => work.push((h.brick, (i, rec))),
                }
            }
        }
    }
    tracer.grouped(work, |_, view, items, _| {
        for (i, rec) in items {
            let (p, h) = (&primaries[i], hits[i].map(|h| h.local_hit()));
            let sum = &mut chunk.radiance[p.tile][p.local];
            shader.shade_primary(view, rec, h, sum, &mut NoProbe, &mut |r| records.push(r));
        }
    })?;
    Ok(records)
}

/// Traces the shaders' records wave by wave until none is left, shading each wave's
/// hits brick by brick. Returns the rays traced.
fn secondary_waves<I: Intersector>(
    tracer: &mut BrickTracer<'_, '_>,
    globals: &SceneView<'_>,
    shader: &Shader,
    chunk: &mut Chunk,
    width: u32,
    mut records: Vec<RayRecord>,
) -> Result<u64> {
    let mut traced = 0;
    while !records.is_empty() {
        traced += records.len() as u64;
        let rays: Vec<Ray> = records.iter().map(|r| r.ray).collect();
        let any: Vec<bool> = records.iter().map(|r| r.kind == RayKind::Shadow).collect();
        let hits = tracer.trace_batch::<I>(&rays, &any)?;
        let mut next = Vec::new();
        let mut work = Vec::new();
        for (rec, hit) in records.into_iter().zip(hits) {
            if rec.kind == RayKind::Shadow {
                if hit.is_none() {
                    if let Some(slot) = chunk.slot(rec.pixel, width) {
                        slot.add(rec.weight);
                    }
                }
                continue;
            }
            match hit {
                None => {
                    let c = shader.shade(globals, &rec, None, &mut NoProbe, &mut |r| next.push(r));
                    if let Some(slot) = chunk.slot(rec.pixel, width) {
                        slot.add(c);
                    }
                }
                Some(h) => work.push((h.brick, (rec, h))),
            }
        }
        tracer.grouped(work, |_, view, items, _| {
            for (rec, h) in items {
                let c = shader.shade(view, &rec, Some(h.local_hit()), &mut NoProbe, &mut |r| next.push(r));
                if let Some(slot) = chunk.slot(rec.pixel, width) {
                    slot.add(c);
                }
            }
        })?;
        records = next;
    }
    Ok(traced)
}
