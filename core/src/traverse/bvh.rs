//! BVH traversal as a step kernel over a fixed-capacity stack, nearer child first, boxes beyond
//! the best hit so far skipped (pbrt-v4 `BVHAggregate::Intersect`, tinybvh
//! `BVH::Intersect`). The stack never overflows: `SceneView::parse` rejects trees deeper
//! than [`MAX_TREE_DEPTH`], and at most one node per level waits on it.

use bytemuck::Zeroable;
use glam::Vec3A;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{BvhNode, BvhView, SceneView, MAX_TREE_DEPTH};
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::{BoxTest, NodeTests};
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::tree_step::{trace_tree, TreeEvent, TreeWalk};

/// The traversal registers of one ray in the BVH: the node it stands on (its record is
/// held, not re-read), a fixed-capacity stack of `(node, entry distance)`, and the best
/// hit so far. One [`BvhTraversal::step`] visits one inner node: it reads the node's two
/// children (adjacent records) and tests both boxes with the box test `B` (the `f32`
/// slab test, or the fixed-point one: [`crate::traverse::boxes::datapath`]).
#[derive(Clone, Debug)]
pub struct BvhTraversal<B: BoxTest = RayBox> {
    rb: B,
    t_min: f32,
    t_max: f32,
    node: BvhNode,
    // A node to read at the next step: the root at the start, then popped nodes.
    pending: Option<u32>,
    stack: heapless::Vec<(u32, f32), { MAX_TREE_DEPTH as usize }>,
    started: bool,
    done: bool,
    /// Closest hit so far.
    pub best: Option<Hit>,
}

impl<B: BoxTest> BvhTraversal<B> {
    /// Starts a ray at the root; an invalid ray is done at once.
    #[inline]
    pub fn new(ray: &Ray) -> BvhTraversal<B> {
        BvhTraversal {
            rb: B::for_ray(ray),
            t_min: ray.t_min,
            t_max: ray.t_max,
            node: BvhNode::zeroed(),
            pending: Some(0),
            stack: heapless::Vec::new(),
            started: false,
            done: !ray.is_valid(),
            best: None,
        }
    }

    /// Visits one inner node (moving to its nearer hit child and pushing the other), or
    /// reports the leaf the walk stands on.
    #[inline(always)]
    pub fn step<P: MemoryProbe>(&mut self, bvh: &BvhView<'_>, probe: &mut P) -> TreeEvent {
        if self.done {
            return TreeEvent::Done;
        }
        if let Some(index) = self.pending.take() {
            self.node = bvh.node(index, probe);
            if !self.started {
                // The root's own box is tested once; children are tested by their parent.
                self.started = true;
                let n = &self.node;
                let (lo, hi) = (Vec3A::from_array(n.min), Vec3A::from_array(n.max));
                if self.rb.entry(lo, hi, self.t_min, self.t_max).is_none() {
                    self.done = true;
                    return TreeEvent::Done;
                }
            }
        }
        let node = self.node;
        if node.count > 0 {
            return TreeEvent::Leaf { first: node.first, count: node.count };
        }
        // Boxes entered beyond the best hit cannot hold a closer one; equal is kept.
        let t_end = self.best.map_or(self.t_max, |h| h.t);
        let (ia, ib) = (node.first, node.first.wrapping_add(1));
        // The children's address comes from the node record.
        probe.dependent();
        let a = bvh.node(ia, probe);
        let b = bvh.node(ib, probe);
        let ta = self.rb.entry(Vec3A::from_array(a.min), Vec3A::from_array(a.max), self.t_min, t_end);
        let tb = self.rb.entry(Vec3A::from_array(b.min), Vec3A::from_array(b.max), self.t_min, t_end);
        match (ta, tb) {
            (Some(ta), Some(tb)) => {
                let (near, far_index, t_far) = if ta <= tb { (a, ib, tb) } else { (b, ia, ta) };
                // Cannot be full: `parse` bounds the depth.
                let _ = self.stack.push((far_index, t_far));
                self.node = near;
            }
            (Some(_), None) => self.node = a,
            (None, Some(_)) => self.node = b,
            (None, None) => self.pop(),
        }
        TreeEvent::Inner
    }

    /// After a leaf's triangles: on to the next entry that may hold a closer hit.
    #[inline(always)]
    pub fn finish_leaf(&mut self) {
        self.pop();
    }

    /// Pops the next node that may still hold a closer hit (read at the next step), or
    /// ends the walk.
    #[inline(always)]
    fn pop(&mut self) {
        loop {
            let Some((index, t_entry)) = self.stack.pop() else {
                self.done = true;
                return;
            };
            if !self.best.is_some_and(|h| t_entry > h.t) {
                self.pending = Some(index);
                return;
            }
        }
    }
}

impl<B: BoxTest> TreeWalk<BvhView<'_>> for BvhTraversal<B> {
    #[inline(always)]
    fn step<P: MemoryProbe>(&mut self, view: &BvhView<'_>, _ray: &Ray, probe: &mut P) -> TreeEvent {
        BvhTraversal::step(self, view, probe)
    }

    #[inline(always)]
    fn finish_leaf(&mut self) {
        BvhTraversal::finish_leaf(self)
    }

    #[inline(always)]
    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.best
    }
}

/// The closest hit of `ray` through the BVH.
#[inline]
pub fn trace_bvh<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &BvhView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let walk = BvhTraversal::<<I::Nodes as NodeTests>::Binary>::new(ray);
    trace_tree::<I, P, _, _>(scene, bvh, walk, ray, probe, counters)
}
