//! "One hit whatever the path" across bricks: for random triangle soups cut into bricks
//! of random sizes, with every structure inside the bricks, the two-level walk returns
//! the flat image's hit bit for bit — closest and any hit — whichever bricks are
//! resident when the ray starts (rays park on missing bricks and resume where they
//! stopped).

use proptest::prelude::*;
use raypipe::build::bricks::{build_bricked, BrickOptions};
use raypipe::input::bricked::{BrickedScene, ResidentBrick};
use raypipe::input::mesh::Mesh;
use raypipe::render::tracer::trace;
use raypipe::scene::{Accel, BuildOptions};
use raypipe_core::image::bricked::Codec;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::two_level::{run_two_level, TopWalk, TwoLevelOutcome};
use raypipe_core::{Hit, NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};
use raypipe_tests::build_soup;

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-8i32..=8).prop_map(|i| i as f32 * 0.5), 1 => -4.0f32..4.0]
}

fn point() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

fn soup() -> impl Strategy<Value = (Vec<[f32; 3]>, Vec<[u32; 3]>)> {
    (prop::collection::vec(point(), 3..40), prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..60)).prop_map(
        |(positions, picks)| {
            let n = positions.len();
            let triangles = picks.iter().map(|t| t.map(|i| i.index(n) as u32)).collect();
            (positions, triangles)
        },
    )
}

fn rays() -> impl Strategy<Value = Vec<([f32; 3], [f32; 3], bool)>> {
    let far = || [-60.0f32..60.0, -60.0f32..60.0, -60.0f32..60.0];
    prop::collection::vec((far(), [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], any::<bool>()), 40)
}

/// A bricked scene of the soup, and every brick loaded.
fn bricked(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    accel: Accel,
    brick_bytes: u64,
    codec: Codec,
    spill: Option<u64>,
) -> (tempfile::TempDir, BrickedScene) {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("soup.rpsb");
    let mesh = Mesh { positions: positions.to_vec(), triangles: triangles.to_vec(), ..Default::default() };
    let opts = BuildOptions { accel, ..Default::default() };
    let mut bopts = BrickOptions::new(brick_bytes, codec);
    // A budget just above the build's working memory (and the mesh's few kilobytes)
    // leaves room for a few dozen records: the partition then runs on disk.
    bopts.memory_budget = spill.map(|s| raypipe::build::bricks::working_memory(&bopts) + 4096 + s);
    build_bricked("soup", mesh, Vec::new(), Default::default(), &opts, &bopts, &out).expect("soup bricks");
    let scene = BrickedScene::open(&out).expect("valid bricked scene");
    (dir, scene)
}

/// Traces `ray` through the bricked scene with only the bricks of `resident` (a bit
/// per brick) in memory at first; a ray that reaches a missing brick is parked, the
/// brick is "loaded", and the ray resumes. Returns the hit and how often it parked.
fn two_level(
    scene: &BrickedScene,
    bricks: &[ResidentBrick],
    ray: &Ray,
    any_hit: bool,
    resident: u64,
) -> (Option<Hit>, u32) {
    let index = scene.view();
    let mut loaded = resident;
    let mut walk = TopWalk::start(ray, any_hit);
    let mut parks = 0;
    loop {
        let mut have = |b: u32| -> Option<SceneView<'_>> {
            (loaded & (1u64 << (b % 64)) != 0).then(|| *bricks[b as usize].view())
        };
        match run_two_level::<Watertight, _>(&mut walk, index, ray, &mut have, &mut NoProbe) {
            TwoLevelOutcome::Done(h) => return (h.map(|h| h.hit), parks),
            TwoLevelOutcome::Missing(b) => {
                // The parked walk is plain data: a copy resumes as well as the original.
                walk = walk.clone();
                parks += 1;
                loaded |= 1u64 << (b % 64);
                if parks > 10_000 {
                    panic!("runaway");
                }
            }
        }
    }
}

fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(&b),
        _ => false,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn bricks_return_the_flat_images_hit(
        (positions, triangles) in soup(),
        accel in prop::sample::select(vec![Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None]),
        brick_bytes in 40u64..600,
        codec in prop::sample::select(vec![Codec::Lz4, Codec::Zstd, Codec::None]),
        resident in any::<u64>(),
        spill in prop::option::of(0u64..8000),
        rays in rays(),
    ) {
        let flat = build_soup(positions.clone(), triangles.clone(), accel, 1);
        let fview = flat.view().expect("valid flat image");
        let (_dir, scene) = bricked(&positions, &triangles, accel, brick_bytes, codec, spill);
        let bricks: Vec<ResidentBrick> =
            (0..scene.view().brick_count()).map(|b| scene.load(b).expect("brick loads").0).collect();
        prop_assert_eq!(scene.view().header().triangle_count, triangles.len() as u64);
        for (o, d, bounded) in &rays {
            let mut ray = Ray::new(Vec3::from(*o), Vec3::from(*d));
            if *bounded {
                ray.t_min = 0.5;
                ray.t_max = 30.0;
            }
            let want = trace::<Watertight, _>(&fview, &ray, &mut NoProbe, &mut RayCounters::default());
            let (got, _) = two_level(&scene, &bricks, &ray, false, resident);
            prop_assert!(same(want, got), "{accel:?}: flat {want:?} != bricked {got:?} for {ray:?}");
            // With nothing resident, a ray that hits must have waited for a brick.
            let (cold, parks) = two_level(&scene, &bricks, &ray, false, 0);
            prop_assert!(same(want, cold));
            prop_assert!(cold.is_none() || parks > 0);
            let blocked = occluded::<Watertight, _>(&fview, &ray, &mut NoProbe, &mut RayCounters::default());
            let (any, _) = two_level(&scene, &bricks, &ray, true, resident);
            prop_assert_eq!(blocked, any.is_some(), "{:?}: any-hit for {:?}", accel, ray);
        }
    }
}

#[test]
fn triangles_shared_by_bricks_give_the_flat_images_hit() {
    // A long floor and long walls under a row of small triangles: the partition's cuts
    // cross the long ones, which every brick they reach then holds.
    let mut positions = vec![[-8.0, 0.0, -1.0], [8.0, 0.0, -1.0], [-8.0, 0.0, 1.0], [8.0, 0.0, 1.0]];
    let mut triangles = vec![[0, 1, 2], [1, 3, 2]];
    for i in 0..40 {
        let x = -8.0 + 0.4 * i as f32;
        let b = positions.len() as u32;
        positions.extend([[x, 0.1, 0.0], [x + 0.3, 0.1, 0.0], [x, 0.5, 0.2], [x, 0.0, -0.9], [x + 0.2, 2.0, -0.9]]);
        triangles.extend([[b, b + 1, b + 2], [b + 3, b + 4, 0]]);
    }
    for accel in [Accel::Bvh4, Accel::Kd, Accel::Grid] {
        let flat = build_soup(positions.clone(), triangles.clone(), accel, 1);
        let fview = flat.view().expect("valid flat image");
        let (_dir, scene) = bricked(&positions, &triangles, accel, 900, Codec::Lz4, None);
        let h = scene.view().header();
        assert_eq!(h.triangle_count, triangles.len() as u64);
        assert!(h.reference_count > h.triangle_count, "{} references", h.reference_count);
        let bricks: Vec<ResidentBrick> =
            (0..scene.view().brick_count()).map(|b| scene.load(b).expect("brick loads").0).collect();
        for k in 0..400u32 {
            let f = |s: u32| ((k.wrapping_mul(2654435761).wrapping_add(s * 40503) >> 8) % 1000) as f32 / 1000.0;
            let o = Vec3::new(-9.0 + 18.0 * f(1), 0.05 + 3.0 * f(2), -3.0 + 6.0 * f(3));
            let d = Vec3::new(f(4) - 0.5, -0.2 - f(5), f(6) - 0.5);
            let ray = Ray::new(o, d);
            let want = trace::<Watertight, _>(&fview, &ray, &mut NoProbe, &mut RayCounters::default());
            for resident in [0, u64::MAX, 0x5555_5555_5555_5555] {
                let (got, _) = two_level(&scene, &bricks, &ray, false, resident);
                assert!(same(want, got), "{accel:?}: flat {want:?} != bricked {got:?}");
            }
        }
    }
}

/// The frames of a scene, flat and bricked, for every cache size, thread count and
/// packet size: the same pixels, bit for bit (radiance included).
fn frames_agree(
    name: &str,
    mesh: Mesh,
    camera: raypipe::input::camera_file::CameraSpec,
    accel: Accel,
    brick_bytes: u64,
) {
    use raypipe::render::bricked::brick_cache::with_cache;
    use raypipe::render::bricked::frame::render_bricked;
    use raypipe::render::packets::PacketSize;
    use raypipe::render::{render, Algorithm, RenderOptions};

    let opts = BuildOptions { accel, ..Default::default() };
    let flat = raypipe::scene::build(name.into(), mesh.clone(), Vec::new(), camera, &opts).expect("flat builds");
    let fview = flat.view().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene.rpsb");
    let bopts = BrickOptions::new(brick_bytes, Codec::Lz4);
    build_bricked(name, mesh, Vec::new(), camera, &opts, &bopts, &out).expect("bricks build");
    let scene = BrickedScene::open(&out).unwrap();
    assert!(scene.view().brick_count() >= 4, "{name}: {} bricks", scene.view().brick_count());
    let mut cam = *fview.camera().unwrap();
    assert_eq!(&cam, scene.view().globals().camera().unwrap());
    (cam.width, cam.height) = (48, 40);
    let largest = scene.view().header().max_brick_size;
    let all: u64 = scene.view().bricks().iter().map(|b| b.image_size).sum();
    for algo in [Algorithm::Cast, Algorithm::Whitted] {
        for (samples, packet, threads) in [(1, PacketSize::Single, 1), (2, PacketSize::P16, 2), (1, PacketSize::P64, 3)]
        {
            let o = RenderOptions { algo, samples, packet, threads: Some(threads), ..Default::default() };
            let want = render(&fview, &cam, &o).unwrap();
            for (cache, loaders) in [(largest, 1), (largest * 3, 2), (all, 3)] {
                let (got, stats) = with_cache(&scene, cache, loaders, |c| render_bricked(&scene, c, &cam, &o)).unwrap();
                assert_eq!(got.pixels, want.pixels, "{name} {algo:?} {packet:?} cache {cache}");
                let bits =
                    |f: &raypipe::render::Frame| f.radiance.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&got), bits(&want), "{name} {algo:?} {packet:?} cache {cache}: radiance");
                assert!(stats.trace.brick_visits > 0);
            }
        }
    }
}

#[test]
fn bricked_frames_equal_flat_frames_for_the_cornell_box() {
    let raypipe::scene::Source::Mesh { mesh, camera, .. } = raypipe::scene::load_source(None).unwrap() else {
        panic!("the default scene is a mesh")
    };
    // Tiny bricks, so that the box's few triangles still make several.
    frames_agree("cornell", mesh, camera, Accel::Bvh4, 300);
}

#[test]
fn bricked_frames_equal_flat_frames_for_a_building() {
    for accel in [Accel::Grid, Accel::Kd, Accel::Bvh] {
        let g = raypipe::input::generate::generate("building:floors=1,rooms=3,seed=4", Some("inside")).unwrap();
        frames_agree("building", g.mesh, g.camera, accel, 24 << 10);
    }
}

/// A PLY file of a generated building, binary or ASCII, with per-vertex normals.
fn write_ply(path: &std::path::Path, mesh: &Mesh, binary: bool) {
    use std::io::Write;
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let format = if binary { "binary_little_endian" } else { "ascii" };
    write!(
        f,
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .unwrap();
    for (i, p) in mesh.positions.iter().enumerate() {
        let n = [0.0f32, (i % 3) as f32 * 0.5, 1.0];
        if binary {
            for c in p.iter().chain(&n) {
                f.write_all(&c.to_le_bytes()).unwrap();
            }
        } else {
            writeln!(f, "{} {} {} {} {} {}", p[0], p[1], p[2], n[0], n[1], n[2]).unwrap();
        }
    }
    for t in &mesh.triangles {
        if binary {
            f.write_all(&[3u8]).unwrap();
            for v in t {
                f.write_all(&(*v as i32).to_le_bytes()).unwrap();
            }
        } else {
            writeln!(f, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
        }
    }
}

#[test]
fn a_streamed_ply_bricks_to_the_flat_images_frame() {
    use raypipe::build::bricks::source::PlySource;
    use raypipe::input::ply_stream::PlyStream;
    use raypipe::render::bricked::brick_cache::with_cache;
    use raypipe::render::bricked::frame::render_bricked;
    use raypipe::render::{render, Algorithm, RenderOptions};

    let g = raypipe::input::generate::generate("building:floors=1,rooms=2,seed=9", Some("inside")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for binary in [true, false] {
        let ply = dir.path().join(if binary { "b.ply" } else { "a.ply" });
        write_ply(&ply, &g.mesh, binary);
        let opts = BuildOptions { accel: Accel::Bvh4, ..Default::default() };
        let flat = raypipe::scene::load(Some(&ply), &opts).unwrap();
        let fview = flat.view().unwrap();
        let out = dir.path().join("b.rpsb");
        let mut bopts = BrickOptions::new(16 << 10, Codec::Zstd);
        bopts.memory_budget = Some(raypipe::build::bricks::working_memory(&bopts) + (2 << 20));
        let mut source = PlySource { ply: PlyStream::open(&ply, u64::MAX).unwrap() };
        raypipe::build::bricks::build_bricked_from(&mut source, Vec::new(), Default::default(), &opts, &bopts, &out)
            .unwrap();
        let scene = BrickedScene::open(&out).unwrap();
        assert!(scene.view().brick_count() > 4);
        let mut cam = *fview.camera().unwrap();
        assert_eq!(&cam, scene.view().globals().camera().unwrap(), "binary {binary}");
        (cam.width, cam.height) = (64, 48);
        for algo in [Algorithm::Cast, Algorithm::Whitted] {
            let o = RenderOptions { algo, ..Default::default() };
            let want = render(&fview, &cam, &o).unwrap();
            let (got, _) = with_cache(&scene, 1 << 20, 2, |c| render_bricked(&scene, c, &cam, &o)).unwrap();
            assert_eq!(got.pixels, want.pixels, "binary {binary} {algo:?}");
        }
    }
}
