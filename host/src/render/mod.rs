//! The host runner: eye rays → traversal/intersection → shading, over image tiles on all
//! cores. Every pixel is computed independently by the same kernels, so the image is
//! identical for any thread count and tile order.

pub mod batch;
pub mod bricked;
pub mod canvas;
pub mod gbuffer;
pub mod instanced;
pub mod packets;
pub mod ray_log;
pub mod ray_order;
pub mod shading;
pub mod tracer;
pub mod view_check;

use anyhow::{anyhow, Result};
use glam::Vec3;
use rayon::prelude::*;
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::CameraRecord;
use raypipe_core::packet::PacketCounters;
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::lambert::shade;
use raypipe_core::{Intersector, NoProbe, Ray, RayCounters, SceneView};

use crate::render::canvas::Canvas;
use crate::render::gbuffer::{gbuffer_hit, rasterize, GBuffer};
use crate::render::packets::{trace_tile, PacketSize, TileRays};
use crate::render::ray_log::TileRayLog;
use crate::render::shading::{shade_tile, StreamCounts, TileGeometry, TileShading};
use raypipe_core::pixel_filter::{Filter, PixelSampler};
use raypipe_core::shade::path::PathOptions;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::whitted::WhittedOptions;

use crate::output::progress;
use crate::platform::thread_pools::map_claimed;
pub use crate::platform::thread_pools::thread_pool;
use crate::render::tracer::IntersectorKind;
use crate::with_intersector;

/// Side of the square tiles rendered as one unit of work.
pub const TILE: u32 = 16;

/// Host runner settings.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Ray–triangle test.
    pub intersector: IntersectorKind,
    /// Show a progress bar on a terminal.
    pub progress: bool,
    /// Rays traced one by one or as packets.
    pub packet: PacketSize,
    /// What the shader does with a hit.
    pub algo: Algorithm,
    /// Largest reflection/refraction depth (Whitted).
    pub max_depth: u8,
    /// Path tracing: bounces after the first hit.
    pub bounces: u8,
    /// Eye rays per pixel (every algorithm; path tracing: one path each).
    pub samples: u32,
    /// The reconstruction filter the eye rays' offsets follow.
    pub filter: Filter,
    /// Path tracing: Russian roulette after the first bounce.
    pub roulette: bool,
    /// Path tracing: largest radiance one path vertex may add to one sample (`None`:
    /// no clamp).
    pub clamp: Option<f32>,
    /// Keep every ray the frame traces ([`render_logged`]).
    pub log_rays: bool,
}

/// The rendering algorithm (Purcell 2002 Fig. 3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Algorithm {
    /// Ray casting: the first hit, Lambert-shaded from the lights without shadows.
    #[default]
    Cast,
    /// Purcell's hybrid shadow caster: visibility from a rasterized G-buffer, then shadow
    /// rays to the point lights.
    Shadow,
    /// Whitted ray tracing: shadow rays to point lights, mirror reflection, refraction.
    Whitted,
    /// Path tracing: diffuse bounces, next-event estimation, samples per pixel.
    Path,
}

impl RenderOptions {
    /// The ray-emitting shader of the algorithm (`None` for ray casting).
    pub fn shader(&self, background: Vec3) -> Option<Shader> {
        match self.algo {
            Algorithm::Cast => None,
            Algorithm::Shadow => Some(Shader::Whitted(WhittedOptions { max_depth: 0, background })),
            Algorithm::Whitted => Some(Shader::Whitted(WhittedOptions { max_depth: self.max_depth, background })),
            Algorithm::Path => {
                // A record's weight carries 1/samples: the limit per sample becomes one
                // per record.
                let clamp = self.clamp.map_or(f32::INFINITY, |c| c / self.samples.max(1) as f32);
                Some(Shader::Path(PathOptions { clamp, ..PathOptions::new(self.bounces, self.roulette, background) }))
            }
        }
    }

    /// Eye rays per pixel and where they go.
    pub fn sampler(&self) -> PixelSampler {
        PixelSampler { samples: self.samples.max(1), filter: self.filter }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            threads: None,
            intersector: IntersectorKind::Watertight,
            progress: false,
            packet: PacketSize::Single,
            algo: Algorithm::Cast,
            max_depth: 5,
            bounces: 2,
            samples: 1,
            filter: Filter::Box,
            roulette: false,
            clamp: None,
            log_rays: false,
        }
    }
}

/// A rendered image, rows top to bottom: its linear radiance and that radiance as 8-bit
/// sRGB (clamped, no exposure or tone mapping: what the golden images and the host =
/// model checks compare).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major, 8-bit sRGB.
    pub pixels: Vec<[u8; 3]>,
    /// Pixels, row-major, linear RGB radiance (empty for an image read from a PNG).
    pub radiance: Vec<[f32; 3]>,
}

impl Frame {
    /// A frame from linear radiance, row-major. Converted on the current thread pool:
    /// a 2048² frame's sRGB encoding took 0.10 s on one thread, a fifth of its tiles'
    /// time on Sponza (two threads' frame went from 1.46× to 1.64× one's).
    pub fn from_radiance(width: u32, height: u32, radiance: Vec<Vec3>) -> Frame {
        Frame {
            width,
            height,
            pixels: radiance.par_iter().map(|&c| rgb8(c)).collect(),
            radiance: radiance.par_iter().map(|c| c.to_array()).collect(),
        }
    }
}

/// Validates a camera record into eye-ray constants; `what` names it in errors.
pub fn eye_rays(camera: &CameraRecord, what: &str) -> Result<EyeRays> {
    EyeRays::new(&Camera::from(camera)).map_err(|e| anyhow!("{what}: {e}"))
}

/// Runs `f` on a pool of `threads` workers (all cores when `None`).
pub fn in_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    Ok(thread_pool(threads)?.install(f))
}

/// The tiles of a `w × h` image as `(x0, y0, x1, y1)`.
pub fn tiles(w: u32, h: u32) -> Vec<(u32, u32, u32, u32)> {
    tiles_in((0, 0, w, h))
}

/// The rectangle `(x0, y0, x1, y1)` cut into tiles, row by row.
pub fn tiles_in((x0, y0, x1, y1): (u32, u32, u32, u32)) -> Vec<(u32, u32, u32, u32)> {
    let mut v = Vec::new();
    for ty in (y0..y1).step_by(TILE as usize) {
        for tx in (x0..x1).step_by(TILE as usize) {
            v.push((tx, ty, (tx + TILE).min(x1), (ty + TILE).min(y1)));
        }
    }
    v
}

/// Rays a frame traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayTotals {
    /// Eye rays traced (those that entered the scene's box; the shadow caster's come from
    /// its G-buffer and are not traced).
    pub primary: u64,
    /// Rays the shaders emitted (shadow, reflection, refraction, path), all traced.
    pub secondary: u64,
}

impl RayTotals {
    /// Adds another part's rays.
    pub fn add(&mut self, o: &RayTotals) {
        self.primary += o.primary;
        self.secondary += o.secondary;
    }

    /// Every ray traced.
    pub fn total(&self) -> u64 {
        self.primary + self.secondary
    }
}

/// Renders the scene as the camera sees it.
pub fn render(scene: &SceneView<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<Frame> {
    Ok(render_counted(scene, camera, opts)?.0)
}

/// [`render`], and the rays it traced.
pub fn render_counted(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<(Frame, RayTotals)> {
    render_timed(scene, camera, opts).map(|(f, r, _)| (f, r))
}

/// [`render_counted`], and the seconds from its start until the first tile was done (the
/// first pixels a viewer could show).
pub fn render_timed(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<(Frame, RayTotals, f64)> {
    render_logged(scene, camera, opts).map(|(f, r, first, _)| (f, r, first))
}

/// [`render_timed`], and with [`RenderOptions::log_rays`] every ray the frame traced,
/// tile by tile in the frame's tile order (empty without).
pub fn render_logged(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<(Frame, RayTotals, f64, Vec<TileRayLog>)> {
    let eye = eye_rays(camera, "camera")?.with_sampler(opts.sampler());
    let first = std::sync::OnceLock::new();
    let start = std::time::Instant::now();
    let (frame, rays, logs) = with_intersector!(opts.intersector, I => render_with::<I>(scene, &eye, Vec3::from(camera.background), opts, (start, &first)))?;
    Ok((frame, rays, first.get().copied().unwrap_or(0.0), logs))
}

fn render_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    background: Vec3,
    opts: &RenderOptions,
    (start, first): (std::time::Instant, &std::sync::OnceLock<f64>),
) -> Result<(Frame, RayTotals, Vec<TileRayLog>)> {
    let (w, h) = (eye.width, eye.height);
    let tiles = tiles(w, h);
    let frame = FrameJob::new(scene, eye, background, opts);
    let bar = progress::bar(tiles.len() as u64, "render", opts.progress);
    let mut canvas = Canvas::new(w, h);
    let canvas_tiles = canvas.tiles();
    // Each worker encodes and places its own tiles (see `Canvas`).
    let done: Vec<(RayTotals, Option<TileRayLog>)> = map_claimed(opts.threads, &tiles, |&tile| {
        let mut log = opts.log_rays.then(TileRayLog::default);
        let (colours, rays) = frame.tile_logged::<I>(tile, log.as_mut());
        let placed = canvas_tiles.put(tile, &colours);
        debug_assert!(placed, "{tile:?} is a tile of the frame's grid, put once");
        bar.inc(1);
        first.get_or_init(|| start.elapsed().as_secs_f64());
        (rays, log)
    })?;
    drop(canvas_tiles);
    bar.finish_and_clear();
    let mut totals = RayTotals::default();
    done.iter().for_each(|(t, _)| totals.add(t));
    Ok((canvas.into_frame(), totals, done.into_iter().filter_map(|(_, log)| log).collect()))
}

/// The colours of the rectangle `area`, row-major, from its `tiles` and their rendered
/// colours (`done`, in the same order), and the rays they traced together.
fn assemble(
    area: (u32, u32, u32, u32),
    tiles: &[(u32, u32, u32, u32)],
    done: Vec<(Vec<Vec3>, RayTotals)>,
) -> (Vec<Vec3>, RayTotals) {
    let (x0, y0, x1, y1) = area;
    let mut radiance = vec![Vec3::ZERO; ((x1 - x0) * (y1 - y0)) as usize];
    let mut totals = RayTotals::default();
    for (&(a, b, c, d), (colours, t)) in tiles.iter().zip(done) {
        place_tile(&mut radiance, x1 - x0, (a - x0, b - y0, c - x0, d - y0), &colours);
        totals.add(&t);
    }
    (radiance, totals)
}

/// Copies a tile's colours (row-major within the tile) into the image's `radiance`.
pub fn place_tile(radiance: &mut [Vec3], image_width: u32, (x0, y0, x1, _): (u32, u32, u32, u32), colours: &[Vec3]) {
    let tw = (x1 - x0) as usize;
    for (row, chunk) in colours.chunks(tw).enumerate() {
        let start = (y0 as usize + row) * image_width as usize + x0 as usize;
        radiance[start..start + tw].copy_from_slice(chunk);
    }
}

/// One frame's work, split into tiles that can be rendered in any order, on any thread or
/// process: each tile's colours depend on the tile alone (the shadow caster's G-buffers
/// are made once, for the whole image, before any tile).
pub struct FrameJob<'a, 's> {
    scene: &'a SceneView<'s>,
    eye: &'a EyeRays,
    background: Vec3,
    opts: &'a RenderOptions,
    gbuffers: Option<Vec<GBuffer>>,
}

impl<'a, 's> FrameJob<'a, 's> {
    /// The frame of `scene` seen through `eye`.
    pub fn new(scene: &'a SceneView<'s>, eye: &'a EyeRays, background: Vec3, opts: &'a RenderOptions) -> Self {
        // The shadow caster's visibility pass: a G-buffer per eye ray of the pixels.
        let gbuffers =
            (opts.algo == Algorithm::Shadow).then(|| (0..eye.samples()).map(|s| rasterize(scene, eye, s)).collect());
        FrameJob { scene, eye, background, opts, gbuffers }
    }

    /// The colours of the rectangle `area`, row-major, rendered as the renderer's own
    /// tiles in parallel (on the current thread pool), and the rays they traced.
    pub fn rect(&self, area: (u32, u32, u32, u32)) -> (Vec<Vec3>, RayTotals) {
        self.rects(&[area]).pop().unwrap_or_default()
    }

    /// The colours and rays of each of `areas`, their tiles all rendered in one parallel
    /// pass: more tiles than threads keep every thread busy to the end.
    pub fn rects(&self, areas: &[(u32, u32, u32, u32)]) -> Vec<(Vec<Vec3>, RayTotals)> {
        let per_area: Vec<Vec<(u32, u32, u32, u32)>> = areas.iter().map(|&a| tiles_in(a)).collect();
        let all: Vec<(u32, u32, u32, u32)> = per_area.iter().flatten().copied().collect();
        let mut done: Vec<(Vec<Vec3>, RayTotals)> =
            all.par_iter().map(|&t| with_intersector!(self.opts.intersector, I => self.tile::<I>(t))).collect();
        let mut out = Vec::with_capacity(areas.len());
        for (&area, tiles) in areas.iter().zip(&per_area) {
            let rest = done.split_off(tiles.len());
            out.push(assemble(area, tiles, std::mem::replace(&mut done, rest)));
        }
        out
    }

    /// The colours of the tile `(x0, y0, x1, y1)`, row-major, and the rays it traced.
    pub fn tile<I: Intersector>(&self, tile: (u32, u32, u32, u32)) -> (Vec<Vec3>, RayTotals) {
        self.tile_logged::<I>(tile, None)
    }

    /// [`FrameJob::tile`], its rays kept in `log` if given.
    pub fn tile_logged<I: Intersector>(
        &self,
        (x0, y0, x1, y1): (u32, u32, u32, u32),
        mut log: Option<&mut TileRayLog>,
    ) -> (Vec<Vec3>, RayTotals) {
        let (scene, eye, opts) = (self.scene, self.eye, self.opts);
        let samples = eye.samples();
        let tw = (x1 - x0) as usize;
        let n = tw * (y1 - y0) as usize;
        let (mut counters, mut pc) = (RayCounters::default(), PacketCounters::default());
        let tile = (x0, y0, x1, y1);
        let mut totals = RayTotals::default();
        // Every eye ray of the tile and its hit, sample-major.
        let mut primaries = vec![(None, None); n * samples as usize];
        for s in 0..samples {
            let at = |x: u32, y: u32| s as usize * n + (y - y0) as usize * tw + (x - x0) as usize;
            match &self.gbuffers {
                Some(g) => {
                    for y in y0..y1 {
                        for x in x0..x1 {
                            primaries[at(x, y)] = gbuffer_hit::<I>(scene, eye, &g[s as usize], x, y);
                        }
                    }
                }
                None => {
                    let mut put = |x: u32, y: u32, ray: Option<Ray>, hit| {
                        totals.primary += ray.is_some() as u64;
                        primaries[at(x, y)] = (ray, hit);
                    };
                    let rays = TileRays { eye, bounds: scene.test_bounds(), tile, sample: s };
                    trace_tile::<I>(scene, rays, opts.packet, &mut counters, &mut pc, &mut put);
                }
            }
        }
        // (The shadow caster's eye rays come from its G-buffer: none is traced.)
        if let Some(log) = log.as_deref_mut().filter(|_| self.gbuffers.is_none()) {
            log.eye.extend(primaries.iter().filter_map(|(ray, _)| *ray));
        }
        let geometry = TileGeometry { x0, y0, width: tw as u32, image_width: eye.width };
        let radiance = match opts.shader(self.background) {
            None => cast_tile(scene, (eye, self.background), samples, geometry, &primaries),
            Some(shader) => {
                let mut counts = StreamCounts::default();
                let shading = TileShading { shader: &shader, background: self.background, samples, eye };
                let radiance =
                    shade_tile::<I, _>(scene, &shading, geometry, &primaries, &mut NoProbe, &mut counts, log);
                totals.secondary = counts.rays.iter().sum();
                radiance
            }
        };
        (radiance, totals)
    }
}

/// Ray casting's colours for a tile's eye rays (sample-major): one sample's colour as it
/// is, several summed exactly ([`RadianceSum`]) with weight `1 / samples` each. An eye
/// ray that missed the scene's box sees what an escaped ray sees.
fn cast_tile(
    scene: &SceneView<'_>,
    (eye, background): (&EyeRays, Vec3),
    samples: u32,
    tile: TileGeometry,
    primaries: &[(Option<Ray>, Option<raypipe_core::Hit>)],
) -> Vec<Vec3> {
    let n = primaries.len() / samples.max(1) as usize;
    let color = |i: usize, (ray, hit): &(Option<Ray>, Option<raypipe_core::Hit>)| match ray {
        Some(ray) => shade(scene, ray, eye.cone(), *hit, background, &mut NoProbe),
        None => {
            let (x, y) = tile.xy(i % n.max(1));
            eye_escaped(scene, eye, (x, y, (i / n.max(1)) as u32), background, &mut NoProbe)
        }
    };
    if samples <= 1 {
        return primaries.iter().enumerate().map(|(i, p)| color(i, p)).collect();
    }
    let mut sum = vec![RadianceSum::default(); n];
    let weight = 1.0 / samples as f32;
    for (i, p) in primaries.iter().enumerate() {
        sum[i % n].add(color(i, p) * weight);
    }
    sum.iter().map(RadianceSum::value).collect()
}
