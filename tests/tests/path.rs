//! Path tracing: a path's weight never grows from bounce to bounce (without
//! Russian roulette), and the image — random numbers included — is the same for every
//! structure, packet size and thread count, and equal to its golden image.

use std::path::Path;

use proptest::prelude::*;
use raypipe::render::packets::PacketSize;
use raypipe::render::tracer::trace;
use raypipe::render::{render, Algorithm, Frame, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions};
use raypipe_core::image::CameraRecord;
use raypipe_core::shade::path::{shade_path, PathOptions};
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::{NoProbe, Ray, RayCounters, Vec3, Watertight};
use raypipe_tests::{check_golden, root};

fn render_path(path: &Path, accel: Accel, packet: PacketSize, threads: usize, roulette: bool) -> Frame {
    let scene = scene::load(Some(path), &BuildOptions { accel, ..Default::default() }).unwrap();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 64, height: 48, ..*view.camera().unwrap() };
    let opts = RenderOptions {
        threads: Some(threads),
        packet,
        algo: Algorithm::Path,
        samples: 4,
        bounces: 3,
        roulette,
        ..Default::default()
    };
    render(&view, &cam, &opts).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Follows random paths through the Whitted fixture (mirror, glass, diffuse): every
    /// bounce's weight is at most its parent's, component by component.
    #[test]
    fn energy_never_grows_along_a_path(
        pixel in 0u32..100_000,
        sample in 0u32..64,
        dir in [-1.0f32..1.0, -1.0f32..0.2, -1.0f32..-0.1],
    ) {
        let scene = scene::load(Some(&root().join("fixtures/whitted.obj")), &BuildOptions::default()).unwrap();
        let view = scene.view().unwrap();
        let opts = PathOptions::new(6, false, Vec3::ZERO);
        let ray = Ray::new(Vec3::new(0.4, 1.7, 4.6), Vec3::from(dir));
        let mut stack = vec![RayRecord { sample, ..RayRecord::primary(ray, pixel) }];
        while let Some(rec) = stack.pop() {
            let hit = trace::<Watertight, _>(&view, &rec.ray, &mut NoProbe, &mut RayCounters::default());
            let mut out = Vec::new();
            let now = shade_path(&view, &rec, hit, &opts, &mut NoProbe, &mut |r| out.push(r));
            prop_assert!(now.is_finite() && now.min_element() >= 0.0);
            for child in out {
                if child.kind == RayKind::Shadow {
                    continue;
                }
                prop_assert!(child.weight.cmple(rec.weight).all(), "{:?} grew to {:?}", rec.weight, child.weight);
                prop_assert_eq!(child.depth, rec.depth + 1);
                stack.push(child);
            }
        }
    }
}

#[test]
fn path_traced_image_is_golden_and_the_same_for_every_structure_packet_and_thread_count() {
    let path = root().join("fixtures/whitted.obj");
    let first = render_path(&path, Accel::Bvh4, PacketSize::P64, 2, false);
    check_golden("path_64x48.png", &first);
    for (i, accel) in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::None].into_iter().enumerate() {
        for packet in [PacketSize::Single, PacketSize::P16] {
            let frame = render_path(&path, accel, packet, 1 + i % 3, false);
            assert!(frame.pixels == first.pixels, "{accel:?} {packet:?}");
        }
    }
    // Roulette changes the image but not its determinism.
    let a = render_path(&path, Accel::Bvh, PacketSize::Single, 1, true);
    let b = render_path(&path, Accel::Grid, PacketSize::P4, 3, true);
    assert!(a.pixels == b.pixels);
    assert!(a.pixels != first.pixels);
}

/// Next-event estimation to an emissive quad above a floor: every sampled shadow ray
/// reaches its point on the emitter unblocked (the emitter does not shadow itself), and
/// its weight falls off with distance.
#[test]
fn area_light_samples_are_never_blocked_by_the_emitter_itself() {
    use raypipe::input::mesh::Mesh;
    use raypipe_core::image::MaterialRecord;
    use raypipe_core::traverse::occlusion::occluded;
    let positions = vec![
        [-2.0, 0.0, -2.0],
        [2.0, 0.0, -2.0],
        [2.0, 0.0, 2.0],
        [-2.0, 0.0, 2.0],
        [-0.3, 2.0, -0.3],
        [0.3, 2.0, -0.3],
        [0.3, 2.0, 0.3],
        [-0.3, 2.0, 0.3],
    ];
    // Floor facing up; emitter facing down.
    let triangles = vec![[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]];
    let light = MaterialRecord { emission: [10.0; 3], ..MaterialRecord::DEFAULT };
    let mesh = Mesh {
        positions,
        triangles,
        tri_materials: vec![0, 0, 1, 1],
        materials: vec![MaterialRecord::DEFAULT, light],
        material_names: vec!["floor".into(), "light".into()],
        ..Default::default()
    };
    let scene = scene::build("lit".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap();
    let view = scene.view().unwrap();
    let opts = PathOptions::new(0, false, Vec3::ZERO);
    let mut near = 0.0f32;
    let mut far = 0.0f32;
    for i in 0..64u32 {
        let x = (i % 8) as f32 * 0.5 - 1.75;
        let z = (i / 8) as f32 * 0.5 - 1.75;
        let ray = Ray::new(Vec3::new(x, 1.0, z + 0.01), Vec3::new(0.0, -1.0, 0.0));
        let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
        assert!(hit.is_some_and(|h| h.prim < 2));
        let mut out = Vec::new();
        shade_path(&view, &RayRecord::primary(ray, i), hit, &opts, &mut NoProbe, &mut |r| out.push(r));
        let shadows: Vec<_> = out.iter().filter(|r| r.kind == RayKind::Shadow).collect();
        assert_eq!(shadows.len(), 1, "one emitting triangle picked by power per hit");
        for s in &shadows {
            assert!(
                !occluded::<Watertight, _>(&view, &s.ray, &mut NoProbe, &mut RayCounters::default()),
                "{:?}",
                s.ray
            );
            let w = s.weight.x;
            if x.abs() < 0.5 && z.abs() < 0.5 {
                near = near.max(w);
            } else if x.abs() > 1.5 && z.abs() > 1.5 {
                far = far.max(w);
            }
        }
    }
    assert!(near > 2.0 * far && far > 0.0, "near {near}, far {far}");
}

/// A ray that leaves the scene sees the sky, in every algorithm, whether or not its eye
/// ray crossed the scene's box: the corners of a small object's frame show the sky's
/// radiance along their own directions.
#[test]
fn every_algorithm_sees_the_sky_outside_the_scene_box() {
    use raypipe_core::camera::{Camera, EyeRays};
    use raypipe_core::image::LightRecord;
    let sky =
        LightRecord { position: [0.9, 0.6, 0.3], kind: LightRecord::ENVIRONMENT, color: [0.2, 0.4, 0.8], triangle: 0 };
    let opts = BuildOptions { lights: vec![sky], ..Default::default() };
    let scene = scene::load(Some(&root().join("fixtures/tetra.obj")), &opts).unwrap();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 32, height: 24, ..*view.camera().unwrap() };
    let eye = EyeRays::new(&Camera::from(&cam)).unwrap();
    let (lo, hi) = view.test_bounds();
    let outside: Vec<(u32, u32)> = (0..24)
        .flat_map(|y| (0..32).map(move |x| (x, y)))
        .filter(|&(x, y)| eye.sample_ray_in_scene(x, y, 0, lo, hi).is_none())
        .collect();
    assert!(outside.len() > 100, "the frame must show much beyond the scene's box");
    for algo in [Algorithm::Cast, Algorithm::Shadow, Algorithm::Whitted, Algorithm::Path] {
        let frame = render(&view, &cam, &RenderOptions { algo, samples: 1, ..Default::default() }).unwrap();
        for &(x, y) in &outside {
            let want = sky.sky(eye.ray(x, y).dir).to_array();
            let got = frame.radiance[(y * 32 + x) as usize];
            // Within rounding: the sky looks up a renormalized direction.
            assert!(got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6), "{algo:?} ({x}, {y}): {got:?} {want:?}");
        }
    }
}

/// A glossy floor under a large emitter, for multiple importance sampling.
fn glossy_floor_under_a_large_emitter() -> raypipe::scene::Scene {
    use raypipe::input::mesh::Mesh;
    use raypipe_core::image::MaterialRecord;
    let positions = vec![
        [-2.0, 0.0, -2.0],
        [2.0, 0.0, -2.0],
        [2.0, 0.0, 2.0],
        [-2.0, 0.0, 2.0],
        [-1.5, 1.0, -1.5],
        [1.5, 1.0, -1.5],
        [1.5, 1.0, 1.5],
        [-1.5, 1.0, 1.5],
    ];
    let triangles = vec![[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7]];
    let floor =
        MaterialRecord { diffuse: [0.1; 3], specular: [0.8; 3], shininess: 200.0, illum: 2, ..MaterialRecord::DEFAULT };
    let light = MaterialRecord { emission: [2.0; 3], ..MaterialRecord::DEFAULT };
    let mesh = Mesh {
        positions,
        triangles,
        tri_materials: vec![0, 0, 1, 1],
        materials: vec![floor, light],
        material_names: vec!["floor".into(), "light".into()],
        ..Default::default()
    };
    scene::build("mis".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap()
}

/// Multiple importance sampling: a glossy bounce that reaches an emitter brings the
/// power heuristic's share of its light (not nothing, as when only next-event estimation
/// counted emitters), and the next-event sample toward the same point gives up the rest.
#[test]
fn a_glossy_bounce_that_finds_an_emitter_brings_its_share_of_the_light() {
    let scene = glossy_floor_under_a_large_emitter();
    let view = scene.view().unwrap();
    let opts = PathOptions::new(1, false, Vec3::ZERO);
    let (mut found, mut nee_weight, mut nee_full) = (0, 0.0f32, 0.0f32);
    for i in 0..256u32 {
        let ray = Ray::new(Vec3::new(0.0, 0.5, 1.5), Vec3::new(0.0, -0.5, -1.0).normalize());
        let rec = RayRecord { sample: i, ..RayRecord::primary(ray, 3) };
        let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
        let mut out = Vec::new();
        shade_path(&view, &rec, hit, &opts, &mut NoProbe, &mut |r| out.push(r));
        for r in &out {
            match r.kind {
                RayKind::Glossy => {
                    assert!(r.pdf > 0.0 && r.indirect, "a sampled bounce carries its density");
                    let hit = trace::<Watertight, _>(&view, &r.ray, &mut NoProbe, &mut RayCounters::default());
                    if hit.is_some_and(|h| h.prim >= 2) {
                        let now = shade_path(&view, r, hit, &opts, &mut NoProbe, &mut |_| {});
                        let full = r.weight * 2.0;
                        assert!(now.x > 0.0 && now.x <= full.x * 1.0001, "{now:?} of {full:?}");
                        found += 1;
                    }
                }
                RayKind::Shadow => {
                    nee_weight += r.weight.x;
                    nee_full = nee_full.max(r.weight.x);
                }
                _ => {}
            }
        }
    }
    assert!(found > 20, "a sharp lobe under a large emitter reaches it often ({found})");
    assert!(nee_weight > 0.0 && nee_full.is_finite());
}

/// `--clamp` bounds what indirect light adds, but leaves what the eye sees directly (the
/// emitter itself) alone, and without it the image is unchanged.
#[test]
fn the_clamp_bounds_indirect_light_only() {
    let scene = glossy_floor_under_a_large_emitter();
    let view = scene.view().unwrap();
    let cam = CameraRecord {
        width: 24,
        height: 16,
        eye: [0.0, 0.5, 1.9],
        look_at: [0.0, 0.6, 0.0],
        ..*view.camera().unwrap()
    };
    let base = RenderOptions { algo: Algorithm::Path, samples: 8, bounces: 2, ..Default::default() };
    let free = render(&view, &cam, &base).unwrap();
    let unclamped = render(&view, &cam, &RenderOptions { clamp: Some(1e9), ..base }).unwrap();
    assert!(free.radiance == unclamped.radiance, "a clamp nothing reaches changes nothing");
    let tight = render(&view, &cam, &RenderOptions { clamp: Some(0.05), ..base }).unwrap();
    let lum = |c: &[f32; 3]| c[0] + c[1] + c[2];
    let (mut lower, mut emitter_kept) = (0, 0);
    for (a, b) in free.radiance.iter().zip(&tight.radiance) {
        assert!(lum(b) <= lum(a) * 1.0001 + 1e-6, "clamping never brightens: {a:?} {b:?}");
        lower += (lum(b) < lum(a) * 0.999) as u32;
        emitter_kept += (lum(a) >= 6.0 && lum(b) >= 6.0) as u32;
    }
    assert!(lower > 10, "a tight clamp darkens the floor's reflections ({lower} pixels)");
    assert!(emitter_kept > 0, "the emitter seen directly keeps its radiance");
}
