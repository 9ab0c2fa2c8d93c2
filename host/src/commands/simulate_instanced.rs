//! `raypipe simulate` of a two-level scene: a compiled `.rpsx` or a scene file with
//! `[[instance]]` entries (its bottoms built with the chip's structure unless `--accel`
//! names one), one view on the chip with its transformation units.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Result};
use raypipe_hw::chip::scene::{ChipScene, InstancedScene};
use raypipe_hw::HwConfig;

use super::args::StructureArgs;
use super::simulate::{measure_of, run_identity, SimulateArgs, Simulated};
use super::{camera_of, structure_summary};
use crate::hw::chip;
use crate::hw::frame_setup::FrameSetup;
use crate::input::instanced::load_instanced;
use crate::render::instanced::frame::check_algorithm;
use crate::render::tracer::IntersectorKind;
use crate::render::RenderOptions;

/// Simulates one view of the two-level scene at `path`.
pub(crate) fn run_instanced_simulation(
    a: &SimulateArgs,
    path: &Path,
    cfg: &HwConfig,
    structure: &StructureArgs,
    show_progress: bool,
) -> Result<Simulated> {
    if a.walk.camera_path.is_some() || a.walk.orbit.is_some() {
        bail!("{}: a walkthrough of a two-level scene is `simulate --animate`'s work (an AFF scene)", path.display());
    }
    let file = load_instanced(path, &structure.options())?;
    if let Some(r) = &file.report {
        for w in &r.warnings {
            eprintln!("warning: {w}");
        }
    }
    let s = file.instances()?;
    // The globals image holds no triangle to judge the view by: no coverage hint.
    let cam = camera_of(&s.globals, &a.camera)?;
    crate::render::eye_rays(&cam, "camera")?;
    let mut opts = RenderOptions::default();
    a.algo.apply(&mut opts)?;
    check_algorithm(&opts)?;
    let kind = IntersectorKind::resolve(a.intersector, &s.bottoms[0]);
    let shader = opts.shader(raypipe_core::Vec3::from(cam.background));
    let views = vec![cam; a.measure.warmup_frames.saturating_add(1).min(crate::input::camera_path::MAX_FRAMES)];
    let measure = measure_of(a);
    if measure.warmup_frames >= views.len() {
        bail!("--warmup-frames {}: too many", measure.warmup_frames);
    }
    let setup = FrameSetup { intersector: kind, shader, shadow_caster: false, sampler: opts.sampler(), show_progress };
    let start = Instant::now();
    let scene = ChipScene::Instanced(InstancedScene::new(s.top, s.bottoms.clone(), s.globals));
    let mut frames = chip::simulate_frames(&scene, &views, &measure, cfg, &setup)?;
    let seconds = start.elapsed().as_secs_f64();
    let view = file.view()?;
    let h = view.header();
    let summary = format!(
        "{} instances of {} meshes, bottoms {}",
        h.instance_count,
        h.bottom_count,
        structure_summary(&s.bottoms[0])
    );
    for f in frames.iter_mut() {
        f.report.run = run_identity(a, &file.bytes, &summary, &opts, cfg, kind, &cam);
    }
    let report = frames.last().map(|f| f.report.clone()).ok_or_else(|| anyhow::anyhow!("no frame simulated"))?;
    Ok(Simulated { frames, report, scene: file.name.clone(), structure: summary, triangles: h.triangle_count, seconds })
}
