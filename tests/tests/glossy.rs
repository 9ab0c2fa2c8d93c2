//! Glossy materials: Blinn–Phong highlights where optics puts them,
//! a glossy lobe that conserves energy under a white sky (a furnace test of the path
//! tracer's lobe pick and importance sampling), and golden Whitted and path-traced images
//! of glossy spheres, the same from every structure and packet size.

use std::path::Path;

use raypipe::input::mesh::Mesh;
use raypipe::render::packets::PacketSize;
use raypipe::render::tracer::trace;
use raypipe::render::{render, Algorithm, Frame, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions, Scene};
use raypipe_core::image::{CameraRecord, LightRecord, MaterialRecord};
use raypipe_core::shade::path::{shade_path, PathOptions};
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::whitted::{shade_whitted, WhittedOptions};
use raypipe_core::{NoProbe, Ray, RayCounters, Vec3, Watertight};
use raypipe_tests::{check_golden, root};

/// A large floor (y = 0) of material `m` lit by `light` alone.
fn floor(m: MaterialRecord, light: LightRecord) -> Scene {
    let s = 100.0;
    let mesh = Mesh {
        positions: vec![[-s, 0.0, -s], [s, 0.0, -s], [s, 0.0, s], [-s, 0.0, s]],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        tri_materials: vec![0, 0],
        materials: vec![m],
        material_names: vec!["m".into()],
        lights: vec![light],
        ..Default::default()
    };
    scene::build("floor".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap()
}

fn glossy(kd: f32, ks: f32, ns: f32) -> MaterialRecord {
    MaterialRecord { diffuse: [kd; 3], specular: [ks; 3], shininess: ns, illum: 2, ..MaterialRecord::DEFAULT }
}

/// Seen from an eye above a glossy floor, the point light's highlight peaks where the
/// floor mirrors the light toward the eye: on the line from the eye to the light's mirror
/// image below the floor.
#[test]
fn the_highlight_peaks_at_the_mirror_point() {
    let light = Vec3::new(0.3, 2.0, -0.4);
    let scene = floor(
        glossy(0.0, 1.0, 500.0),
        LightRecord { position: light.to_array(), kind: LightRecord::POINT, color: [1.0; 3], triangle: 0 },
    );
    let view = scene.view().unwrap();
    let eye = Vec3::new(-0.5, 1.5, 2.0);
    let image = Vec3::new(light.x, -light.y, light.z);
    let want = eye + (image - eye) * (eye.y / (eye.y + light.y));
    let opts = WhittedOptions { max_depth: 0, background: Vec3::ZERO };
    let (mut best, mut at) = (0.0f32, Vec3::ZERO);
    for i in 0..200 {
        for j in 0..200 {
            let target = Vec3::new(-1.5 + i as f32 * 0.015, 0.0, -1.5 + j as f32 * 0.015);
            let ray = Ray::new(eye, (target - eye).normalize());
            let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            let mut weight = Vec3::ZERO;
            shade_whitted(&view, &RayRecord::primary(ray, 0), hit, &opts, &mut NoProbe, &mut |r| weight += r.weight);
            if weight.x > best {
                (best, at) = (weight.x, ray.at(hit.unwrap().t));
            }
        }
    }
    assert!(best > 1.0, "a sharp lobe's peak exceeds a white Lambertian's: {best}");
    assert!(at.distance(want) < 0.03, "peak at {at}, mirror point {want}");
    // A matte floor has no highlight: its brightest point is right under the light.
    let matte = floor(
        MaterialRecord { diffuse: [1.0; 3], illum: 2, ..MaterialRecord::DEFAULT },
        LightRecord { position: light.to_array(), kind: LightRecord::POINT, color: [1.0; 3], triangle: 0 },
    );
    let view = matte.view().unwrap();
    let under = Vec3::new(light.x, 0.0, light.z);
    let ray = Ray::new(eye, (under - eye).normalize());
    let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
    let mut weight = Vec3::ZERO;
    shade_whitted(&view, &RayRecord::primary(ray, 0), hit, &opts, &mut NoProbe, &mut |r| weight += r.weight);
    assert!((weight.x - 1.0).abs() < 1e-4, "{weight}");
}

/// The mean radiance of a floor under a uniformly white sky, seen from direction `view`
/// (toward the floor), over `k` path samples of one bounce.
fn furnace(m: MaterialRecord, view_dir: Vec3, k: u32) -> f64 {
    let sky = LightRecord { position: [1.0; 3], kind: LightRecord::ENVIRONMENT, color: [1.0; 3], triangle: 0 };
    let scene = floor(m, sky);
    let view = scene.view().unwrap();
    let opts = PathOptions::new(1, false, Vec3::ZERO);
    let origin = -view_dir.normalize() * 2.0;
    let mut total = 0.0f64;
    for sample in 0..k {
        let mut stack = vec![RayRecord { sample, ..RayRecord::primary(Ray::new(origin, view_dir.normalize()), 3) }];
        while let Some(rec) = stack.pop() {
            let hit = trace::<Watertight, _>(&view, &rec.ray, &mut NoProbe, &mut RayCounters::default());
            if rec.kind == RayKind::Shadow {
                total += if hit.is_none() { rec.weight.x as f64 } else { 0.0 };
                continue;
            }
            total += shade_path(&view, &rec, hit, &opts, &mut NoProbe, &mut |r| stack.push(r)).x as f64;
        }
    }
    total / k as f64
}

/// A white furnace: half diffuse, half glossy (Kd + Ks = 1) under a sky of radiance 1
/// reflects radiance 1 seen along the normal (the lobe's normalisation is exact there and
/// the pick between lobes is unbiased), and no more at a slant (the horizon clips the
/// lobe); a glossy-only floor reflects Ks.
#[test]
fn a_glossy_floor_in_a_white_furnace_reflects_what_it_should() {
    let down = Vec3::new(0.0, -1.0, 0.0);
    for ns in [1.0, 20.0, 300.0] {
        let l = furnace(glossy(0.5, 0.5, ns), down, 40_000);
        assert!((l - 1.0).abs() < 0.01, "Ns {ns}: {l}");
        let slant = furnace(glossy(0.5, 0.5, ns), Vec3::new(1.0, -0.6, 0.0), 40_000);
        assert!(slant < 1.01 && slant > 0.6, "Ns {ns} at a slant: {slant}");
        let only = furnace(glossy(0.0, 0.7, ns), down, 40_000);
        assert!((only - 0.7).abs() < 0.01, "Ns {ns}, glossy only: {only}");
    }
    // Kd + Ks above one is scaled back to one: the floor reflects no more than arrives.
    let over = furnace(glossy(0.6, 0.9, 40.0), down, 40_000);
    assert!((over - 1.0).abs() < 0.01, "{over}");
}

fn render_glossy(path: &Path, algo: Algorithm, accel: Accel, packet: PacketSize, size: (u32, u32)) -> Frame {
    let scene = scene::load(Some(path), &BuildOptions { accel, ..Default::default() }).unwrap();
    let view = scene.view().unwrap();
    let cam = CameraRecord { width: size.0, height: size.1, ..*view.camera().unwrap() };
    let samples = if algo == Algorithm::Path { 4 } else { 1 };
    let opts =
        RenderOptions { packet, algo, samples, bounces: 3, max_depth: 3, threads: Some(2), ..Default::default() };
    render(&view, &cam, &opts).unwrap()
}

#[test]
fn glossy_whitted_and_path_images_are_golden_from_every_structure_and_packet_size() {
    let path = root().join("fixtures/glossy.obj");
    for (algo, name, size) in [
        (Algorithm::Whitted, "glossy_whitted_160x120.png", (160, 120)),
        (Algorithm::Path, "glossy_path_64x48.png", (64, 48)),
    ] {
        let first = render_glossy(&path, algo, Accel::Bvh, PacketSize::Single, size);
        check_golden(name, &first);
        for (accel, packet) in
            [(Accel::Grid, PacketSize::P4), (Accel::Kd, PacketSize::P16), (Accel::Bvh8, PacketSize::P64)]
        {
            let frame = render_glossy(&path, algo, accel, packet, size);
            assert!(frame.pixels == first.pixels, "{algo:?} {accel:?} {packet:?}");
        }
    }
}
