//! One frame through the chip: the tetrahedron's scene image, the `saarcor` preset with
//! a DRAM channel, 64 × 64 eye rays. Prints the frame's cycles, frame rate at the
//! preset's clock, each unit's busy share and the memory traffic by data class, then
//! checks the chip's image against core's kernels run directly.
//!
//!     cargo run --release -p raypipe-hw --example one_frame

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::lambert::shade;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, SceneView, Vec3, Watertight};
use raypipe_hw::config::MemoryModel;
use raypipe_hw::{HwConfig, Simulator};

static SCENE: &[u8] = raypipe_core::include_scene!("../../fixtures/tetra-bvh4.rpsi");

fn main() -> Result<(), String> {
    let view = SceneView::parse(SCENE).map_err(|e| format!("the scene image: {e:?}"))?;
    let mut camera = Camera::from(view.camera().ok_or("the scene image has no camera")?);
    (camera.width, camera.height) = (64, 64);
    let eye = EyeRays::new(&camera).map_err(|e| format!("the camera: {e:?}"))?;

    let mut cfg = HwConfig::preset("saarcor")?;
    cfg.memory.model = MemoryModel::Dram;
    let mut chip = Simulator::<Watertight>::new(view, eye, Vec3::ZERO, &cfg)?;
    chip.run(|_, _| {})?;
    let report = chip.report();

    println!(
        "{} rays in {} cycles: {:.0} frames/s at {} MHz",
        report.rays, report.cycles, report.frames_per_second, cfg.clock_mhz
    );
    for unit in &report.units {
        println!("  {:<24} busy {:5.1}%", unit.name, 100.0 * unit.busy_cycles as f64 / report.cycles as f64);
    }
    for (class, bytes) in &report.memory.bytes {
        println!("  memory {class:<12} {bytes:>8} bytes");
    }
    println!("  bottleneck: {}", report.bottleneck);

    // The chip computes with core's kernels: its image is theirs, pixel for pixel.
    let image = chip.framebuffer();
    for y in 0..eye.height {
        for x in 0..eye.width {
            let ray = eye.ray(x, y);
            let hit = trace_walk::<Watertight, _>(&view, &ray, &mut NoProbe);
            let direct = rgb8(shade(&view, &ray, eye.cone(), hit, Vec3::ZERO, &mut NoProbe));
            if image[(y * eye.width + x) as usize] != direct {
                return Err(format!("pixel ({x}, {y}) differs from core's kernels"));
            }
        }
    }
    println!("the chip's image equals core's kernels run directly");
    Ok(())
}
