//! Purcell 2002's scene statistics (his Table 2) for one camera: how many rays hit, how
//! many nodes and triangles each ray visits, how many list entries it reads, and how
//! many bytes of each data class it touches.

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::image::CameraRecord;
use raypipe_core::probe::ByteCounter;
use raypipe_core::{Intersector, RayCounters, SceneView};

use raypipe_core::packet::PacketCounters;

use crate::packets::{trace_tile, PacketSize};
use crate::render::{eye_rays, in_pool, tiles, RenderOptions};
use crate::tracer::trace;
use crate::with_intersector;

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
    fn add_ray(&mut self, c: &RayCounters, hit: bool, missed_bounds: bool) {
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

    fn merge(mut self, o: SceneStats) -> SceneStats {
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
                trace_tile::<I>(scene, eye, bounds, tile, size, &mut c, &mut pc, &mut |_, _, _, _| {});
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
