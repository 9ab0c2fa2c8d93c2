//! The scene statistics of a ray batch rather than of a view: the same counters as
//! [`crate::study::scene_stats`] (nodes, leaves, triangle tests, bytes read per data
//! class), gathered on the rays `raypipe trace` reads from a `.npy` file — bounces, shadow
//! rays, any rays a user logged — through the single-ray kernels `trace` runs on them.
//! Comparing a structure's visits per ray with another tracer's on the same rays tells
//! whether it is the tree or the cost per visit that differs.

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::probe::ByteCounter;
use raypipe_core::traverse::occlusion::occluded_cached;
use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;
use raypipe_core::{Intersector, Ray, RayCounters, SceneView};

use crate::render::in_pool;
use crate::render::tracer::{trace, IntersectorKind};
use crate::study::scene_stats::SceneStats;
use crate::with_intersector;

/// Rays per task: neighbouring rays stay together, as in `trace`'s batches (the any-hit
/// query's shadow cache is kept per run of neighbours).
const CHUNK: usize = 4096;

/// What each ray of a batch asks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchQuery {
    /// The closest hit.
    Closest,
    /// Whether anything is hit (the any-hit query, with the shadow cache of the wide
    /// BVHs as `trace --query any` uses it).
    Any,
}

/// Traces every ray of `rays` whose `invalid` flag is clear (a row that is no ray is
/// counted as a ray that misses, with no work) and gathers the statistics; `hits` counts
/// the rays that hit (closest) or are blocked (any).
pub fn gather_batch(
    scene: &SceneView<'_>,
    rays: &[Ray],
    invalid: &[bool],
    query: BatchQuery,
    intersector: IntersectorKind,
    threads: Option<usize>,
) -> Result<SceneStats> {
    with_intersector!(intersector, I => in_pool(threads, || gather_with::<I>(scene, rays, invalid, query)))
}

fn gather_with<I: Intersector>(scene: &SceneView<'_>, rays: &[Ray], invalid: &[bool], query: BatchQuery) -> SceneStats {
    rays.par_chunks(CHUNK)
        .zip(invalid.par_chunks(CHUNK))
        .map(|(rays, invalid)| {
            let mut s = SceneStats::default();
            let mut bytes = ByteCounter::default();
            let mut cache = LastOccluder::default();
            for (ray, &bad) in rays.iter().zip(invalid) {
                let mut c = RayCounters::default();
                let hit = !bad
                    && match query {
                        BatchQuery::Closest => trace::<I, _>(scene, ray, &mut bytes, &mut c).is_some(),
                        BatchQuery::Any => occluded_cached::<I, _>(scene, ray, &mut cache, &mut bytes, &mut c),
                    };
                s.add_ray(&c, hit, false);
            }
            s.bytes = bytes;
            s
        })
        .reduce(SceneStats::default, SceneStats::merge)
}
