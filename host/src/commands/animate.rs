//! `raypipe animate`: a BART scene (Lext, Assarsson & Möller 2001) rendered frame by
//! frame, in order, at the scene's resolution, as the benchmark's rules ask: every
//! frame's update (the moved meshes' structures and the top level) and render timed
//! apart, the frames written as PNG (and, with an installed ffmpeg, as a video).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use clap::Args;

use super::args::{AlgoArgs, DisplayArgs, RunArgs, StructureArgs};
use crate::build::dynamic::{DynamicImages, DynamicState, Update};
use crate::input::aff::{load_aff, AffScene};
use crate::output;
use crate::render::instanced::frame::{check_algorithm, render_instanced};
use crate::render::tracer::IntersectorKind;
use crate::render::RenderOptions;
use crate::study::animation_report::{AnimationReport, FrameTimes};

/// `raypipe animate`.
#[derive(Args, Debug)]
pub struct AnimateArgs {
    /// The scene's entry AFF file (e.g. kitchen/aff/kitchen.aff).
    pub scene: PathBuf,
    /// The frames to render, `A..B` (B excluded) or one frame `A`; default: all of them.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    /// How moved meshes' structures follow them: refit, rebuild (Morton LBVH), full
    /// (binned SAH), auto (refit until the SAH cost grows past --auto-threshold, then
    /// rebuild) or parker (no structure for the moving triangles).
    #[arg(long, value_enum, default_value_t = Update::Auto)]
    pub update: Update,
    /// auto: rebuild once a refitted tree's SAH cost exceeds this many times its cost
    /// when last built.
    #[arg(long, value_name = "RATIO", default_value_t = 1.5)]
    pub auto_threshold: f64,
    /// Folder for the frames (frame-0000.png, …); created if missing.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Also encode the frames as this video with ffmpeg, if one is installed (skipped
    /// with a note if not).
    #[arg(long, value_name = "FILE")]
    pub video: Option<PathBuf>,
    /// Write every frame's times as CSV.
    #[arg(long, value_name = "FILE")]
    pub times: Option<PathBuf>,
    /// Render at this size instead of the scene's (not BART's rules; for quick looks).
    #[arg(long, value_name = "WxH", value_parser = super::args::parse_size)]
    pub size: Option<(u32, u32)>,
    #[command(flatten)]
    pub algo: AlgoArgs,
    #[command(flatten)]
    pub display: DisplayArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
}

/// The frame range `A..B` or `A` of `n` frames.
fn frame_range(spec: Option<&str>, n: u32) -> Result<std::ops::Range<u32>> {
    let Some(s) = spec else { return Ok(0..n) };
    let bad = || anyhow!("--frames {s}: expected A..B or A, frames 0..{n}");
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (a.trim().parse::<u32>().map_err(|_| bad())?, b.trim().parse::<u32>().map_err(|_| bad())?),
        None => {
            let a = s.trim().parse::<u32>().map_err(|_| bad())?;
            (a, a.saturating_add(1))
        }
    };
    if a >= b || b > n {
        bail!("--frames {s}: the scene has frames 0..{n}");
    }
    Ok(a..b)
}

/// Posts frame `k`'s transforms and vertices.
fn post_frame(aff: &AffScene, state: &mut DynamicState, t: f64) -> Result<()> {
    for i in 0..aff.scene.instances.len() {
        if aff.instance_moves(i) {
            state.set_transform(i as u32, aff.instance_transform(i, t))?;
        }
    }
    for (bottom, verts) in aff.deformed(t) {
        state.set_vertices(bottom, &verts)?;
    }
    Ok(())
}

pub(crate) fn cmd_animate(a: AnimateArgs) -> Result<()> {
    a.run.check()?;
    if !(a.auto_threshold.is_finite() && a.auto_threshold >= 1.0) {
        bail!("--auto-threshold {} must be a ratio of at least 1", a.auto_threshold);
    }
    let loading = Instant::now();
    let aff = load_aff(&a.scene)?;
    crate::output::warnings::warnings(&aff.scene.name, &aff.scene.warnings);
    let range = frame_range(a.frames.as_deref(), aff.frame_count())?;
    let mut ropts = RenderOptions { threads: a.run.threads, ..Default::default() };
    a.algo.apply(&mut ropts)?;
    check_algorithm(&ropts)?;
    let mut opts = a.structure.options();
    opts.camera = aff.scene.camera;
    let images = DynamicImages::build(&aff.scene, &aff.deforming, &opts, a.update)?;
    let views = images.views()?;
    let mut state = DynamicState::new(&aff.scene, &views, &aff.deforming, a.update, a.auto_threshold)?;
    let load_secs = loading.elapsed().as_secs_f64();
    ropts.intersector = IntersectorKind::resolve(a.run.intersector, &views.bottoms[0]);
    std::fs::create_dir_all(&a.output).map_err(|e| anyhow!("{}: cannot create: {e}", a.output.display()))?;
    let display = a.display.choice(ropts.algo);
    let bar = output::progress::bar(range.len() as u64, "frames", true);
    let mut report = AnimationReport::new(&aff, &a, load_secs);
    let pool = crate::render::thread_pool(a.run.threads)?;
    for k in range.clone() {
        let t = aff.time(k);
        let update = Instant::now();
        post_frame(&aff, &mut state, t)?;
        let stats = state.commit(&views);
        let frame = state.frame(&views)?;
        let update_secs = update.elapsed().as_secs_f64();
        let mut camera = aff.camera(t);
        if let Some((w, h)) = a.size {
            (camera.width, camera.height) = (w, h);
        }
        let render = Instant::now();
        let (image, rays) = pool.install(|| render_instanced(&frame, &camera, &ropts))?;
        let render_secs = render.elapsed().as_secs_f64();
        output::write_frame(&frame_file(&a.output, k), &image, &display)?;
        report.add(FrameTimes { frame: k, time: t, update: stats, update_secs, render_secs, rays: rays.total() });
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let Some(path) = &a.times {
        output::write_bytes(path, report.csv().as_bytes())?;
    }
    report.print();
    if let Some(video) = &a.video {
        encode_video(&a.output, range.start, video)?;
    }
    Ok(())
}

/// Frame `k`'s file in `dir`.
pub fn frame_file(dir: &Path, k: u32) -> PathBuf {
    dir.join(format!("frame-{k:04}.png"))
}

/// The frames as a video with an installed ffmpeg (25 frames per second, H.264 where it
/// has it); a note and no video when there is none.
fn encode_video(dir: &Path, first: u32, video: &Path) -> Result<()> {
    let found = std::process::Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success());
    if !found {
        println!("video    skipped: no ffmpeg on PATH (the frames are in {})", dir.display());
        return Ok(());
    }
    let tmp = video.with_extension(format!("partial.{}", video.extension().and_then(|e| e.to_str()).unwrap_or("mp4")));
    let status = std::process::Command::new("ffmpeg")
        .args(["-y", "-loglevel", "error", "-framerate", "25", "-start_number", &first.to_string(), "-i"])
        .arg(dir.join("frame-%04d.png"))
        .args(["-pix_fmt", "yuv420p"])
        .arg(&tmp)
        .status()
        .map_err(|e| anyhow!("ffmpeg: {e}"))?;
    if !status.success() {
        let _ = std::fs::remove_file(&tmp);
        bail!("{}: ffmpeg failed ({status})", video.display());
    }
    std::fs::rename(&tmp, video).map_err(|e| anyhow!("{}: cannot write: {e}", video.display()))?;
    println!("video    {}", video.display());
    Ok(())
}
