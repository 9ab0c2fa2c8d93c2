//! The kernels' speed, measured by divan (`cargo bench -p raypipe-tests --bench kernels`):
//! single rays through every structure, packets of 64 through the 4-wide BVH, and one
//! leaf's triangles tested by the watertight test — on a generated building seen from
//! inside (the same scene every run, built once per structure), 256 × 256 eye rays.
//! Figures are throughput in rays (or ray–triangle tests) per second; compare builds
//! with the same machine and scene, never against a threshold.

use std::sync::OnceLock;

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use raypipe::input::generate::generate;
use raypipe::scene::{self, Accel, BuildOptions, Scene};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::packet::bvh4::trace_bvh4_packet;
use raypipe_core::packet::{PacketCounters, PacketHits, RayPacket};
use raypipe_core::traverse::tree_step::test_leaf;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, Ray, SceneView, Watertight};

fn main() {
    divan::main();
}

/// Pixels per side of the view.
const SIDE: u32 = 256;

/// The building, built with `accel` (once per structure for the whole run).
fn scene(accel: Accel) -> &'static Scene {
    static SCENES: [OnceLock<Scene>; 5] = [const { OnceLock::new() }; 5];
    let slot = match accel {
        Accel::Grid => 0,
        Accel::Kd => 1,
        Accel::Bvh => 2,
        Accel::Bvh4 => 3,
        _ => 4,
    };
    SCENES[slot].get_or_init(|| {
        let g = generate("building:floors=2,rooms=6", Some("inside")).expect("the generator's scene");
        let opts = BuildOptions { accel, ..Default::default() };
        scene::build(g.name, g.mesh, Vec::new(), g.camera, &opts).expect("the building builds")
    })
}

/// The view and its eye rays, row by row (`SIDE` × `SIDE`).
fn eye_rays(view: &SceneView<'_>) -> Vec<Ray> {
    let mut camera = Camera::from(view.camera().expect("the image has a camera"));
    (camera.width, camera.height) = (SIDE, SIDE);
    let eye = EyeRays::new(&camera).expect("a usable camera");
    (0..SIDE * SIDE).map(|i| eye.ray(i % SIDE, i / SIDE)).collect()
}

/// Eye rays by 8 × 8 pixel blocks (one packet each).
fn blocks(view: &SceneView<'_>) -> Vec<Vec<Ray>> {
    let rays = eye_rays(view);
    let mut out = Vec::new();
    for by in (0..SIDE).step_by(8) {
        for bx in (0..SIDE).step_by(8) {
            out.push((0..64).map(|j| rays[((by + j / 8) * SIDE + bx + j % 8) as usize]).collect());
        }
    }
    out
}

const STRUCTURES: [&str; 5] = ["grid", "kd", "bvh", "bvh4", "bvh8"];

fn accel_of(name: &str) -> Accel {
    match name {
        "grid" => Accel::Grid,
        "kd" => Accel::Kd,
        "bvh" => Accel::Bvh,
        "bvh4" => Accel::Bvh4,
        _ => Accel::Bvh8,
    }
}

/// One eye ray at a time through the image's structure (the generic walk, as firmware
/// calls it).
#[divan::bench(args = STRUCTURES)]
fn single_ray(bencher: Bencher, structure: &str) {
    let scene = scene(accel_of(structure));
    let view = scene.view().expect("a valid image");
    let rays = eye_rays(&view);
    bencher.counter(ItemsCount::new(rays.len())).bench_local(|| {
        for ray in &rays {
            black_box(trace_walk::<Watertight, _>(&view, ray, &mut NoProbe));
        }
    });
}

/// Packets of 64 rays (8 × 8 pixels) through the 4-wide BVH in lock-step, with the
/// frustum test.
#[divan::bench]
fn packet_bvh4_64(bencher: Bencher) {
    let scene = scene(Accel::Bvh4);
    let view = scene.view().expect("a valid image");
    let bvh = *view.bvh4().expect("a 4-wide BVH");
    let packets: Vec<RayPacket<64>> = blocks(&view)
        .iter()
        .map(|rays| {
            let mut p = RayPacket::<64>::new();
            p.fill(rays);
            p
        })
        .collect();
    bencher.counter(ItemsCount::new(packets.len() * 64)).bench_local(|| {
        let mut hits: PacketHits<64> = [None; 64];
        let mut counters = PacketCounters::default();
        for p in &packets {
            trace_bvh4_packet::<Watertight, _, 64>(&view, &bvh, p, &mut hits, &mut NoProbe, &mut counters);
            black_box(&hits);
        }
    });
}

/// One leaf of 16 list entries, tested by every eye ray with the watertight test: the
/// leaf kernel alone, without traversal (counted in ray–triangle tests).
#[divan::bench]
fn leaf_watertight_16(bencher: Bencher) {
    let scene = scene(Accel::Bvh);
    let view = scene.view().expect("a valid image");
    let bvh = *view.bvh().expect("a binary BVH");
    let rays = eye_rays(&view);
    let count = 16.min(view.prim_list_len() as u32);
    bencher.counter(ItemsCount::new(rays.len() * count as usize)).bench_local(|| {
        for ray in &rays {
            let prep = <Watertight as raypipe_core::Intersector>::prepare(ray);
            let mut best = None;
            test_leaf::<Watertight, _, _>(&view, &bvh, &prep, ray, (0, count), &mut best, &mut NoProbe);
            black_box(best);
        }
    });
}
