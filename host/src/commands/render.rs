//! `raypipe render`: a PNG of the scene on the host renderer.

use crate::cli::RenderArgs;
use crate::output;
use crate::packets::PacketSize;
use crate::render::{self, RenderOptions};
use crate::tracer::IntersectorKind;
use anyhow::Result;
use std::time::Instant;

use super::{camera_for, check_image_path, lights_summary, load_scene, warn};

pub(crate) fn cmd_render(a: RenderArgs) -> Result<()> {
    a.run.check()?;
    check_image_path(&a.output)?;
    let display = a.display.display()?;
    let loading = Instant::now();
    let scene = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
    let load_secs = loading.elapsed().as_secs_f64();
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let packet = a.packet.unwrap_or_else(|| PacketSize::auto_for(&view));
    let mut opts =
        RenderOptions { threads: a.run.threads, intersector: kind, progress: true, packet, ..Default::default() };
    a.algo.apply(&mut opts)?;
    let start = Instant::now();
    let (frame, rays) = render::render_counted(&view, &cam, &opts)?;
    let secs = start.elapsed().as_secs_f64();
    output::write_frame(&a.output, &frame, &display)?;
    // Building the structure is part of loading an OBJ; the report says how long it took.
    let build_secs = scene.report.as_ref().map_or(0.0, |r| r.grid_seconds);
    println!(
        "rendered {} ({} triangles) at {}x{}, {} sample{} per pixel -> {}",
        scene.name,
        view.triangle_count(),
        frame.width,
        frame.height,
        opts.samples,
        if opts.samples == 1 { "" } else { "s" },
        a.output.display()
    );
    println!("lights   {}", lights_summary(&scene)?);
    println!(
        "time     load {:.3} s, build {:.3} s, render {:.3} s",
        (load_secs - build_secs).max(0.0),
        build_secs,
        secs
    );
    println!(
        "rays     {} traced ({} eye, {} secondary): {:.2} Mrays/s",
        rays.total(),
        rays.primary,
        rays.secondary,
        rays.total() as f64 / secs.max(1e-9) / 1e6
    );
    Ok(())
}
