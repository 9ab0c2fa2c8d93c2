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
                let (i, j) = crate::render::packets::lane_pixel(lane, b);
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
    crate::input::npy::write_f32_2d(&a.output, &crate::input::npy::Array2 { rows, cols: 8, data })?;
    if let Some(path) = &a.triangles {
        let mut data = Vec::with_capacity(view.triangle_count() as usize * 9);
        for prim in 0..view.triangle_count() {
            for v in view.triangle(prim, &mut raypipe_core::NoProbe) {
                data.extend_from_slice(&v.to_array());
            }
        }
        let tris = crate::input::npy::Array2 { rows: view.triangle_count() as usize, cols: 9, data };
        crate::input::npy::write_f32_2d(path, &tris)?;
        println!("wrote {} triangles -> {}", tris.rows, path.display());
    }
    println!("wrote {rows} primary rays ({}x{}) -> {}", cam.width, cam.height, a.output.display());
    Ok(())
}
