//! The event a tree traversal step reports — what a hardware traversal unit emits each
//! cycle: an inner node was read (step again), a leaf was reached (hand its primitive
//! list to the intersection unit, then call the walk's `finish_leaf`), or the walk is
//! over. kd-tree, BVH and 4-wide BVH steps all speak it.

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::SceneView;
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// What one tree traversal step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeEvent {
    /// An inner node was read; step again.
    Inner,
    /// A leaf: test PRIM_LISTS entries `first .. first + count`, then finish the leaf.
    Leaf {
        /// First list entry.
        first: u32,
        /// Number of triangles.
        count: u32,
    },
    /// The walk is over.
    Done,
}

/// One ray's registers in a tree, advanced one node per step.
pub trait TreeWalk<V> {
    /// Reads one node of `view` and moves on, or reports the leaf the walk stands on.
    fn step<P: MemoryProbe>(&mut self, view: &V, ray: &Ray, probe: &mut P) -> TreeEvent;
    /// After a leaf's triangles were tested into [`TreeWalk::best_mut`].
    fn finish_leaf(&mut self);
    /// The closest hit so far.
    fn best_mut(&mut self) -> &mut Option<Hit>;
}

/// A tree whose leaves index a primitive-list section.
pub trait PrimLists {
    /// Reads primitive-list entry `pos`.
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32;
}

/// The closest hit of `ray` by driving `walk` to the end: the host's loop over a tree's
/// step kernel, shared by the kd-tree, the BVH and the 4-wide BVH. `counters` receives
/// inner nodes visited, leaves visited and triangles tested.
#[inline(always)]
pub fn trace_tree<I: Intersector, P: MemoryProbe, V: PrimLists, W: TreeWalk<V>>(
    scene: &SceneView<'_>,
    view: &V,
    mut walk: W,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let prep = I::prepare(ray);
    let (mut nodes, mut leaves, mut tests) = (0u32, 0u32, 0u32);
    loop {
        match walk.step(view, ray, probe) {
            TreeEvent::Inner => nodes += 1,
            TreeEvent::Leaf { first, count } => {
                leaves += 1;
                test_leaf::<I, P, V>(scene, view, &prep, ray, (first, count), walk.best_mut(), probe);
                // Cannot overflow: a ray tests at most PRIM_LISTS' length (the parse bounds it).
                tests += count;
                walk.finish_leaf();
            }
            TreeEvent::Done => break,
        }
    }
    counters.nodes = counters.nodes.saturating_add(nodes);
    counters.leaves = counters.leaves.saturating_add(leaves);
    counters.tri_tests = counters.tri_tests.saturating_add(tests);
    *walk.best_mut()
}

/// A tree leaf's triangles — PRIM_LISTS entries `first .. first + count` of `view` —
/// tested against `ray`, keeping the closest hit in `best`.
#[inline(always)]
pub fn test_leaf<I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'_>,
    view: &V,
    prep: &I::Prepared,
    ray: &Ray,
    (first, count): (u32, u32),
    best: &mut Option<Hit>,
    probe: &mut P,
) {
    for e in first..first.wrapping_add(count) {
        let prim = view.prim(e, probe);
        let verts = I::fetch(scene, prim, probe);
        test_triangle::<I>(prep, ray, &verts, prim, best);
    }
}
