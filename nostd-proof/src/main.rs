//! A `#![no_std]`, `#![no_main]` program, as firmware would be: it embeds a scene image
//! with `include_scene!`, validates it, traces every eye ray of the image's default
//! camera through the grid, checks each hit against brute force, and returns the
//! number of rays that hit (as the process exit code's complement: 0 means success).
//! It links only `core` and the C start-up code of the host; no `std`, no `alloc`.
#![no_std]
#![no_main]

use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::traverse::grid::trace_grid;
use raypipe_core::{NoProbe, RayCounters, SceneView, Watertight};

static SCENE: &[u8] = raypipe_core::include_scene!("../../fixtures/tetra.rpsi");

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

/// The precompiled `core` still names the unwinding personality routine even with
/// `panic = "abort"`; with nothing to unwind it is never called.
#[no_mangle]
pub extern "C" fn rust_eh_personality() {}

/// Exit codes: 0 all good, 2 image rejected, 3 no camera, 4 grid and brute force
/// disagree, 5 implausible hit count.
#[no_mangle]
pub extern "C" fn main(_argc: i32, _argv: *const *const u8) -> i32 {
    let Ok(view) = SceneView::parse(SCENE) else { return 2 };
    let (Some(grid), Some(cam)) = (view.grid(), view.camera()) else { return 3 };
    let Ok(eye) = EyeRays::new(&Camera::from(cam)) else { return 3 };
    let mut hits = 0u32;
    for y in 0..eye.height {
        for x in 0..eye.width {
            let ray = eye.ray(x, y);
            let g = trace_grid::<Watertight, _>(&view, grid, &ray, &mut NoProbe, &mut RayCounters::default());
            let b = trace_brute_force::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            match (g, b) {
                (None, None) => {}
                (Some(g), Some(b)) if g.bits_eq(&b) => hits += 1,
                _ => return 4,
            }
        }
    }
    // The floor fills the lower part of the view: some rays hit, some miss.
    let total = eye.width * eye.height;
    if hits == 0 || hits == total {
        return 5;
    }
    0
}
