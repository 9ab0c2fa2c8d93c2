//! `raypipe animate`: a BART scene (Lext, Assarsson & Möller 2001) rendered frame by
//! frame, in order, at the scene's resolution, as the benchmark's rules ask: every
//! frame's update (the moved meshes' structures and the top level) and render timed
//! apart, the frames written as PNG (and, with an installed ffmpeg, as a video).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use clap::Args;

use super::args::{AlgoArgs, DisplayArgs, RunArgs, StructureArgs};
use crate::build::dynamic::{BaseViews, CommitStats, DynamicImages, DynamicState, Update};
use crate::input::aff::{load_aff, AffScene};
use crate::output;
use crate::render::instanced::frame::{check_algorithm, render_instanced};
use crate::render::tracer::IntersectorKind;
use crate::render::RenderOptions;
use crate::study::animation_report::{AnimationReport, FrameTimes};

/// How the host updates moved meshes' structures each frame.
#[derive(Args, Debug, Clone)]
pub struct UpdateArgs {
    /// How moved meshes' structures follow them: refit, rebuild (Morton LBVH), full
    /// (binned SAH), auto (refit until the SAH cost grows past --auto-threshold, then
    /// rebuild), parker (no structure for the moving triangles) or reinhard (a
    /// hierarchical grid with wrap-around, triangles moved between its cells).
    #[arg(long, value_enum, default_value_t = Update::Auto)]
    pub update: Update,
    /// auto: rebuild once a refitted tree's SAH cost exceeds this many times its cost
    /// when last built.
    #[arg(long, value_name = "RATIO", default_value_t = 1.5)]
    pub auto_threshold: f64,
}

/// An animated scene ready to play: the AFF scene, its images built and validated once
/// (the bottoms' structures as `structure` says), and the state that moves them.
pub(crate) struct Animation {
    /// The scene and its tracks.
    pub aff: AffScene,
    /// The bottoms' images.
    pub images: DynamicImages,
    /// Seconds reading and building.
    pub load_secs: f64,
}

impl Animation {
    /// Reads the AFF scene at `path` and builds its images.
    pub fn open(path: &Path, structure: &StructureArgs, u: &UpdateArgs) -> Result<Animation> {
        if !(u.auto_threshold.is_finite() && u.auto_threshold >= 1.0) {
            bail!("--auto-threshold {} must be a ratio of at least 1", u.auto_threshold);
        }
        let loading = Instant::now();
        let aff = load_aff(path)?;
        crate::output::warnings::warnings(&aff.scene.name, &aff.scene.warnings);
        let mut opts = structure.options();
        opts.camera = aff.scene.camera;
        let images = DynamicImages::build(&aff.scene, &aff.deforming, &opts, u.update)?;
        Ok(Animation { aff, images, load_secs: loading.elapsed().as_secs_f64() })
    }

    /// The state that moves the scene's views (built once).
    pub fn state(&self, views: &BaseViews<'_>, u: &UpdateArgs) -> Result<DynamicState> {
        DynamicState::new(&self.aff.scene, views, &self.aff.deforming, u.update, u.auto_threshold)
    }

    /// Posts frame `k`'s changes and commits them: the update's statistics and seconds.
    pub fn update(&self, state: &mut DynamicState, views: &BaseViews<'_>, k: u32) -> Result<(CommitStats, f64)> {
        let start = Instant::now();
        post_frame(&self.aff, state, self.aff.time(k))?;
        let stats = state.commit(views);
        Ok((stats, start.elapsed().as_secs_f64()))
    }
}

/// `raypipe animate`.
#[derive(Args, Debug)]
pub struct AnimateArgs {
    /// The scene's entry AFF file (e.g. kitchen/aff/kitchen.aff).
    pub scene: PathBuf,
    /// The frames to render, `A..B` (B excluded) or one frame `A`; default: all of them.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<String>,
    #[command(flatten)]
    pub updates: UpdateArgs,
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

/// The frame range `A..B` or `A` of `n` frames, given with option `flag`.
pub(crate) fn frame_range(flag: &str, spec: Option<&str>, n: u32) -> Result<std::ops::Range<u32>> {
    let Some(s) = spec else { return Ok(0..n) };
    let bad = || anyhow!("{flag} {s}: expected A..B or A, frames 0..{n}");
    let (a, b) = match s.split_once("..") {
        Some((a, b)) => (a.trim().parse::<u32>().map_err(|_| bad())?, b.trim().parse::<u32>().map_err(|_| bad())?),
        None => {
            let a = s.trim().parse::<u32>().map_err(|_| bad())?;
            (a, a.saturating_add(1))
        }
    };
    if a >= b || b > n {
        bail!("{flag} {s}: the scene has frames 0..{n}");
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
    let anim = Animation::open(&a.scene, &a.structure, &a.updates)?;
    let aff = &anim.aff;
    let range = frame_range("--frames", a.frames.as_deref(), aff.frame_count())?;
    let mut ropts = RenderOptions { threads: a.run.threads, ..Default::default() };
    a.algo.apply(&mut ropts)?;
    check_algorithm(&ropts)?;
    let views = anim.images.views()?;
    let mut state = anim.state(&views, &a.updates)?;
    ropts.intersector = IntersectorKind::resolve(a.run.intersector, &views.bottoms[0]);
    std::fs::create_dir_all(&a.output).map_err(|e| anyhow!("{}: cannot create: {e}", a.output.display()))?;
    let display = a.display.choice(ropts.algo);
    let bar = output::progress::bar(range.len() as u64, "frames", true);
    let mut report = AnimationReport::new(aff, &a, anim.load_secs);
    let pool = crate::render::thread_pool(a.run.threads)?;
    for k in range.clone() {
        let t = aff.time(k);
        let update = Instant::now();
        let (stats, _) = anim.update(&mut state, &views, k)?;
        let levels = state.levels();
        let frame = state.frame(&views, &levels)?;
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
