//! Whitted ray tracing: the any-hit query agrees with the
//! closest-hit query, shadow rays toward an unobstructed light are never blocked, a
//! mirror's reflected ray finds what the explicitly reflected ray finds, a slab whose
//! index equals the air's changes nothing, and the image is the same for every
//! structure, packet size and thread count (and equal to its golden image).

use std::path::Path;

use proptest::prelude::*;
use raypipe::input::mesh::Mesh;
use raypipe::render::packets::PacketSize;
use raypipe::render::tracer::trace;
use raypipe::render::{render, Algorithm, Frame, RenderOptions};
use raypipe::scene::{self, Accel, BuildOptions, Scene};
use raypipe_core::image::{CameraRecord, LightRecord, MaterialRecord};
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::specular::reflect;
use raypipe_core::shade::whitted::{shade_whitted, WhittedOptions};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::{NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};
use raypipe_tests::{build_soup, check_golden, root};

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5), 1 => -2.0f32..2.0]
}

fn point() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Any-hit = "the closest-hit query finds something", for every structure.
    #[test]
    fn occlusion_agrees_with_the_closest_hit(
        positions in prop::collection::vec(point(), 3..16),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..24),
        rays in prop::collection::vec((point(), point(), 0.0f32..1.0, 0.5f32..3.0), 24),
    ) {
        let n = positions.len();
        let tris: Vec<[u32; 3]> = picks.iter().map(|[a, b, c]| [a.index(n) as u32, b.index(n) as u32, c.index(n) as u32]).collect();
        for accel in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None] {
            let scene = build_soup(positions.clone(), tris.clone(), accel, 3);
            let view = scene.view().unwrap();
            for (o, target, t_min, t_max) in &rays {
                let origin = Vec3::from(*o) * 2.0;
                let ray = Ray { origin, dir: Vec3::from(*target) - origin, t_min: *t_min, t_max: *t_max };
                let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
                prop_assert_eq!(occluded::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default()), hit.is_some(), "{:?} {:?}", accel, ray);
            }
        }
    }

    /// From any point of a lit floor, the shadow ray toward a light with nothing in
    /// between reaches it (the new ray never hits the surface it leaves).
    #[test]
    fn shadow_rays_to_an_unobstructed_light_are_never_blocked(
        size in 0.01f32..1000.0,
        offset in [-100.0f32..100.0, -100.0f32..100.0, -100.0f32..100.0],
        tilt in -0.5f32..0.5,
        pixels in prop::collection::vec((0.05f32..0.95, 0.05f32..0.95), 32),
    ) {
        let o = Vec3::from(offset);
        let corner = |x: f32, z: f32| (o + Vec3::new(x, tilt * x, z) * size).to_array();
        let positions = vec![corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
        let light = o + Vec3::new(0.2, 3.0, 0.1) * size;
        let scene = floor_scene(positions, MaterialRecord::DEFAULT, light);
        let view = scene.view().unwrap();
        let opts = WhittedOptions { max_depth: 3, background: Vec3::ZERO };
        for (u, v) in pixels {
            let target = o + Vec3::new(u * 2.0 - 1.0, tilt * (u * 2.0 - 1.0), v * 2.0 - 1.0) * size;
            let eye = o + Vec3::new(0.3, 2.0, 2.5) * size;
            let ray = Ray::new(eye, target - eye);
            let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            prop_assume!(hit.is_some());
            let mut shadows = Vec::new();
            shade_whitted(&view, &RayRecord::primary(ray, 0), hit, &opts, &mut NoProbe, &mut |r| shadows.push(r));
            prop_assert_eq!(shadows.len(), 1);
            let s = shadows[0];
            prop_assert_eq!(s.kind, RayKind::Shadow);
            prop_assert!(!occluded::<Watertight, _>(&view, &s.ray, &mut NoProbe, &mut RayCounters::default()), "blocked: {:?}", s.ray);
        }
    }
}

/// A floor quad with the given material, one point light and no ambient light.
fn floor_scene(positions: Vec<[f32; 3]>, material: MaterialRecord, light: Vec3) -> Scene {
    let mesh = Mesh {
        positions,
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        tri_materials: vec![0, 0],
        materials: vec![material],
        material_names: vec!["m".into()],
        lights: vec![LightRecord {
            position: light.to_array(),
            kind: LightRecord::POINT,
            color: [1.0; 3],
            triangle: 0,
        }],
        ..Default::default()
    };
    scene::build(
        "floor".into(),
        mesh,
        Vec::new(),
        Default::default(),
        &BuildOptions { accel: Accel::Bvh, ..Default::default() },
    )
    .unwrap()
}

/// A mirror floor under a box of walls: the reflected record's ray finds the same wall
/// as the mirror direction traced from the hit point.
#[test]
fn a_mirror_reflects_into_the_explicitly_reflected_direction() {
    let mut positions = vec![[-2.0, 0.0, -2.0], [2.0, 0.0, -2.0], [2.0, 0.0, 2.0], [-2.0, 0.0, 2.0]];
    let mut triangles = vec![[0, 2, 1], [0, 3, 2]];
    // Four walls around the mirror, each its own pair of triangles.
    for (a, b) in
        [([-2.0, -2.0], [2.0, -2.0]), ([2.0, -2.0], [2.0, 2.0]), ([2.0, 2.0], [-2.0, 2.0]), ([-2.0, 2.0], [-2.0, -2.0])]
    {
        let base = positions.len() as u32;
        positions.extend([[a[0], 0.0, a[1]], [b[0], 0.0, b[1]], [b[0], 3.0, b[1]], [a[0], 3.0, a[1]]]);
        triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
    }
    let mirror = MaterialRecord { specular: [0.9; 3], illum: 3, diffuse: [0.0; 3], ..MaterialRecord::DEFAULT };
    let mut tri_materials = vec![0; triangles.len()];
    tri_materials[2..].fill(1);
    let mesh = Mesh {
        positions,
        triangles,
        tri_materials,
        materials: vec![mirror, MaterialRecord::DEFAULT],
        material_names: vec!["mirror".into(), "wall".into()],
        lights: vec![LightRecord { position: [0.0, 2.5, 0.0], kind: LightRecord::POINT, color: [1.0; 3], triangle: 0 }],
        ..Default::default()
    };
    let scene = scene::build("mirror".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap();
    let view = scene.view().unwrap();
    let opts = WhittedOptions { max_depth: 2, background: Vec3::ZERO };
    let mut checked = 0;
    for i in 0..200 {
        let (u, v) = ((i % 20) as f32 / 20.0 * 3.6 - 1.8, (i / 20) as f32 / 10.0 * 3.6 - 1.8);
        let eye = Vec3::new(0.3, 2.7, 0.2);
        let ray = Ray::new(eye, Vec3::new(u, 0.0, v) - eye);
        let hit = trace::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default()).unwrap();
        assert!(hit.prim < 2, "the eye looks at the mirror");
        let mut out = Vec::new();
        shade_whitted(&view, &RayRecord::primary(ray, 0), Some(hit), &opts, &mut NoProbe, &mut |r| out.push(r));
        let refl = out.iter().find(|r| r.kind == RayKind::Reflection).expect("a mirror reflects");
        assert_eq!(refl.weight, Vec3::splat(0.9));
        let explicit = reflect(ray.dir.normalize(), Vec3::Y);
        assert!((refl.ray.dir - explicit).length() < 1e-6, "{:?} vs {explicit:?}", refl.ray.dir);
        let wall =
            |r: &Ray| trace::<Watertight, _>(&view, r, &mut NoProbe, &mut RayCounters::default()).map(|h| h.prim / 2);
        let from_hit = Ray { origin: ray.at(hit.t), dir: explicit, t_min: 1e-4, t_max: f32::INFINITY };
        // The wall seen in the mirror (the two triangles of a wall share a plane), or the
        // open sky for both.
        assert_eq!(wall(&refl.ray), wall(&from_hit), "ray {i}");
        checked += 1;
    }
    assert_eq!(checked, 200);
}

fn render_whitted(path: &Path, accel: Accel, packet: PacketSize, threads: usize, size: (u32, u32)) -> Frame {
    let scene = scene::load(Some(path), &BuildOptions { accel, ..Default::default() }).unwrap();
    let view: SceneView<'_> = scene.view().unwrap();
    let cam = CameraRecord { width: size.0, height: size.1, ..*view.camera().unwrap() };
    let opts =
        RenderOptions { threads: Some(threads), packet, algo: Algorithm::Whitted, max_depth: 5, ..Default::default() };
    render(&view, &cam, &opts).unwrap()
}

/// A wall behind a slab (a box) of transparent material: with the index of air, a ray
/// refracts straight through both faces and meets the wall where it would without the
/// slab.
#[test]
fn a_slab_with_the_index_of_air_changes_nothing() {
    let wall = [[-3.0, -3.0, -2.0], [3.0, -3.0, -2.0], [3.0, 3.0, -2.0], [-3.0, 3.0, -2.0]];
    let (lo, hi) = ([-1.0f32, -1.0, -0.5], [1.0f32, 1.0, 0.5]);
    let corner = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let mut positions: Vec<[f32; 3]> = wall.to_vec();
    positions.extend((0..8).map(corner));
    let mut triangles = vec![[0, 1, 2], [0, 2, 3]];
    // The box's faces, outward: (-z, +z, -x, +x, -y, +y) as corner-index quads.
    for q in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3]] {
        let q = q.map(|c| c + 4);
        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
    }
    let glass = MaterialRecord { diffuse: [0.0; 3], specular: [0.0; 3], ior: 1.0, illum: 7, ..MaterialRecord::DEFAULT };
    let mut tri_materials = vec![1; triangles.len()];
    tri_materials[..2].fill(0);
    let light = LightRecord { position: [0.0, 0.0, 5.0], kind: LightRecord::POINT, color: [1.0; 3], triangle: 0 };
    let build = |tris: Vec<[u32; 3]>, mats: Vec<u32>| {
        let mesh = Mesh {
            positions: positions.clone(),
            triangles: tris,
            tri_materials: mats,
            materials: vec![MaterialRecord::DEFAULT, glass],
            material_names: vec!["wall".into(), "glass".into()],
            lights: vec![light],
            ..Default::default()
        };
        scene::build("slab".into(), mesh, Vec::new(), Default::default(), &BuildOptions::default()).unwrap()
    };
    let with = build(triangles.clone(), tri_materials.clone());
    let without = build(triangles[..2].to_vec(), tri_materials[..2].to_vec());
    let (with, without) = (with.view().unwrap(), without.view().unwrap());
    let opts = WhittedOptions { max_depth: 4, background: Vec3::ZERO };
    let eye = Vec3::new(0.1, 0.2, 4.0);
    for i in 0..100 {
        let target = Vec3::new((i % 10) as f32 * 0.17 - 0.8, (i / 10) as f32 * 0.17 - 0.8, 0.5);
        let primary = Ray::new(eye, target - eye);
        let direct = trace::<Watertight, _>(&without, &primary, &mut NoProbe, &mut RayCounters::default()).unwrap();
        // Follow the refracted rays through the slab to the wall.
        let mut rec = RayRecord::primary(primary, 0);
        let mut hops = 0;
        let wall_hit = loop {
            let hit = trace::<Watertight, _>(&with, &rec.ray, &mut NoProbe, &mut RayCounters::default()).unwrap();
            if hit.prim < 2 {
                break (rec.ray, hit);
            }
            let mut out = Vec::new();
            shade_whitted(&with, &rec, Some(hit), &opts, &mut NoProbe, &mut |r| out.push(r));
            let refracted: Vec<_> = out.iter().filter(|r| r.kind != RayKind::Shadow).collect();
            assert_eq!(refracted.len(), 1, "only a refracted ray: {out:?}");
            assert_eq!(refracted[0].kind, RayKind::Refraction);
            assert_eq!(refracted[0].weight, Vec3::ONE, "nothing reflected, nothing lost");
            assert_eq!(refracted[0].ray.dir, rec.ray.dir.normalize(), "straight through");
            rec = *refracted[0];
            hops += 1;
        };
        assert_eq!(hops, 2, "in and out of the slab");
        let (ray, hit) = wall_hit;
        assert_eq!(hit.prim, direct.prim);
        // Only the new rays' start points moved: 1e-4 of the scene off each face.
        let shift = (ray.at(hit.t) - primary.at(direct.t)).length();
        assert!(shift < 2e-3, "ray {i}: {shift}");
    }
}

#[test]
fn whitted_image_is_golden_and_the_same_for_every_structure_packet_and_thread_count() {
    let path = root().join("fixtures/whitted.obj");
    let first = render_whitted(&path, Accel::Grid, PacketSize::Single, 1, (160, 120));
    check_golden("whitted_160x120.png", &first);
    for (i, accel) in [Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None].into_iter().enumerate() {
        for packet in [PacketSize::Single, PacketSize::P4, PacketSize::P64] {
            let frame = render_whitted(&path, accel, packet, 1 + i % 3, (160, 120));
            assert!(frame.pixels == first.pixels, "{accel:?} {packet:?}");
        }
    }
}

/// Purcell's hybrid shadow caster: the rasterizer's G-buffer replaces primary rays, and
/// the image is ray casting plus shadows except where the two disagree on which triangle
/// covers a pixel centre (at triangle edges) — few pixels.
#[test]
fn the_shadow_caster_equals_ray_casting_plus_shadows_where_coverage_agrees() {
    for (scene_path, size) in
        [(root().join("fixtures/whitted.obj"), (160, 120)), (root().join("fixtures/cornell_box.obj"), (96, 96))]
    {
        let scene = scene::load(Some(&scene_path), &BuildOptions { accel: Accel::Bvh4, ..Default::default() }).unwrap();
        let view = scene.view().unwrap();
        let cam = CameraRecord { width: size.0, height: size.1, ..*view.camera().unwrap() };
        let base = RenderOptions { threads: Some(2), max_depth: 0, ..Default::default() };
        let hybrid = render(&view, &cam, &RenderOptions { algo: Algorithm::Shadow, ..base }).unwrap();
        let traced = render(&view, &cam, &RenderOptions { algo: Algorithm::Whitted, ..base }).unwrap();
        let eye = raypipe_core::camera::EyeRays::new(&raypipe_core::Camera::from(&cam)).unwrap();
        let g = raypipe::render::gbuffer::rasterize(&view, &eye, 0);
        let (lo, hi) = view.test_bounds();
        let mut disagree = 0;
        for y in 0..cam.height {
            for x in 0..cam.width {
                let i = (y * cam.width + x) as usize;
                let cast = eye
                    .ray_in_scene(x, y, lo, hi)
                    .and_then(|r| trace::<Watertight, _>(&view, &r, &mut NoProbe, &mut RayCounters::default()))
                    .map_or(raypipe_core::image::NULL_INDEX, |h| h.prim);
                if cast != g.prim[i] {
                    disagree += 1;
                } else {
                    assert_eq!(hybrid.pixels[i], traced.pixels[i], "{} pixel ({x}, {y})", scene_path.display());
                }
            }
        }
        let n = (cam.width * cam.height) as usize;
        assert!(disagree * 100 < n, "{}: {disagree} of {n} pixels disagree", scene_path.display());
        assert_eq!(g.clipped, 0);
        if scene_path.ends_with("whitted.obj") {
            check_golden("shadow_160x120.png", &hybrid);
        }
    }
}
