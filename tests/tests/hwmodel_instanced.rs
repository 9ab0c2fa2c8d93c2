//! The chip on two-level scenes: rays walk the top level, enter instances through the
//! transformation units and walk their bottoms. For random soups placed by random
//! instances, every bottom structure and random chips (packet sizes, units, threads,
//! transformation units' latency, interval and width, caches, memory models, tick order),
//! ray casting and Whitted: each pixel's hit and the image are the host's, bit for bit;
//! and the report accounts every transformed ray.

use glam::Vec3;
use proptest::prelude::*;
use raypipe::render::instanced::frame::render_instanced;
use raypipe::render::instanced::tracer::trace_instance;
use raypipe::render::instanced::Instances;
use raypipe::render::{Algorithm, RenderOptions};
use raypipe::scene::{Accel, BuildOptions};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::instanced::InstancedView;
use raypipe_core::image::CameraRecord;
use raypipe_core::{RayCounters, Watertight};
use raypipe_hw::chip::scene::{ChipScene, InstancedScene};
use raypipe_hw::config::MemoryModel;
use raypipe_hw::{HwConfig, Simulator};
use raypipe_tests::instanced_soup::{scene_of, soup, transform};

fn accel() -> impl Strategy<Value = Accel> {
    prop_oneof![Just(Accel::Grid), Just(Accel::Kd), Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::None)]
}

/// A random chip: packet size, units, threads, the transformation unit's latency,
/// initiation interval and width, node cache on or off, memory model.
fn chip() -> impl Strategy<Value = HwConfig> {
    (
        (prop_oneof![Just(1u32), Just(4), Just(16), Just(64)], 1u32..4, 1u32..5),
        (1u32..30, 1u32..4, 1u32..5),
        (any::<bool>(), prop_oneof![Just(MemoryModel::Perfect), Just(MemoryModel::Fixed), Just(MemoryModel::Dram)]),
    )
        .prop_map(|((packet, units, threads), (lat, ii, lanes), (cache, model))| {
            let mut c = HwConfig { packet_size: packet, ..HwConfig::default() };
            (c.traversal.units, c.traversal.threads) = (units, threads);
            (c.transform.latency, c.transform.initiation_interval, c.transform.lanes_per_cycle) = (lat, ii, lanes);
            if !cache {
                c.cache.nodes.size_bytes = 0;
            }
            c.memory.model = model;
            c
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

    #[test]
    fn the_chip_renders_two_level_scenes_as_the_host_does(
        bottoms in prop::collection::vec(soup(), 1..4),
        placed in prop::collection::vec((any::<prop::sample::Index>(), transform()), 1..7),
        accel in accel(),
        cfg in chip(),
        whitted in any::<bool>(),
        shuffle in any::<bool>(),
    ) {
        let inst = scene_of(&bottoms, &placed);
        let built = inst.build(&BuildOptions { accel, ..Default::default() }).expect("the instanced soup builds");
        let view = InstancedView::parse(&built.bytes).expect("a valid instanced scene");
        let s = Instances::of(&view, "soup").expect("valid bottoms");
        let cam = CameraRecord { width: 20, height: 14, ..*s.globals.camera().expect("a camera") };
        let algo = if whitted { Algorithm::Whitted } else { Algorithm::Cast };
        let opts = RenderOptions { algo, max_depth: 2, threads: Some(1), ..Default::default() };
        let (host, _) = render_instanced(&s, &cam, &opts).expect("the host renders");
        let eye = EyeRays::new(&Camera::from(&cam)).expect("a camera");
        let background = Vec3::from(cam.background);
        let scene = ChipScene::Instanced(InstancedScene::new(s.top, s.bottoms.clone(), s.globals));
        let mut sim = Simulator::<Watertight>::for_scene(scene, eye, background, opts.shader(background), &cfg)
            .expect("a valid chip");
        if shuffle {
            sim.shuffle_tick_order(7);
        }
        sim.run(|_, _| {}).expect("the frame finishes");
        // Each pixel's hit: the host's walk of the same eye ray.
        let (lo, hi) = s.globals.test_bounds();
        for y in 0..cam.height {
            for x in 0..cam.width {
                let want = eye.sample_ray_in_scene(x, y, 0, lo, hi)
                    .and_then(|r| trace_instance::<Watertight>(&s, &r, &mut RayCounters::default()))
                    .map(|h| h.hit);
                let got = sim.hits()[(y * cam.width + x) as usize];
                let same = match (want, got) {
                    (Some(a), Some(b)) => a.bits_eq(&b),
                    (a, b) => a.is_none() && b.is_none(),
                };
                prop_assert!(
                    same,
                    "pixel ({x}, {y}) {accel:?}: chip {got:?}, host {want:?}"
                );
            }
        }
        prop_assert!(sim.framebuffer() == host.pixels, "{accel:?} {algo:?}: the chip's image differs");
        prop_assert!(sim.radiance_image().iter().map(|c| c.to_array()).eq(host.radiance.iter().copied()));
        // Every ray that entered an instance went through a transformation unit, and the
        // units report it.
        let r = sim.report();
        prop_assert_eq!(r.conservation.rays_issued, r.conservation.rays_retired);
        let transformed: u64 = r.units.iter().filter_map(|u| u.transform.as_ref()).map(|t| t.rays).sum();
        let units = r.units.iter().filter(|u| u.name.starts_with("transform")).count();
        prop_assert_eq!(units, cfg.traversal.units as usize);
        if sim.hits().iter().any(|h| h.is_some()) {
            prop_assert!(transformed > 0, "hits without a transformed ray");
        }
    }
}

/// The transformation unit's latency is paid, and only it: on a chip with one thread
/// of one ray and perfect memory nothing overlaps, so ten more cycles of latency cost
/// exactly ten cycles per transformed ray, and the rays transformed do not change.
#[test]
fn each_cycle_of_transform_latency_is_paid_once_per_entering_ray() {
    use raypipe::build::instanced::{affine_of, Instance, InstancedScene as Placed};
    use raypipe::input::mesh::Mesh;
    let quad = Mesh {
        positions: vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    };
    let at = |x: f32, z: f32| Instance {
        bottom: 0,
        to_world: affine_of(glam::Mat4::from_translation(Vec3::new(x, 0.0, z))),
        material: None,
    };
    let placed = Placed {
        name: "quads".into(),
        bottoms: vec![quad],
        bottom_names: vec!["quad".into()],
        instances: vec![at(-1.5, 0.0), at(1.5, -1.0), at(0.0, -2.0)],
        ..Default::default()
    };
    let built = placed.build(&BuildOptions { accel: Accel::Bvh, ..Default::default() }).unwrap();
    let view = InstancedView::parse(&built.bytes).unwrap();
    let s = Instances::of(&view, "quads").unwrap();
    let cam = CameraRecord { width: 12, height: 8, ..*s.globals.camera().unwrap() };
    let run = |latency: u32| {
        let mut c = HwConfig::preset("minimal").unwrap();
        c.memory.model = MemoryModel::Perfect;
        c.transform.latency = latency;
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
        let scene = ChipScene::Instanced(InstancedScene::new(s.top, s.bottoms.clone(), s.globals));
        let mut sim = Simulator::<Watertight>::for_scene(scene, eye, Vec3::ZERO, None, &c).unwrap();
        sim.run(|_, _| {}).unwrap();
        let r = sim.report();
        let t = r.units.iter().find(|u| u.name == "transform0").and_then(|u| u.transform.clone()).unwrap();
        (r.cycles, t.rays, t.requests, sim.framebuffer())
    };
    let (fast, rays, requests, image) = run(1);
    let (slow, rays_slow, requests_slow, image_slow) = run(11);
    assert!(rays > 0 && rays == rays_slow && requests == requests_slow);
    assert_eq!(requests, rays, "one ray per packet");
    assert_eq!(slow - fast, 10 * requests, "latency 1 → 11");
    assert!(image == image_slow, "timing never changes the image");
}
