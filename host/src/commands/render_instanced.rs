//! `raypipe render` of an instanced scene: a compiled `.rpsx`, or a scene file with
//! `[[instance]]` entries built in memory (the bottoms with `--accel`).

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Result};

use super::camera_of;
use super::render::RenderArgs;
use crate::input::instanced::load_instanced;
use crate::output;
use crate::render::instanced::frame::{check_algorithm, render_instanced};
use crate::render::tracer::IntersectorKind;
use crate::render::{self, RenderOptions};

/// Renders the instanced scene at `path`.
pub(crate) fn cmd_render_instanced(a: &RenderArgs, path: &Path) -> Result<()> {
    if a.walk.camera_path.is_some() || a.walk.orbit.is_some() {
        bail!("{}: a walkthrough of an instanced scene is `raypipe animate`'s work; render one view", path.display());
    }
    let open = Instant::now();
    let scene = load_instanced(path, &a.structure.options())?;
    if let Some(r) = &scene.report {
        for w in &r.warnings {
            eprintln!("warning: {w}");
        }
    }
    let view = scene.view()?;
    let s = scene.instances()?;
    let opened = open.elapsed().as_secs_f64();
    let cam = camera_of(&s.globals, &a.camera)?;
    render::eye_rays(&cam, "camera")?;
    let kind = IntersectorKind::resolve(a.run.intersector, &s.bottoms[0]);
    let mut opts = RenderOptions { threads: a.run.threads, intersector: kind, progress: true, ..Default::default() };
    a.algo.apply(&mut opts)?;
    check_algorithm(&opts)?;
    let display = a.display.choice(opts.algo);
    let start = Instant::now();
    let (frame, rays) = render_instanced(&s, &cam, &opts)?;
    let secs = start.elapsed().as_secs_f64();
    let auto = output::write_frame(&a.output, &frame, &display)?;
    let h = view.header();
    println!(
        "rendered {} ({} triangles drawn, {} stored, {} instances of {} meshes) at {}x{} -> {}",
        scene.name,
        h.triangle_count,
        h.stored_triangles,
        h.instance_count,
        h.bottom_count,
        frame.width,
        frame.height,
        a.output.display()
    );
    if let Some(auto) = auto {
        println!("exposure {}", auto.describe());
    }
    let build = scene.report.as_ref().map_or(0.0, |r| r.grid_seconds);
    println!("time     open, build and validate {opened:.3} s (structures {build:.3} s), render {secs:.3} s");
    println!(
        "rays     {} primary, {} secondary, {:.2} Mrays/s",
        rays.primary,
        rays.secondary,
        rays.total() as f64 / secs.max(1e-9) / 1e6
    );
    Ok(())
}
