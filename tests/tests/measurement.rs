//! Measuring the hardware model the way architects do: interval statistics
//! that sum to the frame, warm-up frames left out of the totals, regions of interest,
//! and walkthroughs whose frames are each the host's image while the caches stay warm.

use raypipe::hw::chip::{simulate_frames, FrameRun, Measure};
use raypipe::hw::frame_setup::FrameSetup;
use raypipe::render::{render, Algorithm, RenderOptions};
use raypipe::scene::{Accel, BuildOptions};
use raypipe_core::image::CameraRecord;
use raypipe_core::Vec3;
use raypipe_hw::config::MemoryModel;
use raypipe_hw::observe::counters::counters;
use raypipe_hw::observe::metrics::metric;
use raypipe_hw::HwConfig;

fn whitted_scene(accel: Accel) -> raypipe::scene::Scene {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    raypipe::scene::load(Some(&root.join("fixtures/whitted.obj")), &BuildOptions { accel, ..Default::default() })
        .unwrap()
}

fn frames(
    scene: &raypipe::scene::Scene,
    views: &[CameraRecord],
    measure: &Measure,
    cfg: &HwConfig,
    algo: Algorithm,
) -> Vec<FrameRun> {
    let view = scene.view().unwrap();
    let opts = RenderOptions { algo, max_depth: 2, ..Default::default() };
    let shader = opts.shader(Vec3::from(views[0].background));
    simulate_frames(
        &raypipe_hw::chip::scene::ChipScene::Flat(view),
        views,
        measure,
        cfg,
        &FrameSetup { shader, sampler: opts.sampler(), ..Default::default() },
    )
    .unwrap()
}

fn dram() -> HwConfig {
    let mut cfg = HwConfig::default();
    cfg.memory.model = MemoryModel::Dram;
    cfg
}

#[test]
fn interval_rows_sum_to_the_frame_and_each_spans_its_cycles() {
    let scene = whitted_scene(Accel::Kd);
    let cam = CameraRecord { width: 32, height: 24, ..*scene.view().unwrap().camera().unwrap() };
    for (cfg, n) in [(HwConfig::default(), 700), (dram(), 1999), (HwConfig::preset("saarcor").unwrap(), 64)] {
        let run =
            frames(&scene, &[cam], &Measure { interval: Some(n), ..Default::default() }, &cfg, Algorithm::Whitted);
        let f = &run[0];
        let totals = counters(&f.report);
        assert!(f.intervals.len() >= 2, "interval {n}: {} rows", f.intervals.len());
        for (name, total) in &totals {
            let sum: u64 =
                f.intervals.iter().map(|i| i.counters.iter().find(|(k, _)| k == name).map_or(0, |(_, v)| *v)).sum();
            assert_eq!(sum, *total, "interval {n}: {name}");
        }
        // Back to back from 0 to the frame's end, every row but the last exactly N
        // cycles (the clock never skips across a boundary).
        let mut at = 0;
        for (k, i) in f.intervals.iter().enumerate() {
            assert_eq!(i.start, at);
            assert_eq!(i.counters[0], ("cycles".to_string(), i.end - i.start));
            if k + 1 < f.intervals.len() {
                assert_eq!(i.end - i.start, n);
            }
            at = i.end;
        }
        assert_eq!(at, f.report.cycles);
        // Intervals observe; they change neither the image nor the report.
        let plain = frames(&scene, &[cam], &Measure::default(), &cfg, Algorithm::Whitted);
        assert_eq!(plain[0].report.to_json(), f.report.to_json());
        assert!(plain[0].frame.pixels == f.frame.pixels);
    }
}

#[test]
fn warm_up_frames_are_left_out_and_warm_the_caches() {
    let scene = whitted_scene(Accel::Bvh4);
    let cam = CameraRecord { width: 32, height: 32, ..*scene.view().unwrap().camera().unwrap() };
    let cfg = dram();
    let cold = frames(&scene, &[cam], &Measure::default(), &cfg, Algorithm::Cast);
    let warm = frames(&scene, &[cam, cam], &Measure { warmup_frames: 1, ..Default::default() }, &cfg, Algorithm::Cast);
    assert!(warm[0].warmup && !warm[1].warmup);
    // The warm-up frame is the cold frame; the measured frame counts itself only.
    assert_eq!(warm[0].report.to_json(), cold[0].report.to_json());
    let (c, w) = (&cold[0].report, &warm[1].report);
    assert_eq!(w.rays, c.rays);
    assert_eq!(w.rays_by_kind, c.rays_by_kind);
    assert_eq!(w.conservation.rays_issued, w.conservation.rays_retired);
    assert_eq!(w.conservation.bytes_requested, w.conservation.bytes_delivered);
    let units = |r: &raypipe_hw::Report| r.units.iter().map(|u| u.busy_cycles + u.stall_cycles + u.idle_cycles).max();
    assert!(units(w) <= Some(w.cycles), "units tick only the measured frame's cycles");
    // A static camera's second frame hits at least as often, and loads less.
    for class in ["hit_rate.nodes", "hit_rate.triangles", "hit_rate.prim_lists", "hit_rate.shading"] {
        let (a, b) = (metric(c, class).unwrap(), metric(w, class).unwrap());
        assert!(a.is_nan() || b >= a, "{class}: {a} then {b}");
    }
    assert!(w.memory.total_bytes < c.memory.total_bytes);
    assert!(w.cycles < c.cycles);
    assert!(warm[1].frame.pixels == cold[0].frame.pixels);
}

#[test]
fn a_region_of_interest_covers_its_cycles_only() {
    let scene = whitted_scene(Accel::Grid);
    let cam = CameraRecord { width: 32, height: 32, ..*scene.view().unwrap().camera().unwrap() };
    let cfg = HwConfig::default();
    let whole = frames(&scene, &[cam], &Measure::default(), &cfg, Algorithm::Whitted);
    let (a, b) = (whole[0].report.cycles / 4, whole[0].report.cycles / 2);
    let roi = frames(
        &scene,
        &[cam],
        &Measure { roi: Some((a, b)), interval: Some(100), ..Default::default() },
        &cfg,
        Algorithm::Whitted,
    );
    let r = &roi[0].report;
    assert_eq!(r.cycles, b - a);
    for u in &r.units {
        assert_eq!(u.busy_cycles + u.stall_cycles + u.idle_cycles, b - a, "{}", u.name);
    }
    for f in &r.fifos {
        assert_eq!(f.stats.occupancy.iter().sum::<u64>(), b - a, "{}", f.name);
    }
    assert!(r.rays > 0 && r.rays < whole[0].report.rays);
    assert_eq!(roi[0].intervals.last().map(|i| i.end), Some(b - a));
    // The image is still the whole frame's.
    assert!(roi[0].frame.pixels == whole[0].frame.pixels);
}

#[test]
fn walkthrough_frames_are_the_hosts_images() {
    let scene = whitted_scene(Accel::Kd);
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 24, height: 24, ..*view.camera().unwrap() };
    let views = raypipe::input::camera_path::orbit(&cam, 3).unwrap();
    let run = frames(&scene, &views, &Measure::default(), &HwConfig::preset("saarcor").unwrap(), Algorithm::Whitted);
    for (k, (f, c)) in run.iter().zip(&views).enumerate() {
        let opts = RenderOptions { algo: Algorithm::Whitted, max_depth: 2, ..Default::default() };
        let host = render(&view, c, &opts).unwrap();
        assert!(f.frame.pixels == host.pixels, "frame {k}");
        assert_eq!(f.report.conservation.rays_issued, f.report.conservation.rays_retired, "frame {k}");
    }
}

#[test]
fn energy_is_the_counters_times_the_published_figures() {
    let scene = whitted_scene(Accel::Bvh4);
    let cam = CameraRecord { width: 32, height: 24, ..*scene.view().unwrap().camera().unwrap() };
    let mut cfg = dram();
    let r = frames(&scene, &[cam], &Measure::default(), &cfg, Algorithm::Whitted).remove(0).report;
    let e = r.energy.as_ref().expect("every run is estimated");
    let pj = 1e-12;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-30);
    // Ray–triangle tests at Möller–Trumbore's 27 multiplies and 23 additions, Horowitz's
    // 3.7 and 0.9 pJ; BVH4 node tests as four slab tests.
    assert!(close(e.joules["intersection"], r.triangle_tests as f64 * (27.0 * 3.7 + 23.0 * 0.9) * pj));
    let node_tests: u64 = r.units.iter().filter(|u| u.name.starts_with("traversal")).map(|u| u.active_lanes).sum();
    assert!(close(e.joules["traversal"], node_tests as f64 * 4.0 * (6.0 * 3.7 + 12.0 * 0.9) * pj));
    let rows: u64 = r.memory.dram.as_ref().unwrap().banks.iter().map(|b| b.row_empty + b.row_conflicts).sum();
    assert!(close(e.joules["dram"], (r.memory.total_bytes as f64 / 8.0 * 1300.0 + rows as f64 * 1300.0) * pj));
    assert!(close(e.joules_per_frame, e.joules.values().sum()));
    assert!(close(e.joules_per_ray * r.rays as f64, e.joules_per_frame));
    assert!(close(e.watts, e.joules_per_frame * r.frames_per_second));
    // The figures are parameters: doubling the multiply energy changes energy only.
    cfg.set("energy.fp_mul_pj=7.4").unwrap();
    cfg.set("energy.leakage_mw_per_mm2=100").unwrap();
    let r2 = frames(&scene, &[cam], &Measure::default(), &cfg, Algorithm::Whitted).remove(0).report;
    let e2 = r2.energy.as_ref().unwrap();
    assert_eq!(r2.cycles, r.cycles);
    assert!(close(e2.joules["intersection"], r.triangle_tests as f64 * (27.0 * 7.4 + 23.0 * 0.9) * pj));
    assert!(close(e2.joules["leakage"], e2.area_mm2 * 0.1 * r.cycles as f64 / (cfg.clock_mhz * 1e6)));
    assert!(cfg.set("energy.fp_add_pj=-1").is_ok() && cfg.validate().is_err());
}

#[test]
fn cost_images_add_up_to_the_report() {
    let scene = whitted_scene(Accel::Kd);
    let cam = CameraRecord { width: 32, height: 24, ..*scene.view().unwrap().camera().unwrap() };
    for algo in [Algorithm::Cast, Algorithm::Whitted] {
        let run = frames(&scene, &[cam], &Measure::default(), &HwConfig::default(), algo).remove(0);
        let r = &run.report;
        assert_eq!(run.cost.len(), 32 * 24);
        let sum = |k: usize| run.cost.iter().map(|c| c[k]).sum::<f64>();
        let node_tests: u64 = r.units.iter().filter(|u| u.name.starts_with("traversal")).map(|u| u.active_lanes).sum();
        assert_eq!(sum(1), node_tests as f64, "{algo:?}: ray-node tests");
        assert_eq!(sum(2), r.triangle_tests as f64, "{algo:?}: ray-triangle tests");
        assert!(run.cost.iter().all(|c| c.iter().all(|v| v.is_finite() && *v >= 0.0)));
        // Every pixel's packets were in flight for some cycles, none longer than the frame.
        assert!(run.cost.iter().all(|c| c[0] > 0.0));
        assert!(sum(3) > 0.0);
    }
}
