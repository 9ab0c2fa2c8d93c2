//! `raypipe stats` and `raypipe bench` of a bricked scene: the camera's primary rays
//! through the brick cache — per-ray work of the two levels and the cache's counts, or
//! the rays' throughput cold (an empty cache) and warm.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::image::CameraRecord;
use raypipe_core::Ray;

use super::fmt_bytes;
use crate::input::bricked::BrickedScene;
use crate::render::bricked::brick_cache::{with_cache, BrickCache};
use crate::render::bricked::brick_tracer::{BrickTracer, TraceStats};
use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;

/// Rays one worker's tracer holds at once.
const CHUNK: usize = 16 * 1024;

/// The camera's primary rays that enter the scene's box, pixel by pixel.
fn primary_rays(scene: &BrickedScene, cam: &CameraRecord) -> Result<Vec<Ray>> {
    let eye = crate::render::eye_rays(cam, "camera")?;
    let (lo, hi) = scene.view().globals().test_bounds();
    let mut rays = Vec::with_capacity((eye.width * eye.height) as usize);
    for y in 0..eye.height {
        for x in 0..eye.width {
            rays.extend(eye.sample_ray_in_scene(x, y, 0, lo, hi));
        }
    }
    Ok(rays)
}

/// Traces `rays` on `threads` workers through `cache`; returns the tracers' counts and
/// the hits.
fn trace_all(
    scene: &BrickedScene,
    cache: &BrickCache<'_>,
    rays: &[Ray],
    kind: IntersectorKind,
    packet: PacketSize,
    threads: Option<usize>,
) -> Result<(TraceStats, u64)> {
    let parts: Vec<Result<(TraceStats, u64)>> = crate::render::in_pool(threads, || {
        rays.par_chunks(CHUNK)
            .map(|chunk| {
                let mut tracer = BrickTracer::new(cache, scene.view(), packet);
                let hits =
                    crate::with_intersector!(kind, I => tracer.trace_batch::<I>(chunk, &vec![false; chunk.len()]))?;
                Ok((tracer.stats, hits.iter().filter(|h| h.is_some()).count() as u64))
            })
            .collect()
    })?;
    let mut stats = TraceStats::default();
    let mut hits = 0;
    for p in parts {
        let (s, h) = p?;
        stats.add(&s);
        hits += h;
    }
    Ok((stats, hits))
}

/// `raypipe stats` of a bricked scene.
pub(crate) fn stats(
    path: &Path,
    cam_args: &super::args::CameraArgs,
    run: &super::args::RunArgs,
    cache: &super::args::CacheArgs,
    packet: PacketSize,
) -> Result<()> {
    let scene = BrickedScene::open(path)?;
    let cam = super::camera_of(scene.view().globals(), cam_args)?;
    let (first, _) = scene.load(0)?;
    let kind = IntersectorKind::resolve(run.intersector, first.view());
    drop(first);
    let rays = primary_rays(&scene, &cam)?;
    let (s, c, hits, secs) = with_cache(&scene, cache.cache, cache.loaders as usize, |cache| {
        let start = Instant::now();
        let (s, hits) = trace_all(&scene, cache, &rays, kind, packet, run.threads)?;
        Ok((s, cache.stats(), hits, start.elapsed().as_secs_f64()))
    })?;
    let n = rays.len().max(1) as f64;
    println!(
        "scene        {} ({} bricks, {} triangles)",
        scene.name,
        scene.view().brick_count(),
        scene.view().header().triangle_count
    );
    println!(
        "view         {}x{}: {} primary rays enter the scene's box, {hits} hit",
        cam.width,
        cam.height,
        rays.len()
    );
    println!(
        "per ray      {:.2} top-level nodes, {:.2} bricks, {:.2} nodes in bricks, {:.2} triangle tests",
        s.top_steps as f64 / n,
        s.brick_visits as f64 / n,
        s.steps as f64 / n,
        s.tests as f64 / n
    );
    println!(
        "cache        {} of {}: hit rate {:.1}%, {} loads, {} evictions",
        fmt_bytes(c.peak_bytes as usize),
        fmt_bytes(cache.cache as usize),
        100.0 * c.hit_rate(),
        c.loads,
        c.evictions
    );
    println!(
        "loaded       {} read, {} decompressed ({:.3} s reading, {:.3} s decompressing)",
        fmt_bytes(c.bytes_read as usize),
        fmt_bytes(c.bytes_decompressed as usize),
        c.read_seconds,
        c.decompress_seconds
    );
    println!(
        "time         {secs:.3} s; rays parked {:.3} ray-s, tracers idle {:.3} s",
        s.parked_ray_seconds, s.idle_seconds
    );
    Ok(())
}

/// `raypipe bench` of a bricked scene: for each packet size, the first run with an empty
/// cache (cold) and the median of the others (warm).
pub(crate) fn bench(
    path: &Path,
    size: (u32, u32),
    packets: &[PacketSize],
    runs: usize,
    threads: Option<usize>,
    cache: &super::args::CacheArgs,
) -> Result<()> {
    let scene = BrickedScene::open(path)?;
    let mut cam = super::camera_of(scene.view().globals(), &super::args::CameraArgs::default())?;
    (cam.width, cam.height) = size;
    let (first, _) = scene.load(0)?;
    let kind = IntersectorKind::resolve(None, first.view());
    drop(first);
    let rays = primary_rays(&scene, &cam)?;
    println!(
        "{} ({} bricks), {}x{} primary rays, cache {}",
        scene.name,
        scene.view().brick_count(),
        size.0,
        size.1,
        fmt_bytes(cache.cache as usize)
    );
    println!("packet   cold Mrays/s   warm Mrays/s   bricks/ray   warm hit rate");
    for &packet in packets {
        with_cache(&scene, cache.cache, cache.loaders as usize, |c| {
            let mut times = Vec::new();
            let mut visits = 0.0;
            let mut before = c.stats();
            let mut warm_rate = 0.0;
            for run in 0..runs.max(2) {
                let start = Instant::now();
                let (s, _) = trace_all(&scene, c, &rays, kind, packet, threads)?;
                times.push(start.elapsed().as_secs_f64());
                visits = s.brick_visits as f64 / rays.len().max(1) as f64;
                let now = c.stats();
                if run > 0 {
                    warm_rate = now.since(&before).hit_rate();
                }
                before = now;
            }
            let mrays = |t: f64| rays.len() as f64 / t.max(1e-9) / 1e6;
            let warm = crate::study::bench::median(&times[1..]);
            println!(
                "{:<8} {:>13.2}   {:>12.2}   {:>10.2}   {:>12.1}%",
                packet.label(),
                mrays(times[0]),
                mrays(warm),
                visits,
                100.0 * warm_rate
            );
            Ok(())
        })?;
    }
    Ok(())
}
