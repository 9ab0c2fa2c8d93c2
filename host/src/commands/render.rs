//! `raypipe render`: a PNG of the scene on the host renderer.

use crate::output;
use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;
use crate::render::{self, RenderOptions};
use anyhow::Result;
use std::time::Instant;

use super::{camera_for, check_image_path, lights_summary, load_scene, warn};

use super::args::AlgoArgs;
use super::args::CameraArgs;
use super::args::DisplayArgs;
use super::args::RunArgs;
use super::args::StructureArgs;
use super::args::WalkArgs;
use clap::Args;
use std::path::PathBuf;

/// `raypipe render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Rays per packet: 1 (single rays), 4 (2×2), 16 (4×4) or 64 (8×8); the image is the
    /// same. Default: the faster one for the structure.
    #[arg(long, value_enum)]
    pub packet: Option<PacketSize>,
    #[command(flatten)]
    pub algo: AlgoArgs,
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    /// Output image: .png (8-bit sRGB through --exposure and --tonemap), .exr (OpenEXR)
    /// or .pfm, both linear radiance.
    #[arg(short, long, value_name = "IMAGE", default_value = "raypipe.png")]
    pub output: PathBuf,
    /// Also write every ray the frame traces into this folder, by query, in tile order:
    /// eye.npy and secondary.npy (closest hit), shadow.npy (any hit), each an (N, 8)
    /// float32 array that `raypipe trace --rays` reads (bench/embree_harness.py times
    /// Embree on them).
    #[arg(long, value_name = "DIR")]
    pub ray_log: Option<PathBuf>,
    #[command(flatten)]
    pub display: DisplayArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub walk: WalkArgs,
    #[command(flatten)]
    pub cache: super::args::CacheArgs,
    #[command(flatten)]
    pub mpi: MpiArgs,
}

/// Rendering across MPI ranks.
#[derive(Args, Debug, Clone)]
pub struct MpiArgs {
    /// Render across the ranks of an MPI job (`mpirun -n N raypipe render … --mpi`): rank 0
    /// hands out tiles and writes the image, the others render. Needs a raypipe built
    /// with the `mpi` feature.
    #[arg(long)]
    pub mpi: bool,
    /// Side of the tiles the master hands out, in pixels (at most 512).
    #[arg(long, value_name = "PIXELS", default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=512))]
    pub mpi_tile: u32,
    /// Seconds a rank that owes a message (a worker its tile, a model server its brick)
    /// may stay silent before the run ends with an error naming it.
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    pub mpi_timeout: f64,
    /// Where a bricked scene's bricks come from: every rank reads the file from shared
    /// storage (replicated), or rank 0 serves them over MPI to the workers' caches
    /// (served).
    #[arg(long, value_enum, value_name = "HOW", default_value = "replicated")]
    pub mpi_data: MpiData,
    /// Write what every tile cost, and the bricks it needed, to this file (JSON lines),
    /// for `raypipe cluster` to replay on a modelled cluster.
    #[arg(long, value_name = "FILE")]
    pub mpi_record: Option<std::path::PathBuf>,
}

/// Where the ranks of a distributed render read the scene.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MpiData {
    /// Every rank reads the scene from shared storage.
    Replicated,
    /// Rank 0 holds a bricked scene and sends bricks on request.
    Served,
}

/// What a render needs once its inputs are read: the scene, the camera, the options and
/// how frames are displayed.
pub(crate) struct Prepared {
    pub scene: crate::scene::Scene,
    pub camera: raypipe_core::image::CameraRecord,
    pub opts: RenderOptions,
    pub display: crate::output::tone_map::DisplayChoice,
    pub load_secs: f64,
}

/// Loads the scene of `a` and settles the camera and the options.
pub(crate) fn prepare(a: &RenderArgs) -> Result<Prepared> {
    let loading = Instant::now();
    let scene = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
    let load_secs = loading.elapsed().as_secs_f64();
    let view = scene.view()?;
    let camera = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let packet = a.packet.unwrap_or_else(|| PacketSize::auto_for(&view));
    let mut opts =
        RenderOptions { threads: a.run.threads, intersector: kind, progress: true, packet, ..Default::default() };
    a.algo.apply(&mut opts)?;
    let display = a.display.choice(opts.algo);
    Ok(Prepared { scene, camera, opts, display, load_secs })
}

pub(crate) fn cmd_render(a: RenderArgs) -> Result<()> {
    a.run.check()?;
    check_image_path(&a.output)?;
    if let Some(dir) = &a.ray_log {
        let scene = a.scene.as_deref();
        let not = [
            (a.mpi.mpi, "--mpi"),
            (a.walk.is_walk(), "a walkthrough"),
            (scene.is_some_and(crate::input::bricked::is_bricked), "a bricked scene"),
            (scene.is_some_and(crate::input::instanced::is_instanced), "an instanced scene"),
        ];
        if let Some((_, what)) = not.iter().find(|(on, _)| *on) {
            anyhow::bail!("--ray-log {}: logs one frame of a flat scene on this machine, not {what}", dir.display());
        }
    }
    if a.mpi.mpi {
        return crate::distributed::cmd_render_mpi(&a);
    }
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::bricked::is_bricked(p)) {
        return super::render_bricked::cmd_render_bricked(&a, path);
    }
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::instanced::is_instanced(p)) {
        return super::render_instanced::cmd_render_instanced(&a, path);
    }
    let Prepared { scene, camera: cam, mut opts, display, load_secs } = prepare(&a)?;
    opts.log_rays = a.ray_log.is_some();
    warn(&scene);
    let view = scene.view()?;
    if let Some(cams) = a.walk.cameras(&cam)? {
        return walkthrough(&a, &scene, &view, &cams, &opts, &display);
    }
    let start = Instant::now();
    let (frame, rays, first_tile, logs) = render::render_logged(&view, &cam, &opts)?;
    let secs = start.elapsed().as_secs_f64();
    // The image and the log together, or neither.
    let outputs = output::batch::Batch::begin();
    let auto = output::write_frame(&a.output, &frame, &display)?;
    let logged = match &a.ray_log {
        Some(dir) => Some(render::ray_log::write_ray_log(dir, &logs)?),
        None => None,
    };
    outputs.commit()?;
    // Building the structure is part of loading an OBJ; the report says how long it took.
    let build_secs = scene.report.as_ref().map_or(0.0, |r| r.grid_seconds);
    println!(
        "rendered {} ({} triangles) at {}x{}, {} sample{} per pixel -> {}",
        scene.name,
        view.triangle_count(),
        frame.width,
        frame.height,
        opts.samples,
        if opts.samples == 1 { "" } else { "s" },
        a.output.display()
    );
    println!("lights   {}", lights_summary(&scene)?);
    if opts.algo != crate::render::Algorithm::Path && view.area_light_count() > 0 {
        println!(
            "note     {} lights the scene with the point light standing in for its emitters; --algo path \
             lights it with the emitters themselves, so the brightness differs",
            format!("{:?}", opts.algo).to_lowercase()
        );
    }
    if let Some(auto) = auto {
        println!("exposure {}", auto.describe());
    }
    println!(
        "time     load {:.3} s, build {:.3} s, render {:.3} s; first pixel after {:.3} s (open, validate, first tile)",
        (load_secs - build_secs).max(0.0),
        build_secs,
        secs,
        load_secs + first_tile
    );
    println!(
        "rays     {} traced ({} eye, {} secondary): {:.2} Mrays/s",
        rays.total(),
        rays.primary,
        rays.secondary,
        rays.total() as f64 / secs.max(1e-9) / 1e6
    );
    if let (Some(dir), Some([eye, secondary, shadow])) = (&a.ray_log, logged) {
        println!("ray log  {eye} eye, {secondary} secondary, {shadow} shadow rays -> {}", dir.display());
    }
    Ok(())
}

/// A walkthrough on the host: every frame rendered and written, its time and frame rate
/// printed, then the whole path's.
fn walkthrough(
    a: &RenderArgs,
    scene: &crate::scene::Scene,
    view: &raypipe_core::SceneView<'_>,
    cams: &[raypipe_core::image::CameraRecord],
    opts: &RenderOptions,
    display: &crate::output::tone_map::DisplayChoice,
) -> Result<()> {
    println!("walkthrough of {} ({} triangles): {} frames", scene.name, view.triangle_count(), cams.len());
    println!("lights   {}", lights_summary(scene)?);
    println!("frame      seconds   frames/s   Mrays/s  image");
    let mut times = Vec::with_capacity(cams.len());
    let mut all_rays = 0u64;
    let mut display = *display;
    for (k, cam) in cams.iter().enumerate() {
        let start = Instant::now();
        let (frame, rays) = render::render_counted(view, cam, opts)?;
        let secs = start.elapsed().as_secs_f64().max(1e-9);
        let path = output::frame_path(&a.output, k);
        if k == 0 {
            let auto;
            (display, auto) = display.fixed_by(&frame.radiance);
            if let Some(auto) = auto.filter(|_| output::ImageFormat::of(&path).ok() == Some(output::ImageFormat::Png)) {
                println!("exposure {} — every frame", auto.describe());
            }
        }
        output::write_frame(&path, &frame, &display)?;
        println!(
            "{k:>5}  {secs:>10.4}  {:>9.2}  {:>8.2}  {}",
            1.0 / secs,
            rays.total() as f64 / secs / 1e6,
            path.display()
        );
        times.push(secs);
        all_rays += rays.total();
    }
    let total: f64 = times.iter().sum();
    times.sort_by(f64::total_cmp);
    println!(
        "path     {} frames in {:.3} s: {:.2} frames/s on average, median frame {:.4} s, {:.2} Mrays/s",
        cams.len(),
        total,
        cams.len() as f64 / total,
        times[times.len() / 2],
        all_rays as f64 / total / 1e6
    );
    Ok(())
}
