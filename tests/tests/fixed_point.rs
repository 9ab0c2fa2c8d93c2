//! The fixed-point datapath: with the fixed-point triangle test, every
//! BVH (binary, 4- and 8-wide, both triangle layouts), the generic walk, the packet
//! kernels and the any-hit query give the fixed-point brute-force hit bit for bit, in
//! Q16.16, Q12.12 and Q8.16 — so the fixed-point box test never drops a box holding a hit,
//! including the boxes of spatial-split leaves, which hold parts of triangles. Rays aim at
//! vertices, edges and inside triangles of scenes both on and off the format's grid;
//! scenes from far below a format's resolution to beyond its range (where it is not
//! exact, and only has to stay bounded).

use proptest::prelude::*;
use raypipe::render::tracer::{trace, trace_packet};
use raypipe::scene::{Accel, TriangleLayout};
use raypipe_core::fixed_ray::FixedRay;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{FixedWatertight, Hit, Intersector, NoProbe, Ray, RayCounters, SceneView, Vec3};
use raypipe_tests::{build_soup, build_soup_layout};

fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(&b),
        _ => false,
    }
}

/// Every path against fixed-point brute force in `Q(B − F).F`, where the scene and the
/// rays' origins fit the format; where they do not (coordinates saturate and the
/// datapath is not exact: see `fixed_ray_box`), the paths run for boundedness only.
fn check<const B: u32, const F: u32>(
    view: &SceneView<'_>,
    rays: &[Ray],
    positions: &[[f32; 3]],
) -> Result<(), TestCaseError> {
    let format = FixedRay::<B, F>::FORMAT;
    let holds = |p: Vec3| p.to_array().iter().all(|&c| format.holds(c));
    let fits = positions.iter().all(|p| holds(Vec3::from(*p))) && rays.iter().all(|r| holds(r.origin));
    if !fits {
        for r in rays {
            let _ = trace::<FixedWatertight<B, F>, _>(view, r, &mut NoProbe, &mut RayCounters::default());
        }
        return Ok(());
    }
    check_paths::<FixedWatertight<B, F>>(view, rays)
}

fn check_paths<I: Intersector>(view: &SceneView<'_>, rays: &[Ray]) -> Result<(), TestCaseError> {
    let c = &mut RayCounters::default();
    for r in rays {
        let want = trace_brute_force::<I, _>(view, r, &mut NoProbe, c);
        let got = trace::<I, _>(view, r, &mut NoProbe, c);
        prop_assert!(
            same(got, want),
            "{} {:?}: {got:?} != brute force {want:?} for {r:?}",
            std::any::type_name::<I>(),
            view.accel()
        );
        let walk = trace_walk::<I, _>(view, r, &mut NoProbe);
        prop_assert!(same(walk, want), "{:?} walk: {walk:?} != {want:?} for {r:?}", view.accel());
        let blocked = occluded::<I, _>(view, r, &mut NoProbe, c);
        prop_assert_eq!(blocked, want.is_some(), "{:?} any-hit for {:?}", view.accel(), r);
    }
    for chunk in rays.chunks(8) {
        let mut packet = RayPacket::<8>::new();
        packet.fill(chunk);
        let mut hits = [None; 8];
        trace_packet::<I, _, 8>(view, &packet, &mut hits, &mut NoProbe, &mut PacketCounters::default());
        for (i, r) in chunk.iter().enumerate() {
            let want = trace_brute_force::<I, _>(view, r, &mut NoProbe, c);
            prop_assert!(same(hits[i], want), "{:?} packet lane {i}: {:?} != {want:?}", view.accel(), hits[i]);
        }
    }
    Ok(())
}

fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![2 => (-8i32..=8).prop_map(|i| i as f32 * 0.25), 1 => -2.0f32..2.0]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn every_bvh_gives_the_fixed_point_brute_force_hit(
        positions in prop::collection::vec([coordinate(), coordinate(), coordinate()], 3..20),
        picks in prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..32),
        // Scenes from far below the formats' resolution to near their range.
        scale_log in prop_oneof![Just(-10i32), Just(-3), Just(0), Just(4), Just(9)],
        offset in [-0.3f32..0.3, -0.3f32..0.3, -0.3f32..0.3],
        rays in prop::collection::vec((
            [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0],
            any::<prop::sample::Index>(),
            0u8..4,
            0u8..3,
            -0.2f32..1.2,
        ), 16),
    ) {
        let scale = 2f32.powi(scale_log);
        // Off the grid: an offset that no format holds exactly.
        let positions: Vec<[f32; 3]> =
            positions.iter().map(|p| [0, 1, 2].map(|k| (p[k] + offset[k] * 0.001) * scale)).collect();
        let n = positions.len();
        let tris: Vec<[u32; 3]> = picks.iter().map(|[a, b, c]| [a.index(n), b.index(n), c.index(n)].map(|i| i as u32)).collect();
        let mut made = Vec::new();
        for (u, tri, feature, axis_parallel, t_end) in &rays {
            let origin = Vec3::from(*u) * 4.0 * scale;
            let t = tris[tri.index(tris.len())];
            let v = t.map(|k| Vec3::from(positions[k as usize]));
            let target = match feature {
                0 => v[0],
                1 => (v[0] + v[1]) * 0.5,
                2 => v[1] * 0.25 + v[2] * 0.75,
                _ => (v[0] + v[1] + v[2]) / 3.0,
            };
            let mut d = target - origin;
            if *axis_parallel == 1 {
                // One component zero: the box test's parallel-axis rule.
                let k = (0..3).min_by(|&a, &b| d[a].abs().total_cmp(&d[b].abs())).unwrap_or(0);
                d[k] = 0.0;
            }
            let mut ray = Ray::new(origin, d);
            if !ray.is_valid() {
                continue;
            }
            if *axis_parallel == 2 {
                // An interval ending near the target (boxes culled by `t1`).
                ray.t_max = t_end.max(0.0);
            }
            made.push(ray);
        }
        prop_assume!(!made.is_empty());
        for accel in [Accel::Bvh, Accel::Bvh4, Accel::Bvh8, Accel::None] {
            let scene = build_soup(positions.clone(), tris.clone(), accel, 3);
            let view = scene.view().unwrap();
            check::<32, 16>(&view, &made, &positions)?;
            check::<24, 12>(&view, &made, &positions)?;
            check::<24, 16>(&view, &made, &positions)?;
        }
        for accel in [Accel::Bvh4, Accel::Bvh8] {
            let scene = build_soup_layout(positions.clone(), tris.clone(), accel, TriangleLayout::Blocks);
            check::<24, 12>(&scene.view().unwrap(), &made, &positions)?;
        }
    }
}

/// A closed surface seen from inside leaks nowhere in fixed point: every ray from the
/// centre of a tessellated, irregular cube hits it, including rays aimed exactly at its
/// vertices and edges, in both formats.
#[test]
fn a_closed_mesh_has_no_leaks() {
    // A 6×6 grid on each face of a cube, with jittered inner vertices (shared between
    // neighbouring triangles, so edges are shared exactly).
    let n = 6;
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    let mut index = std::collections::HashMap::new();
    let jitter = |i: i32, j: i32| (((i * 7 + j * 13) % 5) as f32 - 2.0) * 0.013;
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let mut id = |i: i32, j: i32| -> u32 {
                // Integer lattice key on the cube's surface (shared across faces).
                let mut key = [0i32; 3];
                key[axis] = side as i32 * n;
                key[(axis + 1) % 3] = 2 * i - n;
                key[(axis + 2) % 3] = 2 * j - n;
                *index.entry(key).or_insert_with(|| {
                    // Vertices off the cube's edges move a little (off the format's grid).
                    let inner = key[(axis + 1) % 3].abs() < n && key[(axis + 2) % 3].abs() < n;
                    let p = key.map(|k| k as f32 / n as f32 * 1.7 + if inner { jitter(i, j) } else { 0.0 });
                    positions.push(p);
                    (positions.len() - 1) as u32
                })
            };
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                }
            }
        }
    }
    let scene = build_soup(positions.clone(), tris.clone(), Accel::Bvh4, 3);
    let view = scene.view().unwrap();
    let centre = Vec3::new(0.013, -0.007, 0.002);
    let mut aimed = 0;
    let mut rays: Vec<Ray> = positions.iter().map(|p| Ray::new(centre, Vec3::from(*p) - centre)).collect();
    for t in &tris {
        let v = t.map(|k| Vec3::from(positions[k as usize]));
        rays.push(Ray::new(centre, (v[0] + v[1]) * 0.5 - centre));
    }
    for r in &rays {
        for (name, hit) in [
            ("Q16.16", trace::<FixedWatertight<32, 16>, _>(&view, r, &mut NoProbe, &mut RayCounters::default())),
            ("Q12.12", trace::<FixedWatertight<24, 12>, _>(&view, r, &mut NoProbe, &mut RayCounters::default())),
        ] {
            assert!(hit.is_some(), "{name}: a leak toward {:?}", r.dir);
        }
        aimed += 1;
    }
    assert!(aimed > 400, "{aimed}");
}
