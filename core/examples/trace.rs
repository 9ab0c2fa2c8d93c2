//! What firmware does with raypipe-core, on a desktop: embed a scene image, validate it
//! once, make the eye rays of its camera, trace each through whatever structure the image
//! holds, check the hit against brute force, shade it and print the view as text. Every
//! call below is `no_std` and allocation-free; only the printing needs `std` here.
//!
//!     cargo run -p raypipe-core --example trace

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::shade::lambert::shade;
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, RayCounters, SceneView, Vec3, Watertight};

/// The tetrahedron on a floor, built with the 4-wide BVH by
/// `raypipe build fixtures/tetra.obj --accel bvh4 -o fixtures/tetra-bvh4.rpsi`.
static SCENE: &[u8] = raypipe_core::include_scene!("../../fixtures/tetra-bvh4.rpsi");

/// Brightness ramp for the text picture, darkest first.
const RAMP: &[u8] = b" .:-=+*#%@";

fn main() {
    let view = match SceneView::parse(SCENE) {
        Ok(view) => view,
        Err(e) => {
            eprintln!("error: the embedded scene image is invalid: {e:?}");
            std::process::exit(1);
        }
    };
    let Some(camera) = view.camera() else {
        eprintln!("error: the embedded scene image has no camera");
        std::process::exit(1);
    };
    // A small view of the image's camera: 48 × 24 characters.
    let mut camera = Camera::from(camera);
    camera.width = 48;
    camera.height = 24;
    let eye = match EyeRays::new(&camera) {
        Ok(eye) => eye,
        Err(e) => {
            eprintln!("error: unusable camera: {e:?}");
            std::process::exit(1);
        }
    };

    let mut hits = 0;
    for y in 0..eye.height {
        let mut line = String::new();
        for x in 0..eye.width {
            let ray = eye.ray(x, y);
            let hit = trace_walk::<Watertight, _>(&view, &ray, &mut NoProbe);
            // One hit whatever the path: the structure's walk agrees with brute force.
            assert_eq!(hit, trace_brute_force::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default()));
            hits += usize::from(hit.is_some());
            let colour = shade(&view, &ray, eye.cone(), hit, Vec3::ZERO, &mut NoProbe);
            let luminance = (0.2126 * colour.x + 0.7152 * colour.y + 0.0722 * colour.z).clamp(0.0, 1.0);
            line.push(RAMP[(luminance * (RAMP.len() - 1) as f32).round() as usize] as char);
        }
        println!("{line}");
    }
    println!("{hits} of {} eye rays hit one of {} triangles", eye.width * eye.height, view.triangle_count());
}
