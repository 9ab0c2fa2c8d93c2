//! Golden images: the renderer's output for the project's own scenes, pixel for pixel.
//! Rendering is deterministic (same kernels, no randomness, any thread count), so the
//! comparison is exact. After an intended change, regenerate with
//! `RAYPIPE_BLESS=1 cargo test -p raypipe-tests --test golden` and look at the images.

use raypipe::build::grid::GridResolution;
use raypipe::render::packets::PacketSize;
use raypipe::render::tracer::IntersectorKind;
use raypipe::render::{render, Frame, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions};
use raypipe_core::image::CameraRecord;
use raypipe_tests::{check_golden, root};

fn render_default(kind: IntersectorKind, threads: usize, accel: Accel, packet: PacketSize) -> Frame {
    let scene = scene::load_default(&BuildOptions { accel, ..Default::default() }).unwrap();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 128, height: 128, ..*view.camera().unwrap() };
    render(
        &view,
        &cam,
        &RenderOptions { threads: Some(threads), intersector: kind, progress: false, packet, ..Default::default() },
    )
    .unwrap()
}

#[test]
fn cornell_box_watertight() {
    check_golden(
        "cornell_box_128.png",
        &render_default(IntersectorKind::Watertight, 2, Accel::Grid, PacketSize::Single),
    );
}

/// One image whatever the structure, packet size and thread count.
#[test]
fn cornell_box_is_the_same_from_every_structure_and_packet_size() {
    for accel in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None] {
        for (i, packet) in PacketSize::ALL.into_iter().enumerate() {
            let frame = render_default(IntersectorKind::Watertight, 1 + i % 3, accel, packet);
            check_golden("cornell_box_128.png", &frame);
        }
    }
}

#[test]
fn cornell_box_moller_trumbore_matches_the_same_golden_image() {
    // Away from edges both kernels find the same triangles; on this scene the 8-bit
    // image is the same.
    check_golden(
        "cornell_box_128.png",
        &render_default(IntersectorKind::MollerTrumbore, 1, Accel::Grid, PacketSize::P16),
    );
}

#[test]
fn tetra_fixture() {
    let scene = scene::load(Some(&root().join("fixtures/tetra.rpsi")), &BuildOptions::default()).unwrap();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 96, height: 72, ..*view.camera().unwrap() };
    let frame = render(&view, &cam, &RenderOptions { threads: Some(3), ..Default::default() }).unwrap();
    check_golden("tetra_96x72.png", &frame);
}

/// The images embedded by the no_std proof are what `raypipe build` makes today.
#[test]
fn tetra_image_fixtures_are_up_to_date() {
    let opts = BuildOptions { grid: GridResolution::MinDim(4), ..Default::default() };
    let built = scene::load(Some(&root().join("fixtures/tetra.obj")), &opts).unwrap();
    let committed = std::fs::read(root().join("fixtures/tetra.rpsi")).unwrap();
    assert!(
        committed == *built.image,
        "fixtures/tetra.rpsi is stale: run `cargo run --release -p raypipe -- build fixtures/tetra.obj -o fixtures/tetra.rpsi --grid-min-dim 4`"
    );
    for (accel, name) in [(Accel::Kd, "kd"), (Accel::Bvh, "bvh"), (Accel::Bvh4, "bvh4"), (Accel::Bvh8, "bvh8")] {
        let built =
            scene::load(Some(&root().join("fixtures/tetra.obj")), &BuildOptions { accel, ..Default::default() })
                .unwrap();
        let committed = std::fs::read(root().join(format!("fixtures/tetra-{name}.rpsi"))).unwrap();
        assert!(
            committed == *built.image,
            "fixtures/tetra-{name}.rpsi is stale: run `cargo run --release -p raypipe -- build fixtures/tetra.obj -o fixtures/tetra-{name}.rpsi --accel {name}`"
        );
    }
}

/// Anti-aliased ray casting: 16 jittered eye rays per pixel through a tent filter, the
/// same image from every structure and packet size (the offsets are counter-based).
#[test]
fn anti_aliased_cast_is_golden_from_every_structure_and_packet_size() {
    use raypipe_core::pixel_filter::Filter;
    for (i, accel) in [Accel::Grid, Accel::Bvh4, Accel::Kd].into_iter().enumerate() {
        let scene = scene::load_default(&BuildOptions { accel, ..Default::default() }).unwrap();
        let view = scene.view().unwrap();
        let cam = CameraRecord { width: 96, height: 96, ..*view.camera().unwrap() };
        let opts = RenderOptions {
            threads: Some(1 + i),
            packet: PacketSize::ALL[i + 1],
            samples: 16,
            filter: Filter::Tent,
            ..Default::default()
        };
        let frame = render(&view, &cam, &opts).unwrap();
        check_golden("cast_aa16_tent_96.png", &frame);
        // Edges are blended: the anti-aliased image has colours the one-sample image
        // does not.
        let centre = render(&view, &cam, &RenderOptions { samples: 1, ..opts }).unwrap();
        let distinct = |f: &Frame| f.pixels.iter().collect::<std::collections::HashSet<_>>().len();
        assert!(distinct(&frame) > 2 * distinct(&centre), "{} vs {}", distinct(&frame), distinct(&centre));
    }
}
