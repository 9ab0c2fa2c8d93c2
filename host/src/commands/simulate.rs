//! `raypipe simulate`: a frame on the cycle-level SaarCOR-like chip model.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::hw::chip::{self, FrameRun, Measure};
use crate::hw::frame_setup::FrameSetup;
use crate::output;
use crate::render::tracer::IntersectorKind;
use crate::render::{Algorithm, RenderOptions};
use crate::scene::{Accel, Scene};
use anyhow::{bail, Result};
use raypipe_hw::chip::scene::ChipScene;
use raypipe_hw::Report;

use super::{camera_for, check_image_path, load_scene, structure_summary, warn};

use super::args::AlgoArgs;
use super::args::CameraArgs;
use super::args::DisplayArgs;
use super::args::StructureArgs;
use super::args::WalkArgs;
use clap::Args;
use std::path::PathBuf;

/// `raypipe simulate`'s arguments from a command line that starts with `simulate` (a
/// sweep point's), with clap's own errors, as `raypipe` itself would parse it.
pub fn parse_simulate_line(args: &[String]) -> Result<SimulateArgs, clap::Error> {
    /// `raypipe` with only its `simulate` subcommand.
    #[derive(clap::Parser)]
    #[command(name = "raypipe")]
    struct Line {
        #[command(subcommand)]
        command: Only,
    }
    #[derive(clap::Subcommand)]
    enum Only {
        Simulate(Box<SimulateArgs>),
    }
    let line =
        <Line as clap::Parser>::try_parse_from(std::iter::once("raypipe".to_string()).chain(args.iter().cloned()))?;
    let Only::Simulate(a) = line.command;
    Ok(*a)
}

/// `raypipe simulate`.
#[derive(Args, Debug, Clone)]
pub struct SimulateArgs {
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    /// Hardware configuration file (TOML; see fixtures/hw/ and docs/hw-model.md).
    #[arg(long, value_name = "FILE.toml", conflicts_with = "preset")]
    pub config: Option<PathBuf>,
    /// A shipped configuration: saarcor or minimal (default: the built-in defaults).
    #[arg(long, value_name = "NAME")]
    pub preset: Option<String>,
    /// Override one parameter, e.g. `--set traversal.threads=16` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Output image: .png (8-bit sRGB through --exposure and --tonemap), .exr (OpenEXR)
    /// or .pfm, both linear radiance.
    #[arg(short, long, value_name = "IMAGE", default_value = "raypipe-sim.png")]
    pub output: PathBuf,
    #[command(flatten)]
    pub display: DisplayArgs,
    /// The report as JSON (schema in docs/hw-model.md).
    #[arg(long, value_name = "JSON", default_value = "raypipe-sim.json")]
    pub report: PathBuf,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    /// Ray–triangle test (default: the one the image's triangle layout is for).
    #[arg(long, value_enum)]
    pub intersector: Option<IntersectorKind>,
    #[command(flatten)]
    pub algo: AlgoArgs,
    #[command(flatten)]
    pub walk: WalkArgs,
    #[command(flatten)]
    pub measure: MeasureArgs,
    /// Run an animated AFF scene (BART) through the chip: all its frames, or frames
    /// A..B (B excluded), or one frame A; each frame's image is written as
    /// `OUTPUT-NNNN.png`, its line to --frames, the last frame's report to --report.
    #[arg(long, value_name = "A..B", num_args = 0..=1, default_missing_value = "all")]
    pub animate: Option<String>,
    #[command(flatten)]
    pub updates: super::animate::UpdateArgs,
    /// With --animate: render every frame on the host too, and stop with an error if the
    /// chip's image differs from it in any pixel.
    #[arg(long, requires = "animate")]
    pub check_host: bool,
}

/// What `simulate` measures: warm-up, region of interest, intervals.
#[derive(Args, Debug, Clone, Default)]
pub struct MeasureArgs {
    /// Simulate the view this many times first, caches and DRAM rows kept warm, and
    /// measure the next (a walkthrough: its first K frames are warm-up).
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub warmup_frames: usize,
    /// Region of interest: the report covers cycles A..B of each measured frame (from its
    /// start) only.
    #[arg(long, value_name = "A..B", value_parser = parse_roi)]
    pub roi: Option<(u64, u64)>,
    /// Write the report's counters every N cycles of the measured part, as JSON lines
    /// (--intervals); the rows of a frame sum to its report.
    #[arg(long, value_name = "N")]
    pub interval: Option<u64>,
    /// Where --interval writes.
    #[arg(long, value_name = "JSONL", default_value = "raypipe-sim.intervals.jsonl")]
    pub intervals: PathBuf,
    /// Waveforms as VCD (GTKWave, Surfer): FIFO occupancies, unit activities, traversal
    /// threads by state, requests waiting in ports and the memory's queue, per cycle.
    #[arg(long, value_name = "FILE.vcd")]
    pub vcd: Option<PathBuf>,
    /// Only cycles A..B of the run in the VCD.
    #[arg(long, value_name = "A..B", value_parser = parse_roi, requires = "vcd")]
    pub vcd_window: Option<(u64, u64)>,
    /// Only the signals whose names start with these (e.g. traversal0,fifos.rays,memory).
    #[arg(long, value_name = "LIST", value_delimiter = ',', requires = "vcd")]
    pub vcd_units: Vec<String>,
    /// A Chrome/Perfetto trace (JSON): packet lifetimes (issue, traversal, intersection,
    /// shading) and memory transactions.
    #[arg(long, value_name = "FILE.json")]
    pub trace: Option<PathBuf>,
    /// Only what overlaps cycles A..B in the trace (a whole frame's trace of a large chip
    /// is more than a viewer opens).
    #[arg(long, value_name = "A..B", value_parser = parse_roi, requires = "trace")]
    pub trace_window: Option<(u64, u64)>,
    /// Every request the memory served (after the L2), one per line: `cycle addr bytes
    /// R|W`, cycles of the chip's clock — to replay against another memory model
    /// (bench/dram_validate.sh).
    #[arg(long, value_name = "FILE.txt")]
    pub memory_trace: Option<PathBuf>,
    /// Per-pixel cost heatmaps of the (last) frame: PREFIX-cycles.png (cycles its packets
    /// were in flight), PREFIX-steps.png (ray–node tests), PREFIX-tests.png (ray–triangle
    /// tests), PREFIX-bytes.png (scene bytes read for it).
    #[arg(long, value_name = "PREFIX")]
    pub cost_image: Option<PathBuf>,
    /// Walkthroughs: one JSON line per frame (cycles, frames/s, bytes loaded, hit rates).
    #[arg(long, value_name = "JSONL", default_value = "raypipe-sim.frames.jsonl")]
    pub frames: PathBuf,
}

pub(crate) fn parse_roi(s: &str) -> Result<(u64, u64), String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("{s:?}: expected A..B (cycles)"))?;
    let parse = |t: &str| t.trim().parse::<u64>().map_err(|_| format!("{s:?}: {t:?} is not a cycle number"));
    Ok((parse(a)?, parse(b)?))
}

pub(crate) fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    check_image_path(&a.output)?;
    if let Some(spec) = &a.animate {
        return super::simulate_animate::cmd_simulate_animate(&a, spec);
    }
    let mut display = a.display.choice(a.algo.algo);
    // Every output's directory before anything is written: never one without the other.
    output::check_writable(&a.output)?;
    output::check_writable(&a.report)?;
    if a.measure.interval.is_some() {
        output::check_writable(&a.measure.intervals)?;
    }
    for p in a.measure.vcd.iter().chain(&a.measure.trace).chain(&a.measure.cost_image).chain(&a.measure.memory_trace) {
        output::check_writable(p)?;
    }
    let walk = a.walk.camera_path.is_some() || a.walk.orbit.is_some();
    if walk {
        output::check_writable(&a.measure.frames)?;
    }
    // All outputs or none: a failure on the last (a full disk) leaves none of the others.
    let outputs = output::batch::Batch::begin();
    let run = run_simulation(&a, None, true)?;
    let measured: Vec<&FrameRun> = run.frames.iter().filter(|f| !f.warmup).collect();
    let mut auto = None;
    if walk {
        if let Some(first) = run.frames.first() {
            (display, auto) = display.fixed_by(&first.frame.radiance);
        }
        for (k, f) in run.frames.iter().enumerate() {
            output::write_frame(&output::frame_path(&a.output, k), &f.frame, &display)?;
        }
        let lines: Vec<String> = run.frames.iter().enumerate().map(|(k, f)| frame_line(k, f)).collect();
        output::write_bytes(&a.measure.frames, (lines.join("\n") + "\n").as_bytes())?;
    } else if let Some(last) = run.frames.last() {
        auto = output::write_frame(&a.output, &last.frame, &display)?;
    }
    if a.measure.interval.is_some() {
        let mut text = String::new();
        for (k, f) in run.frames.iter().enumerate().filter(|(_, f)| !f.warmup) {
            for crate::hw::chip::Interval { start, end, counters } in &f.intervals {
                let c: serde_json::Map<String, serde_json::Value> =
                    counters.iter().map(|(n, v)| (n.clone(), serde_json::Value::from(*v))).collect();
                let row = serde_json::json!({ "frame": k, "start": start, "end": end, "counters": c });
                text.push_str(&row.to_string());
                text.push('\n');
            }
        }
        output::write_bytes(&a.measure.intervals, text.as_bytes())?;
    }
    if let (Some(prefix), Some(last)) = (&a.measure.cost_image, run.frames.last()) {
        let (w, h) = (last.frame.width, last.frame.height);
        for (k, (what, title)) in [
            ("cycles", "cycles in flight per pixel"),
            ("steps", "ray-node tests per pixel"),
            ("tests", "ray-triangle tests per pixel"),
            ("bytes", "scene bytes read per pixel"),
        ]
        .into_iter()
        .enumerate()
        {
            let values: Vec<f64> = last.cost.iter().map(|c| c[k]).collect();
            crate::study::cost_image::write(&crate::study::cost_image::path(prefix, what), w, h, &values, title)?;
        }
    }
    output::write_bytes(&a.report, run.report.to_json().as_bytes())?;
    outputs.commit()?;
    let target = if walk {
        format!("{} frames, {}", run.frames.len(), output::frame_path(&a.output, 0).display())
    } else {
        a.output.display().to_string()
    };
    println!("simulated {} ({}, {} triangles) -> {target}", run.scene, run.structure, run.triangles);
    if let Some(auto) = auto.filter(|_| output::ImageFormat::of(&a.output).ok() == Some(output::ImageFormat::Png)) {
        println!("exposure {}", auto.describe());
    }
    if walk {
        print_walkthrough(&run.frames, a.measure.warmup_frames);
        println!("last frame:");
    } else if a.measure.warmup_frames > 0 {
        println!("after {} warm-up frame(s), caches warm:", a.measure.warmup_frames);
    }
    print!("{}", crate::hw::chip_summary::summary(&run.report));
    let rays: u64 = measured.iter().map(|f| f.report.rays).sum();
    println!(
        "simulator      {:.2} s wall, {:.3} Mrays/s simulated; report -> {}{}{}",
        run.seconds,
        rays as f64 / run.seconds / 1e6,
        a.report.display(),
        if a.measure.interval.is_some() {
            format!(", intervals -> {}", a.measure.intervals.display())
        } else {
            String::new()
        },
        if walk { format!(", frames -> {}", a.measure.frames.display()) } else { String::new() }
    );
    Ok(())
}

/// A walkthrough frame's line: Wald & Slusallek's walkthrough figures (frame rate and
/// data loaded over time) and the caches' hit rates.
fn frame_line(k: usize, f: &FrameRun) -> String {
    let r = &f.report;
    let hit: serde_json::Map<String, serde_json::Value> = raypipe_hw::observe::metrics::metrics(r)
        .into_iter()
        .filter(|(n, _)| n.starts_with("hit_rate."))
        .map(|(n, v)| {
            (
                n["hit_rate.".len()..].to_string(),
                serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number),
            )
        })
        .collect();
    serde_json::json!({
        "frame": k,
        "warmup": f.warmup,
        "cycles": r.cycles,
        "fps": r.frames_per_second,
        "rays": r.rays,
        "memory_bytes": r.memory.total_bytes,
        "distinct_scene_bytes": r.memory.distinct_scene_bytes,
        "hit_rate": hit,
        "bottleneck": r.bottleneck,
    })
    .to_string()
}

/// Each frame of a walkthrough, then the steady state (the measured frames).
fn print_walkthrough(frames: &[FrameRun], warmup: usize) {
    println!("frame     cycles   frames/s   memory bytes   scene bytes read   node hits   triangle hits");
    let pct = |r: &Report, m: &str| {
        raypipe_hw::observe::metrics::metric(r, m)
            .filter(|v| v.is_finite())
            .map_or("-".to_string(), |v| format!("{:.1}%", 100.0 * v))
    };
    for (k, f) in frames.iter().enumerate() {
        let r = &f.report;
        println!(
            "{k:>5}{} {:>10} {:>10.2} {:>14} {:>18} {:>11} {:>15}",
            if f.warmup { "w" } else { " " },
            r.cycles,
            r.frames_per_second,
            r.memory.total_bytes,
            r.memory.distinct_scene_bytes,
            pct(r, "hit_rate.nodes"),
            pct(r, "hit_rate.triangles")
        );
    }
    let measured: Vec<&Report> = frames.iter().filter(|f| !f.warmup).map(|f| &f.report).collect();
    if let Some(first) = measured.first() {
        let cycles: u64 = measured.iter().map(|r| r.cycles).sum();
        let bytes: u64 = measured.iter().map(|r| r.memory.total_bytes).sum();
        let secs = cycles as f64 / (first.config.clock_mhz * 1e6);
        println!(
            "steady state   {} frames after {} warm-up: {:.2} frames/s, {:.0} cycles and {:.0} memory bytes per frame",
            measured.len(),
            warmup.min(frames.len()),
            measured.len() as f64 / secs,
            cycles as f64 / measured.len() as f64,
            bytes as f64 / measured.len() as f64
        );
    }
}

/// Where the simulated structure came from, said on the summary line: a preset's
/// structure must never be a silent default.
fn structure_origin(a: &SimulateArgs, cfg: &raypipe_hw::HwConfig, scene: &Scene) -> String {
    let chip = match (&a.preset, &a.config) {
        (_, Some(file)) => format!("{}", file.display()),
        (Some(p), None) => format!("preset {p}"),
        (None, None) => "the default chip".into(),
    };
    if scene.report.is_none() {
        format!("built into the scene image ({chip} names {:?})", cfg.structure)
    } else if a.structure.accel.is_some() {
        format!("from --accel ({chip} names {:?})", cfg.structure)
    } else {
        format!("the structure of {chip} (--accel to change)")
    }
}

/// One simulation's results.
pub(crate) struct Simulated {
    /// Every frame (one unless a walkthrough or warm-up).
    pub frames: Vec<FrameRun>,
    /// The last frame's report, with the run's identity.
    pub report: Report,
    /// The scene's name, its structure and triangle count (for the summary line).
    pub scene: String,
    pub structure: String,
    pub triangles: u64,
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
    fn get(&self, a: &SimulateArgs, structure: &StructureArgs) -> Result<Arc<Scene>> {
        let key = format!("{:?}|{:?}|{:?}", a.scene, structure, a.camera);
        if let Some(s) = self.scenes.lock().map_err(|_| anyhow::anyhow!("scene cache poisoned"))?.get(&key) {
            return Ok(s.clone());
        }
        let scene = Arc::new(load_scene(a.scene.as_deref(), structure, &a.camera)?);
        warn(&scene);
        let mut map = self.scenes.lock().map_err(|_| anyhow::anyhow!("scene cache poisoned"))?;
        Ok(map.entry(key).or_insert(scene).clone())
    }
}

/// Runs what `a` describes: the configuration is checked before the scene is even
/// loaded (through `cache` when given). `raypipe simulate` and every sweep point go
/// through here, so a sweep point's report is the stand-alone run's.
pub(crate) fn run_simulation(a: &SimulateArgs, cache: Option<&SceneCache>, show_progress: bool) -> Result<Simulated> {
    let cfg = chip::load_config(a.preset.as_deref(), a.config.as_deref(), &a.set)?;
    if let (Some(k), true) = (a.intersector, cfg.datapath != raypipe_hw::Datapath::F32) {
        bail!(
            "--intersector {}: datapath {} has its own triangle test (fixed-point watertight)",
            k.name(),
            cfg.datapath.name()
        );
    }
    if a.animate.is_some() {
        bail!("--animate runs on its own (raypipe simulate SCENE.aff --animate), not as a sweep point");
    }
    let structure = chip_structure(a, &cfg)?;
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::instanced::is_instanced(p)) {
        return super::simulate_instanced::run_instanced_simulation(a, path, &cfg, &structure, show_progress);
    }
    let scene = match cache {
        Some(c) => c.get(a, &structure)?,
        None => {
            let s = load_scene(a.scene.as_deref(), &structure, &a.camera)?;
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
    let views = match a.walk.cameras(&cam)? {
        Some(cams) => cams,
        // One view: repeated for its warm-up frames, then measured.
        None => vec![cam; a.measure.warmup_frames.saturating_add(1).min(crate::input::camera_path::MAX_FRAMES)],
    };
    let measure = measure_of(a);
    if measure.warmup_frames >= views.len() {
        bail!("--warmup-frames {}: the walkthrough has only {} frames", measure.warmup_frames, views.len());
    }
    let start = Instant::now();
    let shadow_caster = opts.algo == Algorithm::Shadow;
    let setup = FrameSetup { intersector: kind, shader, shadow_caster, sampler: opts.sampler(), show_progress };
    let mut frames = chip::simulate_frames(&ChipScene::Flat(view), &views, &measure, &cfg, &setup)?;
    let seconds = start.elapsed().as_secs_f64();
    for (f, cam) in frames.iter_mut().zip(&views) {
        f.report.run = run_identity(a, view.bytes(), &structure_summary(&view), &opts, &cfg, kind, cam);
    }
    let report = frames.last().map(|f| f.report.clone()).ok_or_else(|| anyhow::anyhow!("no frame simulated"))?;
    Ok(Simulated {
        frames,
        report,
        scene: scene.name.clone(),
        structure: format!("{}, {}", structure_summary(&view), structure_origin(a, &cfg, &scene)),
        triangles: view.triangle_count() as u64,
        seconds,
    })
}

/// What `a` measures: warm-up, region of interest, intervals, waveforms and trace.
pub(crate) fn measure_of(a: &SimulateArgs) -> Measure {
    Measure {
        warmup_frames: a.measure.warmup_frames,
        roi: a.measure.roi,
        interval: a.measure.interval,
        vcd: a.measure.vcd.clone().map(|path| chip::VcdSpec {
            path,
            window: a.measure.vcd_window,
            units: a.measure.vcd_units.clone(),
        }),
        trace: a.measure.trace.clone(),
        trace_window: a.measure.trace_window,
        memory_trace: a.measure.memory_trace.clone(),
    }
}

/// The run's identity in its report: the scene (and a hash of its bytes), structure,
/// algorithm, triangle test and camera.
pub(crate) fn run_identity(
    a: &SimulateArgs,
    bytes: &[u8],
    structure: &str,
    opts: &RenderOptions,
    cfg: &raypipe_hw::HwConfig,
    kind: IntersectorKind,
    cam: &raypipe_core::image::CameraRecord,
) -> raypipe_hw::observe::report::RunIdentity {
    raypipe_hw::observe::report::RunIdentity {
        scene: a.scene.as_ref().map_or("built-in Cornell box".to_string(), |p| p.display().to_string()),
        scene_hash: format!("{:016x}", raypipe_hw::observe::report::fnv1a64(bytes)),
        structure: structure.to_string(),
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
    }
}

/// The structure arguments with the chip's own structure as the default (used unless the
/// command line names one).
pub(crate) fn chip_structure(a: &SimulateArgs, cfg: &raypipe_hw::HwConfig) -> Result<StructureArgs> {
    let mut structure = a.structure.clone();
    structure.default_accel = <Accel as clap::ValueEnum>::from_str(&cfg.structure, true)
        .map_err(|_| anyhow::anyhow!("the chip's structure {:?} is not one raypipe builds", cfg.structure))?;
    Ok(structure)
}
