//! The any-hit query of shadow rays: is anything in the way within `[t_min, t_max]`?
//! The walk is the structure's own step kernel ([`crate::traverse::walk::Walk`]), and it stops at
//! the first triangle hit in range — no closest-hit ordering is needed, so a shadow ray
//! usually ends long before a closest-hit query would (Purcell 2002 §3.1.4). On the
//! wide BVHs with the `f32` box tests the walk is their fast loop's, ended by the first
//! leaf holding a hit ([`crate::traverse::wide_bvh::occluded_wide_bvh`]).

use crate::counters::RayCounters;
use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::walk::{Walk, WalkEvent};
use crate::traverse::wide_bvh::last_occluder::LastOccluder;
use crate::traverse::wide_bvh::node4::occluded_bvh4_cached;
use crate::traverse::wide_bvh::node8::occluded_bvh8_cached;

/// True if some triangle is hit by `ray` within its interval. Exactly the closest-hit
/// query's "is there a hit", found sooner. `counters` receives the steps (nodes or
/// voxels), leaves and triangle tests it took.
pub fn occluded<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    occluded_cached::<I, P>(scene, ray, &mut LastOccluder::default(), probe, counters)
}

/// [`occluded`] with the shadow cache `cache` on the wide BVHs (see
/// [`crate::traverse::wide_bvh::last_occluder`]): the same answer for every ray and
/// cache. Keep one cache per run of neighbouring rays to one light.
pub fn occluded_cached<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    if !ray.is_valid() {
        return false;
    }
    if <I::Nodes as NodeTests>::FLOAT {
        if let Some(bvh) = scene.bvh8() {
            return occluded_bvh8_cached::<I, P>(scene, bvh, ray, cache, probe, counters);
        }
        if let Some(bvh) = scene.bvh4() {
            return occluded_bvh4_cached::<I, P>(scene, bvh, ray, cache, probe, counters);
        }
    }
    let prep = I::prepare(ray);
    let mut walk = Walk::<I::Nodes>::start(scene, ray);
    loop {
        match walk.step(scene, ray, probe) {
            WalkEvent::Inner => counters.nodes = counters.nodes.saturating_add(1),
            WalkEvent::Leaf(leaf) => {
                counters.leaves = counters.leaves.saturating_add(1);
                let mut hit = None;
                let tests = leaf.test::<I, P>(scene, &prep, ray, true, &mut hit, probe);
                counters.tri_tests = counters.tri_tests.saturating_add(tests);
                if hit.is_some() {
                    return true;
                }
                walk.finish_leaf();
            }
            WalkEvent::Done => return false,
        }
    }
}
