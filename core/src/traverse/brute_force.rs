//! The reference tracer: every triangle, the same intersection kernel, the same order.
//! Every acceleration structure must return exactly what this returns.

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::SceneView;
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// The closest hit of `ray` among all triangles of `scene`.
pub fn trace_brute_force<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    if !ray.is_valid() {
        return None;
    }
    let prep = I::prepare(ray);
    let mut best = None;
    for prim in 0..scene.triangle_count() {
        let verts = I::fetch(scene, prim, probe);
        test_triangle::<I>(&prep, ray, &verts, prim, &mut best);
    }
    counters.tri_tests = counters.tri_tests.saturating_add(scene.triangle_count());
    best
}
