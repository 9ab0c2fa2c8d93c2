//! `raypipe simulate SCENE.aff --animate [A..B]`: a BART scene's frames (Lext, Assarsson
//! & Möller 2001) through the chip, in order. The host updates the moved meshes'
//! structures and the top level each frame (the chip does not build), and that update's
//! time is reported beside the chip's cycles for the frame. Each frame's data is new to
//! the chip — the host has just written it — so each frame starts with cold caches.

use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use raypipe_hw::chip::scene::{ChipScene, InstancedScene};

use super::animate::{frame_range, Animation};
use super::simulate::{chip_structure, measure_of, run_identity, SimulateArgs};
use crate::hw::chip::{self, FrameRun};
use crate::hw::frame_setup::FrameSetup;
use crate::output;
use crate::render::instanced::frame::{check_algorithm, render_instanced};
use crate::render::tracer::IntersectorKind;
use crate::render::RenderOptions;

/// One frame's line: the chip's cycles and rate beside the host's update.
struct FrameLine {
    frame: u32,
    run: FrameRun,
    update_secs: f64,
    refits: u32,
    rebuilds: u32,
}

impl FrameLine {
    fn json(&self) -> String {
        let r = &self.run.report;
        serde_json::json!({
            "frame": self.frame,
            "cycles": r.cycles,
            "chip_fps": r.frames_per_second,
            "rays": r.rays,
            "memory_bytes": r.memory.total_bytes,
            "host_update_ms": 1e3 * self.update_secs,
            "refits": self.refits,
            "rebuilds": self.rebuilds,
            "bottleneck": r.bottleneck,
        })
        .to_string()
    }
}

/// Checks what `--animate` cannot be combined with.
fn check_args(a: &SimulateArgs, frames: usize) -> Result<()> {
    if a.walk.camera_path.is_some() || a.walk.orbit.is_some() {
        bail!("--animate follows the scene's own camera track: drop --camera-path and --orbit");
    }
    let c = &a.camera;
    if c.camera.is_some() || c.eye.is_some() || c.look_at.is_some() || c.up.is_some() || c.fov.is_some() {
        bail!("--animate follows the scene's own camera track: only --size may change it");
    }
    if a.measure.warmup_frames > 0 {
        bail!("--warmup-frames with --animate: every frame is new data to the chip (cold caches)");
    }
    let m = &a.measure;
    let one_frame_only = m.vcd.is_some() || m.trace.is_some() || m.interval.is_some() || m.roi.is_some();
    if frames > 1 && (one_frame_only || m.cost_image.is_some()) {
        bail!("--vcd, --trace, --interval, --roi and --cost-image look at one frame: name it (--animate K)");
    }
    Ok(())
}

pub(crate) fn cmd_simulate_animate(a: &SimulateArgs, spec: &str) -> Result<()> {
    let path =
        a.scene.as_deref().ok_or_else(|| anyhow!("--animate needs an AFF scene (e.g. kitchen/aff/kitchen.aff)"))?;
    let cfg = chip::load_config(a.preset.as_deref(), a.config.as_deref(), &a.set)?;
    let structure = chip_structure(a, &cfg)?;
    let anim = Animation::open(path, &structure, &a.updates)?;
    let aff = &anim.aff;
    let range = frame_range("--animate", (spec != "all").then_some(spec), aff.frame_count())?;
    check_args(a, range.len())?;
    let mut opts = RenderOptions::default();
    a.algo.apply(&mut opts)?;
    check_algorithm(&opts)?;
    for p in [&a.output, &a.report, &a.measure.frames] {
        output::check_writable(p)?;
    }
    let views = anim.images.views()?;
    let mut state = anim.state(&views, &a.updates)?;
    let kind = IntersectorKind::resolve(a.intersector, &views.bottoms[0]);
    let measure = measure_of(a);
    let display = a.display.choice(opts.algo);
    let outputs = output::batch::Batch::begin();
    let bar = output::progress::bar(range.len() as u64, "frames", true);
    let start = Instant::now();
    let mut lines = Vec::new();
    for k in range.clone() {
        let update = Instant::now();
        let (stats, _) = anim.update(&mut state, &views, k)?;
        let levels = state.levels();
        let frame = state.frame(&views, &levels)?;
        let update_secs = update.elapsed().as_secs_f64();
        let mut camera = aff.camera(aff.time(k));
        if let Some((w, h)) = a.camera.size {
            // Not BART's rules (frames at the scene's resolution); for quick looks.
            (camera.width, camera.height) = (w, h);
        }
        let shader = opts.shader(raypipe_core::Vec3::from(camera.background));
        let setup = FrameSetup {
            intersector: kind,
            shader,
            shadow_caster: false,
            sampler: opts.sampler(),
            show_progress: false,
        };
        let scene = ChipScene::Instanced(InstancedScene::new(frame.top, frame.bottoms.clone(), frame.globals));
        let mut run = chip::simulate_frames(&scene, std::slice::from_ref(&camera), &measure, &cfg, &setup)?
            .pop()
            .ok_or_else(|| anyhow!("frame {k}: nothing simulated"))?;
        if a.check_host {
            let (host, _) = render_instanced(&frame, &camera, &opts)?;
            let differ = host.pixels.iter().zip(&run.frame.pixels).filter(|(h, c)| h != c).count();
            if differ > 0 || host.pixels.len() != run.frame.pixels.len() {
                bail!("frame {k}: the chip's image differs from the host's in {differ} pixels");
            }
        }
        let placement: &[u8] = bytemuck::cast_slice(frame.top.instances());
        let summary = format!("{} instances, update {}", frame.top.instance_count(), a.updates.update.name());
        run.report.run = run_identity(a, placement, &summary, &opts, &cfg, kind, &camera);
        output::write_frame(&output::frame_path(&a.output, k as usize), &run.frame, &display)?;
        lines.push(FrameLine { frame: k, run, update_secs, refits: stats.refits, rebuilds: stats.rebuilds });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let text: String = lines.iter().map(|l| l.json() + "\n").collect();
    output::write_bytes(&a.measure.frames, text.as_bytes())?;
    let last = lines.last().ok_or_else(|| anyhow!("no frame simulated"))?;
    output::write_bytes(&a.report, last.run.report.to_json().as_bytes())?;
    outputs.commit()?;
    print_frames(a, &lines, anim.load_secs, start.elapsed().as_secs_f64());
    Ok(())
}

/// The frames' table and the totals: the chip's frame rate beside the host's update.
fn print_frames(a: &SimulateArgs, lines: &[FrameLine], load_secs: f64, wall: f64) {
    let n = lines.len();
    println!(
        "simulated {} frames of {} (update {}) -> {} .. {}",
        n,
        a.scene.as_deref().map_or(String::new(), |p| p.display().to_string()),
        a.updates.update.name(),
        output::frame_path(&a.output, lines[0].frame as usize).display(),
        output::frame_path(&a.output, lines[n - 1].frame as usize).display()
    );
    println!("frame       cycles   chip frames/s   host update ms   refits  rebuilds   bottleneck");
    for l in lines {
        let r = &l.run.report;
        println!(
            "{:>5} {:>12} {:>15.1} {:>16.2} {:>8} {:>9}   {}",
            l.frame,
            r.cycles,
            r.frames_per_second,
            1e3 * l.update_secs,
            l.refits,
            l.rebuilds,
            r.bottleneck.split(':').next().unwrap_or_default()
        );
    }
    let cycles: u64 = lines.iter().map(|l| l.run.report.cycles).sum();
    let clock = lines[0].run.report.config.clock_mhz * 1e6;
    let update: f64 = lines.iter().map(|l| l.update_secs).sum();
    println!(
        "total    chip {cycles} cycles = {:.3} s at {} MHz ({:.1} frames/s); host updates {:.3} s ({:.2} ms per frame)",
        cycles as f64 / clock,
        clock / 1e6,
        n as f64 * clock / cycles.max(1) as f64,
        update,
        1e3 * update / n as f64
    );
    println!(
        "simulator      load {load_secs:.2} s, {wall:.2} s wall; report (last frame) -> {}, frames -> {}",
        a.report.display(),
        a.measure.frames.display()
    );
}
