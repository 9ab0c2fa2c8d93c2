//! Mipmapped textures filtered by ray cones: a checkerboard floor running
//! to the horizon fades to its mean grey far away instead of aliasing into noise, the
//! image carries the whole chain and validates it, and the hardware models read the
//! same texels as the host — bit for bit, whatever the algorithm.

use raypipe::input::mesh::Mesh;
use raypipe::input::texture::TextureImage;
use raypipe::render::tracer::trace;
use raypipe::render::{render, Algorithm, Frame, RenderOptions};
use raypipe::scene::{self, BuildOptions, Scene};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::image::{
    CameraRecord, LightRecord, MaterialRecord, SceneError, SectionKind, ShadingVertex, TextureRecord,
};
use raypipe_core::pixel_filter::Filter;
use raypipe_core::{NoProbe, RayCounters, SceneView, Vec3, Watertight};
use raypipe_hw::{HwConfig, Simulator};
use raypipe_tests::{corrupt_image, put_u32, reseal, section_entry};

const SIDE: u32 = 64;

/// A 40 × 42 floor tiled 8 × 8.4 times by a 64 × 64 checkerboard of one-texel squares,
/// lit from high above.
fn checker_floor() -> Scene {
    let (x0, x1, z0, z1) = (-20.0f32, 20.0f32, -40.0f32, 2.0f32);
    let positions = vec![[x0, 0.0, z0], [x1, 0.0, z0], [x1, 0.0, z1], [x0, 0.0, z1]];
    let shading = positions
        .iter()
        .map(|p| ShadingVertex { normal: [0.0, 1.0, 0.0], uv: [p[0] / 5.0, p[2] / 5.0], color: [1.0; 3] })
        .collect();
    let rgba = (0..SIDE * SIDE)
        .flat_map(|i| if (i % SIDE + i / SIDE).is_multiple_of(2) { [255u8; 4] } else { [0, 0, 0, 255] })
        .collect();
    let mesh = Mesh {
        positions,
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        shading,
        tri_materials: vec![0, 0],
        materials: vec![MaterialRecord { diffuse: [1.0; 3], texture: 0, ..MaterialRecord::DEFAULT }],
        material_names: vec!["checker".into()],
        lights: vec![LightRecord {
            position: [0.0, 1e4, -20.0],
            kind: LightRecord::POINT,
            color: [1.0; 3],
            triangle: 0,
        }],
        textures: vec![TextureImage { width: SIDE, height: SIDE, rgba, wrap: TextureRecord::REPEAT }],
        objects: Vec::new(),
        margin_bounds: None,
    };
    scene::build("checker".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap()
}

fn camera() -> CameraRecord {
    CameraRecord {
        eye: [0.0, 1.0, 3.0],
        look_at: [0.0, 0.4, -10.0],
        up: [0.0, 1.0, 0.0],
        vfov_deg: 50.0,
        width: 128,
        height: 96,
        background: [0.0; 3],
        _pad: 0,
    }
}

/// The image of `scene` with its textures cut down to level 0 (what raypipe read before
/// mipmaps).
fn without_mipmaps(scene: &Scene) -> raypipe::platform::aligned::AlignedBytes {
    let mut bytes = raypipe::platform::aligned::AlignedBytes::from_slice(&scene.image);
    let (_, e) = section_entry(&bytes, SectionKind::Textures);
    // `levels` is the fifth word of the record.
    put_u32(&mut bytes, e.offset as usize + 16, 1);
    reseal(&mut bytes);
    bytes
}

/// Mean and standard deviation of the red channel over the pixels whose eye ray meets the
/// floor between 15 and 45 units away.
fn far_statistics(view: &SceneView<'_>, frame: &Frame) -> (f64, f64, usize) {
    let eye = EyeRays::new(&Camera::from(&camera())).unwrap();
    let mut values = Vec::new();
    for y in 0..frame.height {
        for x in 0..frame.width {
            let ray = eye.ray(x, y);
            if let Some(hit) = trace::<Watertight, _>(view, &ray, &mut NoProbe, &mut RayCounters::default()) {
                if (15.0..45.0).contains(&hit.t) {
                    values.push(frame.pixels[(y * frame.width + x) as usize][0] as f64);
                }
            }
        }
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var.sqrt(), values.len())
}

/// Far away each pixel covers many checks: with mipmaps it shows their mean (linear
/// 0.5, sRGB code 188), without them one texel's black or white at random.
#[test]
fn a_checkerboard_fades_to_grey_toward_the_horizon_instead_of_aliasing() {
    let scene = checker_floor();
    let view = scene.view().unwrap();
    let opts = RenderOptions { threads: Some(2), ..Default::default() };
    let mipmapped = render(&view, &camera(), &opts).unwrap();
    let bytes = without_mipmaps(&scene);
    let flat = SceneView::parse(&bytes).unwrap();
    let aliased = render(&flat, &camera(), &opts).unwrap();
    let (mean, sd, n) = far_statistics(&view, &mipmapped);
    let (_, sd_aliased, _) = far_statistics(&flat, &aliased);
    assert!(n > 500, "{n} far pixels");
    // Measured: sd 33 without mipmaps (moiré), 0 with them.
    assert!(sd_aliased > 25.0, "without mipmaps the far floor is moiré: sd {sd_aliased}");
    assert!(sd < 0.2 * sd_aliased, "with mipmaps: sd {sd} vs {sd_aliased}");
    assert!((mean - 188.0).abs() < 12.0, "far mean {mean}");
    // Close to the eye the footprint is under a texel: the same bilinear image.
    let eye = EyeRays::new(&Camera::from(&camera())).unwrap();
    let near = (0..96 * 128)
        .filter(|&i| {
            let ray = eye.ray(i % 128, i / 128);
            trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default()).is_some_and(|h| h.t < 2.5)
        })
        .collect::<Vec<_>>();
    assert!(!near.is_empty());
    let same = near.iter().filter(|&&i| mipmapped.pixels[i as usize] == aliased.pixels[i as usize]).count();
    assert!(same * 10 >= near.len() * 9, "{same} of {} near pixels unchanged", near.len());
}

/// Every level is written and validated: a level count past the full chain, or of zero,
/// is an impossible texture, and so is a chain that runs past TEXELS.
#[test]
fn the_image_holds_the_whole_chain_and_rejects_impossible_levels() {
    let scene = checker_floor();
    let view = scene.view().unwrap();
    let t = view.texture(0).unwrap();
    assert_eq!(t.levels, 7);
    assert_eq!(TextureRecord::chain_texels(64, 64, 7), 64 * 64 + 32 * 32 + 16 * 16 + 8 * 8 + 4 * 4 + 2 * 2 + 1);
    assert_eq!(t.level(6).width, 1);
    let (_, e) = section_entry(&scene.image, SectionKind::Textures);
    let (_, texels) = section_entry(&scene.image, SectionKind::Texels);
    assert_eq!(texels.count as u64, TextureRecord::chain_texels(64, 64, 7));
    for bad in [0, 8, u32::MAX] {
        let err = corrupt_image(&scene.image, |b| put_u32(b, e.offset as usize + 16, bad));
        assert_eq!(err, SceneError::BadTexture { texture: 0 }, "levels {bad}");
    }
    // The chain moved one texel on: its last texel would lie past TEXELS.
    let err = corrupt_image(&scene.image, |b| put_u32(b, e.offset as usize + 8, 1));
    assert_eq!(err, SceneError::BadTexture { texture: 0 });
    // A texture of (2³² − 1)² texels with its full chain of 32 levels: the chain's
    // length overflows u64 (a panic under overflow checks, as in this test build, or a
    // small wrapped count that passed in release); it saturates and is refused.
    assert_eq!(TextureRecord::chain_texels(u32::MAX, u32::MAX, 32), u64::MAX);
    let err = corrupt_image(&scene.image, |b| {
        put_u32(b, e.offset as usize, u32::MAX);
        put_u32(b, e.offset as usize + 4, u32::MAX);
        put_u32(b, e.offset as usize + 16, 32);
    });
    assert_eq!(err, SceneError::BadTexture { texture: 0 });
}

/// The chip and the stream machine filter with the same cones and read the same levels:
/// their images equal the host's, bit for bit.
#[test]
fn the_models_read_the_same_mipmap_levels_as_the_host() {
    let scene = checker_floor();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: 48, height: 36, ..camera() };
    for (algo, samples) in [(Algorithm::Cast, 1), (Algorithm::Cast, 4), (Algorithm::Whitted, 1), (Algorithm::Path, 2)] {
        let opts =
            RenderOptions { algo, samples, filter: Filter::Tent, bounces: 1, max_depth: 2, ..Default::default() };
        let host = render(&view, &cam, &opts).unwrap();
        let shader = opts.shader(Vec3::from(cam.background));
        let eye = EyeRays::new(&Camera::from(&cam)).unwrap().with_sampler(opts.sampler());
        let cfg = HwConfig::preset("saarcor").unwrap();
        let mut sim = Simulator::<Watertight>::with_shader(view, eye, Vec3::ZERO, shader, &cfg).unwrap();
        sim.run(|_, _| {}).unwrap();
        assert!(sim.framebuffer() == host.pixels, "simulate {algo:?} {samples}");
        let (frame, _) = raypipe::hw::stream::run_stream(
            &view,
            &cam,
            &raypipe_hw::stream::StreamConfig::default(),
            &raypipe_hw::stream::CostModel::default(),
            &raypipe::hw::frame_setup::FrameSetup { shader, sampler: opts.sampler(), ..Default::default() },
        )
        .unwrap();
        assert!(frame.pixels == host.pixels, "stream {algo:?} {samples}");
    }
}
