//! Packets of shadow rays from a block of pixels' hits to one point light: the 4-wide
//! BVH's packet walk culls them by the pyramid from the light, and each ray's answer is
//! still its single-ray any-hit answer.

use proptest::prelude::*;
use raypipe::render::tracer::{occluded_packet, trace};
use raypipe::scene::{Accel, TriangleLayout};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::packet::bvh4::takes_shadow_pyramid;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::{NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};
use raypipe_tests::{build_soup, build_soup_layout};

/// A floor and a cloud of small triangles above it (the occluders), from `seed`.
fn floor_and_cloud(seed: u64, count: usize, size: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut unit = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut positions = vec![[-10.0, 0.0, -10.0], [10.0, 0.0, -10.0], [10.0, 0.0, 10.0], [-10.0, 0.0, 10.0]];
    let mut triangles = vec![[0, 1, 2], [0, 2, 3]];
    for _ in 0..count {
        let c = [unit() * 16.0 - 8.0, 1.0 + unit() * 4.0, unit() * 16.0 - 8.0];
        let base = positions.len() as u32;
        for _ in 0..3 {
            positions.push([c[0] + (unit() - 0.5) * size, c[1] + (unit() - 0.5) * size, c[2] + (unit() - 0.5) * size]);
        }
        triangles.push([base, base + 1, base + 2]);
    }
    (positions, triangles)
}

/// Every block of `N` pixels' shadow rays: the packet's answers against the single-ray
/// query's; returns how many packets took the pyramid.
fn check_blocks<const N: usize>(view: &SceneView<'_>, cam: &Camera, light: Vec3) -> Result<usize, TestCaseError> {
    let Ok(eye) = EyeRays::new(cam) else { return Ok(0) };
    let side = (N as f64).sqrt() as u32;
    let mut pyramids = 0;
    for by in (0..cam.height).step_by(side as usize) {
        for bx in (0..cam.width).step_by(side as usize) {
            let shadow: Vec<Ray> = (0..N as u32)
                .map(|k| {
                    let r = eye.ray(bx + k % side, by + k / side);
                    let t = trace::<Watertight, _>(view, &r, &mut NoProbe, &mut RayCounters::default())
                        .map_or(30.0, |h| h.t);
                    let p = r.origin + r.dir * (t * 0.999);
                    Ray { origin: p, dir: light - p, t_min: 0.0, t_max: 1.0 - 1e-4 }
                })
                .collect();
            let mut packet = RayPacket::<N>::new();
            packet.fill(&shadow);
            pyramids += takes_shadow_pyramid(view, &packet) as usize;
            let blocked =
                occluded_packet::<Watertight, _, N>(view, &packet, &mut NoProbe, &mut PacketCounters::default());
            for (i, r) in shadow.iter().enumerate() {
                let single = occluded::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
                prop_assert_eq!(blocked & (1 << i) != 0, single, "packet of {}, lane {}: {:?}", N, i, r);
            }
        }
    }
    Ok(pyramids)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Narrow views of the floor under a cloud of occluders, lit from above: blocks of
    /// 8×8 pixels take the pyramid (those of 4×4 the many-origin walk), and every shadow
    /// ray answers as it does alone, on both triangle layouts, at scales from 1e-3 to
    /// 1e3.
    #[test]
    fn shadow_packets_to_one_light_answer_as_single_rays(
        seed in 1u64..1_000_000,
        size in 0.02f32..0.2,
        light in [-3.0f32..3.0, 8.0f32..14.0, -3.0f32..3.0],
        target in [-4.0f32..4.0, -4.0f32..4.0],
        scale_exp in -3i32..=3,
        blocks in any::<bool>(),
    ) {
        let scale = 10f32.powi(scale_exp);
        let (mut positions, triangles) = floor_and_cloud(seed, 2000, size);
        for p in &mut positions {
            *p = p.map(|c| c * scale);
        }
        let scene = if blocks {
            build_soup_layout(positions, triangles, Accel::Bvh4, TriangleLayout::Blocks)
        } else {
            build_soup(positions, triangles, Accel::Bvh4, 3)
        };
        let view = scene.view().unwrap();
        let cam = Camera {
            eye: Vec3::new(target[0] * 0.5, 9.0, target[1] - 14.0) * scale,
            look_at: Vec3::new(target[0], 0.0, target[1]) * scale,
            up: Vec3::Y,
            vfov_deg: 4.0,
            width: 64,
            height: 64,
        };
        let light = Vec3::from(light) * scale;
        let p16 = check_blocks::<16>(&view, &cam, light)?;
        let p64 = check_blocks::<64>(&view, &cam, light)?;
        prop_assert_eq!(p16, 0, "packets of 16 take the many-origin walk");
        prop_assert!(p64 > 8, "few packets took the pyramid: {} of 64", p64);
    }
}
