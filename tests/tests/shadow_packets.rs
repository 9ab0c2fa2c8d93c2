//! Packets of shadow rays from a block of pixels' hits to one point light: the 4-wide
//! BVH's packet walk culls them by the pyramid from the light, and each ray's answer is
//! still its single-ray any-hit answer.

use proptest::prelude::*;
use raypipe::platform::isa::{set_avx16, set_avx512};
use raypipe::render::tracer::{occluded_packet, trace};
use raypipe::scene::{Accel, TriangleLayout};
use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::packet::bvh4::takes_shadow_pyramid;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;
use raypipe_core::traverse::wide_bvh::node4::{occluded_bvh4_cached, occluded_bvh4_cached4};
use raypipe_core::traverse::wide_bvh::node8::{occluded_bvh8_cached, occluded_bvh8_cached4};
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
    // One shadow cache across the frame's packets, as the batches keep it.
    let mut cache = LastOccluder::default();
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
            // In sixteen lanes with AVX-512 and with AVX where the CPU has them, and in
            // groups of four.
            for (w512, w16) in [(true, true), (false, true), (false, false)] {
                let wide = (set_avx512(w512), set_avx16(w16));
                let blocked = occluded_packet::<Watertight, _, N>(
                    view,
                    &packet,
                    &mut cache,
                    &mut NoProbe,
                    &mut PacketCounters::default(),
                );
                for (i, r) in shadow.iter().enumerate() {
                    let single = occluded::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
                    let got = blocked & (1 << i) != 0;
                    prop_assert_eq!(got, single, "packet of {}, lane {}, (AVX-512, AVX) {:?}: {:?}", N, i, wide, r);
                }
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

    /// Single shadow rays with the shadow cache, in the 4- and 8-wide BVHs and both
    /// triangle layouts: each answers as the uncached query, with a cache kept across
    /// the frame, a cache from the other tree's image, and one from another scene. Under
    /// a ceiling that blocks every ray, the cache answers most of them without a node
    /// visited.
    #[test]
    fn cached_shadow_rays_answer_as_uncached(
        seed in 1u64..1_000_000,
        size in 0.3f32..1.0,
        light in [-3.0f32..3.0, 8.0f32..14.0, -3.0f32..3.0],
        blocks in any::<bool>(),
        ceiling in any::<bool>(),
    ) {
        let s = CacheScenes::new(seed, size, blocks, ceiling);
        let (v4, v8, vo) = (s.b4.view().unwrap(), s.b8.view().unwrap(), s.other.view().unwrap());
        let (t4, t8, to) = (v4.bvh4().unwrap(), v8.bvh8().unwrap(), vo.bvh8().unwrap());
        let (mut c4, mut c8, mut foreign) = (LastOccluder::default(), LastOccluder::default(), LastOccluder::default());
        let (mut by_cache, mut blocked) = (0, 0);
        let rays = shadow_rays(&v4, &[Vec3::from(light)]);
        for (i, shadow) in rays.iter().enumerate() {
            let want = occluded::<Watertight, _>(&v4, shadow, &mut NoProbe, &mut RayCounters::default());
            let mut rc = RayCounters::default();
            let got4 = occluded_bvh4_cached::<Watertight, _>(&v4, t4, shadow, &mut c4, &mut NoProbe, &mut rc);
            by_cache += usize::from(got4 && rc.nodes == 0);
            blocked += usize::from(want);
            let got8 = occluded_bvh8_cached::<Watertight, _>(&v8, t8, shadow, &mut c8, &mut NoProbe, &mut rc);
            // A cache filled in another image: whatever leaf it names, the answer holds.
            let mut swapped = c4;
            let got8x = occluded_bvh8_cached::<Watertight, _>(&v8, t8, shadow, &mut swapped, &mut NoProbe, &mut rc);
            let _ = occluded_bvh8_cached::<Watertight, _>(&vo, to, shadow, &mut foreign, &mut NoProbe, &mut rc);
            let mut stray = foreign;
            let got8o = occluded_bvh8_cached::<Watertight, _>(&v8, t8, shadow, &mut stray, &mut NoProbe, &mut rc);
            prop_assert_eq!((got4, got8, got8x, got8o), (want, want, want, want), "pixel {}: {:?}", i, shadow);
        }
        if ceiling {
            prop_assert_eq!(blocked, rays.len(), "the ceiling blocks every ray");
            prop_assert!(2 * by_cache > rays.len(), "the cache answered {} of {} blocked rays", by_cache, rays.len());
        }
    }

    /// Shadow rays four at a time with the shadow cache (the cached leaf tested by the
    /// four at once), in both wide BVHs and layouts: each ray answers as it does alone,
    /// with lanes left empty or holding no ray, rays of two lights mixed in one group (so
    /// that some groups cannot share one frame), a cache kept across the frame and one
    /// from another scene. Under a ceiling, most groups are answered with no node visited.
    #[test]
    fn four_cached_shadow_rays_answer_as_alone(
        seed in 1u64..1_000_000,
        size in 0.3f32..1.0,
        lights in [-3.0f32..3.0, 8.0f32..14.0, -3.0f32..3.0, -30.0f32..30.0, 1.0f32..14.0, -30.0f32..30.0],
        mixed in any::<bool>(),
        mix in 1u32..16,
        holes in 0u32..16,
        blocks in any::<bool>(),
        ceiling in any::<bool>(),
    ) {
        let s = CacheScenes::new(seed, size, blocks, ceiling);
        let (v4, v8, vo) = (s.b4.view().unwrap(), s.b8.view().unwrap(), s.other.view().unwrap());
        let (t4, t8, to) = (v4.bvh4().unwrap(), v8.bvh8().unwrap(), vo.bvh8().unwrap());
        let (above, side) = (Vec3::new(lights[0], lights[1], lights[2]), Vec3::new(lights[3], lights[4], lights[5]));
        let mut rays = shadow_rays(&v4, &[above, side]);
        // With `mixed`, lanes of `mix` take the second light's rays; in every third group
        // `holes` marks lanes with no ray, and one lane in eight groups holds an invalid ray.
        let mix = if mixed { mix } else { 0 };
        let mut keep = Vec::with_capacity(rays.len() / 2);
        for (i, pair) in rays.chunks(2).enumerate() {
            keep.push(pair[usize::from(mix & (1 << (i % 4)) != 0 && pair.len() > 1)]);
        }
        rays = keep;
        let (mut c4, mut c8, mut foreign) = (LastOccluder::default(), LastOccluder::default(), LastOccluder::default());
        let (mut by_cache, mut whole) = (0, 0);
        for (g, group) in rays.chunks(4).enumerate() {
            let mut lanes: [Option<Ray>; 4] = [None; 4];
            for (k, r) in group.iter().enumerate() {
                if holes & (1 << k) == 0 || g % 3 != 0 {
                    lanes[k] = Some(if g % 8 == 5 && k == 1 { Ray { t_min: 2.0, t_max: 1.0, ..*r } } else { *r });
                }
            }
            let refs = [0, 1, 2, 3].map(|k| lanes[k].as_ref());
            let want = lanes.iter().enumerate().fold(0u32, |m, (k, r)| {
                let b = r.is_some_and(|r| occluded::<Watertight, _>(&v4, &r, &mut NoProbe, &mut RayCounters::default()));
                m | (u32::from(b) << k)
            });
            let mut rc = RayCounters::default();
            let got4 = occluded_bvh4_cached4::<Watertight, _>(&v4, t4, refs, &mut c4, &mut NoProbe, &mut rc);
            if lanes.iter().all(|r| r.is_some_and(|r| r.is_valid())) {
                whole += 1;
                by_cache += usize::from(rc.nodes == 0 && got4 == 0xF);
            }
            let got8 = occluded_bvh8_cached4::<Watertight, _>(&v8, t8, refs, &mut c8, &mut NoProbe, &mut rc);
            let _ = occluded_bvh8_cached4::<Watertight, _>(&vo, to, refs, &mut foreign, &mut NoProbe, &mut rc);
            let mut stray = foreign;
            let got8o = occluded_bvh8_cached4::<Watertight, _>(&v8, t8, refs, &mut stray, &mut NoProbe, &mut rc);
            prop_assert_eq!((got4, got8, got8o), (want, want, want), "group {}: {:?}", g, lanes);
        }
        if ceiling && !mixed {
            prop_assert!(2 * by_cache > whole, "the cache answered {} of {} whole groups", by_cache, whole);
        }
    }
}

/// The scenes of the cache tests: the floor and cloud of `seed` (with a ceiling above the
/// cloud if asked) in the 4- and 8-wide BVHs, and another scene's 8-wide BVH.
struct CacheScenes {
    b4: raypipe::scene::Scene,
    b8: raypipe::scene::Scene,
    other: raypipe::scene::Scene,
}

impl CacheScenes {
    fn new(seed: u64, size: f32, blocks: bool, ceiling: bool) -> CacheScenes {
        let (mut positions, mut triangles) = floor_and_cloud(seed, 1500, size);
        if ceiling {
            // Two large triangles at y = 7, between the cloud and any light above.
            let base = positions.len() as u32;
            positions.extend([[-40.0, 7.0, -40.0], [40.0, 7.0, -40.0], [40.0, 7.0, 40.0], [-40.0, 7.0, 40.0]]);
            triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
        let layout = if blocks { TriangleLayout::Blocks } else { TriangleLayout::Indexed };
        let b4 = build_soup_layout(positions.clone(), triangles.clone(), Accel::Bvh4, layout);
        let b8 = build_soup_layout(positions, triangles, Accel::Bvh8, layout);
        let (other_p, other_t) = floor_and_cloud(seed + 1, 300, 1.0);
        CacheScenes { b4, b8, other: build_soup_layout(other_p, other_t, Accel::Bvh8, layout) }
    }
}

/// A 48×48 view's shadow rays, pixel by pixel, to each of `lights` in turn: from each
/// eye ray's hit (or a point 30 along a ray that misses) in `view`.
fn shadow_rays(view: &SceneView<'_>, lights: &[Vec3]) -> Vec<Ray> {
    let cam = Camera {
        eye: Vec3::new(0.0, 6.0, -14.0),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 30.0,
        width: 48,
        height: 48,
    };
    let Ok(eye) = EyeRays::new(&cam) else { return Vec::new() };
    let mut rays = Vec::new();
    for i in 0..cam.width * cam.height {
        let r = eye.ray(i % cam.width, i / cam.width);
        let t = trace::<Watertight, _>(view, &r, &mut NoProbe, &mut RayCounters::default()).map_or(30.0, |h| h.t);
        let p = r.origin + r.dir * (t * 0.999);
        rays.extend(lights.iter().map(|&l| Ray { origin: p, dir: l - p, t_min: 0.0, t_max: 1.0 - 1e-4 }));
    }
    rays
}
