//! The hardware model against the host: for random small scenes, views,
//! structures and hardware configurations, every pixel's hit equals the host runner's
//! exactly, every run terminates, rays issued = rays retired, and every byte the channel
//! delivered was requested. The tick order of the units cannot change anything, and the
//! watchdog turns a stuck unit into an error naming the units and FIFOs.

use proptest::prelude::*;
use raypipe::render::tracer::trace;
use raypipe::scene::{framing_camera, Accel};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::CameraRecord;
use raypipe_core::pixel_filter::Filter;
use raypipe_core::{FixedWatertight, Hit, Intersector, NoProbe, RayCounters, SceneView, Vec3, Watertight};
use raypipe_hw::config::MemoryModel;
use raypipe_hw::{HwConfig, Simulator};
use raypipe_tests::build_soup;
use raypipe_tests::hw_configs::config;
use raypipe_tests::soup_rays::coord;

/// A random triangle soup (shared vertices and edges, coplanar and degenerate triangles).
fn soup() -> impl Strategy<Value = (Vec<[f32; 3]>, Vec<[u32; 3]>)> {
    (
        prop::collection::vec([coord(), coord(), coord()], 3..20),
        prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..30),
    )
        .prop_map(|(positions, picks)| {
            let n = positions.len();
            let tris =
                picks.iter().map(|[a, b, c]| [a.index(n) as u32, b.index(n) as u32, c.index(n) as u32]).collect();
            (positions, tris)
        })
}

fn accel() -> impl Strategy<Value = Accel> {
    prop_oneof![
        Just(Accel::Grid),
        Just(Accel::Kd),
        Just(Accel::Bvh),
        Just(Accel::Bvh4),
        Just(Accel::Bvh8),
        Just(Accel::None)
    ]
}

fn camera(view: &SceneView<'_>, size: (u32, u32), eye_jitter: [f32; 3]) -> CameraRecord {
    let (lo, hi) = view.bounds();
    let mut cam = framing_camera(lo.to_array(), hi.to_array());
    for (e, j) in cam.eye.iter_mut().zip(eye_jitter) {
        *e += j;
    }
    (cam.width, cam.height) = size;
    cam
}

/// The host's per-pixel hits for the view.
fn host_hits(view: &SceneView<'_>, eye: &EyeRays) -> Vec<Option<Hit>> {
    host_hits_with::<Watertight>(view, eye)
}

/// The host's per-pixel hits for the view with the triangle test `I`.
fn host_hits_with<I: Intersector>(view: &SceneView<'_>, eye: &EyeRays) -> Vec<Option<Hit>> {
    let (lo, hi) = view.test_bounds();
    let mut out = Vec::new();
    for y in 0..eye.height {
        for x in 0..eye.width {
            out.push(
                eye.ray_in_scene(x, y, lo, hi)
                    .and_then(|r| trace::<I, _>(view, &r, &mut NoProbe, &mut RayCounters::default())),
            );
        }
    }
    out
}

fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(b),
        _ => false,
    }
}

/// How to clock a run: reshuffle the tick order every cycle with this seed, and/or tick
/// every single cycle instead of skipping the ones in which nothing can change.
#[derive(Clone, Copy, Default)]
struct Clocking {
    shuffle: Option<u64>,
    every_cycle: bool,
}

fn run<'a>(view: &SceneView<'a>, cam: &CameraRecord, cfg: &HwConfig, clocking: Clocking) -> Simulator<'a, Watertight> {
    let eye = EyeRays::new(&Camera::from(cam)).expect("valid camera");
    let mut sim = Simulator::<Watertight>::new(*view, eye, Vec3::from(cam.background), cfg).expect("valid config");
    if let Some(seed) = clocking.shuffle {
        sim.shuffle_tick_order(seed);
    }
    if clocking.every_cycle {
        sim.tick_every_cycle();
    }
    sim.run(|_, _| {}).expect("the run terminates");
    sim
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn model_hits_equal_the_host_for_any_chip(
        (positions, tris) in soup(),
        accel in accel(),
        cfg in config(),
        w in 1u32..32,
        h in 1u32..32,
        jitter in [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0],
    ) {
        let scene = build_soup(positions, tris, accel, 2);
        let view = scene.view().expect("valid image");
        let cam = camera(&view, (w, h), jitter);
        let sim = run(&view, &cam, &cfg, Clocking::default());
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
        let want = host_hits(&view, &eye);
        for (i, (m, h)) in sim.hits().iter().zip(&want).enumerate() {
            prop_assert!(same(m, h), "pixel {i}: model {m:?} != host {h:?} ({accel:?}, {cfg:?})");
        }
        let r = sim.report();
        prop_assert_eq!(r.conservation.rays_issued, r.conservation.rays_retired);
        prop_assert_eq!(r.conservation.rays_issued, want.len() as u64 - count_outside(&view, &eye));
        prop_assert_eq!(r.conservation.bytes_requested, r.conservation.bytes_delivered);
        prop_assert!(r.memory.traffic_over_compulsory == 0.0 || r.memory.traffic_over_compulsory >= 1.0);
        // Every unit is busy, stalled or idle in each cycle it ticked (all of them).
        let ticked = |u: &raypipe_hw::observe::report::UnitReport| u.busy_cycles + u.stall_cycles + u.idle_cycles;
        for u in &r.units {
            prop_assert_eq!(ticked(u), ticked(&r.units[0]), "{}", u.name);
        }
        prop_assert!(ticked(&r.units[0]) <= r.cycles);
        // Skipping the cycles in which nothing can change is exact (and the watchdog,
        // which `run` demands silent, agrees).
        let every = run(&view, &cam, &cfg, Clocking { every_cycle: true, ..Clocking::default() });
        prop_assert_eq!(every.report().to_json(), r.to_json());
        // No frame beats its closed-form lower bounds (bytes over the channel's peak,
        // tests over the datapaths' lanes, rays over the generation and shading rates).
        for (name, &bound) in &r.bounds.cycles {
            prop_assert!(r.cycles as f64 >= bound - 1e-9, "{name}: {} cycles < bound {bound}", r.cycles);
        }
        prop_assert!(r.bounds.achieved_over_largest.is_nan() || r.bounds.achieved_over_largest >= 1.0 - 1e-9);
        // Every stall cycle has exactly one reason.
        for u in &r.units {
            prop_assert_eq!(u.stall_reasons.values().sum::<u64>(), u.stall_cycles, "{}", u.name);
        }
        // A shared packet walk fetches one node per step (the kd-tree and the wide BVHs;
        // the binary BVH reads a node's two children, and a popped node before them).
        if matches!(accel, Accel::Kd | Accel::Bvh4 | Accel::Bvh8) {
            for u in r.units.iter().filter(|u| u.name.starts_with("traversal")) {
                prop_assert!(u.node_reads_per_step.unwrap_or(0.0) <= 1.0, "{}: {:?}", u.name, u.node_reads_per_step);
            }
        }
        // Perfect memory answers every request no later than any other memory, but the
        // frame is a greedy schedule of rays over shared units: when data arrives at other
        // times the units take their work in another order, and a frame can end sooner
        // than under perfect memory — a scheduling anomaly (Graham 1969), seen here at
        // 0.9% (fixed latency 0, 17 bytes a cycle, a grid), and at 2.7% and 5.2% under
        // DRAMsim3's reordering. Graham bounds such anomalies in list schedules by a
        // factor 2 − 1/m; a perfect-memory frame slower than twice another memory's is a
        // defect, not an anomaly.
        if cfg.memory.model != MemoryModel::Perfect {
            let mut perfect = cfg.clone();
            perfect.memory.model = MemoryModel::Perfect;
            let p = run(&view, &cam, &perfect, Clocking::default());
            prop_assert!(p.cycles() <= 2 * sim.cycles(), "perfect {} > 2 × {:?} {}", p.cycles(), cfg.memory.model, sim.cycles());
        }
    }
}

/// The model with the fixed-point datapath on `view`: its hits.
fn fixed_model_hits<I: Intersector>(view: &SceneView<'_>, cam: &CameraRecord, cfg: &HwConfig) -> Vec<Option<Hit>> {
    let eye = EyeRays::new(&Camera::from(cam)).expect("valid camera");
    let mut sim = Simulator::<I>::new(*view, eye, Vec3::from(cam.background), cfg).expect("valid config");
    sim.run(|_, _| {}).expect("the run terminates");
    sim.hits().to_vec()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 80, ..ProptestConfig::default() })]

    /// With the fixed-point datapath the model's traversal units walk
    /// each ray with the fixed-point box test and its intersection units run the
    /// fixed-point triangle test: every pixel's hit is the host's with the same datapath,
    /// on every BVH and any chip.
    #[test]
    fn fixed_point_model_hits_equal_the_host(
        (positions, tris) in soup(),
        accel in prop_oneof![Just(Accel::Bvh), Just(Accel::Bvh4), Just(Accel::Bvh8)],
        cfg in config(),
        w in 1u32..24,
        h in 1u32..24,
        jitter in [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0],
    ) {
        let scene = build_soup(positions, tris, accel, 2);
        let view = scene.view().expect("valid image");
        let cam = camera(&view, (w, h), jitter);
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
        let model = fixed_model_hits::<FixedWatertight<32, 16>>(&view, &cam, &cfg);
        let host = host_hits_with::<FixedWatertight<32, 16>>(&view, &eye);
        for (i, (m, h)) in model.iter().zip(&host).enumerate() {
            prop_assert!(same(m, h), "Q16.16 pixel {i}: model {m:?} != host {h:?} ({accel:?})");
        }
        let model = fixed_model_hits::<FixedWatertight<24, 12>>(&view, &cam, &cfg);
        let host = host_hits_with::<FixedWatertight<24, 12>>(&view, &eye);
        for (i, (m, h)) in model.iter().zip(&host).enumerate() {
            prop_assert!(same(m, h), "Q12.12 pixel {i}: model {m:?} != host {h:?} ({accel:?})");
        }
    }
}

/// Pixels whose eye ray misses the scene's bounds (no ray is traced for them).
fn count_outside(view: &SceneView<'_>, eye: &EyeRays) -> u64 {
    let (lo, hi) = view.test_bounds();
    (0..eye.height)
        .flat_map(|y| (0..eye.width).map(move |x| (x, y)))
        .filter(|&(x, y)| eye.ray_in_scene(x, y, lo, hi).is_none())
        .count() as u64
}

#[test]
fn the_tick_order_changes_nothing() {
    let positions = vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [2.0, 2.0, 1.0]];
    let tris = vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3], [1, 4, 2], [3, 4, 0]];
    for accel in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8] {
        let scene = build_soup(positions.clone(), tris.clone(), accel, 3);
        let view = scene.view().unwrap();
        let cam = camera(&view, (24, 20), [0.3, -0.2, 0.1]);
        for preset in ["saarcor", "minimal"] {
            let mut cfg = HwConfig::preset(preset).unwrap();
            cfg.traversal.units = 3;
            cfg.traversal.threads = 3;
            cfg.packet_size = 4;
            let base = run(&view, &cam, &cfg, Clocking::default());
            let want = base.report().to_json();
            for seed in [1u64, 7, 12345] {
                let other = run(&view, &cam, &cfg, Clocking { shuffle: Some(seed), every_cycle: seed == 7 });
                assert_eq!(other.framebuffer(), base.framebuffer(), "{accel:?} {preset} seed {seed}");
                assert_eq!(other.cycles(), base.cycles(), "{accel:?} {preset} seed {seed}");
                assert_eq!(other.report().to_json(), want, "{accel:?} {preset} seed {seed}");
            }
        }
    }
}

#[test]
fn the_watchdog_names_the_stuck_units_and_fifos() {
    let scene = build_soup(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]], Accel::Bvh, 1);
    let view = scene.view().unwrap();
    let cam = camera(&view, (16, 16), [0.0; 3]);
    let mut cfg = HwConfig::default();
    cfg.traversal.units = 2;
    cfg.watchdog_cycles = 500;
    let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
    let mut sim = Simulator::<Watertight>::new(view, eye, Vec3::ZERO, &cfg).unwrap();
    sim.freeze_traversal_unit(1);
    let err = sim.run(|_, _| {}).unwrap_err();
    assert!(err.starts_with("watchdog: no unit made progress for 500 cycles"), "{err}");
    for part in ["rgs:", "traversal0:", "traversal1:", "intersection1:", "rays1 ", "hits0 "] {
        assert!(err.contains(part), "{part} missing from: {err}");
    }
    assert!(!err.contains('\n'));
}

#[test]
fn impossible_configurations_are_rejected_before_the_run() {
    let scene = build_soup(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]], Accel::Grid, 1);
    let view = scene.view().unwrap();
    let cam = camera(&view, (4, 4), [0.0; 3]);
    for (key, what) in [
        ("fifo.hits=0", "fifo.hits"),
        ("cache.nodes.size_bytes=16", "smaller than one"),
        ("traversal.threads=0", "traversal.threads"),
        ("packet_size=32", "packet_size"),
        ("memory.bytes_per_cycle=0", "memory.bytes_per_cycle"),
        // A cache slower than the memory behind it (fixed: 100 cycles and a transfer).
        ("cache.nodes.hit_latency=102", "slower than the memory behind it"),
        // An L1 slower than the L2 behind it (the L2 switched on below).
        ("cache.triangles.hit_latency=11", "slower than the one behind it"),
    ] {
        let mut cfg = HwConfig::default();
        cfg.cache.l2.size_bytes = if key.starts_with("cache.triangles") { 4096 } else { 0 };
        cfg.set(key).unwrap();
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
        let err = Simulator::<Watertight>::new(view, eye, Vec3::ZERO, &cfg).err().expect(key);
        assert!(err.contains(what), "{key}: {err}");
    }
}

/// Perfect memory has no queue to fill: a queue of one request, which stalls the fixed
/// memory's units, costs it nothing, and a miss is never cheaper than a hit.
#[test]
fn perfect_memory_takes_every_request_at_once() {
    let scene = build_soup(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.5]],
        vec![[0, 1, 2], [1, 3, 2]],
        Accel::Bvh4,
        1,
    );
    let view = scene.view().unwrap();
    let cam = camera(&view, (24, 24), [0.0; 3]);
    let queue_stalls = |model: MemoryModel| {
        let mut cfg = HwConfig::default();
        cfg.memory.model = model;
        cfg.memory.queue_depth = 1;
        cfg.cache.nodes.size_bytes = 0;
        let sim = run(&view, &cam, &cfg, Clocking::default());
        let r = sim.report();
        (r.units.iter().map(|u| u.stall_reasons.get("memory_queue_full").copied().unwrap_or(0)).sum::<u64>(), r.cycles)
    };
    let (perfect_stalls, perfect_cycles) = queue_stalls(MemoryModel::Perfect);
    let (fixed_stalls, fixed_cycles) = queue_stalls(MemoryModel::Fixed);
    assert_eq!(perfect_stalls, 0);
    assert!(fixed_stalls > 0, "the comparison needs a queue that fills under fixed memory");
    assert!(perfect_cycles < fixed_cycles);
}

/// Whitted ray tracing and path tracing on the chip: the shading unit emits shadow and
/// secondary packets, and the image is the host's, bit for bit, whatever the chip.
#[test]
fn model_images_equal_the_host_for_every_algorithm() {
    use raypipe::render::{render, Algorithm, RenderOptions};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    // Mirrors and glass; Blinn–Phong lobes; a small object under a sky, which eye rays
    // that miss the scene's box must see too.
    let sky = raypipe_core::image::LightRecord {
        position: [0.9, 0.6, 0.3],
        kind: raypipe_core::image::LightRecord::ENVIRONMENT,
        color: [0.2, 0.4, 0.8],
        triangle: 0,
    };
    let cases =
        [("whitted.obj", Accel::Grid, None), ("whitted.obj", Accel::Bvh4, None), ("glossy.obj", Accel::Bvh, None)];
    for (fixture, accel, light) in cases.into_iter().chain([("tetra.obj", Accel::Kd, Some(sky))]) {
        let lights = light.into_iter().collect();
        let scene = raypipe::scene::load(
            Some(&root.join("fixtures").join(fixture)),
            &raypipe::scene::BuildOptions { accel, lights, ..Default::default() },
        )
        .unwrap();
        let view = scene.view().unwrap();
        let cam = CameraRecord { width: 40, height: 30, ..*view.camera().unwrap() };
        // One eye ray per pixel (its centre), and four anti-aliased ones through a tent.
        let samplings = [(1, Filter::Box), (4, Filter::Tent)];
        for (algo, (samples, filter)) in [Algorithm::Cast, Algorithm::Shadow, Algorithm::Whitted, Algorithm::Path]
            .into_iter()
            .flat_map(|a| samplings.map(|s| (a, s)))
        {
            let opts = RenderOptions { algo, samples, filter, bounces: 2, max_depth: 3, ..Default::default() };
            let host = render(&view, &cam, &opts).unwrap();
            let shader = opts.shader(Vec3::from(cam.background));
            let mut configs = vec![HwConfig::preset("saarcor").unwrap(), HwConfig::preset("minimal").unwrap()];
            let mut odd = HwConfig { packet_size: 4, ..HwConfig::default() };
            odd.traversal.units = 3;
            odd.traversal.threads = 2;
            odd.fifo.leaves = 1;
            odd.cache.nodes.size_bytes = 0;
            configs.push(odd);
            for (k, cfg) in configs.iter().enumerate() {
                let eye = EyeRays::new(&Camera::from(&cam)).unwrap().with_sampler(opts.sampler());
                let mut sim =
                    Simulator::<Watertight>::with_shader(view, eye, Vec3::from(cam.background), shader, cfg).unwrap();
                if k == 2 {
                    sim.shuffle_tick_order(99);
                }
                if algo == Algorithm::Shadow {
                    let mut hits = Vec::new();
                    for s in 0..samples {
                        let g = raypipe::render::gbuffer::rasterize(&view, &eye, s);
                        hits.extend((0..cam.height).flat_map(|y| (0..cam.width).map(move |x| (x, y))).map(|(x, y)| {
                            raypipe::render::gbuffer::gbuffer_hit::<Watertight>(&view, &eye, &g, x, y).1
                        }));
                    }
                    sim.set_visibility(hits);
                }
                sim.run(|_, _| {}).unwrap();
                assert!(sim.framebuffer() == host.pixels, "{fixture} {accel:?} {algo:?} {samples} samples config {k}");
                assert!(
                    sim.radiance_image().iter().map(|c| c.to_array()).eq(host.radiance.iter().copied()),
                    "linear radiance: {fixture} {accel:?} {algo:?} {samples} samples config {k}"
                );
                let r = sim.report();
                assert_eq!(r.conservation.rays_issued, r.conservation.rays_retired);
                // Ray steps: each packet step counts its active rays.
                assert!(r.ray_steps >= r.traversal_steps && r.ray_steps <= r.traversal_steps * cfg.packet_size as u64);
                if cfg.packet_size == 1 {
                    assert_eq!(r.ray_steps, r.traversal_steps);
                    assert_eq!(r.traversal_simd_efficiency, 1.0);
                }
                assert_eq!(r.conservation.bytes_requested, r.conservation.bytes_delivered);
                let secondary: u64 = r.rays_by_kind.iter().filter(|(k, _)| *k != "primary").map(|(_, n)| n).sum();
                // A sky casts no shadow ray outside the path tracer.
                let emits = algo == Algorithm::Path || (algo != Algorithm::Cast && light.is_none());
                assert_eq!(secondary > 0, emits, "{algo:?}: {:?}", r.rays_by_kind);
                assert_eq!(
                    r.rays_by_kind["primary"] == 0,
                    algo == Algorithm::Shadow,
                    "the shadow caster traces no primary ray"
                );
            }
        }
    }
}

fn one_triangle(accel: Accel) -> raypipe::scene::Scene {
    build_soup(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]], accel, 1)
}

/// With one ray–node test per cycle, the traversal datapath is busy exactly one cycle
/// per active ray of each step: datapath width is a parameter, not the packet's size.
#[test]
fn one_lane_per_cycle_costs_a_cycle_per_active_ray() {
    let scene = build_soup(
        vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [2.0, 2.0, 1.0]],
        vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3], [1, 4, 2], [3, 4, 0]],
        Accel::Kd,
        1,
    );
    let view = scene.view().unwrap();
    let cam = camera(&view, (16, 16), [0.2, 0.1, -0.1]);
    for lanes in [1u32, 4, 64] {
        let mut cfg = HwConfig::preset("saarcor").unwrap();
        cfg.packet_size = 64;
        cfg.traversal.lanes_per_cycle = lanes;
        let r = run(&view, &cam, &cfg, Clocking::default()).report();
        for u in r.units.iter().filter(|u| u.name.starts_with("traversal")) {
            let active = (u.simd_efficiency * (u.issues * 64) as f64).round() as u64;
            if lanes == 1 {
                assert_eq!(u.busy_cycles, active, "{}: busy cycles = active lanes over steps", u.name);
            } else {
                assert!(u.busy_cycles >= active.div_ceil(lanes as u64) && u.busy_cycles <= active, "{}", u.name);
            }
        }
    }
}

/// An uncached intersection job reads a list entry, then the triangle record, then its
/// vertices: three dependent round trips, each at least the memory latency.
#[test]
fn an_uncached_leaf_job_takes_three_memory_latencies() {
    let scene = one_triangle(Accel::Bvh);
    let view = scene.view().unwrap();
    let cam = camera(&view, (1, 1), [0.0; 3]);
    let mut cfg = HwConfig::preset("minimal").unwrap();
    cfg.memory.latency = 1000;
    cfg.memory.model = MemoryModel::Fixed;
    for c in [&mut cfg.cache.nodes, &mut cfg.cache.triangles, &mut cfg.cache.lists, &mut cfg.cache.shading] {
        c.size_bytes = 0;
    }
    let r = run(&view, &cam, &cfg, Clocking::default()).report();
    assert_eq!(r.rays, 1);
    let i = r.units.iter().find(|u| u.name == "intersection0").unwrap();
    assert!(i.issues >= 1);
    // The unit holds the job from its arrival to its result: three round trips at least.
    assert!(i.busy_cycles + i.stall_cycles >= 3 * 1000, "{} busy + {} stalled", i.busy_cycles, i.stall_cycles);
    assert!(i.stall_reasons["triangle_data"] >= 3 * 1000 - 3, "{:?}", i.stall_reasons);
}

/// One MSHR per cache serialises the misses: never faster than several.
#[test]
fn one_mshr_serialises_misses() {
    let scene = build_soup(
        vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0], [2.0, 2.0, 1.0]],
        vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3], [1, 4, 2], [3, 4, 0]],
        Accel::Bvh4,
        1,
    );
    let view = scene.view().unwrap();
    let cam = camera(&view, (24, 24), [0.0; 3]);
    let cycles = |mshrs: u32| {
        let mut cfg = HwConfig::preset("saarcor").unwrap();
        cfg.packet_size = 4;
        for c in [&mut cfg.cache.nodes, &mut cfg.cache.triangles, &mut cfg.cache.lists, &mut cfg.cache.shading] {
            c.mshrs = mshrs;
            c.line_bytes = 16;
        }
        let sim = run(&view, &cam, &cfg, Clocking::default());
        let r = sim.report();
        let mshr_stalls: u64 = r.units.iter().map(|u| u.stall_reasons["mshr"]).sum();
        (sim.cycles(), mshr_stalls)
    };
    let (one, stalls_one) = cycles(1);
    let (many, stalls_many) = cycles(16);
    assert!(one > many, "1 MSHR: {one} cycles, 16: {many}");
    assert!(stalls_one > stalls_many, "{stalls_one} vs {stalls_many}");
}

/// The issue's repros: very slow datapaths are legitimate waits, not deadlocks, and the
/// verdict is the same whether the clock skips cycles or ticks every one.
#[test]
fn slow_but_legal_chips_finish_in_both_clock_modes() {
    let scene = build_soup(
        vec![[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]],
        vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]],
        Accel::Grid,
        2,
    );
    let view = scene.view().unwrap();
    let cam = camera(&view, (4, 4), [0.0; 3]);
    for (ii, watchdog) in [(100_000u32, 100_000u64), (2000, 1000)] {
        let mut cfg = HwConfig::default();
        cfg.intersection.initiation_interval = ii;
        cfg.watchdog_cycles = watchdog;
        let a = run(&view, &cam, &cfg, Clocking::default());
        let b = run(&view, &cam, &cfg, Clocking { every_cycle: true, ..Clocking::default() });
        assert_eq!(a.report().to_json(), b.report().to_json());
        assert!(a.cycles() > ii as u64);
    }
}
