//! `raypipe bench`: build time, image size and primary-ray throughput (trace only: eye
//! ray, traversal, intersection; no shading), single-threaded and on all cores, as the
//! median of several runs measured in one process.

use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::packet::PacketCounters;
use raypipe_core::shade::ray_record::RayKind;
use raypipe_core::{Intersector, RayCounters, SceneView};

use crate::render::packets::{trace_tile, PacketSize, TileRays};
use crate::render::tracer::IntersectorKind;
use crate::render::{eye_rays, in_pool, tiles, RenderOptions};
use crate::with_intersector;

/// One scene's figures.
#[derive(Clone, Debug)]
pub struct BenchResult {
    /// Rays per run.
    pub rays: u64,
    /// Median Mrays/s on one thread.
    pub mrays_single: f64,
    /// Median Mrays/s on all threads.
    pub mrays_all: f64,
    /// Threads used for the all-threads figure.
    pub threads: usize,
    /// Fraction of packet lanes that needed the nodes the packets visited.
    pub simd_efficiency: f64,
}

/// The median of a list of numbers.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    match s.len() {
        0 => 0.0,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// Traces all primary rays of the view `runs` times with one thread and with `threads`.
pub fn primary_rays(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    kind: IntersectorKind,
    packet: PacketSize,
    runs: usize,
    threads: Option<usize>,
) -> Result<BenchResult> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(kind, I => run::<I>(scene, &eye, packet, runs.max(1), threads))
}

fn trace_all<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    tiles: &[(u32, u32, u32, u32)],
    packet: PacketSize,
) -> PacketCounters {
    let bounds = scene.test_bounds();
    tiles
        .par_iter()
        .map(|&tile| {
            let (mut c, mut pc) = (RayCounters::default(), PacketCounters::default());
            // Each hit goes through black_box so that no tracing can be optimised away.
            let rays = TileRays { eye, bounds, tile, sample: 0 };
            trace_tile::<I>(scene, rays, packet, &mut c, &mut pc, &mut |_, _, _, h| {
                std::hint::black_box(h);
            });
            pc
        })
        .reduce(PacketCounters::default, |mut a, b| {
            a.add(&b);
            a
        })
}

fn run<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    packet: PacketSize,
    runs: usize,
    threads: Option<usize>,
) -> Result<BenchResult> {
    let tiles = tiles(eye.width, eye.height);
    let rays = eye.width as u64 * eye.height as u64;
    let time = |n: Option<usize>| -> Result<(Vec<f64>, PacketCounters, usize)> {
        in_pool(n, || {
            let mut out = trace_all::<I>(scene, eye, &tiles, packet); // warm-up
            let mut secs = Vec::new();
            for _ in 0..runs {
                let t = Instant::now();
                out = trace_all::<I>(scene, eye, &tiles, packet);
                secs.push(t.elapsed().as_secs_f64());
            }
            (secs, out, rayon::current_num_threads())
        })
    };
    let (single_runs, pc, _) = time(Some(1))?;
    let (all_runs, _, threads) = time(threads)?;
    let simd_efficiency = pc.active_lanes as f64 / (pc.visits.max(1) as f64 * packet.rays() as f64);
    let mrays = |s: &[f64]| rays as f64 / median(s) / 1e6;
    Ok(BenchResult { rays, mrays_single: mrays(&single_runs), mrays_all: mrays(&all_runs), threads, simd_efficiency })
}

/// An algorithm's whole frame: every ray it traces, by kind, and how many per second.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AlgoBench {
    /// Rays per frame by kind (`RayKind as usize`).
    pub rays: [u64; RayKind::COUNT],
    /// Million rays per second, one thread (median of the runs).
    pub mrays_single: f64,
    /// Million rays per second, all threads.
    pub mrays_all: f64,
    /// Threads of the all-threads figure.
    pub threads: usize,
}

/// Times rendering the view with `opts.algo` (primary rays in `opts.packet`, then the
/// ray stream) and divides every ray it traced by the time.
pub fn algorithm_rays(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    opts: &RenderOptions,
    runs: usize,
    threads: Option<usize>,
) -> Result<AlgoBench> {
    let costs = crate::study::scene_stats::algorithm_costs(scene, camera, &RenderOptions { threads, ..*opts })?;
    let total: u64 = costs.rays.iter().sum();
    let time = |n: Option<usize>| -> Result<(f64, usize)> {
        let o = RenderOptions { threads: n, progress: false, ..*opts };
        crate::render::render(scene, camera, &o)?; // warm-up
        let mut secs = Vec::new();
        for _ in 0..runs.max(1) {
            let t = Instant::now();
            std::hint::black_box(crate::render::render(scene, camera, &o)?);
            secs.push(t.elapsed().as_secs_f64());
        }
        let used = n.unwrap_or_else(rayon::current_num_threads);
        Ok((median(&secs), used))
    };
    let (single, _) = time(Some(1))?;
    let (all, used) = time(threads)?;
    Ok(AlgoBench {
        rays: costs.rays,
        mrays_single: total as f64 / single / 1e6,
        mrays_all: total as f64 / all / 1e6,
        threads: used,
    })
}
