//! BVH traversal: one loop over a fixed-capacity stack, nearer child first, boxes beyond
//! the best hit so far skipped (pbrt-v4 `BVHAggregate::Intersect`, tinybvh
//! `BVH::Intersect`). The stack never overflows: `SceneView::parse` rejects trees deeper
//! than [`MAX_TREE_DEPTH`], and at most one node per level waits on it.

use glam::Vec3A;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{BvhView, SceneView, MAX_TREE_DEPTH};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::ray_box::RayBox;
use crate::triangle::{test_triangle, Intersector};

/// The closest hit of `ray` through the BVH.
#[inline]
pub fn trace_bvh<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &BvhView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    if !ray.is_valid() {
        return None;
    }
    let rb = RayBox::new(ray);
    let prep = I::prepare(ray);
    let mut best: Option<Hit> = None;
    let mut stack: heapless::Vec<(u32, f32), { MAX_TREE_DEPTH as usize }> = heapless::Vec::new();
    let (mut nodes, mut leaves, mut tests) = (1u32, 0u32, 0u32);
    let root = bvh.node(0, probe);
    if rb.entry(Vec3A::from_array(root.min), Vec3A::from_array(root.max), ray.t_min, ray.t_max).is_none() {
        counters.nodes += 1;
        return None;
    }
    let mut node = root;
    loop {
        if node.count > 0 {
            leaves += 1;
            for k in node.first..node.first.wrapping_add(node.count) {
                let prim = bvh.prim(k, probe);
                let verts = I::fetch(scene, prim, probe);
                test_triangle::<I>(&prep, ray, &verts, prim, &mut best);
            }
            tests += node.count;
        } else {
            // Boxes entered beyond the best hit cannot hold a closer one; equal is kept.
            let t_end = best.map_or(ray.t_max, |h| h.t);
            let (ia, ib) = (node.first, node.first.wrapping_add(1));
            let a = bvh.node(ia, probe);
            let b = bvh.node(ib, probe);
            nodes += 2;
            let ta = rb.entry(Vec3A::from_array(a.min), Vec3A::from_array(a.max), ray.t_min, t_end);
            let tb = rb.entry(Vec3A::from_array(b.min), Vec3A::from_array(b.max), ray.t_min, t_end);
            match (ta, tb) {
                (Some(ta), Some(tb)) => {
                    let (near, far_index, t_far) = if ta <= tb { (a, ib, tb) } else { (b, ia, ta) };
                    // Cannot be full: `parse` bounds the depth.
                    let _ = stack.push((far_index, t_far));
                    node = near;
                    continue;
                }
                (Some(_), None) => {
                    node = a;
                    continue;
                }
                (None, Some(_)) => {
                    node = b;
                    continue;
                }
                (None, None) => {}
            }
        }
        // Pop the next node that may still hold a closer hit.
        loop {
            let Some((index, t_entry)) = stack.pop() else {
                counters.nodes += nodes;
                counters.leaves += leaves;
                counters.tri_tests += tests;
                return best;
            };
            if best.is_some_and(|h| t_entry > h.t) {
                continue;
            }
            node = bvh.node(index, probe);
            break;
        }
    }
}
