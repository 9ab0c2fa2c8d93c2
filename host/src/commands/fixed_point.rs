//! `raypipe fixed-point`: the fixed-point datapaths against `f32` on the same rays.

use crate::render;
use crate::scene::{self, Accel, BuildOptions};
use anyhow::{bail, Result};
use std::path::Path;

use super::{accel_name, camera_for, warn};

use super::args::parse_size;
use super::args::CameraArgs;
use clap::Args;
use std::path::PathBuf;

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

pub(crate) fn cmd_fixed_point(a: FixedPointArgs) -> Result<()> {
    use crate::study::fixed_point::{compare, fits, rays, RayKind};
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
        if let Some(why) = crate::render::tracer::fixed_point_unsupported(&view) {
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
                crate::output::warnings::warning(&format!(
                    "{}: coordinates up to {largest:.4} do not fit {} (largest {:.4}): they saturate",
                    scene.name,
                    d.name(),
                    format.max_value()
                ));
            }
        }
    }
    Ok(())
}
