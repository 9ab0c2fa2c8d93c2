//! The host runner: eye rays → traversal/intersection → shading, over image tiles on all
//! cores. Every pixel is computed independently by the same kernels, so the image is
//! identical for any thread count and tile order.

use anyhow::{anyhow, Result};
use glam::Vec3;
use rayon::prelude::*;
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::CameraRecord;
use raypipe_core::packet::PacketCounters;
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::lambert::shade;
use raypipe_core::{Intersector, NoProbe, Ray, RayCounters, SceneView};

use crate::packets::{trace_tile, PacketSize};
use crate::raster::{gbuffer_hit, rasterize};
use crate::ray_stream::{shade_tile, StreamCounts, TileGeometry};
use raypipe_core::shade::path::PathOptions;
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::whitted::WhittedOptions;

use crate::progress;
use crate::tracer::IntersectorKind;
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
    /// Path tracing: samples per pixel.
    pub samples: u32,
    /// Path tracing: Russian roulette after the first bounce.
    pub roulette: bool,
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
            Algorithm::Path => Some(Shader::Path(PathOptions {
                bounces: self.bounces,
                samples: self.samples,
                roulette: self.roulette,
                background,
            })),
        }
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
            samples: 16,
            roulette: false,
        }
    }
}

/// An 8-bit sRGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major.
    pub pixels: Vec<[u8; 3]>,
}

/// Validates a camera record into eye-ray constants; `what` names it in errors.
pub fn eye_rays(camera: &CameraRecord, what: &str) -> Result<EyeRays> {
    EyeRays::new(&Camera::from(camera)).map_err(|e| anyhow!("{what}: {e}"))
}

/// Runs `f` on a pool of `threads` workers (all cores when `None`).
pub fn in_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(n.max(1));
    }
    let pool = b.build().map_err(|e| anyhow!("cannot start worker threads: {e}"))?;
    Ok(pool.install(f))
}

/// The tiles of a `w × h` image as `(x0, y0, x1, y1)`.
pub fn tiles(w: u32, h: u32) -> Vec<(u32, u32, u32, u32)> {
    let mut v = Vec::new();
    for ty in (0..h).step_by(TILE as usize) {
        for tx in (0..w).step_by(TILE as usize) {
            v.push((tx, ty, (tx + TILE).min(w), (ty + TILE).min(h)));
        }
    }
    v
}

/// Renders the scene as the camera sees it.
pub fn render(scene: &SceneView<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<Frame> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(opts.intersector, I => render_with::<I>(scene, &eye, Vec3::from(camera.background), opts))
}

fn render_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    background: Vec3,
    opts: &RenderOptions,
) -> Result<Frame> {
    let (w, h) = (eye.width, eye.height);
    let (lo, hi) = scene.test_bounds();
    let tiles = tiles(w, h);
    // The shadow caster's visibility pass.
    let gbuffer = (opts.algo == Algorithm::Shadow).then(|| rasterize(scene, eye));
    let bar = progress::bar(tiles.len() as u64, "render", opts.progress);
    let done: Vec<Vec<[u8; 3]>> = in_pool(opts.threads, || {
        tiles
            .par_iter()
            .map(|&(x0, y0, x1, y1)| {
                let tw = (x1 - x0) as usize;
                let mut out = vec![[0u8; 3]; tw * (y1 - y0) as usize];
                let (mut counters, mut pc) = (RayCounters::default(), PacketCounters::default());
                let tile = (x0, y0, x1, y1);
                match opts.shader(background) {
                    None => {
                        let mut put = |x: u32, y: u32, ray: Option<Ray>, hit| {
                            let color = match ray {
                                Some(ray) => shade(scene, &ray, hit, background, &mut NoProbe),
                                None => background,
                            };
                            out[(y - y0) as usize * tw + (x - x0) as usize] = rgb8(color);
                        };
                        trace_tile::<I>(scene, eye, (lo, hi), tile, opts.packet, &mut counters, &mut pc, &mut put);
                    }
                    Some(shader) => {
                        // Primary hits first (in packets), then the tile's ray stream in
                        // pixel order.
                        let mut primaries = vec![(None, None); out.len()];
                        match &gbuffer {
                            Some(g) => {
                                for y in y0..y1 {
                                    for x in x0..x1 {
                                        primaries[(y - y0) as usize * tw + (x - x0) as usize] =
                                            gbuffer_hit::<I>(scene, eye, g, x, y);
                                    }
                                }
                            }
                            None => {
                                let mut put = |x: u32, y: u32, ray: Option<Ray>, hit| {
                                    primaries[(y - y0) as usize * tw + (x - x0) as usize] = (ray, hit);
                                };
                                trace_tile::<I>(
                                    scene,
                                    eye,
                                    (lo, hi),
                                    tile,
                                    opts.packet,
                                    &mut counters,
                                    &mut pc,
                                    &mut put,
                                );
                            }
                        }
                        let geometry = TileGeometry { x0, y0, width: tw as u32, image_width: w };
                        let mut counts = StreamCounts::default();
                        let radiance = shade_tile::<I, _>(
                            scene,
                            &shader,
                            background,
                            geometry,
                            &primaries,
                            &mut NoProbe,
                            &mut counts,
                        );
                        for (o, r) in out.iter_mut().zip(radiance) {
                            *o = rgb8(r);
                        }
                    }
                }
                bar.inc(1);
                out
            })
            .collect()
    })?;
    bar.finish_and_clear();
    let mut pixels = vec![[0u8; 3]; (w * h) as usize];
    for (&(x0, y0, x1, _), tile) in tiles.iter().zip(done) {
        let tw = (x1 - x0) as usize;
        for (row, chunk) in tile.chunks(tw).enumerate() {
            let start = (y0 as usize + row) * w as usize + x0 as usize;
            pixels[start..start + tw].copy_from_slice(chunk);
        }
    }
    Ok(Frame { width: w, height: h, pixels })
}
