//! `raypipe simulate`: the hardware model on a scene and a view. Configuration comes from
//! a preset or a TOML file, then `--set key=value` overrides; the model's image is the
//! host renderer's image (same kernels), and its report adds cycles and traffic.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::CameraRecord;
use raypipe_core::pixel_filter::PixelSampler;
use raypipe_core::shade::shader::Shader;
use raypipe_core::{Intersector, SceneView};
use raypipe_hw::{Datapath, HwConfig, Report, Simulator};

use crate::progress;
use crate::raster::gbuffer_visibility;
use crate::render::{eye_rays, Frame};
use crate::tracer::{fixed_point_unsupported, IntersectorKind};
use crate::{with_datapath, with_intersector};

/// Builds the configuration: a preset or a file (else the defaults), then overrides;
/// validated before anything runs.
pub fn load_config(preset: Option<&str>, file: Option<&Path>, sets: &[String]) -> Result<HwConfig> {
    let mut cfg = match (preset, file) {
        (Some(name), _) => HwConfig::preset(name).map_err(|e| anyhow!(e))?,
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
            HwConfig::from_toml(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?
        }
        (None, None) => HwConfig::default(),
    };
    for s in sets {
        cfg.set(s).map_err(|e| anyhow!(e))?;
    }
    cfg.validate().map_err(|e| anyhow!("hardware configuration: {e}"))?;
    Ok(cfg)
}

/// Simulates one frame with `sampler`'s eye rays per pixel; the image and the report.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    cfg: &HwConfig,
    intersector: IntersectorKind,
    shader: Option<Shader>,
    shadow_caster: bool,
    sampler: PixelSampler,
    show_progress: bool,
) -> Result<(Frame, Report)> {
    let eye = eye_rays(camera, "camera")?.with_sampler(sampler);
    if cfg.datapath != Datapath::F32 {
        if let Some(why) = fixed_point_unsupported(scene) {
            bail!(
                "datapath {}: {why}; the fixed-point box test is for BVHs (build with --accel bvh, bvh4 or bvh8)",
                cfg.datapath.name()
            );
        }
    }
    let run = Run {
        scene,
        eye,
        background: raypipe_core::Vec3::from(camera.background),
        cfg,
        shader,
        shadow_caster,
        show_progress,
    };
    with_datapath!(cfg.datapath, I => run.go::<I>(), f32 => with_intersector!(intersector, I => run.go::<I>()))
}

/// One simulation's inputs, run with the triangle test `I` (and its box tests).
struct Run<'a, 's> {
    scene: &'a SceneView<'s>,
    eye: raypipe_core::camera::EyeRays,
    background: raypipe_core::Vec3,
    cfg: &'a HwConfig,
    shader: Option<Shader>,
    shadow_caster: bool,
    show_progress: bool,
}

impl Run<'_, '_> {
    fn go<I: Intersector>(&self) -> Result<(Frame, Report)> {
        let Run { scene, eye, background, cfg, shader, shadow_caster, show_progress } = *self;
        let (width, height) = (eye.width, eye.height);
        let mut sim = Simulator::<I>::with_shader(*scene, eye, background, shader, cfg)
            .map_err(|e| anyhow!("hardware configuration: {e}"))?;
        if shadow_caster {
            // Visibility from the host's rasterizer (the G-buffer pass), as on the host.
            let hits = (0..eye.samples()).flat_map(|s| gbuffer_visibility::<I>(scene, &eye, s)).map(|(_, hit)| hit);
            sim.set_visibility(hits.collect());
        }
        let bar = progress::bar(0, "simulate", show_progress);
        sim.run(|done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })
        .map_err(|e| anyhow!(e))?;
        bar.finish_and_clear();
        let frame = Frame::from_radiance(width, height, sim.radiance_image());
        Ok((frame, sim.report()))
    }
}
