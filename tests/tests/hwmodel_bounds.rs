//! The chip held against closed-form figures: a memory-bound stream takes its bytes over
//! the channel's bandwidth plus the latency, exactly; and a frame made to be bound by one
//! stage runs at that stage's throughput — its closed-form bound — plus no more than the
//! pipeline's fill and drain.

use raypipe::build::sah::BvhParams;
use raypipe::input::mesh::Mesh;
use raypipe::scene::{self, framing_camera, Accel, BuildOptions};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::{SceneView, Vec3, Watertight};
use raypipe_hw::config::{CacheConfig, MemoryModel};
use raypipe_hw::memory::port::MemPort;
use raypipe_hw::memory::Memory;
use raypipe_hw::{HwConfig, Report, Simulator};
use raypipe_tests::build_soup;

/// `n` posted 64-byte requests taken at one edge by the fixed memory: the channel moves
/// them back to back from the next cycle, and the last one's data is there `latency`
/// cycles after its transfer: `1 + n·64 / bytes_per_cycle + latency`.
#[test]
fn a_memory_bound_stream_takes_bytes_over_bandwidth_plus_latency() {
    for (n, bpc, latency) in [(100u64, 16u32, 50u32), (7, 3, 0), (1, 64, 200)] {
        let mut cfg = HwConfig::default();
        cfg.memory.model = MemoryModel::Fixed;
        cfg.memory.bytes_per_cycle = bpc;
        cfg.memory.latency = latency;
        cfg.memory.min_burst_bytes = 4;
        cfg.memory.queue_depth = 1024;
        let mut memory = Memory::new(&cfg).unwrap();
        let none = CacheConfig { size_bytes: 0, ..CacheConfig::default() };
        let mut port = MemPort::new("stream".into(), &none, 1024);
        for k in 0..n {
            port.write(0, k * 64, 64, 0);
        }
        assert!(memory.accept(0, &mut [&mut port]));
        assert!(!port.has_staged(), "the memory took every request at once");
        let want = 1 + (n * 64).div_ceil(bpc as u64) + latency as u64;
        assert_eq!(memory.drained_at(), want, "{n} requests at {bpc} B/cycle, latency {latency}");
    }
}

/// A grid of small triangles filling the view: many ray–triangle tests per ray.
fn tiles() -> raypipe::scene::Scene {
    let (mut positions, mut tris) = (Vec::new(), Vec::new());
    for i in 0..8 {
        for j in 0..8 {
            let (x, y) = (i as f32, j as f32);
            let base = positions.len() as u32;
            positions.extend([[x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.0]]);
            tris.push([base, base + 1, base + 2]);
        }
    }
    build_soup(positions, tris, Accel::Grid, 1)
}

fn run(view: &SceneView<'_>, cfg: &HwConfig) -> Report {
    let (lo, hi) = view.bounds();
    let mut cam = framing_camera(lo.to_array(), hi.to_array());
    (cam.width, cam.height) = (12, 12);
    let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
    let mut sim = Simulator::<Watertight>::new(*view, eye, Vec3::from(cam.background), cfg).unwrap();
    sim.run(|_, _| {}).unwrap();
    sim.report()
}

/// Perfect memory, one intersection unit taking one test every `ii` cycles: the frame is
/// its last test's entry, (tests − 1) × `ii`, and the pipeline's latency (the
/// intersection bound) plus the fill of the other stages, which does not grow with `ii`.
#[test]
fn an_intersection_bound_frame_runs_at_the_intersection_throughput() {
    let scene = tiles();
    let view = scene.view().unwrap();
    let mut fills = Vec::new();
    for ii in [200u32, 400, 800] {
        let mut cfg = HwConfig::default();
        cfg.memory.model = MemoryModel::Perfect;
        cfg.traversal.units = 1;
        cfg.intersection.lanes_per_cycle = 1;
        cfg.intersection.initiation_interval = ii;
        cfg.watchdog_cycles = 1_000_000;
        let r = run(&view, &cfg);
        let bound = r.bounds.cycles["intersection"];
        let want = (r.triangle_tests - 1) * ii as u64 + cfg.intersection.latency as u64;
        assert_eq!(bound, want as f64, "the bound is (tests - 1) × II + latency");
        assert_eq!(r.bounds.largest, "intersection");
        assert!(r.cycles as f64 >= bound);
        fills.push(r.cycles - bound as u64);
    }
    // What is left over is the other stages' fill and drain: the same whatever the II.
    assert!(fills.iter().all(|&f| f == fills[0]), "fill and drain {fills:?} grow with the II");
}

/// A channel of one byte per cycle and caches off: the frame is its bytes over that
/// bandwidth (the memory bound) plus no more than one request's latency per dependent
/// read in flight at the end.
#[test]
fn a_memory_bound_frame_runs_at_the_channel_bandwidth() {
    let scene = tiles();
    let view = scene.view().unwrap();
    let mut cfg = HwConfig::default();
    cfg.memory.model = MemoryModel::Fixed;
    cfg.memory.bytes_per_cycle = 1;
    cfg.memory.latency = 10;
    cfg.memory.min_burst_bytes = 4;
    cfg.watchdog_cycles = 1_000_000;
    for c in [&mut cfg.cache.nodes, &mut cfg.cache.triangles, &mut cfg.cache.lists, &mut cfg.cache.shading] {
        c.size_bytes = 0;
        c.hit_latency = 0;
    }
    let r = run(&view, &cfg);
    assert_eq!(r.bounds.largest, "memory");
    let bound = r.bounds.cycles["memory"];
    assert_eq!(bound, r.memory.total_bytes as f64);
    assert!(r.cycles as f64 >= bound);
    assert!(r.bounds.achieved_over_largest < 1.05, "{} cycles for a {bound}-cycle bound", r.cycles);
}

/// One ray through a known tree under perfect memory. The scene: a triangle facing the
/// camera and a small one straight behind it, built into a BVH of one triangle per leaf
/// without triangle splitting — a root over two leaves. The one eye ray (a 1×1 image
/// through the middle of the box, one ray per packet) takes one node step, the root,
/// which tests both children's boxes; the front leaf goes to intersection, where the ray
/// hits, and the back leaf, popped afterwards, starts beyond the hit: one step, one
/// triangle test. With one thread and one unit nothing overlaps, so the frame is exactly
/// a constant plus the root step's two dependent node-cache lookups (the root's record,
/// then its children's, whose address it holds) and its step latency, and the leaf's
/// three dependent lookups in the triangle cache (list entry, triangle record, vertices)
/// and its intersection latency.
#[test]
fn one_ray_through_a_known_tree_takes_exactly_its_latencies() {
    let positions = vec![
        [-4.0, -4.0, 0.0],
        [4.0, -4.0, 0.0],
        [0.0, 4.0, 0.0],
        [-0.5, -0.5, -8.0],
        [0.5, -0.5, -8.0],
        [0.0, 0.5, -8.0],
    ];
    let mesh = Mesh { positions, triangles: vec![[0, 1, 2], [3, 4, 5]], ..Default::default() };
    let bvh = BvhParams { max_leaf: 1, presplit_extent: 0.0, spatial_alpha: 0.0, ..BvhParams::default() };
    let opts = BuildOptions { accel: Accel::Bvh, bvh, ..Default::default() };
    let scene = scene::build("two".into(), mesh, Vec::new(), Default::default(), &opts).unwrap();
    let view = scene.view().unwrap();
    let (lo, hi) = view.bounds();
    let mut cam = framing_camera(lo.to_array(), hi.to_array());
    (cam.width, cam.height) = (1, 1);
    let cycles = |step: u32, node_hit: u32, tri_hit: u32, isect: u32| {
        let mut cfg = HwConfig::default();
        cfg.memory.model = MemoryModel::Perfect;
        cfg.packet_size = 1;
        cfg.traversal.units = 1;
        cfg.traversal.threads = 1;
        cfg.traversal.step_latency = step;
        cfg.cache.nodes.hit_latency = node_hit;
        cfg.cache.triangles.hit_latency = tri_hit;
        cfg.intersection.latency = isect;
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
        let mut sim = Simulator::<Watertight>::new(view, eye, Vec3::from(cam.background), &cfg).unwrap();
        sim.run(|_, _| {}).unwrap();
        let r = sim.report();
        (r.cycles, r.traversal_steps, r.triangle_tests, sim.hits()[0].map(|h| h.prim))
    };
    let (base, steps, tests, hit) = cycles(1, 1, 1, 1);
    assert_eq!((steps, tests, hit), (1, 1, Some(0)), "the root, one test, a hit on the front triangle");
    for (s, n, t, i) in [(5, 1, 1, 1), (1, 7, 1, 1), (1, 1, 4, 1), (1, 1, 1, 30), (9, 3, 6, 12)] {
        let want = base + (s - 1) as u64 + 2 * (n - 1) as u64 + 3 * (t - 1) as u64 + (i - 1) as u64;
        assert_eq!(cycles(s, n, t, i).0, want, "step {s}, node hit {n}, triangle hit {t}, intersection {i}");
    }
}
