//! The guaranteed range (`raypipe_core::range`) holds at its edges:
//! scenes of extent 2^-20 … 2^20, origins up to 16 extents outside the scene, directions
//! whose largest component is 2^-20 … 2^20 with other components down to 2^-40 of it,
//! and intervals ending or starting exactly at the hit. Every structure, triangle layout,
//! packet size and the hardware model's packet walk return the brute-force hit bit for
//! bit (watertight test); equal-distance ties (duplicated triangles) go to the lower
//! triangle id on every path. Rays and scenes just outside are flagged.

use proptest::prelude::*;
use raypipe::render::tracer::{trace, trace_packet};
use raypipe::scene::{Accel, TriangleLayout};
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::range::{check_bounds, check_ray, check_scene, OutOfRange, MIN_COMPONENT_RATIO, ORIGIN_EXTENTS};
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{Hit, NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};
use raypipe_tests::{build_soup, build_soup_layout};

fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(&b),
        _ => false,
    }
}

fn lattice() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5), 1 => -2.0f32..2.0]
}

/// Every path's hit for `rays` equals brute force's (and the walk's and the packets').
fn check_paths(view: &SceneView<'_>, rays: &[Ray]) -> Result<(), TestCaseError> {
    for r in rays {
        let want = trace_brute_force::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
        let got = trace::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
        prop_assert!(same(got, want), "{:?}: {got:?} != brute force {want:?} for {r:?}", view.accel());
        let walk = trace_walk::<Watertight, _>(view, r, &mut NoProbe);
        prop_assert!(same(walk, want), "{:?} walk: {walk:?} != {want:?} for {r:?}", view.accel());
    }
    for chunk in rays.chunks(16) {
        let mut packet = RayPacket::<16>::new();
        packet.fill(chunk);
        let mut hits = [None; 16];
        trace_packet::<Watertight, _, 16>(view, &packet, &mut hits, &mut NoProbe, &mut PacketCounters::default());
        let mut lanes = [Ray::new(Vec3::ZERO, Vec3::X); 16];
        lanes[..chunk.len()].copy_from_slice(chunk);
        let mut stepped = [None; 16];
        trace_packet_steps::<Watertight, _, 16>(view, &lanes, packet.active, &mut stepped, &mut NoProbe);
        for (i, r) in chunk.iter().enumerate() {
            let want = trace_brute_force::<Watertight, _>(view, r, &mut NoProbe, &mut RayCounters::default());
            prop_assert!(
                same(hits[i], want),
                "{:?} packet lane {i}: {:?} != {want:?} for {r:?}",
                view.accel(),
                hits[i]
            );
            prop_assert!(
                same(stepped[i], want),
                "{:?} packet steps lane {i}: {:?} != {want:?}",
                view.accel(),
                stepped[i]
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn every_path_gives_the_brute_force_hit_at_the_edges_of_the_range(
        positions in prop::collection::vec([lattice(), lattice(), lattice()], 3..16),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..24),
        scale_log in prop_oneof![Just(-22i32), Just(0), Just(18)],
        rays in prop::collection::vec((
            [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0],
            0usize..3,
            any::<prop::sample::Index>(),
            0u8..3,
            prop_oneof![Just(-20i32), Just(0), Just(20)],
            0u8..4,
        ), 24),
    ) {
        let scale = 2f32.powi(scale_log);
        let positions: Vec<[f32; 3]> = positions.iter().map(|p| p.map(|c| c * scale)).collect();
        let n = positions.len();
        let mut tris: Vec<[u32; 3]> = picks.iter().map(|[a, b, c]| [a.index(n), b.index(n), c.index(n)].map(|i| i as u32)).collect();
        // Duplicates in reverse winding: hits at equal distance, ties to the lower id.
        tris.push([tris[0][2], tris[0][1], tris[0][0]]);
        let reference = build_soup(positions.clone(), tris.clone(), Accel::None, 3);
        let rview = reference.view().unwrap();
        prop_assume!(check_scene(&rview).is_ok());
        let (lo, hi) = rview.bounds();
        let extent = (hi - lo).max_element();
        let mut made = Vec::new();
        for (u, axis, tri, feature, dir_log, tiny) in &rays {
            // An origin up to 16 extents out; on one axis exactly at the limit.
            let mut o = (lo + hi) * 0.5 + Vec3::from(*u) * (ORIGIN_EXTENTS + 0.5) * extent;
            o[*axis] = if u[*axis] < 0.0 { lo[*axis] - ORIGIN_EXTENTS * extent } else { hi[*axis] + ORIGIN_EXTENTS * extent };
            let t = tris[tri.index(tris.len())];
            let v = t.map(|k| Vec3::from(positions[k as usize]));
            let target = match feature {
                0 => v[0],
                1 => (v[0] + v[1]) * 0.5,
                _ => (v[0] + v[1] + v[2]) / 3.0,
            };
            let mut d = target - o;
            // The largest component 2^-20, 1 or 2^20 (a power of two: the target stays on the ray).
            let m = d.abs().max_element();
            if m == 0.0 {
                continue;
            }
            d *= 2f32.powi(*dir_log) / 2f32.powi(m.log2().round() as i32);
            if *tiny > 0 {
                // One other component at the smallest allowed ratio (or zero).
                let big = d.abs().max_element();
                let k = (0..3).find(|&k| d[k].abs() != big).unwrap_or(0);
                d[k] = if *tiny == 1 { 0.0 } else { big * MIN_COMPONENT_RATIO * if *tiny == 2 { 1.0 } else { -1.0 } };
            }
            let ray = Ray::new(o, d);
            if check_ray(&rview, &ray).is_err() {
                continue;
            }
            made.push(ray);
            // The interval ending, and starting, exactly at the hit.
            if let Some(h) = trace_brute_force::<Watertight, _>(&rview, &ray, &mut NoProbe, &mut RayCounters::default()) {
                made.push(Ray { t_max: h.t, ..ray });
                made.push(Ray { t_min: h.t, ..ray });
            }
        }
        prop_assume!(!made.is_empty());
        for accel in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8] {
            let scene = build_soup(positions.clone(), tris.clone(), accel, 3);
            check_paths(&scene.view().unwrap(), &made)?;
        }
        for accel in [Accel::Bvh4, Accel::Bvh8] {
            let scene = build_soup_layout(positions.clone(), tris.clone(), accel, TriangleLayout::Blocks);
            check_paths(&scene.view().unwrap(), &made)?;
        }
    }
}

/// Just outside the range, rays and scenes are flagged with the reason.
#[test]
fn rays_and_scenes_outside_the_range_are_flagged() {
    let tri = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let scene = build_soup(tri.clone(), vec![[0, 1, 2]], Accel::Bvh, 3);
    let view = scene.view().unwrap();
    assert_eq!(check_scene(&view), Ok(()));
    let at = |o: Vec3, d: Vec3| check_ray(&view, &Ray::new(o, d));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0)), Ok(()));
    assert_eq!(at(Vec3::new(0.2, 0.2, 16.0), Vec3::new(0.0, 0.0, -1.0)), Ok(()));
    assert_eq!(at(Vec3::new(0.2, 0.2, 16.5), Vec3::new(0.0, 0.0, -1.0)), Err(OutOfRange::FarOrigin));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1e-7)), Err(OutOfRange::DirectionScale));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1e7)), Err(OutOfRange::DirectionScale));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::new(1e-13, 0.0, -1.0)), Err(OutOfRange::TinyComponent));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::new(1e-12, 0.0, -1.0)), Ok(()));
    assert_eq!(at(Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO), Err(OutOfRange::InvalidRay));
    for (s, ok) in [(1e-7f32, false), (1e-6, true), (1e6, true), (2e6, false)] {
        let big: Vec<[f32; 3]> = tri.iter().map(|p| p.map(|c| c * s)).collect();
        let scene = build_soup(big, vec![[0, 1, 2]], Accel::Bvh, 3);
        let got = check_scene(&scene.view().unwrap());
        assert_eq!(got.is_ok(), ok, "extent {s}: {got:?}");
    }
}

/// With `f64-fallback` (the host, the models) a scene's distance from the origin is no
/// limit: zero edge functions get their true sign. The build without it (firmware)
/// ends its range 4096 extents out; `nostd-proof` checks that side.
#[test]
fn only_the_build_without_f64_ends_its_range_near_the_origin() {
    let unit = Vec3::splat(1.0);
    assert_eq!(check_bounds(Vec3::splat(1e5), Vec3::splat(1e5) + unit), Ok(()));
    assert_eq!(check_bounds(Vec3::ZERO, Vec3::splat(1e-9)), Err(OutOfRange::SceneScale));
}
