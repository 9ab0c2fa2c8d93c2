//! `raypipe rays`: writes a batch of rays (eye or bounce rays of a view).

use crate::render;
use crate::scene::{self, Accel, BuildOptions};
use anyhow::Result;

use super::camera_for;

use super::args::CameraArgs;
use clap::Args;
use std::path::PathBuf;

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

pub(crate) fn cmd_rays(a: RaysArgs) -> Result<()> {
    // Both outputs can be written before either is: never one without the other.
    crate::output::check_writable(&a.output)?;
    if let Some(path) = &a.triangles {
        crate::output::check_writable(path)?;
    }
    let scene = scene::load(a.scene.as_deref(), &BuildOptions { accel: Accel::None, ..Default::default() })?;
    let view = scene.view()?;
    let cam = camera_for(&view, &a.camera)?;
    let eye = render::eye_rays(&cam, "camera")?;
    let outputs = crate::output::batch::Batch::begin();
    let rows = cam.width as usize * cam.height as usize;
    let b = a.block;
    // Streamed: a batch at the largest size (268 M rays, 8.6 GB) is never held in memory.
    crate::input::npy::write_f32_rows(&a.output, rows, 8, |out| {
        for by in (0..cam.height).step_by(b as usize) {
            for bx in (0..cam.width).step_by(b as usize) {
                // The lane order of the host's packets (Z-order within the block).
                for lane in 0..b * b {
                    let (i, j) = crate::render::packets::lane_pixel(lane, b);
                    let (x, y) = (bx + i, by + j);
                    if x < cam.width && y < cam.height {
                        let r = eye.ray(x, y);
                        let (o, d) = (r.origin, r.dir);
                        out.push(&[o.x, o.y, o.z, d.x, d.y, d.z, r.t_min, r.t_max])?;
                    }
                }
            }
        }
        Ok(())
    })?;
    if let Some(path) = &a.triangles {
        let count = view.triangle_count() as usize;
        crate::input::npy::write_f32_rows(path, count, 9, |out| {
            for prim in 0..view.triangle_count() {
                let [p, q, r] = view.triangle(prim, &mut raypipe_core::NoProbe);
                out.push(&[p.x, p.y, p.z, q.x, q.y, q.z, r.x, r.y, r.z])?;
            }
            Ok(())
        })?;
    }
    outputs.commit()?;
    if let Some(path) = &a.triangles {
        println!("wrote {} triangles -> {}", view.triangle_count(), path.display());
    }
    println!("wrote {rows} primary rays ({}x{}) -> {}", cam.width, cam.height, a.output.display());
    Ok(())
}
