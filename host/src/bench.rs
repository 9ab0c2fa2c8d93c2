//! `raypipe bench`: build time, image size and primary-ray throughput (trace only: eye
//! ray, traversal, intersection; no shading), single-threaded and on all cores, as the
//! median of several runs measured in one process.

use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::{Intersector, NoProbe, RayCounters, SceneView};

use crate::render::{eye_rays, in_pool, tiles};
use crate::tracer::{trace, IntersectorKind};
use crate::with_intersector;

/// One scene's figures.
#[derive(Clone, Debug)]
pub struct BenchResult {
    /// Rays per run.
    pub rays: u64,
    /// Rays that hit.
    pub hits: u64,
    /// Median Mrays/s on one thread.
    pub mrays_single: f64,
    /// Median Mrays/s on all threads.
    pub mrays_all: f64,
    /// Threads used for the all-threads figure.
    pub threads: usize,
    /// Every single-thread run, seconds.
    pub single_runs: Vec<f64>,
    /// Every all-thread run, seconds.
    pub all_runs: Vec<f64>,
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
    runs: usize,
    threads: Option<usize>,
) -> Result<BenchResult> {
    let eye = eye_rays(camera, "camera")?;
    with_intersector!(kind, I => run::<I>(scene, &eye, runs.max(1), threads))
}

fn trace_all<I: Intersector>(scene: &SceneView<'_>, eye: &EyeRays, tiles: &[(u32, u32, u32, u32)]) -> u64 {
    let (lo, hi) = scene.bounds();
    tiles
        .par_iter()
        .map(|&(x0, y0, x1, y1)| {
            let mut hits = 0u64;
            let mut c = RayCounters::default();
            for y in y0..y1 {
                for x in x0..x1 {
                    if let Some(ray) = eye.ray_in_scene(x, y, lo, hi) {
                        hits += trace::<I, _>(scene, &ray, &mut NoProbe, &mut c).is_some() as u64;
                    }
                }
            }
            hits
        })
        .sum()
}

fn run<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    runs: usize,
    threads: Option<usize>,
) -> Result<BenchResult> {
    let tiles = tiles(eye.width, eye.height);
    let rays = eye.width as u64 * eye.height as u64;
    let time = |n: Option<usize>| -> Result<(Vec<f64>, u64, usize)> {
        in_pool(n, || {
            let mut hits = trace_all::<I>(scene, eye, &tiles); // warm-up
            let mut secs = Vec::new();
            for _ in 0..runs {
                let t = Instant::now();
                hits = trace_all::<I>(scene, eye, &tiles);
                secs.push(t.elapsed().as_secs_f64());
            }
            (secs, hits, rayon::current_num_threads())
        })
    };
    let (single_runs, hits, _) = time(Some(1))?;
    let (all_runs, _, threads) = time(threads)?;
    let mrays = |s: &[f64]| rays as f64 / median(s) / 1e6;
    Ok(BenchResult {
        rays,
        hits,
        mrays_single: mrays(&single_runs),
        mrays_all: mrays(&all_runs),
        threads,
        single_runs,
        all_runs,
    })
}
