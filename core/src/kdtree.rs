//! kd-tree traversal (Wald & Slusallek 2001 §3; pbrt-v3 `KdTreeAccel::Intersect`): one
//! loop over a fixed-capacity stack of `(node, t_min, t_max)` entries. At an inner node
//! the ray visits the child on its origin's side first and pushes the other if it
//! crosses the plane inside its interval. A hit is final once it is nearer than the end
//! of the current leaf's interval; it may lie beyond the leaf (the triangle spans
//! several), so the walk goes on until it has passed it (as for the grid, Purcell §3.1.3).

use crate::aabb::clip_ray;
use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{KdNode, KdTreeView, SceneView, MAX_TREE_DEPTH};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::triangle::{test_triangle, Intersector};

/// The closest hit of `ray` through the kd-tree.
#[inline]
pub fn trace_kdtree<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    kd: &KdTreeView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    if !ray.is_valid() {
        return None;
    }
    let (mut t_min, mut t_max) = clip_ray(ray, kd.min, kd.max)?;
    let prep = I::prepare(ray);
    let mut best: Option<Hit> = None;
    let mut stack = [(0u32, 0f32, 0f32); MAX_TREE_DEPTH as usize];
    let mut sp = 0usize;
    let (mut nodes, mut leaves, mut tests) = (0u32, 0u32, 0u32);
    let mut index = 0u32;
    loop {
        let node = kd.node(index, probe);
        nodes += 1;
        let axis = node.axis();
        if axis != KdNode::LEAF {
            let a = axis as usize;
            let (o, d, split) = (ray.origin[a], ray.dir[a], node.split());
            let c = node.index();
            let below_first = o < split || (o == split && d <= 0.0);
            let (first, second) = if below_first { (c, c.wrapping_add(1)) } else { (c.wrapping_add(1), c) };
            if d == 0.0 {
                index = first;
                continue;
            }
            let t_split = (split - o) / d;
            if t_split > t_max || t_split <= 0.0 {
                index = first;
            } else if t_split < t_min {
                index = second;
            } else {
                if let Some(slot) = stack.get_mut(sp) {
                    *slot = (second, t_split, t_max);
                    sp += 1;
                }
                index = first;
                t_max = t_split;
            }
            continue;
        }
        // Leaf: test its triangles.
        leaves += 1;
        let first = node.index();
        for k in first..first.wrapping_add(node.value) {
            let prim = kd.prim(k, probe);
            let verts = scene.triangle(prim, probe);
            test_triangle::<I>(&prep, ray, &verts, prim, &mut best);
        }
        tests += node.value;
        // Final once the walk has passed the hit.
        if best.is_some_and(|h| h.t < t_max) || sp == 0 {
            break;
        }
        sp -= 1;
        (index, t_min, t_max) = stack[sp];
        if best.is_some_and(|h| h.t < t_min) {
            break;
        }
    }
    counters.nodes += nodes;
    counters.leaves += leaves;
    counters.tri_tests += tests;
    best
}
