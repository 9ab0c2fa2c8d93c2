//! Path tracing (issue 5): a path's weight never grows from bounce to bounce (without
//! Russian roulette), and the image — random numbers included — is the same for every
//! structure, packet size and thread count, and equal to its golden image.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use raypipe::packets::PacketSize;
use raypipe::render::{render, Algorithm, Frame, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions};
use raypipe::tracer::trace;
use raypipe_core::image::CameraRecord;
use raypipe_core::path::{shade_path, PathOptions};
use raypipe_core::ray_record::{RayKind, RayRecord};
use raypipe_core::{NoProbe, Ray, RayCounters, Vec3, Watertight};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

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
        let opts = PathOptions { bounces: 6, samples: 1, roulette: false, background: Vec3::ZERO };
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
    let golden_path = root().join("fixtures/golden/path_64x48.png");
    let first = render_path(&path, Accel::Bvh4, PacketSize::P64, 2, false);
    if std::env::var_os("RAYPIPE_BLESS").is_some() {
        raypipe::output::write_png(&golden_path, first.width, first.height, &first.pixels).unwrap();
    }
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&golden_path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let golden: Vec<[u8; 3]> = buf.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    assert!(first.pixels == golden, "differs from fixtures/golden/path_64x48.png");
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
