//! Any bytes as a scene image: `SceneView::parse` returns an error or a view, and on a
//! view every kernel (the structure's walk, the generic walk, any-hit, packets, shading)
//! runs on rays made from the input without panicking, and within the work bound of
//! docs/scene-format.md ("Work bounds").
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::platform::aligned::AlignedBytes;
use raypipe::render::tracer::trace;
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::ray_cone::RayCone;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight, Q12_12};

fuzz_target!(|data: &[u8]| {
    let bytes = AlignedBytes::from_slice(data);
    let Ok(view) = SceneView::parse(&bytes) else { return };
    let (lo, hi) = view.bounds();
    let centre = (lo + hi) * 0.5;
    // Rays from outside the box at the centre, and along the axes, plus a few directions
    // taken from the input's last bytes.
    let tail: Vec<f32> = data.iter().rev().take(12).map(|&b| b as f32 / 127.5 - 1.0).collect();
    let mut rays = vec![
        Ray::new(centre + Vec3::new(0.3, 0.7, 5.0) * (hi - lo + Vec3::ONE), Vec3::new(-0.05, -0.1, -1.0)),
        Ray::new(lo - Vec3::ONE, hi - lo + Vec3::ONE),
        Ray::new(centre, Vec3::X),
        Ray::new(centre, -Vec3::Y),
    ];
    if tail.len() == 12 {
        rays.push(Ray::new(centre + Vec3::new(tail[0], tail[1], tail[2]), Vec3::new(tail[3], tail[4], tail[5])));
        rays.push(Ray::new(
            lo + (hi - lo) * Vec3::new(tail[6], tail[7], tail[8]).abs(),
            Vec3::new(tail[9], tail[10], tail[11]),
        ));
    }
    for ray in &rays {
        let mut c = RayCounters::default();
        let hit = trace::<Watertight, _>(&view, ray, &mut NoProbe, &mut c);
        let generic = trace_walk::<Watertight, _>(&view, ray, &mut NoProbe);
        assert_eq!(hit.map(|h| (h.t.to_bits(), h.prim)), generic.map(|h| (h.t.to_bits(), h.prim)));
        let any = occluded::<Watertight, _>(&view, ray, &mut NoProbe, &mut RayCounters::default());
        assert_eq!(any, hit.is_some());
        let _ = shade(&view, ray, RayCone::POINT, hit, Vec3::ZERO, &mut NoProbe);
        // The fixed-point datapath: bounded and panic-free on any image; on a BVH (or
        // none) its walk agrees with its own single-ray kernel.
        let fixed = trace_walk::<Q12_12, _>(&view, ray, &mut NoProbe);
        let fixed_kernel = trace::<Q12_12, _>(&view, ray, &mut NoProbe, &mut RayCounters::default());
        if view.grid().is_none() && view.kdtree().is_none() {
            assert_eq!(fixed.map(|h| (h.t.to_bits(), h.prim)), fixed_kernel.map(|h| (h.t.to_bits(), h.prim)));
        }
    }
    let packet: [Ray; 4] = core::array::from_fn(|i| rays[i % rays.len()]);
    let mut hits = [None; 4];
    trace_packet_steps::<Watertight, _, 4>(&view, &packet, u64::MAX, &mut hits, &mut NoProbe);
});
