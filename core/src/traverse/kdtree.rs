//! kd-tree traversal (Wald & Slusallek 2001 §3; pbrt-v3 `KdTreeAccel::Intersect`) as a
//! step kernel over plain registers: a fixed-capacity stack of `(node, t_min, t_max)`
//! entries. At an inner node the ray visits the child on its origin's side first and
//! pushes the other if it crosses the plane inside its interval. A hit is final once it
//! is nearer than the end of the current leaf's interval; it may lie beyond the leaf (the
//! triangle spans several), so the walk goes on until it has passed it (as for the grid,
//! Purcell §3.1.3).

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{KdNode, KdTreeView, SceneView, MAX_TREE_DEPTH};
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::clip::clip_ray;
use crate::traverse::tree_step::{trace_tree, TreeEvent, TreeWalk};

/// The traversal registers of one ray.
#[derive(Clone, Debug)]
pub struct KdTraversal {
    index: u32,
    t_min: f32,
    t_max: f32,
    stack: heapless::Vec<(u32, f32, f32), { MAX_TREE_DEPTH as usize }>,
    done: bool,
    /// Closest hit so far.
    pub best: Option<Hit>,
}

impl KdTraversal {
    /// Starts a ray at the root, clipped to the tree's box.
    pub fn new(kd: &KdTreeView<'_>, ray: &Ray) -> KdTraversal {
        let clip = if ray.is_valid() { clip_ray(ray, kd.min, kd.max) } else { None };
        let (t_min, t_max) = clip.unwrap_or((0.0, 0.0));
        KdTraversal { index: 0, t_min, t_max, stack: heapless::Vec::new(), done: clip.is_none(), best: None }
    }

    /// Reads one node and moves down (inner node) or reports a leaf.
    #[inline]
    pub fn step<P: MemoryProbe>(&mut self, kd: &KdTreeView<'_>, ray: &Ray, probe: &mut P) -> TreeEvent {
        if self.done {
            return TreeEvent::Done;
        }
        let node = kd.node(self.index, probe);
        let axis = node.axis();
        if axis == KdNode::LEAF {
            return TreeEvent::Leaf { first: node.index(), count: node.value };
        }
        let a = axis as usize;
        let (o, d, split) = (ray.origin[a], ray.dir[a], node.split());
        let c = node.index();
        let below_first = o < split || (o == split && d <= 0.0);
        let (first, second) = if below_first { (c, c.wrapping_add(1)) } else { (c.wrapping_add(1), c) };
        if d == 0.0 {
            self.index = first;
            return TreeEvent::Inner;
        }
        let t_split = (split - o) / d;
        if t_split > self.t_max || t_split <= 0.0 {
            self.index = first;
        } else if t_split < self.t_min {
            self.index = second;
        } else {
            // Cannot be full: `parse` bounds the depth.
            let _ = self.stack.push((second, t_split, self.t_max));
            self.index = first;
            self.t_max = t_split;
        }
        TreeEvent::Inner
    }

    /// After a leaf's triangles: the hit is final once it is nearer than the leaf's end;
    /// otherwise the walk resumes at the next pushed node.
    #[inline]
    pub fn finish_leaf(&mut self) {
        if self.best.is_some_and(|h| h.t < self.t_max) {
            self.done = true;
            return;
        }
        let Some(next) = self.stack.pop() else {
            self.done = true;
            return;
        };
        (self.index, self.t_min, self.t_max) = next;
        if self.best.is_some_and(|h| h.t < self.t_min) {
            self.done = true;
        }
    }
}

impl TreeWalk<KdTreeView<'_>> for KdTraversal {
    #[inline(always)]
    fn step<P: MemoryProbe>(&mut self, view: &KdTreeView<'_>, ray: &Ray, probe: &mut P) -> TreeEvent {
        KdTraversal::step(self, view, ray, probe)
    }

    #[inline(always)]
    fn finish_leaf(&mut self) {
        KdTraversal::finish_leaf(self)
    }

    #[inline(always)]
    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.best
    }
}

/// The closest hit of `ray` through the kd-tree.
#[inline]
pub fn trace_kdtree<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    kd: &KdTreeView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    trace_tree::<I, P, _, _>(scene, kd, KdTraversal::new(kd, ray), ray, probe, counters)
}
