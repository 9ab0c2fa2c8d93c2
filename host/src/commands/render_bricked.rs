//! `raypipe render` of a bricked scene: bricks demand-loaded through a cache of
//! `--cache` bytes, one frame or a walkthrough, with the cache's and the tracers' counts
//! and the time to first pixel.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;

use super::render::RenderArgs;
use super::{camera_of, fmt_bytes};
use crate::input::bricked::BrickedScene;
use crate::output;
use crate::output::tone_map::DisplayChoice;
use crate::render::bricked::brick_cache::{with_cache, CacheStats};
use crate::render::bricked::frame::{check_algorithm, render_bricked, BrickedFrame};
use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;
use crate::render::{self, RenderOptions};
use raypipe_core::image::CameraRecord;

/// Renders the bricked scene at `path`.
pub(crate) fn cmd_render_bricked(a: &RenderArgs, path: &Path) -> Result<()> {
    let open = Instant::now();
    let scene = BrickedScene::open(path)?;
    let index = scene.view();
    let (cam, opts, display) = bricked_setup(a, &scene)?;
    let opened = open.elapsed().as_secs_f64();
    let cams = a.walk.cameras(&cam)?;
    with_cache(&scene, a.cache.cache, a.cache.loaders as usize, |cache| {
        if let Some(cams) = &cams {
            return walkthrough(a, &scene, cache, cams, &opts, &display);
        }
        let start = Instant::now();
        let (frame, stats) = render_bricked(&scene, cache, &cam, &opts)?;
        let secs = start.elapsed().as_secs_f64();
        let auto = output::write_frame(&a.output, &frame, &display)?;
        let h = index.header();
        println!(
            "rendered {} ({} triangles in {} bricks) at {}x{} -> {}",
            scene.name,
            h.triangle_count,
            index.brick_count(),
            frame.width,
            frame.height,
            a.output.display()
        );
        if let Some(auto) = auto {
            println!("exposure {}", auto.describe());
        }
        println!(
            "time     open and validate {opened:.3} s, first pixel after {:.3} s, frame {secs:.3} s",
            opened + stats.first_tile_seconds
        );
        print_counts(&stats, &cache.stats(), secs, a.cache.cache);
        Ok(())
    })
}

/// The camera, options and display of a render of `scene`: the bricks' structure and
/// triangle layout decide the defaults, as a flat image's do.
pub(crate) fn bricked_setup(
    a: &RenderArgs,
    scene: &BrickedScene,
) -> Result<(CameraRecord, RenderOptions, DisplayChoice)> {
    let cam = camera_of(scene.view().globals(), &a.camera)?;
    render::eye_rays(&cam, "camera")?;
    let (first, _) = scene.load(0)?;
    let kind = IntersectorKind::resolve(a.run.intersector, first.view());
    let packet = a.packet.unwrap_or_else(|| PacketSize::auto_for(first.view()));
    drop(first);
    let mut opts =
        RenderOptions { threads: a.run.threads, intersector: kind, progress: true, packet, ..Default::default() };
    a.algo.apply(&mut opts)?;
    check_algorithm(&opts)?;
    let display = a.display.choice(opts.algo);
    Ok((cam, opts, display))
}

/// The frame's rays, the cache's counts and the tracers' waits.
fn print_counts(f: &BrickedFrame, c: &CacheStats, secs: f64, capacity: u64) {
    let r = &f.rays;
    println!(
        "rays     {} traced ({} eye, {} secondary): {:.2} Mrays/s",
        r.total(),
        r.primary,
        r.secondary,
        r.total() as f64 / secs.max(1e-9) / 1e6
    );
    println!(
        "bricks   {} visits, hit rate {:.1}%, {} loads, {} evictions; cache {} of {}",
        f.trace.brick_visits,
        100.0 * c.hit_rate(),
        c.loads,
        c.evictions,
        fmt_bytes(c.peak_bytes as usize),
        fmt_bytes(capacity as usize)
    );
    println!(
        "loaded   {} read, {} decompressed; reading {:.3} s, decompressing {:.3} s (loader threads)",
        fmt_bytes(c.bytes_read as usize),
        fmt_bytes(c.bytes_decompressed as usize),
        c.read_seconds,
        c.decompress_seconds
    );
    println!(
        "waiting  rays parked {:.3} ray-s in all; tracers idle {:.3} s in all",
        f.trace.parked_ray_seconds, f.trace.idle_seconds
    );
}

/// A walkthrough over a bricked scene: per frame its rate, the bytes loaded and the
/// cache's hit rate, the cache kept warm from frame to frame.
fn walkthrough(
    a: &RenderArgs,
    scene: &BrickedScene,
    cache: &crate::render::bricked::brick_cache::BrickCache<'_>,
    cams: &[raypipe_core::image::CameraRecord],
    opts: &RenderOptions,
    display: &crate::output::tone_map::DisplayChoice,
) -> Result<()> {
    println!("walkthrough of {} ({} bricks): {} frames", scene.name, scene.view().brick_count(), cams.len());
    println!("frame      seconds   frames/s   MB loaded  hit rate  image");
    let mut display = *display;
    let mut rows = Vec::with_capacity(cams.len());
    for (k, cam) in cams.iter().enumerate() {
        let before = cache.stats();
        let start = Instant::now();
        let (frame, _) = render_bricked(scene, cache, cam, opts)?;
        let secs = start.elapsed().as_secs_f64().max(1e-9);
        let c = cache.stats().since(&before);
        let path = output::frame_path(&a.output, k);
        if k == 0 {
            (display, _) = display.fixed_by(&frame.radiance);
        }
        output::write_frame(&path, &frame, &display)?;
        let mb = c.bytes_decompressed as f64 / 1e6;
        println!(
            "{k:>5}  {secs:>10.4}  {:>9.2}  {mb:>10.2}  {:>7.1}%  {}",
            1.0 / secs,
            100.0 * c.hit_rate(),
            path.display()
        );
        rows.push((secs, mb));
    }
    let total: f64 = rows.iter().map(|r| r.0).sum();
    let loaded: f64 = rows.iter().map(|r| r.1).sum();
    println!(
        "path     {} frames in {total:.3} s: {:.2} frames/s on average, {loaded:.1} MB loaded",
        cams.len(),
        cams.len() as f64 / total
    );
    // Wald & Slusallek's Figure 10: frame rate and data loaded over the walk.
    let fps: Vec<(f64, f64)> = rows.iter().map(|&(secs, mb)| (1.0 / secs, mb)).collect();
    let title = format!("{}: frames/s and MB loaded", scene.name);
    let chart = crate::output::walk_chart::write_walk_chart(&a.output, &fps, &title, "MB loaded")?;
    println!("chart    {}", chart.display());
    Ok(())
}
