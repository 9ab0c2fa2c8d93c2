//! `raypipe simulate`: a frame on the cycle-level SaarCOR-like chip model.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::cli::SimulateArgs;
use crate::output;
use crate::render::{Algorithm, Frame, RenderOptions};
use crate::scene::Scene;
use crate::simulate;
use crate::tracer::IntersectorKind;
use anyhow::{bail, Result};
use raypipe_hw::Report;

use super::{camera_for, check_image_path, load_scene, structure_summary, warn};

pub(crate) fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    check_image_path(&a.output)?;
    let display = a.display.display()?;
    // Both outputs' directories before anything is written: never one without the other.
    output::check_dir(&a.output)?;
    output::check_dir(&a.report)?;
    let run = simulate_args(&a, None, true)?;
    output::write_frame(&a.output, &run.frame, &display)?;
    output::write_bytes(&a.report, run.report.to_json().as_bytes())?;
    println!("simulated {} ({}, {} triangles) -> {}", run.scene, run.structure, run.triangles, a.output.display());
    print!("{}", run.report.summary());
    println!(
        "simulator      {:.2} s wall, {:.3} Mrays/s simulated; report -> {}",
        run.seconds,
        run.report.rays as f64 / run.seconds / 1e6,
        a.report.display()
    );
    Ok(())
}

/// One simulation's results.
pub(crate) struct Simulated {
    pub frame: Frame,
    pub report: Report,
    /// The scene's name, its structure and triangle count (for the summary line).
    pub scene: String,
    pub structure: String,
    pub triangles: u32,
    /// Wall-clock seconds of the simulation proper.
    pub seconds: f64,
}

/// Scenes already loaded, shared by the points of a sweep that name the same scene,
/// structure flags and camera (what [`load_scene`] depends on).
#[derive(Default)]
pub(crate) struct SceneCache {
    scenes: Mutex<HashMap<String, Arc<Scene>>>,
}

impl SceneCache {
    fn get(&self, a: &SimulateArgs) -> Result<Arc<Scene>> {
        let key = format!("{:?}|{:?}|{:?}", a.scene, a.structure, a.camera);
        if let Some(s) = self.scenes.lock().map_err(|_| anyhow::anyhow!("scene cache poisoned"))?.get(&key) {
            return Ok(s.clone());
        }
        let scene = Arc::new(load_scene(a.scene.as_deref(), &a.structure, &a.camera)?);
        warn(&scene);
        let mut map = self.scenes.lock().map_err(|_| anyhow::anyhow!("scene cache poisoned"))?;
        Ok(map.entry(key).or_insert(scene).clone())
    }
}

/// Runs what `a` describes: the configuration is checked before the scene is even
/// loaded (through `cache` when given). `raypipe simulate` and every sweep point go
/// through here, so a sweep point's report is the stand-alone run's.
pub(crate) fn simulate_args(a: &SimulateArgs, cache: Option<&SceneCache>, show_progress: bool) -> Result<Simulated> {
    let cfg = simulate::load_config(a.preset.as_deref(), a.config.as_deref(), &a.set)?;
    if let (Some(k), true) = (a.intersector, cfg.datapath != raypipe_hw::Datapath::F32) {
        bail!(
            "--intersector {}: datapath {} has its own triangle test (fixed-point watertight)",
            k.name(),
            cfg.datapath.name()
        );
    }
    let scene = match cache {
        Some(c) => c.get(a)?,
        None => {
            let s = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
            warn(&s);
            Arc::new(s)
        }
    };
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.intersector, &view);
    let mut opts = RenderOptions::default();
    a.algo.apply(&mut opts)?;
    let shader = opts.shader(raypipe_core::Vec3::from(cam.background));
    let start = Instant::now();
    let shadow_caster = opts.algo == Algorithm::Shadow;
    let (frame, mut report) =
        simulate::simulate(&view, &cam, &cfg, kind, shader, shadow_caster, opts.sampler(), show_progress)?;
    let seconds = start.elapsed().as_secs_f64();
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
    Ok(Simulated {
        frame,
        report,
        scene: scene.name.clone(),
        structure: structure_summary(&view),
        triangles: view.triangle_count(),
        seconds,
    })
}
