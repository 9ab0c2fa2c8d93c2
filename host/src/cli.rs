//! The `raypipe` command line: clap parses into one options struct per subcommand; every
//! error becomes one line on stderr and a non-zero exit.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use clap::{Args, Parser, Subcommand};
use raypipe_core::image::CameraRecord;
use raypipe_core::DataClass;

use crate::bench::{self, median};
use crate::bvh_builder::BvhParams;
use crate::camera_file::CameraSpec;
use crate::grid_builder::{GridResolution, DEFAULT_CELLS_PER_TRIANGLE};
use crate::kd_builder::KdParams;
use crate::output;
use crate::packets::PacketSize;
use crate::render::{self, Algorithm, RenderOptions};
use crate::scene::{self, Accel, BuildOptions, Scene, TriangleLayout};
use crate::simulate;
use crate::stats;
use crate::tracer::IntersectorKind;

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
    Simulate(SimulateArgs),
    /// Compare the fixed-point datapath's hits with f32's (same triangle, distance between
    /// the hit points, nodes visited) on scenes, per format.
    FixedPoint(FixedPointArgs),
    /// Run Purcell's stream machine (a programmable GPU ray tracing in rendering passes,
    /// multipass or branching) on a scene: passes, instructions, memory words, texture
    /// cache, frame time; image, JSON report and charts.
    Stream(StreamArgs),
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
    /// Rendering algorithm.
    #[arg(long, value_enum, default_value_t = Algorithm::Cast)]
    pub algo: Algorithm,
    /// Whitted: largest number of reflection/refraction bounces.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub max_depth: u32,
    /// Path tracing: bounces after the first hit.
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub bounces: u32,
    /// Path tracing: samples per pixel (one eye ray each).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub samples: u32,
    /// Ray–triangle test (default: the one the image's triangle layout is for).
    #[arg(long, value_enum)]
    pub intersector: Option<IntersectorKind>,
    /// Output PNG.
    #[arg(short, long, value_name = "PNG", default_value = "raypipe-stream.png")]
    pub output: PathBuf,
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
#[derive(Args, Debug)]
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
    /// Output PNG.
    #[arg(short, long, value_name = "PNG", default_value = "raypipe-sim.png")]
    pub output: PathBuf,
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
}

/// `raypipe trace`.
#[derive(Args, Debug)]
pub struct TraceArgs {
    /// An OBJ file or a scene image.
    pub scene: PathBuf,
    /// Rays: float32 array of shape (N, 6) — origin, direction — or (N, 8) with t_min, t_max.
    #[arg(long, value_name = "NPY")]
    pub rays: PathBuf,
    /// Output: structured array of N records (t, u, v float32; prim int32, -1 on a miss).
    #[arg(long, value_name = "NPY")]
    pub hits: PathBuf,
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
    /// A point light "x,y,z" or "x,y,z,r,g,b" (repeatable), instead of the default light
    /// (OBJ input; an image keeps its lights).
    #[arg(long, value_name = "X,Y,Z[,R,G,B]", value_parser = parse_light, allow_hyphen_values = true)]
    pub light: Vec<[f32; 6]>,
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
    fn options(&self) -> BuildOptions {
        BuildOptions {
            lights: self
                .light
                .iter()
                .map(|l| raypipe_core::image::LightRecord {
                    position: [l[0], l[1], l[2]],
                    kind: raypipe_core::image::LightRecord::POINT,
                    color: [l[3], l[4], l[5]],
                    triangle: 0,
                })
                .collect(),
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
    fn check(&self) -> Result<()> {
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
    /// Path tracing: samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub samples: u32,
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
        if self.samples == 0 || self.samples > 65536 {
            bail!("--samples must be between 1 and 65536 (got {})", self.samples);
        }
        opts.algo = self.algo;
        opts.max_depth = self.max_depth as u8;
        opts.bounces = self.bounces as u8;
        opts.samples = self.samples;
        opts.roulette = self.roulette;
        Ok(())
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
    /// Output PNG.
    #[arg(short, long, value_name = "PNG", default_value = "raypipe.png")]
    pub output: PathBuf,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
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

/// Parses the process arguments, runs, and turns any error into one line on stderr.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

/// Runs a parsed command.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Build(a) => cmd_build(a),
        Command::Render(a) => cmd_render(a),
        Command::Stats(a) => cmd_stats(a),
        Command::Bench(a) => cmd_bench(a),
        Command::Trace(a) => cmd_trace(a),
        Command::Rays(a) => cmd_rays(a),
        Command::Simulate(a) => cmd_simulate(a),
        Command::FixedPoint(a) => cmd_fixed_point(a),
        Command::Stream(a) => cmd_stream(a),
    }
}

fn warn(scene: &Scene) {
    if let Some(r) = &scene.report {
        for w in &r.warnings {
            eprintln!("warning: {w}");
        }
    }
}

fn accel_name(a: Accel) -> &'static str {
    match a {
        Accel::Grid => "grid",
        Accel::Kd => "kd-tree",
        Accel::Bvh => "BVH",
        Accel::Bvh4 => "BVH4",
        Accel::Bvh8 => "BVH8",
        Accel::None => "brute force",
    }
}

/// A short description of the structure a scene image holds.
fn structure_summary(view: &raypipe_core::SceneView<'_>) -> String {
    if let Some(g) = view.grid() {
        format!("grid {}x{}x{}", g.dims[0], g.dims[1], g.dims[2])
    } else if let Some(b) = view.bvh4() {
        format!("BVH4 {} nodes{}", b.node_count(), blocks_note(view))
    } else if let Some(b) = view.bvh8() {
        format!("BVH8 {} nodes{}", b.node_count(), blocks_note(view))
    } else if let Some(b) = view.bvh() {
        format!("BVH {} nodes", b.node_count())
    } else if let Some(k) = view.kdtree() {
        format!("kd {} nodes", k.node_count())
    } else {
        "none".to_string()
    }
}

fn blocks_note(view: &raypipe_core::SceneView<'_>) -> &'static str {
    if view.has_tri_blocks() {
        ", leaf blocks"
    } else {
        ""
    }
}

fn fmt_bytes(b: usize) -> String {
    if b >= 1 << 20 {
        format!("{:.2} MiB", b as f64 / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", b as f64 / 1024.0)
    }
}

fn cmd_build(a: BuildArgs) -> Result<()> {
    let start = Instant::now();
    let (input, scene) = match (&a.generate, &a.scene) {
        (Some(spec), _) => {
            let g = crate::generate::generate(spec, a.view.as_deref())?;
            let scene = scene::build(
                g.name.clone(),
                g.mesh,
                Vec::new(),
                g.camera.merged(a.camera.spec()?),
                &a.structure.options(),
            )?;
            (format!("generated {}", g.name), scene)
        }
        (None, Some(path)) => {
            let scene::Source::Mesh { name, mesh, warnings, camera } = scene::load_source(Some(path))? else {
                bail!("{}: is already a scene image; build takes an OBJ file", path.display());
            };
            // The camera file and flags, over the OBJ's sidecar camera, become the image's default.
            let scene = scene::build(name, mesh, warnings, camera.merged(a.camera.spec()?), &a.structure.options())?;
            (path.display().to_string(), scene)
        }
        (None, None) => bail!("build: name an OBJ file or --generate a scene"),
    };
    warn(&scene);
    let what = a.camera.camera.as_ref().map_or("camera".to_string(), |p| p.display().to_string());
    let view = scene.view()?;
    let camera = view.camera().ok_or_else(|| anyhow!("internal error: built image lacks a camera"))?;
    render::eye_rays(camera, &what)?;
    let elapsed = start.elapsed().as_secs_f64();
    output::write_bytes(&a.output, &scene.image)?;
    let r = scene.report.as_ref().ok_or_else(|| anyhow!("internal error: no build report"))?;
    println!("scene        {input}");
    println!("triangles    {} ({} degenerate), vertices {}", r.triangles, r.degenerate, r.vertices);
    match a.structure.accel {
        Accel::Kd | Accel::Bvh | Accel::Bvh4 | Accel::Bvh8 => {
            println!(
                "{:<12} {} nodes, depth {}, {} triangle references ({:.2} per triangle)",
                accel_name(a.structure.accel),
                r.tree_nodes,
                r.tree_depth,
                r.references,
                r.references as f64 / r.triangles.max(1) as f64
            );
            println!(
                "build        {:.3} s, structure {} bytes ({:.1} bytes/triangle)",
                r.grid_seconds,
                r.structure_bytes,
                r.structure_bytes as f64 / r.triangles.max(1) as f64
            );
        }
        Accel::None => {}
        Accel::Grid => {
            let [x, y, z] = r.dims;
            println!(
                "grid         {x} x {y} x {z} = {} cells, {} non-empty ({:.1}%)",
                r.cells,
                r.full_cells,
                100.0 * r.full_cells as f64 / r.cells.max(1) as f64
            );
            println!(
                "lists        {} entries ({} triangle references, {:.2} per triangle)",
                r.list_entries,
                r.references,
                r.references as f64 / r.triangles.max(1) as f64
            );
            println!("grid build   {:.3} s", r.grid_seconds);
        }
    }
    println!(
        "image        {} bytes ({}), {:.1} bytes/triangle",
        r.image_bytes,
        fmt_bytes(r.image_bytes),
        r.image_bytes as f64 / r.triangles.max(1) as f64
    );
    println!("total        {elapsed:.3} s -> {}", a.output.display());
    Ok(())
}

fn camera_for(view: &raypipe_core::SceneView<'_>, args: &CameraArgs) -> Result<CameraRecord> {
    let base = match view.camera() {
        Some(c) => *c,
        None => {
            let (lo, hi) = view.bounds();
            scene::framing_camera(lo.to_array(), hi.to_array())
        }
    };
    let cam = args.resolve(&base)?;
    // Each image's own rays are not checked one by one; its corners and centre stand
    // for them (they bound the directions, and share the eye).
    let eye = render::eye_rays(&cam, "camera")?;
    let (w, h) = (eye.width.saturating_sub(1), eye.height.saturating_sub(1));
    let rays = [(0, 0), (w, 0), (0, h), (w, h), (w / 2, h / 2)].map(|(x, y)| eye.ray(x, y));
    warn_range(view, &rays, "camera rays (corners and centre)");
    Ok(cam)
}

/// Warns about a scene or rays outside raypipe-core's guaranteed range.
fn warn_range(view: &raypipe_core::SceneView<'_>, rays: &[raypipe_core::Ray], what: &str) {
    for w in crate::range_check::warnings(view, rays, what) {
        eprintln!("warning: {w}");
    }
}

fn cmd_render(a: RenderArgs) -> Result<()> {
    a.run.check()?;
    check_png_path(&a.output)?;
    let scene = scene::load(a.scene.as_deref(), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let packet = a.packet.unwrap_or_else(|| PacketSize::auto_for(&view));
    let mut opts =
        RenderOptions { threads: a.run.threads, intersector: kind, progress: true, packet, ..Default::default() };
    a.algo.apply(&mut opts)?;
    let start = Instant::now();
    let frame = render::render(&view, &cam, &opts)?;
    let secs = start.elapsed().as_secs_f64();
    output::write_png(&a.output, frame.width, frame.height, &frame.pixels)?;
    println!(
        "rendered {} ({} triangles) at {}x{} in {:.3} s ({:.2} Mrays/s) -> {}",
        scene.name,
        view.triangle_count(),
        frame.width,
        frame.height,
        secs,
        (frame.width as f64 * frame.height as f64) / secs / 1e6,
        a.output.display()
    );
    Ok(())
}

fn cmd_fixed_point(a: FixedPointArgs) -> Result<()> {
    use crate::fixed_point::{compare, fits, rays, RayKind};
    if let Some(d) = a.datapath.iter().find(|d| d.format().is_none()) {
        bail!("--datapath {}: name fixed-point formats to compare with f32", d.name());
    }
    if !matches!(a.accel, Accel::Bvh | Accel::Bvh4 | Accel::Bvh8) {
        bail!("--accel {}: the fixed-point box test is for BVHs (bvh, bvh4 or bvh8)", accel_name(a.accel));
    }
    let paths: Vec<Option<&Path>> =
        if a.scenes.is_empty() { vec![None] } else { a.scenes.iter().map(|p| Some(p.as_path())).collect() };
    println!(
        "{:<22} {:<7} {:<8} {:>4} {:>8} {:>8} {:>7} {:>7} {:>7}  {:<34} {:<14} tests/ray (f32 -> fixed)",
        "scene",
        "rays",
        "datapath",
        "fits",
        "rays",
        "agree%",
        "oth.tri",
        "f32only",
        "fixonly",
        "hit offset median/p99/max (median ulp)",
        "nodes/ray",
    );
    for path in paths {
        let opts = BuildOptions { accel: a.accel, ..Default::default() };
        let scene = scene::load(path, &opts)?;
        warn(&scene);
        let view = scene.view()?;
        if let Some(why) = crate::tracer::fixed_point_unsupported(&view) {
            bail!("{}: {why}; the fixed-point box test is for BVHs (rebuild it with --accel bvh4)", scene.name);
        }
        let camera_args = CameraArgs { camera: a.camera.clone(), size: Some(a.size), ..CameraArgs::default() };
        let cam = camera_for(&view, &camera_args)?;
        let eye = render::eye_rays(&cam, "camera")?;
        let (primary, bounce) = rays(&view, &eye);
        for d in &a.datapath {
            let Some(format) = d.format() else { continue };
            let (largest, ok) = fits(&view, &eye, format);
            for (kind, rays) in [(RayKind::Primary, &primary), (RayKind::Bounce, &bounce)] {
                let r = compare(&view, rays, *d);
                let per = |x: u64| x as f64 / r.rays.max(1) as f64;
                let offset = format!(
                    "{:.2e}/{:.2e}/{:.2e} ({:.2})",
                    r.offset(0.5),
                    r.offset(0.99),
                    r.offset(1.0),
                    r.offset(0.5) / format.ulp()
                );
                let nodes = format!("{:.1} -> {:.1}", per(r.visits[0]), per(r.visits[1]));
                let tests = format!("{:.2} -> {:.2}", per(r.tests[0]), per(r.tests[1]));
                println!(
                    "{:<22} {:<7} {:<8} {:>4} {:>8} {:>8.3} {:>7} {:>7} {:>7}  {offset:<34} {nodes:<14} {tests}",
                    scene.name,
                    kind.name(),
                    d.name(),
                    if ok { "yes" } else { "NO" },
                    r.rays,
                    r.agree_percent(),
                    r.other_triangle,
                    r.f32_only,
                    r.fixed_only,
                );
            }
            if !ok {
                eprintln!(
                    "warning: {}: coordinates up to {largest:.4} do not fit {} (largest {:.4}): they saturate",
                    scene.name,
                    d.name(),
                    format.max_value()
                );
            }
        }
    }
    Ok(())
}

fn cmd_simulate(a: SimulateArgs) -> Result<()> {
    check_png_path(&a.output)?;
    // Both outputs' directories before anything is written: never one without the other.
    output::check_dir(&a.output)?;
    output::check_dir(&a.report)?;
    // The configuration is checked before the scene is even loaded.
    let cfg = simulate::load_config(a.preset.as_deref(), a.config.as_deref(), &a.set)?;
    if let (Some(k), true) = (a.intersector, cfg.datapath != raypipe_hw::Datapath::F32) {
        bail!(
            "--intersector {}: datapath {} has its own triangle test (fixed-point watertight)",
            k.name(),
            cfg.datapath.name()
        );
    }
    let scene = scene::load(a.scene.as_deref(), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.intersector, &view);
    let mut opts = RenderOptions::default();
    a.algo.apply(&mut opts)?;
    let shader = opts.shader(raypipe_core::Vec3::from(cam.background));
    let start = Instant::now();
    let shadow_caster = opts.algo == Algorithm::Shadow;
    let (frame, mut report) = simulate::simulate(&view, &cam, &cfg, kind, shader, shadow_caster, true)?;
    let secs = start.elapsed().as_secs_f64();
    report.run = raypipe_hw::report::RunIdentity {
        scene: a.scene.as_ref().map_or("built-in Cornell box".to_string(), |p| p.display().to_string()),
        scene_hash: format!("{:016x}", raypipe_hw::report::fnv1a64(view.bytes())),
        structure: structure_summary(&view),
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
    };
    output::write_png(&a.output, frame.width, frame.height, &frame.pixels)?;
    output::write_bytes(&a.report, report.to_json().as_bytes())?;
    println!(
        "simulated {} ({}, {} triangles) -> {}",
        scene.name,
        structure_summary(&view),
        view.triangle_count(),
        a.output.display()
    );
    print!("{}", report.summary());
    println!(
        "simulator      {:.2} s wall, {:.3} Mrays/s simulated; report -> {}",
        secs,
        report.rays as f64 / secs / 1e6,
        a.report.display()
    );
    Ok(())
}

fn cmd_stream(a: StreamArgs) -> Result<()> {
    use raypipe_hw::stream::{CostModel, StreamConfig};
    check_png_path(&a.output)?;
    output::check_dir(&a.output)?;
    output::check_dir(&a.report)?;
    let cfg = StreamConfig {
        arch: a.arch,
        oracle: a.oracle,
        unroll: a.unroll,
        suppress: a.suppress,
        simd: a.simd,
        cache: a.cache,
        cache_state: a.cache_state,
        machine: a.machine.unwrap_or_default(),
    };
    cfg.validate().map_err(|e| anyhow!("stream configuration: {e}"))?;
    let costs = match &a.costs {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| anyhow!("{}: {e}", p.display()))?;
            CostModel::from_toml(&text, &p.display().to_string()).map_err(|e| anyhow!("{}: {e}", p.display()))?
        }
        None => CostModel::default(),
    };
    let algo =
        AlgoArgs { algo: a.algo, max_depth: a.max_depth, bounces: a.bounces, samples: a.samples, roulette: false };
    let mut opts = RenderOptions::default();
    algo.apply(&mut opts)?;
    let scene = scene::load(a.scene.as_deref(), &a.structure.options())?;
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
    let (frame, report) = crate::stream::run_stream(&view, &cam, &cfg, &costs, kind, shader, shadow_caster, true)?;
    let secs = start.elapsed().as_secs_f64();
    // The same frame from the host renderer: the model must agree bit for bit.
    opts.intersector = kind;
    opts.packet = crate::packets::PacketSize::auto_for(&view);
    let host = render::render(&view, &cam, &opts)?;
    let same = host.pixels == frame.pixels;
    let cast = if opts.algo != Algorithm::Cast && !a.no_table3 {
        Some(crate::stream::run_stream(&view, &cam, &cfg, &costs, kind, None, false, true)?.1)
    } else {
        None
    };
    output::write_png(&a.output, frame.width, frame.height, &frame.pixels)?;
    output::write_bytes(&a.report, report.to_json().as_bytes())?;
    println!(
        "stream {} ({} triangles, {}), {}x{}, {} {}",
        scene.name,
        view.triangle_count(),
        structure_summary(&view),
        frame.width,
        frame.height,
        format!("{:?}", opts.algo).to_lowercase(),
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
    );
    let label = format!("{} {}", scene.name, cfg.arch);
    print!("{}", crate::stream::table2(&report, &label));
    print!("{}", crate::stream::kernel_table(&report));
    print!("{}", crate::stream::class_table(&report));
    print!("{}", crate::stream::frame_lines(&report));
    if let Some(c) = &cast {
        print!("{}", crate::stream::table3(&format!("{:?}", opts.algo).to_lowercase(), &report, c));
    }
    if !a.no_charts {
        let written = crate::stream_charts::write_all(&a.charts, &report)?;
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

fn check_png_path(p: &Path) -> Result<()> {
    match p.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("png") => Ok(()),
        _ => bail!("{}: output must be a .png file", p.display()),
    }
}

fn cmd_stats(a: StatsArgs) -> Result<()> {
    a.run.check()?;
    let scene = scene::load(a.scene.as_deref(), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let opts = RenderOptions {
        threads: a.run.threads,
        intersector: kind,
        progress: false,
        packet: a.packet,
        ..Default::default()
    };
    let s = stats::gather(&view, &cam, &opts)?;
    println!("scene                     {} ({} triangles)", scene.name, view.triangle_count());
    println!("structure                 {}", structure_summary(&view));
    let (node, leaf) = if view.grid().is_some() { ("voxels", "non-empty voxels") } else { ("nodes", "leaves") };
    println!("view                      {}x{} = {} primary rays", cam.width, cam.height, s.rays);
    println!("rays that hit             {:.2}%", 100.0 * s.hits as f64 / s.rays.max(1) as f64);
    println!("rays missing scene bounds {:.2}%", 100.0 * s.missed_bounds as f64 / s.rays.max(1) as f64);
    println!("{:<25} avg {:.2}, max {}", format!("{node} visited per ray"), s.per_ray(s.total.nodes), s.max_nodes);
    println!("{:<25} avg {:.2}", format!("{leaf} per ray"), s.per_ray(s.total.leaves));
    println!("triangles tested per ray  avg {:.2}, max {}", s.per_ray(s.total.tri_tests), s.max_tri_tests);
    println!(
        "list entries read         {} total, {:.2} per ray",
        s.total.list_entries,
        s.per_ray(s.total.list_entries)
    );
    let classes: Vec<String> =
        DataClass::ALL.iter().map(|c| format!("{} {:.1}", c.name(), s.per_ray(s.bytes.bytes[*c as usize]))).collect();
    println!("bytes read per ray        {}", classes.join(", "));
    if a.packet != PacketSize::Single && !crate::tracer::has_packet_kernel(&view) {
        println!("packets {:<17} none: the structure has no packet kernel (rays traced one by one)", a.packet.label());
    } else if a.packet != PacketSize::Single {
        let p = stats::gather_packets(&view, &cam, &opts, a.packet)?;
        let n = a.packet.rays() as f64;
        println!(
            "packets {:<17} {} packets, {:.1} node visits per packet, SIMD efficiency {:.1}%, {:.2} triangle tests per ray",
            a.packet.label(),
            p.packets,
            p.counters.visits as f64 / p.packets.max(1) as f64,
            100.0 * p.counters.active_lanes as f64 / (p.counters.visits.max(1) as f64 * n),
            p.counters.tri_tests as f64 / s.rays.max(1) as f64
        );
    }
    if a.algo.algo != Algorithm::Cast {
        let mut algo_opts = opts;
        a.algo.apply(&mut algo_opts)?;
        let cast = stats::algorithm_costs(&view, &cam, &RenderOptions { algo: Algorithm::Cast, ..algo_opts })?;
        let c = stats::algorithm_costs(&view, &cam, &algo_opts)?;
        let px = c.pixels.max(1) as f64;
        let kinds: Vec<String> = raypipe_core::shade::ray_record::RayKind::ALL
            .iter()
            .map(|k| format!("{} {:.2}", k.name(), c.rays[*k as usize] as f64 / px))
            .collect();
        let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        println!("algorithm                 {:?}", a.algo.algo);
        println!("rays per pixel            {}; total {:.2}", kinds.join(", "), c.rays.iter().sum::<u64>() as f64 / px);
        println!(
            "relative to ray casting   traversal steps x{:.2}, triangle tests x{:.2}, shading x{:.2}, scene bytes x{:.2}",
            ratio(c.steps, cast.steps),
            ratio(c.tests, cast.tests),
            ratio(c.shades, cast.shades),
            ratio(c.bytes, cast.bytes)
        );
        if a.algo.algo == Algorithm::Shadow {
            let (differ, pixels, clipped) = stats::coverage_mismatch(&view, &cam, &algo_opts)?;
            println!(
                "shadow caster coverage    rasterization and ray casting disagree at {:.4}% of pixels ({differ} of {pixels}); {clipped} triangles clipped at the near plane",
                100.0 * differ as f64 / pixels.max(1) as f64
            );
        }
    }
    Ok(())
}

fn cmd_bench(a: BenchArgs) -> Result<()> {
    if a.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let mut targets: Vec<Option<PathBuf>> = Vec::new();
    if !a.no_default {
        targets.push(None);
    }
    targets.extend(a.scenes.iter().cloned().map(Some));
    if targets.is_empty() {
        bail!("nothing to measure: --no-default without scenes");
    }
    let kernel = a.intersector.map_or("default", IntersectorKind::name);
    let chip = match &a.simulate {
        Some(preset) => Some(simulate::load_config(Some(preset), None, &[])?),
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
            let opts = BuildOptions {
                accel: accel.unwrap_or_default(),
                grid: match a.grid_min_dim {
                    Some(n) => GridResolution::MinDim(n),
                    None => GridResolution::default(),
                },
                triangles: a.triangles,
                ..Default::default()
            };
            // Structure build time: median of up to three builds (one for large scenes).
            let mut builds = Vec::new();
            let mut built = None;
            for _ in 0..3 {
                let s = source.build(&opts)?;
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
                } else if !crate::tracer::has_packet_kernel(&view) {
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
                let mut opts =
                    RenderOptions { intersector: kind, packet: PacketSize::auto_for(&view), ..Default::default() };
                a.algo.apply(&mut opts)?;
                let r = bench::algorithm_rays(&view, &cam, &opts, a.runs, a.threads)?;
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
            }
            if let (Some(cfg), Some(preset)) = (&chip, &a.simulate) {
                // The simulator is deterministic; its wall time is the median of up to 3 runs.
                let mut walls = Vec::new();
                let mut last = None;
                for _ in 0..a.runs.min(3) {
                    let start = Instant::now();
                    let out = simulate::simulate(&view, &cam, cfg, kind, None, false, false)?;
                    walls.push(start.elapsed().as_secs_f64());
                    last = Some(out.1);
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
            }
        }
    }
    Ok(())
}

fn cmd_rays(a: RaysArgs) -> Result<()> {
    let scene = scene::load(a.scene.as_deref(), &BuildOptions { accel: Accel::None, ..Default::default() })?;
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let eye = render::eye_rays(&cam, "camera")?;
    let mut data = Vec::with_capacity(cam.width as usize * cam.height as usize * 8);
    let b = a.block;
    for by in (0..cam.height).step_by(b as usize) {
        for bx in (0..cam.width).step_by(b as usize) {
            // The lane order of the host's packets (Z-order within the block).
            for lane in 0..b * b {
                let (i, j) = crate::packets::lane_pixel(lane, b);
                let (x, y) = (bx + i, by + j);
                if x < cam.width && y < cam.height {
                    let r = eye.ray(x, y);
                    data.extend_from_slice(&[
                        r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.t_min, r.t_max,
                    ]);
                }
            }
        }
    }
    let rows = data.len() / 8;
    crate::npy::write_f32_2d(&a.output, &crate::npy::Array2 { rows, cols: 8, data })?;
    if let Some(path) = &a.triangles {
        let mut data = Vec::with_capacity(view.triangle_count() as usize * 9);
        for prim in 0..view.triangle_count() {
            for v in view.triangle(prim, &mut raypipe_core::NoProbe) {
                data.extend_from_slice(&v.to_array());
            }
        }
        let tris = crate::npy::Array2 { rows: view.triangle_count() as usize, cols: 9, data };
        crate::npy::write_f32_2d(path, &tris)?;
        println!("wrote {} triangles -> {}", tris.rows, path.display());
    }
    println!("wrote {rows} primary rays ({}x{}) -> {}", cam.width, cam.height, a.output.display());
    Ok(())
}

fn cmd_trace(a: TraceArgs) -> Result<()> {
    a.run.check()?;
    let rays = crate::npy::read_f32_2d(&a.rays)?;
    let name = a.rays.display();
    let rays = crate::batch::rays_from_array(&rays).map_err(|e| anyhow!("{name}: {e}"))?;
    let scene = scene::load(Some(&a.scene), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    warn_range(&view, &rays, &format!("rays of {name}"));
    let mut times = Vec::new();
    // One output for all runs, as a caller tracing batch after batch keeps one: only the
    // first run pays for touching fresh pages.
    let mut hits = Vec::new();
    for _ in 0..a.runs {
        let start = Instant::now();
        crate::batch::trace_batch_into(
            &view,
            &rays,
            IntersectorKind::resolve(a.run.intersector, &view),
            a.packet,
            a.run.threads,
            &mut hits,
        )?;
        times.push(start.elapsed().as_secs_f64());
    }
    let secs = median(&times);
    crate::npy::write_hits(&a.hits, &hits)?;
    let n_hit = hits.iter().filter(|h| h.prim >= 0).count();
    println!(
        "traced {} rays through {} ({}): {} hits ({:.2}%) in {:.3} s ({:.2} Mrays/s) -> {}",
        rays.len(),
        scene.name,
        structure_summary(&view),
        n_hit,
        100.0 * n_hit as f64 / rays.len().max(1) as f64,
        secs,
        rays.len() as f64 / secs / 1e6,
        a.hits.display()
    );
    Ok(())
}
