//! `raypipe stream`: a frame on Purcell's GPU seen as a stream processor.

use crate::hw::frame_setup::FrameSetup;
use crate::output;
use crate::render::tracer::IntersectorKind;
use crate::render::{self, Algorithm, RenderOptions};
use crate::scene::Accel;
use anyhow::{anyhow, bail, Result};
use raypipe_hw::stream::{CostModel, StreamConfig};
use std::time::Instant;

use super::{camera_for, check_image_path, load_scene, structure_summary, warn};

use super::args::AlgoArgs;
use super::args::CameraArgs;
use super::args::DisplayArgs;
use super::args::StructureArgs;
use clap::Args;
use std::path::PathBuf;

/// `raypipe stream`.
#[derive(Args, Debug)]
pub struct StreamArgs {
    /// An OBJ file or a scene image with a uniform grid; the built-in Cornell box when
    /// omitted.
    pub scene: Option<PathBuf>,
    /// Architecture: multipass (stencil-routed passes) or branching (fused kernels).
    #[arg(long, default_value = "multipass")]
    pub arch: raypipe_hw::stream::Architecture,
    /// Multipass oracle: delany[:FRACTION] (intersect once that fraction of active rays
    /// waits; 0.2), naive (alternate), optimal (clairvoyant).
    #[arg(long, default_value = "delany")]
    pub oracle: raypipe_hw::stream::Oracle,
    /// Multipass loop unrolling: kernel iterations per pass, "traverse=N,intersect=M".
    #[arg(long, value_name = "traverse=N,intersect=M", default_value = "traverse=1,intersect=1")]
    pub unroll: raypipe_hw::stream::Unroll,
    /// Suppress the memory references of unrolled iterations after a ray has finished.
    #[arg(long)]
    pub suppress: bool,
    /// Branching: fragments in lock step (1: each fragment branches alone).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub simd: u32,
    /// Texture cache "SIZE,WAYS,LINE" (e.g. 64K,1,48, the default) or "off".
    #[arg(long, value_name = "SIZE,WAYS,LINE", default_value = "64K,1,48")]
    pub cache: raypipe_hw::stream::TextureCacheConfig,
    /// State-texture reads bypass the texture cache (default: they go through it, as
    /// every texture read does on Purcell's machine).
    #[arg(long)]
    pub uncached_state: bool,
    /// Words a fragment program writes per pass (Purcell §2.2: two RGBA outputs, 8).
    #[arg(long, default_value_t = 8, value_name = "WORDS")]
    pub output_words: u32,
    /// How instructions are counted: vec4 (4-wide fragment-program instructions, as the
    /// paper counts) or scalar (one per scalar operation).
    #[arg(long, default_value = "vec4")]
    pub isa: raypipe_hw::stream::Isa,
    /// Kernel cost table (TOML) over raypipe's counted one: [kernel] instructions, r, w,
    /// b_instructions, br, bw, m.
    #[arg(long, value_name = "FILE.toml")]
    pub costs: Option<PathBuf>,
    /// Machine rates "INSTR_PER_S,BYTES_PER_S" (default: Radeon 9700 Pro, 2.6e9,19.84e9).
    #[arg(long, value_name = "I,B")]
    pub machine: Option<raypipe_hw::stream::Machine>,
    /// The algorithm and its settings (here --samples defaults to 1 for every algorithm:
    /// Purcell's frames trace one eye ray per pixel).
    #[command(flatten)]
    pub algo: AlgoArgs,
    /// Ray–triangle test (default: the one the image's triangle layout is for).
    #[arg(long, value_enum)]
    pub intersector: Option<IntersectorKind>,
    /// Output image: .png (8-bit sRGB through --exposure and --tonemap), .exr (OpenEXR)
    /// or .pfm, both linear radiance.
    #[arg(short, long, value_name = "IMAGE", default_value = "raypipe-stream.png")]
    pub output: PathBuf,
    #[command(flatten)]
    pub display: DisplayArgs,
    /// The report as JSON.
    #[arg(long, value_name = "JSON", default_value = "raypipe-stream.json")]
    pub report: PathBuf,
    /// Directory for the charts (Figures 7–9 and active rays per pass, SVG and PNG).
    #[arg(long, value_name = "DIR", default_value = "raypipe-stream-charts")]
    pub charts: PathBuf,
    /// Write no charts.
    #[arg(long)]
    pub no_charts: bool,
    /// Skip the ray-casting frame that Table 3's ratios need (other algorithms).
    #[arg(long)]
    pub no_table3: bool,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
}

pub(crate) fn cmd_stream(a: StreamArgs) -> Result<()> {
    check_image_path(&a.output)?;
    let display = a.display.choice(a.algo.algo);
    output::check_writable(&a.output)?;
    output::check_writable(&a.report)?;
    let (cfg, costs) = machine_of(&a)?;
    let algo = AlgoArgs { samples: Some(a.algo.samples.unwrap_or(1)), ..a.algo.clone() };
    let mut opts = RenderOptions::default();
    algo.apply(&mut opts)?;
    // Purcell's machine traverses a uniform grid unless told otherwise.
    let structure = StructureArgs { default_accel: Accel::Grid, ..a.structure.clone() };
    let scene = load_scene(a.scene.as_deref(), &structure, &a.camera)?;
    warn(&scene);
    let view = scene.view()?;
    if view.grid().is_none() {
        bail!(
            "{}: the image holds a {}; Purcell's stream machine walks a uniform grid (build with --accel grid)",
            scene.name,
            structure_summary(&view)
        );
    }
    // Purcell's screen: 1024 x 1024 unless the size is given.
    let camera = CameraArgs { size: a.camera.size.or(Some((1024, 1024))), ..a.camera.clone() };
    let cam = camera_for(&view, &camera)?;
    let kind = IntersectorKind::resolve(a.intersector, &view);
    let background = raypipe_core::Vec3::from(cam.background);
    let shader = opts.shader(background);
    let shadow_caster = opts.algo == Algorithm::Shadow;
    let start = Instant::now();
    let (frame, report) = crate::hw::stream::run_stream(
        &view,
        &cam,
        &cfg,
        &costs,
        &FrameSetup { intersector: kind, shader, shadow_caster, sampler: opts.sampler(), show_progress: true },
    )?;
    let secs = start.elapsed().as_secs_f64();
    // The same frame from the host renderer: the model must agree bit for bit.
    opts.intersector = kind;
    opts.packet = crate::render::packets::PacketSize::auto_for(&view);
    let host = render::render(&view, &cam, &opts)?;
    let same = host.pixels == frame.pixels;
    let cast = if opts.algo != Algorithm::Cast && !a.no_table3 {
        Some(
            crate::hw::stream::run_stream(
                &view,
                &cam,
                &cfg,
                &costs,
                &FrameSetup { intersector: kind, sampler: opts.sampler(), show_progress: true, ..Default::default() },
            )?
            .1,
        )
    } else {
        None
    };
    let outputs = output::batch::Batch::begin();
    let auto = output::write_frame(&a.output, &frame, &display)?;
    output::write_bytes(&a.report, report.to_json().as_bytes())?;
    outputs.commit()?;
    println!(
        "stream {} ({} triangles, {}), {}x{}, {} {}",
        scene.name,
        view.triangle_count(),
        structure_summary(&view),
        frame.width,
        frame.height,
        format!("{:?}", opts.algo).to_lowercase(),
        architecture_label(&cfg)
    );
    if let Some(auto) = auto {
        println!("exposure {}", auto.describe());
    }
    let label = format!("{} {}", scene.name, cfg.arch);
    print!("{}", crate::hw::stream::table2(&report, &label));
    print!("{}", crate::hw::stream::kernel_table(&report));
    print!("{}", crate::hw::stream::class_table(&report));
    print!("{}", crate::hw::stream::frame_lines(&report));
    if let Some(c) = &cast {
        print!("{}", crate::hw::stream::table3(&format!("{:?}", opts.algo).to_lowercase(), &report, c));
    }
    if !a.no_charts {
        let written = crate::hw::stream_charts::write_all(&a.charts, &report)?;
        println!("charts        {} files -> {}", written, a.charts.display());
    }
    println!(
        "image         {} raypipe render's -> {}; report -> {}",
        if same { "equals" } else { "DIFFERS FROM" },
        a.output.display(),
        a.report.display()
    );
    println!("wall time     {secs:.2} s for the frame");
    if !same {
        bail!("internal error: the stream machine's image differs from the host renderer's");
    }
    Ok(())
}

/// The machine the flags describe: its architecture and cache, and the kernels' costs
/// (Purcell's Table 1 unless a file gives others).
fn machine_of(a: &StreamArgs) -> Result<(StreamConfig, CostModel)> {
    let cfg = StreamConfig {
        arch: a.arch,
        oracle: a.oracle,
        unroll: a.unroll,
        suppress: a.suppress,
        simd: a.simd,
        cache: a.cache,
        cache_state: !a.uncached_state,
        output_words: a.output_words,
        machine: a.machine.unwrap_or_default(),
    };
    cfg.validate().map_err(|e| anyhow!("stream configuration: {e}"))?;
    let costs = match &a.costs {
        Some(p) => {
            let text = crate::input::read_file::read_text(p, crate::input::read_file::TEXT_LIMIT)?;
            CostModel::from_toml(&text, &p.display().to_string(), a.isa).map_err(|e| anyhow!("{}: {e}", p.display()))?
        }
        None => CostModel::counted(a.isa),
    };
    Ok((cfg, costs))
}

/// The architecture in a few words, for the summary's first line.
fn architecture_label(cfg: &StreamConfig) -> String {
    match cfg.arch {
        raypipe_hw::stream::Architecture::Multipass => format!(
            "multipass, oracle {}, unroll traverse={},intersect={}{}",
            cfg.oracle,
            cfg.unroll.traverse,
            cfg.unroll.intersect,
            if cfg.suppress { ", suppressed" } else { "" }
        ),
        raypipe_hw::stream::Architecture::Branching => format!("branching, simd {}", cfg.simd),
    }
}
