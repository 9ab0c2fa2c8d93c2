//! `raypipe bench`: timed runs of the host renderer.

use crate::build::grid::GridResolution;
use crate::hw::frame_setup::FrameSetup;
use raypipe_core::SceneView;
use raypipe_hw::HwConfig;

use crate::hw::chip;
use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;
use crate::render::{Algorithm, RenderOptions};
use crate::scene::{self, Accel, BuildOptions};
use crate::study::bench::{self, median};
use anyhow::{anyhow, bail, Result};
use raypipe_core::image::CameraRecord;
use std::path::PathBuf;
use std::time::Instant;

use super::{camera_for, structure_summary};

use super::args::parse_size;
use super::args::AlgoArgs;
use super::args::CameraArgs;
use crate::scene::TriangleLayout;
use clap::Args;

/// `raypipe bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// OBJ files or scene images to measure besides the built-in Cornell box.
    pub scenes: Vec<PathBuf>,
    /// Structures to build and measure (for OBJ scenes; an image has its own).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8])]
    pub accel: Vec<Accel>,
    /// Image size of the primary-ray frame.
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "1024x1024")]
    pub size: (u32, u32),
    /// Packet sizes to measure (1 = single rays).
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [PacketSize::Single, PacketSize::P16])]
    pub packet: Vec<PacketSize>,
    /// Camera file for every scene's view (default: each scene's own camera).
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
    /// Timed runs per figure (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Threads for the all-threads figure (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Leave out the built-in Cornell box.
    #[arg(long)]
    pub no_default: bool,
    /// Grid cells along the shortest axis (default: derived from the triangle count).
    #[arg(long, value_name = "N")]
    pub grid_min_dim: Option<u32>,
    /// Triangle layout: indexed vertices, or also Wald's 48-byte precomputed triangles, or
    /// also leaf blocks of four triangles (bvh4, bvh8; fastest for single rays).
    #[arg(long, value_enum, default_value_t = TriangleLayout::Indexed)]
    pub triangles: TriangleLayout,
    /// Ray–triangle intersection test (default: wald for an image with Wald triangles,
    /// watertight otherwise).
    #[arg(long, value_enum)]
    pub intersector: Option<IntersectorKind>,
    /// Also run the hardware model with this preset (saarcor, minimal) on each frame and
    /// report its wall time against the host's fastest single-thread frame.
    #[arg(long, value_name = "PRESET")]
    pub simulate: Option<String>,
    /// Also time a whole frame of this algorithm: every ray it traces (shadow, secondary,
    /// path rays) per second.
    #[command(flatten)]
    pub algo: AlgoArgs,
    #[command(flatten)]
    pub cache: super::args::CacheArgs,
}

pub(crate) fn cmd_bench(a: BenchArgs) -> Result<()> {
    if a.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let (bricked, flat): (Vec<&PathBuf>, Vec<&PathBuf>) =
        a.scenes.iter().partition(|p| crate::input::bricked::is_bricked(p));
    for path in &bricked {
        super::bricked_study::bench(path, a.size, &a.packet, a.runs, a.threads, &a.cache)?;
    }
    // Bricked scenes alone: the built-in default is measured only when asked for
    // alongside flat scenes.
    if !bricked.is_empty() && flat.is_empty() {
        return Ok(());
    }
    let mut targets: Vec<Option<PathBuf>> = Vec::new();
    if !a.no_default {
        targets.push(None);
    }
    targets.extend(flat.into_iter().cloned().map(Some));
    if targets.is_empty() {
        bail!("nothing to measure: --no-default without scenes");
    }
    let kernel = a.intersector.map_or("default", IntersectorKind::name);
    let chip = match &a.simulate {
        Some(preset) => Some(chip::load_config(Some(preset), None, &[])?),
        None => None,
    };
    println!(
        "primary rays {}x{}, trace only (eye ray, traversal, {kernel} intersection), median of {} runs",
        a.size.0, a.size.1, a.runs
    );
    println!(
        "{:<24} {:>8} {:<30} {:>8} {:>8} {:<7} {:>10} {:>10} {:>8} {:>6}",
        "scene", "tris", "structure", "build s", "B/tri", "packet", "Mrays/s 1t", "Mrays/s", "threads", "SIMD"
    );
    for t in targets {
        let source = scene::load_source(t.as_deref())?;
        let name = t.as_ref().map_or("built-in Cornell box".to_string(), |p| {
            p.file_name().map_or(p.display().to_string(), |f| f.to_string_lossy().into_owned())
        });
        let accels: Vec<Option<Accel>> = match source {
            scene::Source::Image(_) => vec![None],
            scene::Source::Mesh { .. } => a.accel.iter().copied().map(Some).collect(),
        };
        for accel in accels {
            bench_structure(&a, chip.as_ref(), &source, &name, accel)?;
        }
    }
    Ok(())
}

/// One scene with one structure (`accel`; `None`: the image's own): its build, then a
/// row per packet size, the algorithm's rays if one is asked for, and the simulator.
fn bench_structure(
    a: &BenchArgs,
    chip: Option<&HwConfig>,
    source: &scene::Source,
    name: &str,
    accel: Option<Accel>,
) -> Result<()> {
    let opts = BuildOptions {
        accel: accel.unwrap_or_default(),
        grid: match a.grid_min_dim {
            Some(n) => GridResolution::MinDim(n),
            None => GridResolution::default(),
        },
        triangles: a.triangles,
        ..Default::default()
    };
    // Structure build time: median of up to three builds (one for large scenes), on
    // the threads the all-threads figure uses.
    let mut builds = Vec::new();
    let mut built = None;
    for _ in 0..3 {
        let s = crate::render::in_pool(a.threads, || source.build(&opts))??;
        let big = s.view()?.triangle_count() > 20_000;
        builds.push(s.report.as_ref().map_or(0.0, |r| r.grid_seconds));
        built = Some(s);
        if big {
            break;
        }
    }
    let scene = built.ok_or_else(|| anyhow!("no scene"))?;
    let view = scene.view()?;
    let cam_args = CameraArgs { camera: a.camera.clone(), ..Default::default() };
    let base = camera_for(&view, &cam_args)?;
    let cam = CameraRecord { width: a.size.0, height: a.size.1, ..base };
    let bytes_per_tri = scene.report.as_ref().map_or(view.bytes().len(), |r| r.structure_bytes) as f64
        / view.triangle_count().max(1) as f64;
    let kind = IntersectorKind::resolve(a.intersector, &view);
    let mut best_single = 0.0f64;
    for &packet in &a.packet {
        let r = bench::primary_rays(&view, &cam, kind, packet, a.runs, a.threads)?;
        best_single = best_single.max(r.mrays_single);
        let simd = if packet == PacketSize::Single {
            "-".to_string()
        } else if !crate::render::tracer::has_packet_kernel(&view) {
            // Traced ray by ray: no lock-step, no SIMD efficiency to report.
            "by ray".to_string()
        } else {
            format!("{:.0}%", 100.0 * r.simd_efficiency)
        };
        println!(
            "{:<24} {:>8} {:<30} {:>8.3} {:>8.1} {:<7} {:>10.2} {:>10.2} {:>8} {:>6}",
            name,
            view.triangle_count(),
            structure_summary(&view),
            median(&builds),
            bytes_per_tri,
            packet.label(),
            r.mrays_single,
            r.mrays_all,
            r.threads,
            simd
        );
    }
    if a.algo.algo != Algorithm::Cast {
        bench_algorithm(a, &view, &cam, kind, name)?;
    }
    if let Some(cfg) = chip {
        bench_simulator(a, &view, &cam, kind, cfg, name, best_single)?;
    }
    Ok(())
}

/// The algorithm's rays of a whole frame: rays per pixel by kind and throughput.
fn bench_algorithm(
    a: &BenchArgs,
    view: &SceneView<'_>,
    cam: &CameraRecord,
    kind: IntersectorKind,
    name: &str,
) -> Result<()> {
    let mut opts = RenderOptions { intersector: kind, packet: PacketSize::auto_for(view), ..Default::default() };
    a.algo.apply(&mut opts)?;
    let r = bench::algorithm_rays(view, cam, &opts, a.runs, a.threads)?;
    let px = cam.width as f64 * cam.height as f64;
    let kinds: Vec<String> = raypipe_core::shade::ray_record::RayKind::ALL
        .iter()
        .filter(|k| r.rays[**k as usize] > 0)
        .map(|k| format!("{} {:.2}", k.name(), r.rays[*k as usize] as f64 / px))
        .collect();
    println!(
        "{:<24} {:?}: rays per pixel {}; all rays {:.2} Mrays/s 1 thread, {:.2} Mrays/s {} threads",
        name,
        a.algo.algo,
        kinds.join(", "),
        r.mrays_single,
        r.mrays_all,
        r.threads
    );
    Ok(())
}

/// The chip model on the same frame: its cycles and frame rate, and how much slower the
/// simulator runs than the host's fastest single-thread frame (`best_single` Mrays/s).
fn bench_simulator(
    a: &BenchArgs,
    view: &SceneView<'_>,
    cam: &CameraRecord,
    kind: IntersectorKind,
    cfg: &HwConfig,
    name: &str,
    best_single: f64,
) -> Result<()> {
    let preset = a.simulate.as_deref().unwrap_or_default();
    // The simulator is deterministic; its wall time is the median of up to 3 runs.
    let mut walls = Vec::new();
    let mut last = None;
    for _ in 0..a.runs.min(3) {
        let start = Instant::now();
        let measure = chip::Measure::default();
        let setup = FrameSetup { intersector: kind, ..Default::default() };
        let mut out = chip::simulate_frames(
            &raypipe_hw::chip::scene::ChipScene::Flat(*view),
            std::slice::from_ref(cam),
            &measure,
            cfg,
            &setup,
        )?;
        walls.push(start.elapsed().as_secs_f64());
        last = out.pop().map(|f| f.report);
    }
    let report = last.ok_or_else(|| anyhow!("no simulation"))?;
    let wall = median(&walls);
    let host = (a.size.0 as f64 * a.size.1 as f64) / (best_single * 1e6);
    println!(
        "{:<24} simulate --preset {preset}: {} cycles ({:.1} frames/s at {} MHz); simulator {:.2} s wall, {:.3} Mrays/s; host 1 thread {:.3} s: {:.1}x slower",
        name,
        report.cycles,
        report.frames_per_second,
        cfg.clock_mhz,
        wall,
        report.rays as f64 / wall / 1e6,
        host,
        wall / host
    );
    Ok(())
}
