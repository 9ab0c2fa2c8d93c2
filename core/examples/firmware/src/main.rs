//! A firmware that traces: the scene image in flash, validated once, a 32 × 32 view of
//! its camera traced through its 4-wide BVH, the hits counted and checked against brute
//! force, the verdict printed and returned as the exit code.
#![no_std]
#![no_main]

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, RayCounters, SceneView, Watertight};
use semihosting::{println, process};

/// The image, aligned as `SceneView::parse` needs, in flash (built on the host with
/// `raypipe build fixtures/tetra.obj --accel bvh4 -o scene.rpsi`).
static SCENE: &[u8] = raypipe_core::include_scene!("../scene.rpsi");

#[cfg(target_arch = "arm")]
use cortex_m_rt::entry;
#[cfg(target_arch = "riscv32")]
use riscv_rt::entry;

#[entry]
fn main() -> ! {
    let Ok(view) = SceneView::parse(SCENE) else { fail("the scene image is invalid") };
    let Some(camera) = view.camera() else { fail("the scene image has no camera") };
    let mut camera = Camera::from(camera);
    (camera.width, camera.height) = (32, 32);
    let Ok(eye) = EyeRays::new(&camera) else { fail("the camera is unusable") };
    let (mut hits, mut disagree) = (0u32, 0u32);
    for y in 0..eye.height {
        for x in 0..eye.width {
            let ray = eye.ray(x, y);
            let hit = trace_walk::<Watertight, _>(&view, &ray, &mut NoProbe);
            let reference = trace_brute_force::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            hits += hit.is_some() as u32;
            disagree += (hit.map(|h| h.prim) != reference.map(|h| h.prim)) as u32;
        }
    }
    println!("{} triangles, {hits} of 1024 rays hit, {disagree} disagree with brute force", view.triangle_count());
    process::exit(if disagree == 0 && hits > 0 { 0 } else { 1 })
}

fn fail(why: &str) -> ! {
    println!("error: {why}");
    process::exit(2)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // raypipe-core cannot panic; this handler is the runtime's requirement.
    process::exit(3)
}
