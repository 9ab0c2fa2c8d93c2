//! Purcell 2002's scene statistics (his Table 2) for one camera: how many rays hit, how
//! many nodes and triangles each ray visits, how many list entries it reads, and how
//! many bytes of each data class it touches.

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::image::CameraRecord;
use raypipe_core::probe::ByteCounter;
use raypipe_core::{Intersector, RayCounters, SceneView};

use raypipe_core::packet::PacketCounters;

use crate::render::gbuffer::{gbuffer_hit, rasterize};
use crate::render::packets::{trace_tile, PacketSize, TileRays};
use crate::render::shading::{shade_tile, StreamCounts, TileGeometry, TileShading};
use crate::render::tracer::trace;
use crate::render::{eye_rays, in_pool, tiles, Algorithm, RenderOptions};
use crate::with_intersector;
use raypipe_core::image::NULL_INDEX;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::ray_record::RayKind;
use raypipe_core::NoProbe;

/// Totals and maxima over all primary rays of a view.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SceneStats {
    /// Rays traced.
    pub rays: u64,
    /// Rays that hit a triangle.
    pub hits: u64,
    /// Rays ended by the scene bounding-box test.
    pub missed_bounds: u64,
    /// Sum of per-ray counters.
    pub total: TotalCounters,
    /// Largest nodes visited by one ray.
    pub max_nodes: u32,
    /// Largest triangles tested by one ray.
    pub max_tri_tests: u32,
    /// Bytes read, per data class.
    pub bytes: ByteCounter,
}

/// Per-ray counters summed in 64 bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TotalCounters {
    /// Voxels visited.
    pub nodes: u64,
    /// Non-empty nodes visited.
    pub leaves: u64,
    /// List entries read.
    pub list_entries: u64,
    /// Triangle tests.
    pub tri_tests: u64,
}

impl SceneStats {
    pub(crate) fn add_ray(&mut self, c: &RayCounters, hit: bool, missed_bounds: bool) {
        self.rays += 1;
        self.hits += hit as u64;
        self.missed_bounds += missed_bounds as u64;
        self.total.nodes += c.nodes as u64;
        self.total.leaves += c.leaves as u64;
        self.total.list_entries += c.list_entries as u64;
        self.total.tri_tests += c.tri_tests as u64;
        self.max_nodes = self.max_nodes.max(c.nodes);
        self.max_tri_tests = self.max_tri_tests.max(c.tri_tests);
    }

    pub(crate) fn merge(mut self, o: SceneStats) -> SceneStats {
        self.rays += o.rays;
        self.hits += o.hits;
        self.missed_bounds += o.missed_bounds;
        self.total.nodes += o.total.nodes;
        self.total.leaves += o.total.leaves;
        self.total.list_entries += o.total.list_entries;
        self.total.tri_tests += o.total.tri_tests;
        self.max_nodes = self.max_nodes.max(o.max_nodes);
        self.max_tri_tests = self.max_tri_tests.max(o.max_tri_tests);
        for i in 0..4 {
            self.bytes.bytes[i] += o.bytes.bytes[i];
            self.bytes.reads[i] += o.bytes.reads[i];
        }
        self
    }

    /// Average per ray of a total.
    pub fn per_ray(&self, total: u64) -> f64 {
        if self.rays == 0 {
            0.0
        } else {
            total as f64 / self.rays as f64
        }
    }
}

/// Traces every primary ray of the view and gathers the statistics.
pub fn gather(scene: &SceneView<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<SceneStats> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(opts.intersector, I => gather_with::<I>(scene, &eye, opts))
}

fn gather_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &raypipe_core::camera::EyeRays,
    opts: &RenderOptions,
) -> Result<SceneStats> {
    let tiles = tiles(eye.width, eye.height);
    let (lo, hi) = scene.test_bounds();
    in_pool(opts.threads, || {
        tiles
            .par_iter()
            .map(|&(x0, y0, x1, y1)| {
                let mut s = SceneStats::default();
                for y in y0..y1 {
                    for x in x0..x1 {
                        let mut c = RayCounters::default();
                        match eye.ray_in_scene(x, y, lo, hi) {
                            Some(ray) => {
                                let hit = trace::<I, _>(scene, &ray, &mut s.bytes, &mut c);
                                s.add_ray(&c, hit.is_some(), false);
                            }
                            None => s.add_ray(&c, false, true),
                        }
                    }
                }
                s
            })
            .reduce(SceneStats::default, SceneStats::merge)
    })
}

/// Each pixel's primary-ray cost, row-major: nodes visited, triangle tests and scene
/// bytes read (the per-pixel counters behind [`gather`]'s totals).
pub fn cost_image(scene: &SceneView<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<Vec<[f64; 3]>> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(opts.intersector, I => cost_image_with::<I>(scene, &eye, opts))
}

fn cost_image_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &raypipe_core::camera::EyeRays,
    opts: &RenderOptions,
) -> Result<Vec<[f64; 3]>> {
    let (lo, hi) = scene.test_bounds();
    let w = eye.width;
    in_pool(opts.threads, || {
        (0..eye.height)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..w).map(move |x| {
                    let (mut c, mut bytes) = (RayCounters::default(), ByteCounter::default());
                    if let Some(ray) = eye.ray_in_scene(x, y, lo, hi) {
                        trace::<I, _>(scene, &ray, &mut bytes, &mut c);
                    }
                    [c.nodes as f64, c.tri_tests as f64, bytes.bytes.iter().sum::<u64>() as f64]
                })
            })
            .collect()
    })
}

/// What tracing the view as packets cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PacketStats {
    /// Packets traced.
    pub packets: u64,
    /// Summed packet counters.
    pub counters: PacketCounters,
}

/// Traces the view as packets of `size` and sums their counters.
pub fn gather_packets(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
    size: PacketSize,
) -> Result<PacketStats> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(opts.intersector, I => gather_packets_with::<I>(scene, &eye, opts, size))
}

fn gather_packets_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &raypipe_core::camera::EyeRays,
    opts: &RenderOptions,
    size: PacketSize,
) -> Result<PacketStats> {
    let tiles = tiles(eye.width, eye.height);
    let bounds = scene.test_bounds();
    let side = size.side();
    in_pool(opts.threads, || {
        tiles
            .par_iter()
            .map(|&tile| {
                let (mut c, mut pc) = (RayCounters::default(), PacketCounters::default());
                let rays = TileRays { eye, bounds, tile, sample: 0 };
                trace_tile::<I>(scene, rays, size, &mut c, &mut pc, &mut |_, _, _, _| {});
                let (w, h) = (tile.2 - tile.0, tile.3 - tile.1);
                PacketStats { packets: (w.div_ceil(side) * h.div_ceil(side)) as u64, counters: pc }
            })
            .reduce(PacketStats::default, |mut a, b| {
                a.packets += b.packets;
                a.counters.add(&b.counters);
                a
            })
    })
}

/// What one frame of an algorithm costs — the analogue of Purcell 2002's Table 3.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AlgoCosts {
    /// Pixels.
    pub pixels: u64,
    /// Rays traced by kind (`RayKind as usize`; the shadow caster traces no primary ray).
    pub rays: [u64; RayKind::COUNT],
    /// Traversal steps (nodes or voxels).
    pub steps: u64,
    /// Ray–triangle tests.
    pub tests: u64,
    /// Hits shaded.
    pub shades: u64,
    /// Scene bytes read (structure, triangles, shading data).
    pub bytes: u64,
}

impl AlgoCosts {
    pub(crate) fn merge(mut self, o: AlgoCosts) -> AlgoCosts {
        self.pixels += o.pixels;
        for (a, b) in self.rays.iter_mut().zip(o.rays) {
            *a += b;
        }
        self.steps += o.steps;
        self.tests += o.tests;
        self.shades += o.shades;
        self.bytes += o.bytes;
        self
    }
}

/// Counts what rendering the view with `opts.algo` costs (single rays; the counts do not
/// depend on threads).
pub fn algorithm_costs(scene: &SceneView<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<AlgoCosts> {
    let eye = eye_rays(camera, "camera")?.with_sampler(opts.sampler());
    with_intersector!(opts.intersector, I => costs_with::<I>(scene, &eye, camera, opts))
}

fn costs_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &raypipe_core::camera::EyeRays,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<AlgoCosts> {
    let background = raypipe_core::Vec3::from(camera.background);
    let shader = opts.shader(background);
    let samples = eye.samples();
    let gbuffers: Option<Vec<_>> =
        (opts.algo == Algorithm::Shadow).then(|| (0..samples).map(|s| rasterize(scene, eye, s)).collect());
    let (lo, hi) = scene.test_bounds();
    in_pool(opts.threads, || {
        tiles(eye.width, eye.height)
            .par_iter()
            .map(|&(x0, y0, x1, y1)| {
                let mut c = AlgoCosts::default();
                let mut probe = ByteCounter::default();
                let mut primaries = Vec::new();
                c.pixels += ((x1 - x0) * (y1 - y0)) as u64;
                for s in 0..samples {
                    for (x, y) in (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))) {
                        primaries.push(match &gbuffers {
                            Some(g) => gbuffer_hit::<I>(scene, eye, &g[s as usize], x, y),
                            None => match eye.sample_ray_in_scene(x, y, s, lo, hi) {
                                Some(ray) => {
                                    let mut rc = RayCounters::default();
                                    let hit = trace::<I, _>(scene, &ray, &mut probe, &mut rc);
                                    c.rays[RayKind::Primary as usize] += 1;
                                    c.steps += rc.nodes as u64;
                                    c.tests += rc.tri_tests as u64;
                                    (Some(ray), hit)
                                }
                                None => (None, None),
                            },
                        });
                    }
                }
                match &shader {
                    None => {
                        for (ray, hit) in &primaries {
                            if let Some(ray) = ray {
                                c.shades += hit.is_some() as u64;
                                std::hint::black_box(shade(scene, ray, eye.cone(), *hit, background, &mut probe));
                            }
                        }
                    }
                    Some(shader) => {
                        let geometry = TileGeometry { x0, y0, width: x1 - x0, image_width: eye.width };
                        let mut s = StreamCounts::default();
                        let shading = TileShading { shader, background, samples, eye };
                        std::hint::black_box(shade_tile::<I, _>(
                            scene, &shading, geometry, &primaries, &mut probe, &mut s, None,
                        ));
                        for (a, b) in c.rays.iter_mut().zip(s.rays) {
                            *a += b;
                        }
                        c.steps += s.steps;
                        c.tests += s.tests;
                        c.shades += s.shades;
                    }
                }
                c.bytes = probe.bytes.iter().sum();
                c
            })
            .reduce(AlgoCosts::default, AlgoCosts::merge)
    })
}

/// Where the rasterizer's nearest triangle differs from ray casting's (the shadow
/// caster's coverage disagreements at triangle edges): the pixels that differ, those of
/// them where both found the same depth (within 1e-5 relative — overlapping coplanar
/// triangles, the same surface point either way), the pixel count, and the triangles
/// clipped at the near plane.
pub fn coverage_mismatch(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
) -> Result<CoverageMismatch> {
    let eye = eye_rays(camera, "camera")?;
    let g = rasterize(scene, &eye, 0);
    let (lo, hi) = scene.test_bounds();
    let (differ, coplanar) = with_intersector!(opts.intersector, I => {
        (0..eye.height)
            .into_par_iter()
            .map(|y| {
                let (mut differ, mut coplanar) = (0u64, 0u64);
                for x in 0..eye.width {
                    let i = (y * eye.width + x) as usize;
                    let hit = eye
                        .ray_in_scene(x, y, lo, hi)
                        .and_then(|r| trace::<I, _>(scene, &r, &mut NoProbe, &mut RayCounters::default()));
                    if hit.map_or(NULL_INDEX, |h| h.prim) != g.prim[i] {
                        differ += 1;
                        let depth = hit.map(|h| h.t * eye.depth_per_distance(x, y));
                        let same = depth.is_some_and(|d| g.prim[i] != NULL_INDEX && (d - g.depth[i]).abs() <= 1e-5 * d.abs());
                        coplanar += same as u64;
                    }
                }
                (differ, coplanar)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    });
    Ok(CoverageMismatch { differ, coplanar, pixels: eye.width as u64 * eye.height as u64, clipped: g.clipped })
}

/// What [`coverage_mismatch`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoverageMismatch {
    /// Pixels whose nearest triangle differs.
    pub differ: u64,
    /// Of those, pixels where both found the same depth (overlapping coplanar triangles).
    pub coplanar: u64,
    /// Pixels compared.
    pub pixels: u64,
    /// Triangles clipped at the near plane.
    pub clipped: u32,
}
