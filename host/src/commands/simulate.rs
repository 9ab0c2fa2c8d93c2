//! `raypipe simulate`: a frame on the cycle-level SaarCOR-like chip model.

use crate::cli::SimulateArgs;
use crate::output;
use crate::render::{Algorithm, RenderOptions};
use crate::simulate;
use crate::tracer::IntersectorKind;
use anyhow::{bail, Result};
use std::time::Instant;

use super::{camera_for, check_image_path, load_scene, structure_summary, warn};

pub(crate) fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    check_image_path(&a.output)?;
    let display = a.display.display()?;
    // Both outputs' directories before anything is written: never one without the other.
    output::check_dir(&a.output)?;
    output::check_dir(&a.report)?;
    // The configuration is checked before the scene is even loaded.
    let cfg = simulate::load_config(a.preset.as_deref(), a.config.as_deref(), &a.set)?;
    if let (Some(k), true) = (a.intersector, cfg.datapath != raypipe_hw::Datapath::F32) {
        bail!(
            "--intersector {}: datapath {} has its own triangle test (fixed-point watertight)",
            k.name(),
            cfg.datapath.name()
        );
    }
    let scene = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.intersector, &view);
    let mut opts = RenderOptions::default();
    a.algo.apply(&mut opts)?;
    let shader = opts.shader(raypipe_core::Vec3::from(cam.background));
    let start = Instant::now();
    let shadow_caster = opts.algo == Algorithm::Shadow;
    let (frame, mut report) = simulate::simulate(&view, &cam, &cfg, kind, shader, shadow_caster, opts.sampler(), true)?;
    let secs = start.elapsed().as_secs_f64();
    report.run = raypipe_hw::report::RunIdentity {
        scene: a.scene.as_ref().map_or("built-in Cornell box".to_string(), |p| p.display().to_string()),
        scene_hash: format!("{:016x}", raypipe_hw::report::fnv1a64(view.bytes())),
        structure: structure_summary(&view),
        algorithm: format!("{:?}", opts.algo).to_lowercase(),
        intersector: match cfg.datapath {
            raypipe_hw::Datapath::F32 => kind.name().to_string(),
            d => format!("fixed-watertight {}", d.name()),
        },
        camera: format!(
            "eye {:?} look_at {:?} up {:?} vfov {} deg, {}x{}",
            cam.eye, cam.look_at, cam.up, cam.vfov_deg, cam.width, cam.height
        ),
        raypipe_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    output::write_frame(&a.output, &frame, &display)?;
    output::write_bytes(&a.report, report.to_json().as_bytes())?;
    println!(
        "simulated {} ({}, {} triangles) -> {}",
        scene.name,
        structure_summary(&view),
        view.triangle_count(),
        a.output.display()
    );
    print!("{}", report.summary());
    println!(
        "simulator      {:.2} s wall, {:.3} Mrays/s simulated; report -> {}",
        secs,
        report.rays as f64 / secs / 1e6,
        a.report.display()
    );
    Ok(())
}
