//! The flag groups several subcommands share — the scene's structure, the camera, the
//! algorithm, the display, threads, walkthroughs — and their value parsers (as cargo's
//! `command_prelude`).

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use raypipe_core::image::{CameraRecord, LightRecord};
use raypipe_core::pixel_filter::Filter;

use crate::build::grid::{GridResolution, DEFAULT_CELLS_PER_TRIANGLE};
use crate::build::kdtree::KdParams;
use crate::build::sah::BvhParams;
use crate::input::camera_file::CameraSpec;
use crate::output::tone_map::{DisplayChoice, Exposure, ToneMap};
use crate::render::tracer::IntersectorKind;
use crate::render::{self, Algorithm, RenderOptions};
use crate::scene::{Accel, BuildOptions, TriangleLayout};

/// Walkthroughs: several frames along a camera path.
#[derive(Args, Debug, Clone, Default)]
pub struct WalkArgs {
    /// A camera path (keyframes interpolated into frames; see docs/hw-model.md): one image
    /// per frame, named OUT-0000.png, OUT-0001.png, …
    #[arg(long, value_name = "FILE", conflicts_with = "orbit")]
    pub camera_path: Option<PathBuf>,
    /// A walkthrough of N frames orbiting the look-at point.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub orbit: Option<usize>,
}

impl WalkArgs {
    /// A walkthrough is asked for (a camera path or an orbit).
    pub fn is_walk(&self) -> bool {
        self.camera_path.is_some() || self.orbit.is_some()
    }

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
    /// r,g,b to the zenith's R,G,B (+y up). Every ray that leaves the scene sees it, in
    /// every algorithm; path tracing samples it as a light, the other algorithms add its
    /// mean as ambient light.
    #[arg(long, value_name = "R,G,B[,R,G,B]", value_parser = parse_sky, allow_hyphen_values = true)]
    pub sky: Option<[f32; 6]>,
    /// Acceleration structure. Default: bvh4, the fastest on the host; `raypipe stream`
    /// uses Purcell's grid and `raypipe simulate` its chip preset's structure unless told.
    #[arg(long, value_enum)]
    pub accel: Option<Accel>,
    /// The structure when --accel is not given (set by the command).
    #[arg(skip = Accel::Bvh4)]
    pub default_accel: Accel,
    /// Grid cells along the scene's shortest axis (Purcell used 64 for the bunny);
    /// default: derived from the triangle count.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub grid_min_dim: Option<u32>,
    /// Target grid cells per triangle when --grid-min-dim is not given.
    #[arg(long, value_name = "F", default_value_t = DEFAULT_CELLS_PER_TRIANGLE, allow_hyphen_values = true)]
    pub grid_density: f64,
    /// Triangle layout: indexed vertices, or also Wald's 48-byte precomputed triangles, or
    /// also leaf blocks of four triangles (bvh4, bvh8; fastest for single rays).
    #[arg(long, value_enum, default_value_t = TriangleLayout::Indexed)]
    pub triangles: TriangleLayout,
    /// kd-tree SAH: cost of a traversal step (pbrt: 1).
    #[arg(long, value_name = "C", default_value_t = KdParams::default().traversal_cost, allow_hyphen_values = true)]
    pub kd_traversal_cost: f64,
    /// kd-tree SAH: cost of a triangle test (pbrt: 80).
    #[arg(long, value_name = "C", default_value_t = KdParams::default().intersection_cost, allow_hyphen_values = true)]
    pub kd_intersection_cost: f64,
    /// kd-tree SAH: bonus for cutting off empty space, 0–1 (pbrt: 0.5).
    #[arg(long, value_name = "B", default_value_t = KdParams::default().empty_bonus, allow_hyphen_values = true)]
    pub kd_empty_bonus: f64,
    /// kd-tree: largest depth (default 8 + 1.3·log2(triangles), at most 60).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub kd_max_depth: Option<u32>,
    /// BVH SAH: cost of visiting a node, relative to a triangle test.
    #[arg(long, value_name = "C", default_value_t = BvhParams::default().traversal_cost, allow_hyphen_values = true)]
    pub bvh_traversal_cost: f64,
    /// BVH: largest leaf.
    #[arg(long, value_name = "N", default_value_t = BvhParams::default().max_leaf, allow_hyphen_values = true)]
    pub bvh_max_leaf: usize,
    /// BVH: cut triangles longer than this fraction of the scene into pieces (0: never).
    #[arg(long, value_name = "F", default_value_t = BvhParams::default().presplit_extent, allow_hyphen_values = true)]
    pub bvh_presplit: f64,
    /// BVH: try spatial splits where an object split's children overlap by more than
    /// this fraction of the scene's surface area (Stich et al. 2009; 0: never).
    #[arg(long, value_name = "F", default_value_t = BvhParams::default().spatial_alpha, allow_hyphen_values = true)]
    pub bvh_spatial_alpha: f64,
}

impl StructureArgs {
    /// The structure to build: the one asked for, else the command's default.
    pub fn accel(&self) -> Accel {
        self.accel.unwrap_or(self.default_accel)
    }

    /// The structure flags given a value other than their default (they apply only when
    /// building).
    pub(crate) fn flags_given(&self) -> Vec<&'static str> {
        let (kd, bvh) = (KdParams::default(), BvhParams::default());
        let mut v = Vec::new();
        let checks = [
            (self.accel.is_some(), "--accel"),
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
            accel: self.accel(),
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
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f32>,
    /// Image size, "WIDTHxHEIGHT".
    #[arg(long, value_name = "WxH", value_parser = parse_size, allow_hyphen_values = true)]
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

pub(crate) fn parse_light(s: &str) -> Result<[f32; 6], String> {
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

pub(crate) fn parse_sky(s: &str) -> Result<[f32; 6], String> {
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

pub(crate) fn parse_filter(s: &str) -> Result<Filter, String> {
    match s.to_ascii_lowercase().as_str() {
        "box" => Ok(Filter::Box),
        "tent" | "triangle" => Ok(Filter::Tent),
        "gaussian" | "gauss" => Ok(Filter::Gaussian),
        _ => Err(format!("unknown filter '{s}' (box, tent or gaussian)")),
    }
}

pub(crate) fn parse_vec3(s: &str) -> Result<[f32; 3], String> {
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

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
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
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
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

/// The rendering algorithm and its settings.
#[derive(Args, Debug, Clone)]
pub struct AlgoArgs {
    /// Rendering algorithm.
    #[arg(long, value_enum, default_value_t = Algorithm::Cast)]
    pub algo: Algorithm,
    /// Whitted: largest number of reflection/refraction bounces.
    #[arg(long, value_name = "N", default_value_t = 5, allow_hyphen_values = true)]
    pub max_depth: u32,
    /// Path tracing: bounces after the first hit.
    #[arg(long, value_name = "N", default_value_t = 2, allow_hyphen_values = true)]
    pub bounces: u32,
    /// Eye rays per pixel, jittered within the pixel by the filter (anti-aliasing; path
    /// tracing: one path each). Default: 16 for path tracing, 1 (the pixel centre)
    /// otherwise.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub samples: Option<u32>,
    /// Reconstruction filter the eye rays' offsets follow: box, tent or gaussian.
    #[arg(long, value_name = "FILTER", default_value = "box", value_parser = parse_filter)]
    pub filter: Filter,
    /// Path tracing: end paths at random after the first bounce (Russian roulette).
    #[arg(long)]
    pub roulette: bool,
    /// Path tracing: the largest radiance one bounce may add to one sample; brighter
    /// contributions are scaled down to it, hue kept. Removes fireflies (rare paths that
    /// find a bright light) at the cost of some energy. Default: no clamp.
    #[arg(long, value_name = "RADIANCE", allow_hyphen_values = true)]
    pub clamp: Option<f32>,
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
        if let Some(c) = self.clamp {
            if !(c.is_finite() && c > 0.0) {
                bail!("--clamp {c} must be a positive radiance");
            }
            if self.algo != Algorithm::Path {
                bail!("--clamp applies to path tracing only (--algo path)");
            }
        }
        opts.clamp = self.clamp;
        Ok(())
    }
}

/// How a PNG output shows linear radiance.
#[derive(Args, Debug, Clone, Default)]
pub struct DisplayArgs {
    /// PNG: exposure in stops (radiance times 2^EV before tone mapping), or "auto": the
    /// frame's log-average luminance to middle grey, at most 1% of pixels clipping.
    /// Default: auto for path tracing (its brightness is the emitters'), 0 otherwise.
    #[arg(long, value_name = "EV|auto", value_parser = parse_exposure, allow_negative_numbers = true)]
    pub exposure: Option<Exposure>,
    /// PNG: tone-mapping operator.
    #[arg(long, value_enum, default_value_t = ToneMap::Clamp)]
    pub tonemap: ToneMap,
}

fn parse_exposure(s: &str) -> std::result::Result<Exposure, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(Exposure::Auto);
    }
    match s.parse::<f32>() {
        Ok(ev) if ev.is_finite() && ev.abs() <= 64.0 => Ok(Exposure::Stops(ev)),
        _ => Err(format!("{s} is not \"auto\" or a number of stops between -64 and 64")),
    }
}

impl DisplayArgs {
    /// The display transform asked for, `algo` deciding the default exposure.
    pub fn choice(&self, algo: Algorithm) -> DisplayChoice {
        let exposure =
            self.exposure.unwrap_or(if algo == Algorithm::Path { Exposure::Auto } else { Exposure::Stops(0.0) });
        DisplayChoice { exposure, tone_map: self.tonemap }
    }
}

/// A byte count with an optional binary unit: `300M`, `4G`, `512K`, `65536` (bytes).
pub(crate) fn parse_byte_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, unit) = match t.find(|c: char| !c.is_ascii_digit() && c != '.') {
        Some(i) => t.split_at(i),
        None => (t, ""),
    };
    let scale: u64 = match unit.to_ascii_uppercase().trim_end_matches("IB").trim_end_matches('B') {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(format!("'{s}': unknown unit (use K, M, G or T)")),
    };
    let v: f64 = digits.parse().map_err(|_| format!("'{s}' is not a size such as 512M or 4G"))?;
    let bytes = v * scale as f64;
    if !(1.0..=1e18).contains(&bytes) {
        return Err(format!("'{s}' is not a size between 1 byte and an exabyte"));
    }
    Ok(bytes as u64)
}

/// How a bricked scene's bricks are cached while rendering.
#[derive(Args, Debug, Clone, Copy)]
pub struct CacheArgs {
    /// Bytes of decompressed bricks kept in memory (least recently used go first), e.g.
    /// 512M or 4G; at least the largest brick. Bricked scenes only.
    #[arg(long, value_name = "SIZE", default_value = "1G", value_parser = parse_byte_size)]
    pub cache: u64,
    /// Threads reading and decompressing bricks. Bricked scenes only.
    #[arg(long, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub loaders: u32,
}
