//! `raypipe render`: a PNG of the scene on the host renderer.

use crate::cli::RenderArgs;
use crate::output;
use crate::packets::PacketSize;
use crate::render::{self, RenderOptions};
use crate::scene;
use crate::tracer::IntersectorKind;
use anyhow::Result;
use std::time::Instant;

use super::{camera_for, check_png_path, warn};

pub(crate) fn cmd_render(a: RenderArgs) -> Result<()> {
    a.run.check()?;
    check_png_path(&a.output)?;
    let scene = scene::load(a.scene.as_deref(), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let packet = a.packet.unwrap_or_else(|| PacketSize::auto_for(&view));
    let mut opts =
        RenderOptions { threads: a.run.threads, intersector: kind, progress: true, packet, ..Default::default() };
    a.algo.apply(&mut opts)?;
    let start = Instant::now();
    let frame = render::render(&view, &cam, &opts)?;
    let secs = start.elapsed().as_secs_f64();
    output::write_png(&a.output, frame.width, frame.height, &frame.pixels)?;
    println!(
        "rendered {} ({} triangles) at {}x{} in {:.3} s ({:.2} Mrays/s) -> {}",
        scene.name,
        view.triangle_count(),
        frame.width,
        frame.height,
        secs,
        (frame.width as f64 * frame.height as f64) / secs / 1e6,
        a.output.display()
    );
    Ok(())
}
