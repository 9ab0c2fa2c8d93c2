//! `raypipe stats --rays`: a ray batch's statistics are the sums of what each ray's own
//! kernel counts, for every structure and both queries.

use proptest::prelude::*;
use raypipe::render::tracer::{trace, IntersectorKind};
use raypipe::scene::{Accel, TriangleLayout};
use raypipe::study::batch_stats::{gather_batch, BatchQuery};
use raypipe_core::probe::ByteCounter;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::{NoProbe, Ray, RayCounters, Vec3, Watertight};
use raypipe_tests::build_soup_layout;

const ACCELS: [Accel; 5] = [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8];

fn coord() -> impl Strategy<Value = f32> {
    -4.0f32..4.0
}

fn point() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn sums_each_rays_own_counters(
        tris in prop::collection::vec([point(), point(), point()], 1..60),
        rays in prop::collection::vec((point(), point()), 1..300),
        bad in prop::collection::vec(any::<bool>(), 300),
    ) {
        let positions: Vec<[f32; 3]> = tris.iter().flatten().copied().collect();
        let triangles: Vec<[u32; 3]> = (0..tris.len() as u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let rays: Vec<Ray> = rays.iter().map(|(o, d)| Ray::new(Vec3::from(*o), Vec3::from(*d))).collect();
        // A few rows that are not rays: counted as rays that miss, with no work.
        let invalid: Vec<bool> = rays.iter().zip(&bad).map(|(r, b)| *b && r.origin.x > 2.0 || !r.is_valid()).collect();
        for accel in ACCELS {
            let wide = matches!(accel, Accel::Bvh4 | Accel::Bvh8);
            let layouts: &[TriangleLayout] = if wide { &[TriangleLayout::Indexed, TriangleLayout::Blocks] } else { &[TriangleLayout::Indexed] };
            for &layout in layouts {
                let scene = build_soup_layout(positions.clone(), triangles.clone(), accel, layout);
                let view = scene.view().expect("valid image");
                let kind = IntersectorKind::resolve(None, &view);
                let (mut hits, mut blocked, mut c, mut a) = (0, 0, RayCounters::default(), RayCounters::default());
                let mut bytes = ByteCounter::default();
                for (ray, _) in rays.iter().zip(&invalid).filter(|(_, b)| !**b) {
                    hits += trace::<Watertight, _>(&view, ray, &mut bytes, &mut c).is_some() as u64;
                    blocked += occluded::<Watertight, _>(&view, ray, &mut NoProbe, &mut a) as u64;
                }
                let s = gather_batch(&view, &rays, &invalid, BatchQuery::Closest, kind, Some(2)).expect("gathers");
                prop_assert_eq!(s.rays, rays.len() as u64);
                prop_assert_eq!(s.hits, hits, "{:?}", accel);
                prop_assert_eq!((s.total.nodes, s.total.leaves), (c.nodes as u64, c.leaves as u64), "{:?}", accel);
                prop_assert_eq!(s.total.tri_tests, c.tri_tests as u64, "{:?}", accel);
                prop_assert_eq!(s.bytes.bytes, bytes.bytes, "{:?}", accel);
                let any = gather_batch(&view, &rays, &invalid, BatchQuery::Any, kind, Some(1)).expect("gathers");
                // Blocked exactly where the closest-hit query hits; the shadow cache may
                // change the work, not the answers.
                prop_assert_eq!(any.hits, hits, "{:?}", accel);
                prop_assert_eq!(blocked, hits, "{:?}", accel);
            }
        }
    }
}
