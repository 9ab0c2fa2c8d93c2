//! Purcell's stream machine: its image is the host's for every architecture,
//! oracle, unrolling and algorithm; every ray retires; per pass, processed iterations =
//! useful + idle and the stencil is read once per covered fragment (multipass) or never
//! (branching); no oracle beats the optimal bound and the clairvoyant one meets it on a
//! single ray; unrolling and suppression change no hit; the naive oracle never needs
//! fewer passes than Delany's; without a cache, texture words are the random-access
//! words.

use proptest::prelude::*;
use raypipe::hw::frame_setup::FrameSetup;
use raypipe::hw::stream::run_stream;
use raypipe::render::tracer::trace;
use raypipe::render::{render, Algorithm, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::{CameraRecord, LightRecord};
use raypipe_core::pixel_filter::Filter;
use raypipe_core::{NoProbe, RayCounters, SceneView, Vec3, Watertight};
use raypipe_hw::stream::counters::PassKind;
use raypipe_hw::stream::{Architecture, CostModel, Kernel, Oracle, StreamConfig, StreamMachine, StreamReport, Unroll};
use raypipe_tests::{build_soup, root};

fn configs() -> Vec<StreamConfig> {
    let m = |oracle, unroll: (u32, u32), suppress| StreamConfig {
        oracle,
        unroll: Unroll { traverse: unroll.0, intersect: unroll.1 },
        suppress,
        ..StreamConfig::default()
    };
    vec![
        m(Oracle::Delany(0.2), (1, 1), false),
        m(Oracle::Naive, (1, 1), false),
        m(Oracle::Optimal, (1, 1), false),
        m(Oracle::Delany(0.2), (4, 2), false),
        m(Oracle::Delany(0.5), (4, 2), true),
        m(Oracle::Optimal, (3, 2), true),
        StreamConfig { arch: Architecture::Branching, ..StreamConfig::default() },
        StreamConfig { arch: Architecture::Branching, simd: 16, ..StreamConfig::default() },
        StreamConfig { cache: "off".parse().unwrap(), ..StreamConfig::default() },
        StreamConfig { cache_state: false, output_words: 16, ..StreamConfig::default() },
    ]
}

/// Conservation laws every report obeys.
fn check_conservation(r: &StreamReport, screen: u64) {
    let multipass = r.config.arch == Architecture::Multipass;
    for p in &r.passes {
        let kind = p.kind.unwrap();
        if multipass {
            assert_ne!(kind, PassKind::Fused);
            if matches!(kind, PassKind::Traverse | PassKind::Intersect) {
                assert_eq!(p.processed * p.iterations as u64, p.useful + p.idle, "{p:?}");
                assert!(p.processed > 0 || r.config.oracle == Oracle::Naive, "an empty pass: {p:?}");
            } else {
                assert_eq!(p.idle, 0);
            }
            if kind == PassKind::Generate {
                assert_eq!(p.stencil.reads, 0);
            } else if p.wave == 0 {
                assert_eq!(p.stencil.reads, screen, "{p:?}");
            }
        } else {
            assert_eq!(kind, PassKind::Fused);
            assert_eq!((p.stencil.reads, p.stencil.writes), (0, 0));
            // Eye rays are made in registers: the first wave reads no stream input.
            if p.wave == 0 {
                assert_eq!(p.state_read, 0, "{p:?}");
            }
        }
    }
    assert_eq!(r.stencil_reads, r.passes.iter().map(|p| p.stencil.reads).sum::<u64>());
    if multipass {
        // Every ray that was set up reaches the shading pass, and each loop ends with
        // no active ray. Setup writes 12 words: as many passes as outputs allow.
        let setup_passes = r.costs.get(Kernel::Setup).w.div_ceil(r.config.output_words as u64);
        for (w, &rays) in r.rays_by_wave.iter().enumerate() {
            let setup: u64 = r
                .passes
                .iter()
                .filter(|p| p.wave == w as u32 && p.kind == Some(PassKind::Setup))
                .map(|p| p.processed)
                .sum();
            assert_eq!(setup, rays * setup_passes, "wave {w}");
        }
        for (i, p) in r.passes.iter().enumerate() {
            if p.kind == Some(PassKind::Shade) && i > 0 {
                let before = &r.passes[i - 1];
                if matches!(before.kind, Some(PassKind::Traverse | PassKind::Intersect | PassKind::Setup)) {
                    assert_eq!(before.active_after, 0, "{before:?}");
                }
            }
        }
        let t = &r.table2;
        assert!(t.traverse_passes + t.intersect_passes >= t.optimal_passes, "{t:?}");
        // Purcell's SIMD efficiency: a share of the screen's fragments.
        if let Some(paper) = t.simd_screen {
            assert!(paper > 0.0 && paper <= 1.0, "{t:?}");
        }
        for p in
            r.passes.iter().filter(|p| p.wave == 0 && matches!(p.kind, Some(PassKind::Traverse | PassKind::Intersect)))
        {
            assert_eq!(p.covered, screen, "{p:?}");
        }
    }
}

fn small_camera(view: &SceneView<'_>, w: u32, h: u32) -> CameraRecord {
    let mut cam = *view.camera().unwrap();
    (cam.width, cam.height) = (w, h);
    cam
}

#[test]
fn the_image_is_the_hosts_for_every_architecture_oracle_and_algorithm() {
    let glossy = root().join("fixtures/glossy.obj");
    let tetra = root().join("fixtures/tetra.obj");
    let sky =
        LightRecord { position: [0.9, 0.6, 0.3], kind: LightRecord::ENVIRONMENT, color: [0.2, 0.4, 0.8], triangle: 0 };
    for (input, algo, samples, filter) in [
        (None, Algorithm::Cast, 1, Filter::Box),
        (None, Algorithm::Cast, 4, Filter::Gaussian),
        (None, Algorithm::Shadow, 4, Filter::Box),
        (None, Algorithm::Whitted, 2, Filter::Tent),
        (None, Algorithm::Path, 2, Filter::Box),
        // Blinn–Phong highlights and glossy bounces.
        (Some(&glossy), Algorithm::Whitted, 1, Filter::Box),
        (Some(&glossy), Algorithm::Path, 2, Filter::Tent),
        // A small object under a sky: eye rays that miss the scene's box see it too.
        (Some(&tetra), Algorithm::Cast, 1, Filter::Box),
        (Some(&tetra), Algorithm::Path, 2, Filter::Box),
    ] {
        let lights = if input == Some(&tetra) { vec![sky] } else { Vec::new() };
        let scene =
            scene::load(input.map(|p| p.as_path()), &BuildOptions { accel: Accel::Grid, lights, ..Default::default() })
                .unwrap();
        let view = scene.view().unwrap();
        let cam = small_camera(&view, 40, 32);
        let opts =
            RenderOptions { algo, samples, filter, bounces: 2, max_depth: 3, threads: Some(2), ..Default::default() };
        let host = render(&view, &cam, &opts).unwrap();
        let shader = opts.shader(Vec3::from(cam.background));
        for cfg in configs() {
            let (frame, report) = run_stream(
                &view,
                &cam,
                &cfg,
                &CostModel::default(),
                &FrameSetup {
                    shader,
                    shadow_caster: algo == Algorithm::Shadow,
                    sampler: opts.sampler(),
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(frame.pixels == host.pixels, "{input:?} {algo:?} {samples} samples {cfg:?}");
            assert!(frame.radiance == host.radiance, "linear radiance: {input:?} {algo:?} {samples} samples {cfg:?}");
            check_conservation(&report, 40 * 32);
            if algo != Algorithm::Cast {
                assert!(report.rays_by_wave.len() > 1, "{algo:?} emitted no rays");
            }
            if cfg.cache.size_bytes == 0 {
                // Without a cache, the texture words are the random-access words.
                let words: u64 = report.classes.iter().filter(|c| c.class != "state").map(|c| c.words).sum();
                let random: f64 = report.kernels.iter().map(|k| k.totals.random_words).sum();
                assert_eq!(words as f64, random);
                assert!(report.classes.iter().all(|c| c.bytes_with_cache == c.bytes_without_cache));
            }
        }
    }
}

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5), 1 => -2.0f32..2.0]
}

fn soup_view(positions: Vec<[f32; 3]>, picks: &[[prop::sample::Index; 3]], min_dim: u32) -> raypipe::scene::Scene {
    let n = positions.len();
    let tris = picks.iter().map(|[a, b, c]| [a.index(n) as u32, b.index(n) as u32, c.index(n) as u32]).collect();
    build_soup(positions, tris, Accel::Grid, min_dim)
}

fn run(view: &SceneView<'_>, eye: EyeRays, cfg: &StreamConfig) -> (Vec<Option<raypipe_core::Hit>>, StreamReport) {
    let mut m = StreamMachine::<Watertight>::new(*view, eye, Vec3::ZERO, None, cfg, CostModel::default()).unwrap();
    m.run(|_, _| {}).unwrap();
    (m.hits.clone(), m.report())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// On random triangle soups and views: every architecture, oracle, unrolling and
    /// suppression gives the host's hit for every pixel, and obeys the conservation laws
    /// (loop passes never beat the bound).
    #[test]
    fn hits_and_pass_counts_on_random_scenes(
        positions in prop::collection::vec([coord(), coord(), coord()], 3..14),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..20),
        min_dim in 1u32..6,
        eye in [-6.0f32..6.0, -6.0f32..6.0, -6.0f32..6.0],
        fov in 30.0f32..100.0,
    ) {
        let scene = soup_view(positions, &picks, min_dim);
        let view = scene.view().unwrap();
        let cam = Camera { eye: Vec3::from(eye) + Vec3::new(0.0, 0.0, 7.0), look_at: Vec3::ZERO, up: Vec3::Y, vfov_deg: fov, width: 12, height: 10 };
        let Ok(eye) = EyeRays::new(&cam) else { return Ok(()) };
        let (lo, hi) = view.test_bounds();
        let host: Vec<_> = (0..10).flat_map(|y| (0..12).map(move |x| (x, y))).map(|(x, y)| {
            eye.ray_in_scene(x, y, lo, hi).and_then(|r| trace::<Watertight, _>(&view, &r, &mut NoProbe, &mut RayCounters::default()))
        }).collect();
        for cfg in configs() {
            let (hits, report) = run(&view, eye, &cfg);
            prop_assert_eq!(&hits, &host, "{:?}", cfg);
            check_conservation(&report, 120);
        }
    }

    /// One ray: the clairvoyant oracle needs exactly the bound, with and without
    /// unrolling.
    #[test]
    fn the_optimal_oracle_meets_the_bound_on_one_ray(
        positions in prop::collection::vec([coord(), coord(), coord()], 3..14),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..20),
        min_dim in 1u32..8,
        eye in [-6.0f32..6.0, -6.0f32..6.0, -6.0f32..6.0],
        unroll in (1u32..5, 1u32..4),
    ) {
        let scene = soup_view(positions, &picks, min_dim);
        let view = scene.view().unwrap();
        let cam = Camera { eye: Vec3::from(eye) + Vec3::new(0.0, 0.0, 7.0), look_at: Vec3::ZERO, up: Vec3::Y, vfov_deg: 10.0, width: 1, height: 1 };
        let Ok(eye) = EyeRays::new(&cam) else { return Ok(()) };
        let cfg = StreamConfig { oracle: Oracle::Optimal, unroll: Unroll { traverse: unroll.0, intersect: unroll.1 }, ..StreamConfig::default() };
        let (_, r) = run(&view, eye, &cfg);
        let t = &r.table2;
        prop_assert_eq!(t.traverse_passes + t.intersect_passes, t.optimal_passes, "{:?}", t);
        if unroll == (1, 1) {
            prop_assert_eq!(t.optimal_passes, t.max_steps + t.max_intersections);
        }
    }
}

/// Naive alternation against Delany's rule over many random scenes and views (a fixed
/// sequence, so the figures are reproducible). Per scene the naive oracle is not always
/// worse — on a tiny screen, Delany's rule can keep a few rays waiting to intersect
/// while the others traverse, and then those few need extra passes at the end (found
/// by the property test above: 23 naive passes against 25) — so the check is on the
/// whole set: naive needs more passes in total and is no better on most scenes.
#[test]
fn naive_alternation_needs_more_passes_than_delany() {
    let mut seed = 0x2002_5eedu64;
    let mut next = move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 33) as u32
    };
    let (mut naive_total, mut delany_total, mut naive_better, mut scenes) = (0u64, 0u64, 0u32, 0u32);
    for _ in 0..200 {
        let n = 3 + next() % 12;
        let positions: Vec<[f32; 3]> = (0..n).map(|_| [0; 3].map(|_| (next() % 17) as f32 * 0.5 - 4.0)).collect();
        let tris: Vec<[u32; 3]> = (0..1 + next() % 30).map(|_| [next() % n, next() % n, next() % n]).collect();
        let scene = build_soup(positions, tris, Accel::Grid, 1 + next() % 8);
        let view = scene.view().unwrap();
        let e = [0; 3].map(|_| (next() % 1200) as f32 / 100.0 - 6.0);
        let cam = Camera {
            eye: Vec3::from(e) + Vec3::new(0.0, 0.0, 7.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_deg: 60.0,
            width: 16,
            height: 16,
        };
        let Ok(eye) = EyeRays::new(&cam) else { continue };
        let passes = |oracle| {
            let t = run(&view, eye, &StreamConfig { oracle, ..StreamConfig::default() }).1.table2;
            t.traverse_passes + t.intersect_passes
        };
        let (naive, delany) = (passes(Oracle::Naive), passes(Oracle::Delany(0.2)));
        naive_total += naive;
        delany_total += delany;
        naive_better += (naive < delany) as u32;
        scenes += 1;
    }
    eprintln!("naive {naive_total} passes, delany {delany_total}; naive better on {naive_better} of {scenes} scenes");
    assert!(naive_total > delany_total, "naive {naive_total} <= delany {delany_total}");
    assert!(naive_better * 10 < scenes, "naive better on {naive_better} of {scenes} scenes");
}

/// Purcell §2.2: a pass writes at most two RGBA outputs. The 12-word setup takes two
/// passes and Whitted's shading (a colour and 12-word records) more than one; a machine
/// with wider outputs needs one of each. Repeats read the stencil again and cost
/// instructions, and the image does not change.
#[test]
fn passes_write_at_most_their_outputs() {
    let scene = scene::load(None, &BuildOptions { accel: Accel::Grid, ..Default::default() }).unwrap();
    let view = scene.view().unwrap();
    let cam = small_camera(&view, 24, 20);
    let opts = RenderOptions { algo: Algorithm::Whitted, samples: 1, max_depth: 2, ..Default::default() };
    let setup = FrameSetup { shader: opts.shader(Vec3::from(cam.background)), ..Default::default() };
    let run_with = |output_words| {
        let cfg = StreamConfig { output_words, ..StreamConfig::default() };
        run_stream(&view, &cam, &cfg, &CostModel::default(), &setup).unwrap()
    };
    let (narrow_frame, narrow) = run_with(8);
    let (wide_frame, wide) = run_with(64);
    assert!(narrow_frame.pixels == wide_frame.pixels);
    let per_screen = |r: &StreamReport, kind: PassKind| -> Vec<usize> {
        let mut groups: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
        for p in r.passes.iter().filter(|p| p.kind == Some(kind)) {
            *groups.entry((p.wave, p.screen)).or_default() += 1;
        }
        groups.into_values().collect()
    };
    assert!(per_screen(&wide, PassKind::Setup).iter().all(|&n| n == 1));
    assert!(per_screen(&wide, PassKind::Shade).iter().all(|&n| n == 1));
    assert!(per_screen(&narrow, PassKind::Setup).iter().all(|&n| n == 2));
    let shades = per_screen(&narrow, PassKind::Shade);
    // The eye rays' shading writes a colour and a shadow ray (the box's one light; its
    // walls are diffuse): 4 + 12 words, two passes. The shadow rays' ends write 4.
    assert_eq!(shades, [2, 1]);
    assert!(narrow.instructions > wide.instructions);
    assert!(narrow.stencil_reads > wide.stencil_reads);
    assert_eq!(narrow.state_written, wide.state_written);
}
