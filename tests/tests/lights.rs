//! Lights: the path tracer's pick of one emitter by power is unbiased
//! (a furnace-style check against the irradiance integrated by quadrature), the other
//! shaders read no area-light record however many emitters there are, and the lights of
//! a built image can be replaced.

use raypipe::input::mesh::Mesh;
use raypipe::scene::{self, Accel, BuildOptions, Scene};
use raypipe_core::image::{LightRecord, MaterialRecord};
use raypipe_core::probe::ByteCounter;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::path::{shade_path, PathOptions};
use raypipe_core::shade::ray_cone::RayCone;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::Watertight;
use raypipe_core::{Hit, NoProbe, Ray, Vec3};

/// A white floor (triangles 0, 1) under `emitters` (triangle, radiance), lit by nothing
/// else; `extra` dim emitters far off to the side (they change nothing seen from the
/// floor's centre except the light list's length).
fn scene_with(emitters: &[([[f32; 3]; 3], [f32; 3])], extra: usize) -> Scene {
    let mut positions = vec![[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]];
    let mut triangles = vec![[0, 2, 1], [0, 3, 2]];
    let mut materials = vec![MaterialRecord { diffuse: [1.0; 3], specular: [0.0; 3], ..MaterialRecord::DEFAULT }];
    let mut tri_materials = vec![0, 0];
    let mut add = |tri: [[f32; 3]; 3], ke: [f32; 3], positions: &mut Vec<[f32; 3]>| {
        let base = positions.len() as u32;
        positions.extend(tri);
        triangles.push([base, base + 1, base + 2]);
        tri_materials.push(materials.len() as u32);
        materials.push(MaterialRecord { diffuse: [0.0; 3], emission: ke, ..MaterialRecord::DEFAULT });
    };
    for &(tri, ke) in emitters {
        add(tri, ke, &mut positions);
    }
    for k in 0..extra {
        let x = 50.0 + k as f32;
        add([[x, -5.0, 0.0], [x, -5.0, 0.01], [x + 0.01, -5.0, 0.0]], [0.01; 3], &mut positions);
    }
    let names = (0..materials.len()).map(|i| format!("m{i}")).collect();
    let mesh = Mesh { positions, triangles, tri_materials, materials, material_names: names, ..Default::default() };
    scene::build(
        "lights".into(),
        mesh,
        Vec::new(),
        Default::default(),
        &BuildOptions { accel: Accel::Bvh, ..Default::default() },
    )
    .unwrap()
}

/// Radiance `ke` times ∫ cos θ cos θ' / (π d²) dA over the triangle, seen from `p` with
/// normal +y: the midpoint rule on a fine barycentric grid.
fn reference(p: Vec3, tri: [[f32; 3]; 3], ke: [f32; 3]) -> Vec3 {
    let [a, b, c] = tri.map(|v| Vec3::from(v).as_dvec3());
    let p = p.as_dvec3();
    let e = (b - a).cross(c - a);
    let (area, normal) = (0.5 * e.length(), e.normalize());
    // The midpoint rule on the square, mapped onto the triangle with uniform area
    // (the map core's sampler uses): every point stands for area / n².
    let n = 800;
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let (s1, s2) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            let r1 = s1.sqrt();
            let q = a * (1.0 - r1) + b * (r1 * (1.0 - s2)) + c * (r1 * s2);
            let to = q - p;
            let d2 = to.length_squared();
            let dir = to / d2.sqrt();
            sum += dir.y.max(0.0) * (-normal.dot(dir)).max(0.0) / (std::f64::consts::PI * d2);
        }
    }
    let g = sum * area / (n * n) as f64;
    Vec3::from(ke) * g as f32
}

/// The mean weight of the path tracer's shadow rays from the floor's centre over many
/// samples — the reflected radiance of a white floor — equals the irradiance from the
/// emitters over π, integrated by quadrature: picking one emitter by power and one point
/// on it is unbiased.
#[test]
fn picking_one_emitter_by_power_is_unbiased() {
    let emitters = [
        ([[-0.3, 1.0, -0.2], [0.2, 1.0, -0.2], [0.0, 1.0, 0.3]], [4.0, 2.0, 1.0]),
        ([[0.8, 0.5, 0.8], [0.8, 0.9, 0.8], [0.8, 0.5, 0.4]], [0.5, 3.0, 0.5]),
        ([[-2.0, 3.0, -2.0], [2.0, 3.0, 0.0], [-2.0, 3.0, 2.0]], [0.2, 0.2, 1.5]),
        ([[-0.6, 0.3, 0.6], [-0.5, 0.3, 0.6], [-0.6, 0.3, 0.7]], [40.0, 40.0, 40.0]),
    ];
    let scene = scene_with(&emitters, 0);
    let view = scene.view().unwrap();
    assert_eq!(view.area_light_count(), 4);
    let p = Vec3::new(0.1, 0.0, 0.05);
    let expected: Vec3 = emitters.iter().map(|&(t, ke)| reference(p, t, ke)).sum();
    // From just above the floor (below every emitter) straight down.
    let ray = Ray::new(Vec3::new(0.1, 0.5, 0.05), Vec3::new(0.0, -1.0, 0.0));
    let hit = raypipe::render::tracer::trace::<raypipe_core::Watertight, _>(
        &view,
        &ray,
        &mut NoProbe,
        &mut Default::default(),
    )
    .unwrap();
    let opts = PathOptions::new(0, false, Vec3::ZERO);
    let n = 200_000u32;
    let mut sum = [0.0f64; 3];
    for s in 0..n {
        let rec = RayRecord { sample: s, ..RayRecord::primary(ray, 7) };
        shade_path(&view, &rec, Some(hit), &opts, &mut NoProbe, &mut |r| {
            assert_eq!(r.kind, RayKind::Shadow);
            for (s, w) in sum.iter_mut().zip(r.weight.to_array()) {
                *s += w as f64;
            }
        });
    }
    let mean = Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32) / n as f32;
    for c in 0..3 {
        let rel = (mean[c] - expected[c]).abs() / expected[c];
        assert!(rel < 0.01, "channel {c}: mean {mean} vs integral {expected} ({rel:.4})");
    }
    // With a bounce to follow, the light sample and the bounce that hits an emitter share
    // the direct light by the power heuristic: together the light sample's estimate alone,
    // nothing counted twice or lost. Both see the emitters shadow each other, which the
    // quadrature above ignores.
    let estimate = |bounces: u8| {
        let opts = PathOptions::new(bounces, false, Vec3::ZERO);
        let mut sum = [0.0f64; 3];
        let mut add = |w: Vec3| {
            for (s, w) in sum.iter_mut().zip(w.to_array()) {
                *s += w as f64;
            }
        };
        for s in 0..n {
            let rec = RayRecord { sample: s, ..RayRecord::primary(ray, 7) };
            let mut out = Vec::new();
            shade_path(&view, &rec, Some(hit), &opts, &mut NoProbe, &mut |r| out.push(r));
            for r in out {
                if r.kind == RayKind::Shadow {
                    if !occluded::<Watertight, _>(&view, &r.ray, &mut NoProbe, &mut Default::default()) {
                        add(r.weight);
                    }
                    continue;
                }
                let hit = raypipe::render::tracer::trace::<Watertight, _>(
                    &view,
                    &r.ray,
                    &mut NoProbe,
                    &mut Default::default(),
                );
                add(shade_path(&view, &r, hit, &opts, &mut NoProbe, &mut |_| {}));
            }
        }
        Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32) / n as f32
    };
    let (light_only, mis) = (estimate(0), estimate(1));
    for c in 0..3 {
        let rel = (mis[c] - light_only[c]).abs() / light_only[c];
        assert!(rel < 0.01, "channel {c}: with MIS {mis} vs light samples alone {light_only} ({rel:.4})");
    }
}

/// Ray casting's shading reads the same bytes whether the scene has 1 emitter or 300:
/// the area-light records are never read (the sports car read 48,882 bytes per ray).
#[test]
fn casting_reads_no_area_light_record() {
    let lamp = ([[-0.3, 1.0, -0.2], [0.2, 1.0, -0.2], [0.0, 1.0, 0.3]], [4.0, 4.0, 4.0]);
    let bytes = |extra: usize| {
        let scene = scene_with(&[lamp], extra);
        let view = scene.view().unwrap();
        assert_eq!(view.area_light_count() as usize, 1 + extra);
        let ray = Ray::new(Vec3::new(0.1, 2.0, 0.05), Vec3::new(0.0, -1.0, 0.0));
        let hit = Hit { t: 2.0, u: 0.2, v: 0.3, prim: 0 };
        let mut probe = ByteCounter::default();
        let c = shade(&view, &ray, RayCone::POINT, Some(hit), Vec3::ZERO, &mut probe);
        assert!(c.max_element() > 0.0);
        probe.bytes.iter().sum::<u64>()
    };
    assert_eq!(bytes(0), bytes(300));
}

/// `--light` on a built image: the image's point lights are replaced, its emitters kept
/// (with their alias table), and the result is a valid image.
#[test]
fn a_built_image_can_be_relit() {
    let lamp = ([[-0.3, 1.0, -0.2], [0.2, 1.0, -0.2], [0.0, 1.0, 0.3]], [4.0, 4.0, 4.0]);
    let scene = scene_with(&[lamp], 3);
    let sun = LightRecord { position: [0.0, 1.0, 0.2], kind: LightRecord::DIRECTIONAL, color: [2.0; 3], triangle: 0 };
    let relit = scene::relight(&scene, &[sun]).unwrap();
    let view = relit.view().unwrap();
    assert_eq!(view.area_light_count(), 4);
    assert_eq!(view.light(0, &mut NoProbe), sun);
    assert_eq!(view.shading_light_count(), 2, "the sun and the ambient term");
    // Shading sees the sun: the floor facing it is lit by 2 × cos.
    let ray = Ray::new(Vec3::new(0.1, 2.0, 0.05), Vec3::new(0.0, -1.0, 0.0));
    let c = shade(&view, &ray, RayCone::POINT, Some(Hit { t: 2.0, u: 0.2, v: 0.3, prim: 0 }), Vec3::ZERO, &mut NoProbe);
    let cos = Vec3::new(0.0, 1.0, 0.2).normalize().y;
    assert!((c.x - (2.0 * cos + 0.1)).abs() < 1e-4, "{c}");
    let zero = LightRecord { position: [0.0; 3], ..sun };
    let e = scene::relight(&scene, &[zero]).err().expect("a sun without direction is refused").to_string();
    assert!(e.contains("direction is zero"), "{e}");
}
