//! `raypipe simulate`: the hardware model on a scene and a view. Configuration comes from
//! a preset or a TOML file, then `--set key=value` overrides; the model's image is the
//! host renderer's image (same kernels), and its report adds cycles and traffic.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::CameraRecord;
use raypipe_core::shade::shader::Shader;
use raypipe_core::Intersector;
use raypipe_hw::chip::scene::ChipScene;
use raypipe_hw::observe::counters::{counters, delta};
use raypipe_hw::observe::waves::Waves;
use raypipe_hw::{Datapath, HwConfig, Report, Simulator};

use crate::hw::frame_setup::FrameSetup;
use crate::output::progress;
use crate::render::gbuffer::gbuffer_visibility;
use crate::render::tracer::fixed_point_unsupported;
use crate::render::{eye_rays, Frame};
use crate::{with_datapath, with_intersector};

/// Builds the configuration: a preset or a file (else the defaults), then overrides;
/// validated before anything runs.
pub fn load_config(preset: Option<&str>, file: Option<&Path>, sets: &[String]) -> Result<HwConfig> {
    let mut cfg = match (preset, file) {
        (Some(name), _) => HwConfig::preset(name).map_err(|e| anyhow!(e))?,
        (None, Some(path)) => {
            let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
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

/// How a run is measured (gem5's warm-up and `resetstats`/`dumpstats`, ChampSim's
/// warm-up instructions): the frames, how many of them only warm the chip, the region of
/// interest within each measured frame, and interval statistics.
#[derive(Clone, Debug, Default)]
pub struct Measure {
    /// Leading frames whose statistics are dropped (caches, DRAM rows and the chip's
    /// clock carry over into the next frame).
    pub warmup_frames: usize,
    /// Cycles `a..b` of each measured frame (from its start): its report covers them only.
    pub roi: Option<(u64, u64)>,
    /// Counters every this many cycles of the measured part.
    pub interval: Option<u64>,
    /// Waveforms.
    pub vcd: Option<VcdSpec>,
    /// A Chrome trace-event file of packet lifetimes and memory transactions.
    pub trace: Option<std::path::PathBuf>,
    /// Only cycles A..B in the trace.
    pub trace_window: Option<(u64, u64)>,
    /// The memory's request stream (`cycle addr bytes R|W` per line).
    pub memory_trace: Option<std::path::PathBuf>,
}

/// Waveforms to write: the VCD file, its window of cycles (of the whole run) and the
/// signal name prefixes kept (all when empty).
#[derive(Clone, Debug, Default)]
pub struct VcdSpec {
    /// The file.
    pub path: std::path::PathBuf,
    /// Cycles `a..b` only.
    pub window: Option<(u64, u64)>,
    /// Signal name prefixes.
    pub units: Vec<String>,
}

/// One frame of a run.
pub struct FrameRun {
    /// The image.
    pub frame: Frame,
    /// The report of its measured part.
    pub report: Report,
    /// A warm-up frame (its report is not part of the totals).
    pub warmup: bool,
    /// The counters of each interval: first and end cycle (from the measured part's
    /// start), then the counters' increase.
    pub intervals: Vec<Interval>,
    /// Per pixel: cycles in flight, ray–node tests, ray–triangle tests, scene bytes.
    pub cost: Vec<[f64; 4]>,
}

/// One interval's counters.
pub struct Interval {
    /// First cycle (from the measured part's start).
    pub start: u64,
    /// End cycle (exclusive).
    pub end: u64,
    /// How much each counter grew.
    pub counters: Vec<(String, u64)>,
}

/// Simulates the frames `views` one after the other on one chip — a walkthrough, or one
/// view repeated for warm-up — measured as `measure` says.
pub fn simulate_frames(
    scene: &ChipScene<'_>,
    views: &[CameraRecord],
    measure: &Measure,
    cfg: &HwConfig,
    setup: &FrameSetup,
) -> Result<Vec<FrameRun>> {
    let FrameSetup { intersector, shader, shadow_caster, sampler, show_progress } = *setup;
    let eyes = views
        .iter()
        .enumerate()
        .map(|(i, c)| Ok(eye_rays(c, &format!("camera of frame {i}"))?.with_sampler(sampler)))
        .collect::<Result<Vec<_>>>()?;
    let Some(first) = views.first() else { bail!("no frame to simulate") };
    if let (ChipScene::Instanced(_), true) = (scene, shadow_caster) {
        bail!(
            "--algo shadow rasterizes one flat triangle list: simulate a two-level scene with --algo cast or whitted"
        );
    }
    if let (Some(flat), true) = (scene.flat(), cfg.datapath != Datapath::F32) {
        if let Some(why) = fixed_point_unsupported(flat) {
            bail!(
                "datapath {}: {why}; the fixed-point box test is for BVHs (build with --accel bvh, bvh4 or bvh8)",
                cfg.datapath.name()
            );
        }
    }
    if let Some(n) = measure.interval.filter(|&n| n == 0) {
        bail!("--interval {n}: an interval is at least one cycle");
    }
    if let Some((a, b)) = measure.roi.filter(|(a, b)| a >= b) {
        bail!("--roi {a}..{b}: the region of interest is empty");
    }
    let run = Run {
        scene,
        eyes: &eyes,
        measure,
        background: raypipe_core::Vec3::from(first.background),
        cfg,
        shader,
        shadow_caster,
        show_progress,
    };
    with_datapath!(cfg.datapath, I => run.go::<I>(), f32 => with_intersector!(intersector, I => run.go::<I>()))
}

/// One simulation's inputs, run with the triangle test `I` (and its box tests).
struct Run<'a, 's> {
    scene: &'a ChipScene<'s>,
    eyes: &'a [raypipe_core::camera::EyeRays],
    measure: &'a Measure,
    background: raypipe_core::Vec3,
    cfg: &'a HwConfig,
    shader: Option<Shader>,
    shadow_caster: bool,
    show_progress: bool,
}

impl Run<'_, '_> {
    fn go<I: Intersector>(&self) -> Result<Vec<FrameRun>> {
        let Run { scene, eyes, measure, background, cfg, shader, shadow_caster, show_progress } = *self;
        let mut sim = Simulator::<I>::for_scene(scene.clone(), eyes[0], background, shader, cfg)
            .map_err(|e| anyhow!("hardware configuration: {e}"))?;
        // Observers only read the chip: the reports are the same without them.
        let mut vcd_file = None;
        if let Some(VcdSpec { path, window, units }) = &measure.vcd {
            if let Some((a, b)) = window.filter(|(a, b)| a >= b) {
                bail!("--vcd-window {a}..{b}: the window is empty");
            }
            let comment = format!(
                "raypipe simulate: time in ps; clock {} MHz, one cycle every {:.3} ps, cycle n at n x the period",
                cfg.clock_mhz,
                1e6 / cfg.clock_mhz
            );
            let (file, sink) = crate::output::waveform::create(path, comment, cfg.clock_mhz)?;
            let waves = Waves::new(Box::new(sink), &sim.signals(), units, window.unwrap_or((0, u64::MAX)))
                .map_err(|e| anyhow!(e))?;
            sim.set_waves(waves);
            vcd_file = Some(file);
        }
        if let Some((a, b)) = measure.trace_window.filter(|(a, b)| a >= b) {
            bail!("--trace-window {a}..{b}: the window is empty");
        }
        if measure.trace.is_some() {
            sim.enable_trace();
        }
        if measure.memory_trace.is_some() {
            sim.record_memory_stream();
        }
        let bar = progress::bar(0, "simulate", show_progress);
        let mut out = Vec::new();
        let mut before = 0;
        for (f, eye) in eyes.iter().enumerate() {
            if f > 0 {
                sim.next_frame(*eye).map_err(|e| anyhow!(e))?;
            }
            if let (true, Some(scene)) = (shadow_caster, scene.flat()) {
                // Visibility from the host's rasterizer (the G-buffer pass), as on the host.
                let hits = (0..eye.samples()).flat_map(|s| gbuffer_visibility::<I>(scene, eye, s)).map(|(_, hit)| hit);
                sim.set_visibility(hits.collect());
            }
            let mut tick = |done: usize, total: usize| {
                bar.set_length((total * eyes.len()) as u64);
                bar.set_position((before + done) as u64);
            };
            let warmup = f < measure.warmup_frames;
            let start = sim.now();
            let mut intervals = Vec::new();
            let report = if warmup {
                sim.run(&mut tick).map_err(|e| anyhow!(e))?;
                sim.report()
            } else {
                // The region of interest: statistics from its first cycle to its end.
                let (roi_start, roi_end) = match measure.roi {
                    Some((a, b)) => (Some(start + a), Some(start + b)),
                    None => (None, None),
                };
                if let Some(a) = roi_start {
                    sim.run_until(Some(a), &mut tick).map_err(|e| anyhow!(e))?;
                    sim.reset_stats();
                }
                let mut last: Vec<(String, u64)> = Vec::new();
                let mut done = sim.is_done();
                while !done && roi_end.is_none_or(|e| sim.now() < e) {
                    let next = match measure.interval {
                        Some(n) => Some(roi_end.map_or(sim.now() + n, |e| e.min(sim.now() + n))),
                        None => roi_end,
                    };
                    done = sim.run_until(next, &mut tick).map_err(|e| anyhow!(e))?;
                    if measure.interval.is_some() {
                        let now = counters(&sim.report());
                        let cycles = |c: &[(String, u64)]| c.first().map_or(0, |(_, v)| *v);
                        intervals.push(Interval {
                            start: cycles(&last),
                            end: cycles(&now),
                            counters: delta(&now, &last),
                        });
                        last = now;
                    }
                }
                let report = sim.report();
                // The rest of the frame, for the image.
                sim.run(&mut tick).map_err(|e| anyhow!(e))?;
                report
            };
            before += sim.packet_count();
            let (width, height) = (eye.width, eye.height);
            let frame = Frame::from_radiance(width, height, sim.radiance_image());
            out.push(FrameRun { frame, report, warmup, intervals, cost: sim.cost_image().to_vec() });
        }
        bar.finish_and_clear();
        if let (Some(file), Some(mut waves)) = (vcd_file, sim.take_waves()) {
            let path = measure.vcd.as_ref().map(|v| v.path.display().to_string()).unwrap_or_default();
            waves.finish(sim.now()).map_err(|e| anyhow!("{path}: {e}"))?;
            file.commit()?;
            if let Some(spec) = &measure.vcd {
                write_gtkwave_files(&spec.path, &spec.units, &sim.signals())?;
            }
        }
        if let (Some(path), Some(log)) = (&measure.trace, sim.take_trace()) {
            let doc = crate::output::trace_events::to_json(&log, cfg.clock_mhz, measure.trace_window);
            crate::output::write_bytes(path, doc.to_string().as_bytes())?;
        }
        if let (Some(path), Some(stream)) = (&measure.memory_trace, sim.take_memory_stream()) {
            let mut text = String::from("# cycle addr bytes R|W (chip cycles)\n");
            for r in stream {
                text.push_str(&format!("{} {} {} {}\n", r.cycle, r.addr, r.bytes, if r.write { 'W' } else { 'R' }));
            }
            crate::output::write_bytes(path, text.as_bytes())?;
        }
        Ok(out)
    }
}

/// The GTKWave save file (`RUN.gtkw`) and activity filter (`RUN.activity.txt`) beside the
/// VCD `RUN.vcd`, listing the signals `units` kept (as the waveform sampler does).
fn write_gtkwave_files(
    vcd: &std::path::Path,
    units: &[String],
    all: &[raypipe_hw::observe::waves::Signal],
) -> Result<()> {
    use crate::output::waveform;
    // A VCD sent to a device or a pipe has no folder of its own to keep files beside.
    if std::fs::metadata(vcd).is_ok_and(|m| !m.is_file()) {
        return Ok(());
    }
    let kept: Vec<_> = all.iter().filter(|s| raypipe_hw::observe::waves::selected(s, units)).cloned().collect();
    let dir = vcd.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let dir = dir.canonicalize().map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    let name = vcd.file_name().map(std::path::PathBuf::from).unwrap_or_else(|| "run.vcd".into());
    let (save, filter) = (dir.join(name.with_extension("gtkw")), dir.join(name.with_extension("activity.txt")));
    crate::output::write_bytes(&filter, waveform::activity_filter().as_bytes())?;
    crate::output::write_bytes(&save, waveform::gtkw(&dir.join(&name), &filter, &kept).as_bytes())
}
