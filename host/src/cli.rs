//! The `raypipe` command line's arguments: clap parses into one options struct per
//! subcommand. What each subcommand does is in [`crate::commands`].
// The argument docs are `--help` text, written for a terminal: `[fixed]` and `<part>`
// there are TOML tables and placeholders, not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::{Args, Parser, Subcommand};
use raypipe_core::image::{CameraRecord, LightRecord};
use raypipe_core::pixel_filter::Filter;

use crate::build::bvh::BvhParams;
use crate::build::grid::{GridResolution, DEFAULT_CELLS_PER_TRIANGLE};
use crate::build::kdtree::KdParams;
use crate::input::camera_file::CameraSpec;
use crate::output::tone_map::{Display, ToneMap};
use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;
use crate::render::{self, Algorithm, RenderOptions};
use crate::scene::{Accel, BuildOptions, TriangleLayout};

/// raypipe: a ray tracing engine whose no_std kernels drive both this host renderer and
/// a cycle-level hardware model.
#[derive(Parser, Debug)]
#[command(name = "raypipe", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Compile an OBJ scene (with its MTL) into a scene image.
    Build(BuildArgs),
    /// Render a scene to a PNG (the built-in Cornell box when no scene is given).
    Render(RenderArgs),
    /// Print Purcell's scene statistics for a view: hits, nodes and triangles per ray.
    Stats(StatsArgs),
    /// Measure build time, image size and primary-ray throughput.
    Bench(BenchArgs),
    /// Trace a batch of rays from a NumPy .npy array and write the closest hits.
    Trace(TraceArgs),
    /// Write the primary rays of a view as a NumPy .npy array (N × 8 float32).
    Rays(RaysArgs),
    /// Run the cycle-level hardware model on a scene (the built-in Cornell box when none
    /// is given): image, summary and JSON report.
    Simulate(Box<SimulateArgs>),
    /// Compare the fixed-point datapath's hits with f32's (same triangle, distance between
    /// the hit points, nodes visited) on scenes, per format.
    FixedPoint(FixedPointArgs),
    /// Run Purcell's stream machine (a programmable GPU ray tracing in rendering passes,
    /// multipass or branching) on a scene: passes, instructions, memory words, texture
    /// cache, frame time; image, JSON report and charts.
    Stream(StreamArgs),
    /// Describe a scene: bounds, triangles, materials, lights, camera, structure and the
    /// image's sections.
    Info(InfoArgs),
    /// Run `simulate` over a grid of parameters (a TOML spec) on local cores, in shards
    /// for a cluster: one row per point (CSV and JSON lines), resumable; `sweep merge`
    /// joins shards.
    Sweep(SweepArgs),
    /// Plot a sweep's rows as SVG or PNG: a metric against a parameter (one line per value
    /// of --series), a heatmap over two parameters (--value), or stacked bars (--stack).
    Plot(PlotArgs),
    /// Work with JSON reports: `report diff A.json B.json` says what changed.
    Report(ReportArgs),
}

/// `raypipe report`.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// What to do with reports.
    #[command(subcommand)]
    pub command: ReportCommand,
}

/// `raypipe report …`.
#[derive(Subcommand, Debug)]
pub enum ReportCommand {
    /// What changed between two reports: the configuration keys, then every number with
    /// its ratio, largest effect first.
    Diff(ReportDiffArgs),
}

/// `raypipe report diff`.
#[derive(Args, Debug)]
pub struct ReportDiffArgs {
    /// The first report (the baseline).
    pub a: PathBuf,
    /// The second report.
    pub b: PathBuf,
    /// Show only the N largest changes (default: all).
    #[arg(long, value_name = "N")]
    pub top: Option<usize>,
}

/// `raypipe plot`.
#[derive(Args, Debug)]
pub struct PlotArgs {
    /// A sweep's rows (.jsonl, from `raypipe sweep` or `sweep merge`).
    #[arg(value_name = "SWEEP.jsonl")]
    pub rows: PathBuf,
    /// The plot: .svg, or .png (rendered from the SVG).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The parameter along the x axis.
    #[arg(long, value_name = "PARAM")]
    pub x: String,
    /// Line plot: the metric on the y axis (e.g. fps, bytes_per_ray.nodes,
    /// hit_rate.triangles); heatmap: the second parameter.
    #[arg(long, value_name = "NAME", required_unless_present = "stack")]
    pub y: Option<String>,
    /// Line plot: one line per value of this parameter.
    #[arg(long, value_name = "PARAM", conflicts_with_all = ["value", "stack"])]
    pub series: Option<String>,
    /// Heatmap: the metric coloured over the --x × --y grid.
    #[arg(long, value_name = "METRIC", conflicts_with = "stack")]
    pub value: Option<String>,
    /// Stacked bars: every metric PREFIX.<part> (e.g. stall.traversal, bytes_per_ray).
    #[arg(long, value_name = "PREFIX", conflicts_with = "y")]
    pub stack: Option<String>,
    /// Line plot: a logarithmic x axis (cache sizes, thread counts).
    #[arg(long)]
    pub log_x: bool,
    /// Only rows whose parameter KEY has VALUE (repeatable; `*` matches any run of
    /// characters, e.g. `scene=*bunny.obj`).
    #[arg(long = "where", value_name = "KEY=VALUE")]
    pub filters: Vec<String>,
    /// The title (default: what is plotted against what).
    #[arg(long)]
    pub title: Option<String>,
}

/// `raypipe sweep`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    /// Join shards' outputs.
    #[command(subcommand)]
    pub merge: Option<SweepCommand>,
    /// The spec: [fixed] parameters, a [grid] of lists (their cartesian product) and
    /// [[points]] (each crossed with the grid); keys are simulate flags or --set keys.
    #[arg(required = true, value_name = "SPEC.toml")]
    pub spec: Option<PathBuf>,
    /// Output prefix: PREFIX.jsonl and PREFIX.csv. Points already in PREFIX.jsonl are
    /// not run again (resume).
    #[arg(short, long, value_name = "PREFIX", default_value = "sweep")]
    pub output: PathBuf,
    /// Run only shard I of N (points whose number is I modulo N, I from 0): one task of a
    /// Slurm job array or of GNU parallel.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::study::sweep::Shard>,
    /// Points run at once (default: all cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Also write each point's full report, DIR/point-<index>.json (the stand-alone
    /// `simulate --report` file).
    #[arg(long, value_name = "DIR")]
    pub reports: Option<PathBuf>,
    /// Run every point again, ignoring rows already in PREFIX.jsonl.
    #[arg(long)]
    pub restart: bool,
}

/// `raypipe sweep merge`.
#[derive(Subcommand, Debug)]
pub enum SweepCommand {
    /// Join the JSON-lines outputs of shards into the files one run would have written.
    Merge(SweepMergeArgs),
}

/// `raypipe sweep merge`.
#[derive(Args, Debug)]
pub struct SweepMergeArgs {
    /// The shards' .jsonl files.
    #[arg(required = true, value_name = "SHARD.jsonl")]
    pub inputs: Vec<PathBuf>,
    /// Output prefix: PREFIX.jsonl and PREFIX.csv.
    #[arg(short, long, value_name = "PREFIX", default_value = "sweep")]
    pub output: PathBuf,
}

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
    /// State-texture reads go through the texture cache too (default: they bypass it).
    #[arg(long)]
    pub cache_state: bool,
    /// Kernel cost table (TOML) over raypipe's counted one: [kernel] instructions, r, w, m.
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

/// `raypipe fixed-point`.
#[derive(Args, Debug)]
pub struct FixedPointArgs {
    /// OBJ files or scene images (with a BVH); the built-in Cornell box when none.
    pub scenes: Vec<PathBuf>,
    /// Fixed-point formats to compare with f32 (q16.16, q20.12, q12.20, q24.8 in 32
    /// bits; q12.12, q8.16, q16.8 in 24).
    #[arg(long, value_delimiter = ',', default_values = ["q16.16", "q12.12", "q8.16"])]
    pub datapath: Vec<raypipe_hw::Datapath>,
    /// Structure to build for OBJ scenes (a BVH: the fixed-point box test is for BVHs).
    #[arg(long, value_enum, default_value_t = Accel::Bvh4)]
    pub accel: Accel,
    /// Image size of each scene's view.
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "512x512")]
    pub size: (u32, u32),
    /// Camera file for every scene's view (default: each scene's own camera).
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
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
}

/// Walkthroughs: several frames along a camera path.
#[derive(Args, Debug, Clone, Default)]
pub struct WalkArgs {
    /// A camera path (keyframes interpolated into frames; see docs/hw-model.md): one image
    /// per frame, named OUT-0000.png, OUT-0001.png, …
    #[arg(long, value_name = "FILE", conflicts_with = "orbit")]
    pub camera_path: Option<PathBuf>,
    /// A walkthrough of N frames orbiting the look-at point.
    #[arg(long, value_name = "N")]
    pub orbit: Option<usize>,
}

impl WalkArgs {
    /// The frames' cameras over `base`, or `None` for a single frame.
    pub fn cameras(&self, base: &CameraRecord) -> Result<Option<Vec<CameraRecord>>> {
        let cams = match (&self.camera_path, self.orbit) {
            (Some(p), _) => crate::input::camera_path::CameraPath::load(p)?.cameras(base),
            (None, Some(n)) => crate::input::camera_path::orbit(base, n)?,
            (None, None) => return Ok(None),
        };
        for (k, c) in cams.iter().enumerate() {
            render::eye_rays(c, &format!("camera of frame {k}"))?;
        }
        Ok(Some(cams))
    }
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
    /// Per-pixel cost heatmaps of the (last) frame: PREFIX-cycles.png (cycles its packets
    /// were in flight), PREFIX-steps.png (ray–node tests), PREFIX-tests.png (ray–triangle
    /// tests), PREFIX-bytes.png (scene bytes read for it).
    #[arg(long, value_name = "PREFIX")]
    pub cost_image: Option<PathBuf>,
    /// Walkthroughs: one JSON line per frame (cycles, frames/s, bytes loaded, hit rates).
    #[arg(long, value_name = "JSONL", default_value = "raypipe-sim.frames.jsonl")]
    pub frames: PathBuf,
}

fn parse_roi(s: &str) -> Result<(u64, u64), String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("{s:?}: expected A..B (cycles)"))?;
    let parse = |t: &str| t.trim().parse::<u64>().map_err(|_| format!("{s:?}: {t:?} is not a cycle number"));
    Ok((parse(a)?, parse(b)?))
}

/// `raypipe trace`.
#[derive(Args, Debug)]
pub struct TraceArgs {
    /// An OBJ file or a scene image.
    pub scene: PathBuf,
    /// Rays: float32 or float64 array of shape (N, 6) — origin, direction — or (N, 8) with
    /// t_min, t_max. A row that is no ray (NaN, zero direction, empty interval) is a miss,
    /// counted.
    #[arg(long, value_name = "NPY")]
    pub rays: PathBuf,
    /// Output: structured array of N records with the --fields chosen (closest: t, u, v
    /// float32 and prim int32, -1 on a miss, by default; any: occluded uint8).
    #[arg(long, value_name = "NPY")]
    pub hits: PathBuf,
    /// What each ray asks: the closest hit, or whether anything lies in its interval
    /// (occlusion, cheaper: traversal stops at the first hit).
    #[arg(long, value_enum, default_value_t = Query::Closest)]
    pub query: Query,
    /// Output fields, comma-separated. Closest: t, u, v, prim, ng (geometric normal,
    /// winding order, unit), ns (shading normal facing the ray, unit), material (id, -1
    /// on a miss), object (OBJ o/g name, glTF node or scene-file mesh, in input order; -1
    /// on a miss); default t,u,v,prim. Any: occluded.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub fields: Vec<String>,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Trace the batch this many times and report the median time.
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// Trace consecutive rays in packets of this many (1 = single rays); hits are the same.
    #[arg(long, value_enum, default_value_t = PacketSize::Single)]
    pub packet: PacketSize,
}

/// `raypipe info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// What `raypipe trace` asks of each ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Query {
    /// The closest hit.
    #[default]
    Closest,
    /// Any hit in the interval (occlusion).
    Any,
}

/// `raypipe rays`.
#[derive(Args, Debug)]
pub struct RaysArgs {
    /// An OBJ file or a scene image (for its default camera); the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    /// Output .npy file.
    #[arg(short, long, value_name = "NPY")]
    pub output: PathBuf,
    /// Also write the scene's triangles, in id order, as a (T, 9) float32 array.
    #[arg(long, value_name = "NPY")]
    pub triangles: Option<PathBuf>,
    /// Write the rays in square blocks of this side (e.g. 8: each run of 64 rays is an 8×8
    /// pixel block, ready for `trace --packet 64`), in the Z-order of the host's packet
    /// lanes within a block (runs of 4 are 2×2 pixels); 1 = row by row.
    #[arg(long, value_name = "SIDE", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub block: u32,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// How to build the acceleration structure when the scene is an OBJ.
#[derive(Args, Debug, Clone)]
pub struct StructureArgs {
    /// A point light "x,y,z" or "x,y,z,r,g,b" (repeatable), instead of the default light;
    /// on a scene image it replaces the image's lights (its emitters stay area lights).
    #[arg(long, value_name = "X,Y,Z[,R,G,B]", value_parser = parse_light, allow_hyphen_values = true)]
    pub light: Vec<[f32; 6]>,
    /// A directional (sun) light from direction "dx,dy,dz" towards the scene, with
    /// irradiance r,g,b (default 1,1,1) (repeatable), instead of the default light.
    #[arg(long, value_name = "DX,DY,DZ[,R,G,B]", value_parser = parse_light, allow_hyphen_values = true)]
    pub sun: Vec<[f32; 6]>,
    /// A sky: constant radiance "r,g,b", or a gradient "r,g,b,R,G,B" from the horizon's
    /// r,g,b to the zenith's R,G,B (+y up). Path tracing samples it; the other
    /// algorithms add its mean as ambient light.
    #[arg(long, value_name = "R,G,B[,R,G,B]", value_parser = parse_sky)]
    pub sky: Option<[f32; 6]>,
    /// Acceleration structure.
    #[arg(long, value_enum, default_value_t = Accel::Grid)]
    pub accel: Accel,
    /// Grid cells along the scene's shortest axis (Purcell used 64 for the bunny);
    /// default: derived from the triangle count.
    #[arg(long, value_name = "N")]
    pub grid_min_dim: Option<u32>,
    /// Target grid cells per triangle when --grid-min-dim is not given.
    #[arg(long, value_name = "F", default_value_t = DEFAULT_CELLS_PER_TRIANGLE)]
    pub grid_density: f64,
    /// Triangle layout: indexed vertices, or also Wald's 48-byte precomputed triangles, or
    /// also leaf blocks of four triangles (bvh4, bvh8; fastest for single rays).
    #[arg(long, value_enum, default_value_t = TriangleLayout::Indexed)]
    pub triangles: TriangleLayout,
    /// kd-tree SAH: cost of a traversal step (pbrt: 1).
    #[arg(long, value_name = "C", default_value_t = KdParams::default().traversal_cost)]
    pub kd_traversal_cost: f64,
    /// kd-tree SAH: cost of a triangle test (pbrt: 80).
    #[arg(long, value_name = "C", default_value_t = KdParams::default().intersection_cost)]
    pub kd_intersection_cost: f64,
    /// kd-tree SAH: bonus for cutting off empty space, 0–1 (pbrt: 0.5).
    #[arg(long, value_name = "B", default_value_t = KdParams::default().empty_bonus)]
    pub kd_empty_bonus: f64,
    /// kd-tree: largest depth (default 8 + 1.3·log2(triangles), at most 60).
    #[arg(long, value_name = "N")]
    pub kd_max_depth: Option<u32>,
    /// BVH SAH: cost of visiting a node, relative to a triangle test.
    #[arg(long, value_name = "C", default_value_t = BvhParams::default().traversal_cost)]
    pub bvh_traversal_cost: f64,
    /// BVH: largest leaf.
    #[arg(long, value_name = "N", default_value_t = BvhParams::default().max_leaf)]
    pub bvh_max_leaf: usize,
    /// BVH: cut triangles longer than this fraction of the scene into pieces (0: never).
    #[arg(long, value_name = "F", default_value_t = BvhParams::default().presplit_extent)]
    pub bvh_presplit: f64,
    /// BVH: try spatial splits where an object split's children overlap by more than
    /// this fraction of the scene's surface area (Stich et al. 2009; 0: never).
    #[arg(long, value_name = "F", default_value_t = BvhParams::default().spatial_alpha)]
    pub bvh_spatial_alpha: f64,
}

impl StructureArgs {
    /// The structure flags given a value other than their default (they apply only when
    /// building).
    pub(crate) fn flags_given(&self) -> Vec<&'static str> {
        let (kd, bvh) = (KdParams::default(), BvhParams::default());
        let mut v = Vec::new();
        let checks = [
            (self.accel != Accel::Grid, "--accel"),
            (self.grid_min_dim.is_some(), "--grid-min-dim"),
            (self.grid_density != DEFAULT_CELLS_PER_TRIANGLE, "--grid-density"),
            (self.triangles != TriangleLayout::Indexed, "--triangles"),
            (self.kd_traversal_cost != kd.traversal_cost, "--kd-traversal-cost"),
            (self.kd_intersection_cost != kd.intersection_cost, "--kd-intersection-cost"),
            (self.kd_empty_bonus != kd.empty_bonus, "--kd-empty-bonus"),
            (self.kd_max_depth.is_some(), "--kd-max-depth"),
            (self.bvh_traversal_cost != bvh.traversal_cost, "--bvh-traversal-cost"),
            (self.bvh_max_leaf != bvh.max_leaf, "--bvh-max-leaf"),
            (self.bvh_presplit != bvh.presplit_extent, "--bvh-presplit"),
            (self.bvh_spatial_alpha != bvh.spatial_alpha, "--bvh-spatial-alpha"),
        ];
        for (given, flag) in checks {
            if given {
                v.push(flag);
            }
        }
        v
    }

    pub(crate) fn options(&self) -> BuildOptions {
        BuildOptions {
            lights: self
                .light
                .iter()
                .map(|l| (l, LightRecord::POINT))
                .chain(self.sun.iter().map(|l| (l, LightRecord::DIRECTIONAL)))
                .map(|(l, kind)| LightRecord {
                    position: [l[0], l[1], l[2]],
                    kind,
                    color: [l[3], l[4], l[5]],
                    triangle: 0,
                })
                .chain(self.sky.iter().map(|s| LightRecord {
                    position: [s[0], s[1], s[2]],
                    kind: LightRecord::ENVIRONMENT,
                    color: [s[3], s[4], s[5]],
                    triangle: 0,
                }))
                .collect(),
            camera: CameraSpec::default(),
            accel: self.accel,
            grid: match self.grid_min_dim {
                Some(n) => GridResolution::MinDim(n),
                None => GridResolution::Auto { cells_per_triangle: self.grid_density },
            },
            triangles: self.triangles,
            kd: KdParams {
                traversal_cost: self.kd_traversal_cost,
                intersection_cost: self.kd_intersection_cost,
                empty_bonus: self.kd_empty_bonus,
                max_depth: self.kd_max_depth,
                ..KdParams::default()
            },
            bvh: BvhParams {
                traversal_cost: self.bvh_traversal_cost,
                max_leaf: self.bvh_max_leaf.max(1),
                presplit_extent: self.bvh_presplit.max(0.0),
                spatial_alpha: self.bvh_spatial_alpha.max(0.0),
                ..BvhParams::default()
            },
        }
    }
}

/// Camera selection: a camera file and/or individual overrides.
#[derive(Args, Debug, Clone, Default)]
pub struct CameraArgs {
    /// Camera file (see fixtures/cornell_box.camera); overrides the scene's default camera.
    #[arg(long, value_name = "FILE")]
    pub camera: Option<PathBuf>,
    /// Eye position, "x,y,z".
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<[f32; 3]>,
    /// Point to look at, "x,y,z".
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub look_at: Option<[f32; 3]>,
    /// Up vector, "x,y,z".
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<[f32; 3]>,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEG")]
    pub fov: Option<f32>,
    /// Image size, "WIDTHxHEIGHT".
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
}

impl CameraArgs {
    /// The camera file's settings with the flags' on top.
    pub fn spec(&self) -> Result<CameraSpec> {
        let file = match &self.camera {
            Some(path) => CameraSpec::load(path)?,
            None => CameraSpec::default(),
        };
        let flags = CameraSpec {
            eye: self.eye,
            look_at: self.look_at,
            up: self.up,
            fov: self.fov,
            size: self.size,
            background: None,
        };
        Ok(file.merged(flags))
    }

    /// The scene's default camera with the file and then the flags applied.
    pub fn resolve(&self, base: &CameraRecord) -> Result<CameraRecord> {
        let cam = self.spec()?.apply(base);
        let what = self.camera.as_ref().map_or("camera".to_string(), |p| p.display().to_string());
        render::eye_rays(&cam, &what)?;
        Ok(cam)
    }
}

fn parse_light(s: &str) -> Result<[f32; 6], String> {
    let v: Vec<f32> =
        s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    let out = match v.as_slice() {
        [x, y, z] => [*x, *y, *z, 1.0, 1.0, 1.0],
        [x, y, z, r, g, b] => [*x, *y, *z, *r, *g, *b],
        _ => return Err(format!("{s:?}: expected x,y,z or x,y,z,r,g,b")),
    };
    if out.iter().any(|c| !c.is_finite()) {
        return Err(format!("{s:?}: not finite"));
    }
    if out[3..].iter().any(|c| *c < 0.0) {
        return Err(format!("{s:?}: negative light colour"));
    }
    Ok(out)
}

fn parse_sky(s: &str) -> Result<[f32; 6], String> {
    let v: Vec<f32> =
        s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    let out = match v.as_slice() {
        [r, g, b] => [*r, *g, *b, *r, *g, *b],
        [r, g, b, r2, g2, b2] => [*r, *g, *b, *r2, *g2, *b2],
        _ => return Err(format!("{s:?}: expected r,g,b or r,g,b,R,G,B")),
    };
    if out.iter().any(|c| !c.is_finite() || *c < 0.0) {
        return Err(format!("{s:?}: radiance must be finite and not negative"));
    }
    Ok(out)
}

fn parse_filter(s: &str) -> Result<Filter, String> {
    match s.to_ascii_lowercase().as_str() {
        "box" => Ok(Filter::Box),
        "tent" | "triangle" => Ok(Filter::Tent),
        "gaussian" | "gauss" => Ok(Filter::Gaussian),
        _ => Err(format!("unknown filter '{s}' (box, tent or gaussian)")),
    }
}

fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>().map_err(|_| format!("'{c}' is not a number")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        [_, _, _] => Err("coordinates must be finite".into()),
        _ => Err(format!("expected x,y,z, got {} values", v.len())),
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WIDTHxHEIGHT, got '{s}'"))?;
    let w: u32 = w.parse().map_err(|_| format!("'{w}' is not a pixel count"))?;
    let h: u32 = h.parse().map_err(|_| format!("'{h}' is not a pixel count"))?;
    if w == 0 || h == 0 {
        return Err(format!("image size {w}x{h} is zero"));
    }
    if w as u64 * h as u64 > 1 << 28 {
        return Err(format!("image size {w}x{h} is too large (at most 2^28 pixels)"));
    }
    Ok((w, h))
}

/// How rays are traced: threads and the intersection test.
#[derive(Args, Debug, Clone, Default)]
pub struct RunArgs {
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Ray–triangle intersection test (default: wald for an image with Wald triangles,
    /// watertight otherwise).
    #[arg(long, value_enum)]
    pub intersector: Option<IntersectorKind>,
}

impl RunArgs {
    pub(crate) fn check(&self) -> Result<()> {
        if self.threads == Some(0) {
            bail!("--threads must be at least 1");
        }
        Ok(())
    }
}

/// `raypipe build`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// The OBJ file to compile (or --generate).
    #[arg(required_unless_present = "generate", conflicts_with = "generate")]
    pub scene: Option<PathBuf>,
    /// Generate a scene instead: building[:floors=F,rooms=R,seed=S] (a Soda Hall
    /// stand-in, ~1M triangles) or forest[:trees=T,leaves=L,seed=S] (~1M triangles).
    #[arg(long, value_name = "NAME[:PARAMS]")]
    pub generate: Option<String>,
    /// The generated scene's view, the image's default camera: building: outside,
    /// inside; forest: top, inside.
    #[arg(long, value_name = "NAME", requires = "generate")]
    pub view: Option<String>,
    /// Where to write the scene image (.rpsi).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// The rendering algorithm and its settings.
#[derive(Args, Debug, Clone)]
pub struct AlgoArgs {
    /// Rendering algorithm.
    #[arg(long, value_enum, default_value_t = Algorithm::Cast)]
    pub algo: Algorithm,
    /// Whitted: largest number of reflection/refraction bounces.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub max_depth: u32,
    /// Path tracing: bounces after the first hit.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub bounces: u32,
    /// Eye rays per pixel, jittered within the pixel by the filter (anti-aliasing; path
    /// tracing: one path each). Default: 16 for path tracing, 1 (the pixel centre)
    /// otherwise.
    #[arg(long, value_name = "N")]
    pub samples: Option<u32>,
    /// Reconstruction filter the eye rays' offsets follow: box, tent or gaussian.
    #[arg(long, value_name = "FILTER", default_value = "box", value_parser = parse_filter)]
    pub filter: Filter,
    /// Path tracing: end paths at random after the first bounce (Russian roulette).
    #[arg(long)]
    pub roulette: bool,
}

impl AlgoArgs {
    /// Checks the values and puts them into render options.
    pub fn apply(&self, opts: &mut RenderOptions) -> Result<()> {
        if self.max_depth > 64 {
            bail!("--max-depth {} is more than 64", self.max_depth);
        }
        if self.bounces > 64 {
            bail!("--bounces {} is more than 64", self.bounces);
        }
        let samples = self.samples.unwrap_or(if self.algo == Algorithm::Path { 16 } else { 1 });
        if samples == 0 || samples > 65536 {
            bail!("--samples must be between 1 and 65536 (got {samples})");
        }
        opts.algo = self.algo;
        opts.max_depth = self.max_depth as u8;
        opts.bounces = self.bounces as u8;
        opts.samples = samples;
        opts.filter = self.filter;
        opts.roulette = self.roulette;
        Ok(())
    }
}

/// How a PNG output shows linear radiance.
#[derive(Args, Debug, Clone, Default)]
pub struct DisplayArgs {
    /// PNG: exposure in stops (radiance times 2^EV before tone mapping).
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// PNG: tone-mapping operator.
    #[arg(long, value_enum, default_value_t = ToneMap::Clamp)]
    pub tonemap: ToneMap,
}

impl DisplayArgs {
    /// Checks the values: the display transform.
    pub fn display(&self) -> Result<Display> {
        if !self.exposure.is_finite() || self.exposure.abs() > 64.0 {
            bail!("--exposure {} is not a number of stops between -64 and 64", self.exposure);
        }
        Ok(Display { exposure: self.exposure, tone_map: self.tonemap })
    }
}

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
}

/// `raypipe stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Also trace the view as packets of this many rays and report their SIMD efficiency.
    #[arg(long, value_enum, default_value_t = PacketSize::Single)]
    pub packet: PacketSize,
    /// Also report what an algorithm costs against ray casting (rays per pixel by kind,
    /// traversal steps, triangle tests, shading, scene bytes).
    #[command(flatten)]
    pub algo: AlgoArgs,
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Per-pixel cost heatmaps of the primary rays: PREFIX-steps.png (nodes visited),
    /// PREFIX-tests.png (triangle tests), PREFIX-bytes.png (scene bytes read).
    #[arg(long, value_name = "PREFIX")]
    pub cost_image: Option<PathBuf>,
}

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
}
