//! Scenes that move: a deforming soup and a static one, placed by instances whose
//! transforms change, animated over frames. Whatever the update — refit, fast or full
//! rebuild, the automatic choice, Parker's unstructured meshes, Reinhard's hierarchical
//! grid with wrap-around — every frame's hits are
//! bit for bit those of the same frame built from scratch as a static instanced scene,
//! for single rays and packets. Bad updates are refused with a message naming them.

use glam::{EulerRot, Mat4, Quat, Vec3};
use proptest::prelude::*;
use raypipe::build::dynamic::{DynamicImages, DynamicState, Update};
use raypipe::build::instanced::{affine_of, Instance, InstancedScene};
use raypipe::input::mesh::Mesh;
use raypipe::render::instanced::tracer::{trace_instance, trace_instance_packet};
use raypipe::render::instanced::Instances;
use raypipe::scene::{Accel, BuildOptions};
use raypipe_core::image::instanced::InstancedView;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::instanced::InstanceHit;
use raypipe_core::{Ray, RayCounters, Watertight};

fn soup(n: usize, seed: u64) -> Mesh {
    let mut g = seed;
    let mut r = move || {
        g = g.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (g >> 40) as f32 / (1u64 << 24) as f32 * 4.0 - 2.0
    };
    let positions: Vec<[f32; 3]> = (0..3 * n).map(|_| [r(), r(), r()]).collect();
    let triangles = (0..n as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    Mesh { positions, triangles, ..Default::default() }
}

fn placed(k: usize, frame: usize) -> [f32; 12] {
    let a = 0.3 * frame as f32 + k as f32;
    affine_of(Mat4::from_scale_rotation_translation(
        Vec3::splat(1.0 + 0.1 * k as f32),
        Quat::from_euler(EulerRot::ZYX, a, 0.5 * a, 0.0),
        Vec3::new(3.0 * k as f32 - 3.0, 0.2 * frame as f32, 0.0),
    ))
}

/// The deforming mesh at `frame`: every vertex moved along its own wave.
fn deformed(base: &Mesh, frame: usize, amplitude: f32) -> Vec<[f32; 3]> {
    base.positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let w = (frame as f32 * 0.7 + i as f32 * 0.37).sin() * amplitude;
            [p[0] + w, p[1] - 0.5 * w, p[2] + (i % 3) as f32 * 0.1 * w]
        })
        .collect()
}

fn scene_at(base: &InstancedScene, deforming: &Mesh, frame: usize, amplitude: f32) -> InstancedScene {
    let mut s = base.clone();
    s.bottoms[0].positions = deformed(deforming, frame, amplitude);
    for (k, inst) in s.instances.iter_mut().enumerate() {
        inst.to_world = placed(k, frame);
    }
    s
}

fn rays(n: usize) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let a = i as f32 * 0.61;
            let o = Vec3::new(12.0 * a.cos(), 3.0 * (a * 1.7).sin(), 12.0 * a.sin());
            let target = Vec3::new(4.0 * (a * 2.3).sin(), 2.0 * (a * 0.9).cos(), 1.5 * (a * 3.1).sin());
            Ray::new(o, target - o)
        })
        .collect()
}

fn hits(s: &Instances<'_>, rays: &[Ray]) -> Vec<Option<(u32, u32, u32)>> {
    let key = |h: Option<InstanceHit>| h.map(|h| (h.hit.t.to_bits(), h.instance, h.hit.prim));
    let single: Vec<_> =
        rays.iter().map(|r| key(trace_instance::<Watertight>(s, r, &mut RayCounters::default()))).collect();
    for chunk in rays.chunks(16).enumerate() {
        let mut p = RayPacket::<16>::new();
        p.fill(chunk.1);
        let mut h = [None; 16];
        trace_instance_packet::<Watertight, 16>(s, &p, false, &mut h, &mut PacketCounters::default());
        for (k, got) in h.iter().take(chunk.1.len()).enumerate() {
            assert_eq!(key(*got), single[chunk.0 * 16 + k], "packet lane {k}");
        }
    }
    single
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn every_update_gives_the_hits_of_a_scene_built_from_scratch(
        seed in any::<u64>(),
        n in 4usize..120,
        amplitude in 0.0f32..1.5,
        threshold in 1.0f64..3.0,
    ) {
        let deforming = soup(n, seed);
        let still = soup(30, seed ^ 0x5555);
        let first = Mesh { positions: deformed(&deforming, 0, amplitude), ..deforming.clone() };
        let base = InstancedScene {
            name: "moving".into(),
            bottoms: vec![first, still],
            bottom_names: vec!["wave".into(), "still".into()],
            instances: (0..4).map(|k| Instance { bottom: (k % 2) as u32, to_world: placed(k, 0), material: None }).collect(),
            ..Default::default()
        };
        let opts = BuildOptions { accel: Accel::Bvh4, ..Default::default() };
        let rays = rays(96);
        let frames = 5;
        // Each frame built from scratch.
        let mut want = Vec::new();
        for f in 0..frames {
            let built = scene_at(&base, &deforming, f, amplitude).build(&opts).expect("frame builds");
            let view = InstancedView::parse(&built.bytes).expect("valid");
            want.push(hits(&Instances::of(&view, "frame").expect("valid"), &rays));
        }
        for update in [Update::Refit, Update::Rebuild, Update::Full, Update::Auto, Update::Parker, Update::Reinhard] {
            let images = DynamicImages::build(&base, &[true, false], &opts, update).expect("images build");
            let views = images.views().expect("valid images");
            let mut state = DynamicState::new(&base, &views, &[true, false], update, threshold).expect("state");
            for (f, want) in want.iter().enumerate() {
                if f > 0 {
                    state.set_vertices(0, &deformed(&deforming, f, amplitude)).expect("vertices");
                    for k in 0..4 {
                        state.set_transform(k, placed(k as usize, f)).expect("transform");
                    }
                    let stats = state.commit(&views);
                    prop_assert!(stats.triangles == n as u64);
                }
                let levels = state.levels();
                let frame = state.frame(&views, &levels).expect("a valid frame");
                let got = hits(&frame, &rays);
                prop_assert_eq!(&got, want, "{:?}, frame {}", update, f);
            }
        }
    }
}

#[test]
fn bad_updates_are_refused_by_name() {
    let base = InstancedScene {
        name: "moving".into(),
        bottoms: vec![soup(10, 1), soup(10, 2)],
        bottom_names: vec!["a".into(), "b".into()],
        instances: vec![Instance { bottom: 0, to_world: placed(0, 0), material: None }],
        ..Default::default()
    };
    let opts = BuildOptions::default();
    let images = DynamicImages::build(&base, &[true, false], &opts, Update::Refit).unwrap();
    let views = images.views().unwrap();
    let mut state = DynamicState::new(&base, &views, &[true, false], Update::Refit, 1.5).unwrap();
    let err = |r: Result<(), _>| -> String {
        let e: Box<dyn std::fmt::Display> = match r {
            Ok(()) => panic!("accepted"),
            Err(e) => Box::new(e),
        };
        e.to_string()
    };
    assert!(err(state.set_vertices(0, &[[0.0; 3]; 5])).contains("5 vertices posted, the mesh has 30"));
    let mut nan = soup(10, 1).positions;
    nan[7][1] = f32::NAN;
    assert!(err(state.set_vertices(0, &nan)).contains("vertex 7 is NaN"));
    assert!(err(state.set_vertices(1, &soup(10, 2).positions)).contains("mesh 1 was not built to deform"));
    assert!(err(state.set_vertices(9, &[])).contains("mesh 9 does not exist"));
    let flat = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    assert!(err(state.set_transform(0, flat)).contains("singular"));
    let mut inf = placed(0, 0);
    inf[3] = f32::INFINITY;
    assert!(err(state.set_transform(0, inf)).contains("NaN or infinite"));
    assert!(err(state.set_transform(3, placed(0, 0))).contains("instance 3 does not exist"));
    // Nothing bad was applied: the frame is still valid.
    state.commit(&views);
    assert!(state.frame(&views, &state.levels()).is_ok());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// Reinhard's grid stays put while its triangles drift out of it — they wrap around,
    /// nothing is rebuilt — and is rebuilt only once their box has outgrown it; every
    /// frame's hits are those of the frame built from scratch.
    #[test]
    fn reinhard_wraps_drifting_triangles_and_rebuilds_when_they_spread(
        seed in any::<u64>(),
        n in 4usize..150,
        drift in prop::array::uniform3(-5.0f32..5.0),
        accel in prop_oneof![Just(Accel::Grid), Just(Accel::Bvh)],
    ) {
        let deforming = soup(n, seed);
        // Frames 0-3 drift by `drift` per frame (the soup is 4 wide); frames 4-5 spread it
        // threefold each time around its centre.
        let at = |f: usize| -> Vec<[f32; 3]> {
            let (moved, spread) = (f.min(3) as f32, 3f32.powi(f.saturating_sub(3) as i32));
            deforming.positions.iter().map(|p| [0, 1, 2].map(|a| p[a] * spread + drift[a] * moved)).collect()
        };
        let base = InstancedScene {
            name: "drift".into(),
            bottoms: vec![deforming.clone()],
            bottom_names: vec!["soup".into()],
            instances: vec![Instance { bottom: 0, to_world: affine_of(Mat4::IDENTITY), material: None }],
            ..Default::default()
        };
        let opts = BuildOptions { accel, ..Default::default() };
        let images = DynamicImages::build(&base, &[true], &opts, Update::Reinhard).expect("images build");
        let views = images.views().expect("valid images");
        let mut state = DynamicState::new(&base, &views, &[true], Update::Reinhard, 1.5).expect("state");
        for f in 0..6 {
            let positions = at(f);
            if f > 0 {
                state.set_vertices(0, &positions).expect("vertices");
                let stats = state.commit(&views);
                let spreading = f >= 4;
                prop_assert_eq!(stats.rebuilds > 0, spreading, "frame {}: {:?}", f, stats);
            }
            let mut scratch = base.clone();
            scratch.bottoms[0].positions = positions;
            let built = scratch.build(&opts).expect("frame builds");
            let view = InstancedView::parse(&built.bytes).expect("valid");
            let want = Instances::of(&view, "frame").expect("valid");
            // Rays at the soup where it is now.
            let c = Vec3::from(drift) * f.min(3) as f32;
            let s = 3f32.powi(f.saturating_sub(3) as i32);
            let rays: Vec<Ray> = rays(96).iter().map(|r| Ray::new(r.origin * s + c, r.dir)).collect();
            let levels = state.levels();
            let frame = state.frame(&views, &levels).expect("a valid frame");
            prop_assert_eq!(hits(&frame, &rays), hits(&want, &rays), "frame {}", f);
        }
    }
}
