//! The walk through a wide BVH (4 or 8 children per node), whatever its width: one node
//! holds its children's boxes, tested together by one SIMD slab test (the node's
//! [`WideSlab`]); hit children are visited nearest first (the any-hit query: in slot
//! order), the others pushed on a fixed-capacity stack (Wald, Benthin & Boulos 2008;
//! Embree's BVH4 and BVH8). Leaves are stack entries like nodes, so a leaf is
//! intersected only when it is the nearest thing left to visit.

pub mod last_occluder;
pub mod node4;
pub mod node8;

use core::marker::PhantomData;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{SceneView, WideBvhView, MAX_WIDE_DEPTH};
use crate::intersect::leaf_blocks::test_leaf_blocks;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::{NodeTests, WideRay};
use crate::traverse::tree_step::{test_leaf, trace_tree, PrimLists, TreeEvent, TreeWalk};
use last_occluder::{test_cached_leaf, test_cached_leaf4, LastOccluder};

pub use crate::traverse::boxes::wide_slab::{NodeRay, WideSlab};

/// Stack capacity for nodes of `width` children: at most `width − 1` entries wait per
/// level of a tree of [`MAX_WIDE_DEPTH`] (the image validation bounds the depth).
pub const fn stack_capacity(width: usize) -> usize {
    (width - 1) * MAX_WIDE_DEPTH as usize + width
}

/// The traversal stack of `C` entries: `(child or first entry, leaf count or 0, entry
/// distance)`. Its capacity is a parameter so that a 4-wide walk does not carry the
/// 8-wide one's (the hardware model keeps a walk per ray in flight).
type Stack<const C: usize> = heapless::Vec<(u32, u32, f32), C>;

/// The traversal registers of one ray in a wide BVH: the entry to visit next, a
/// fixed-capacity stack of `(child or first entry, leaf count or 0, entry distance)`, and
/// the best hit so far. One [`WideBvhTraversal::step`] reads one node and tests its
/// boxes with `R` (the `f32` SIMD tests, or the fixed-point test:
/// [`crate::traverse::boxes::datapath`]).
#[derive(Clone, Debug)]
pub struct WideBvhTraversal<N: WideSlab, const C: usize, R: WideRay<N> = NodeRay> {
    ray: R,
    t_min: f32,
    // The best hit's distance (or the ray's end): boxes entered beyond it are skipped.
    t_end: f32,
    current: (u32, u32),
    // heapless: fixed capacity, and nothing is written until pushed (no per-ray memset).
    stack: Stack<C>,
    done: bool,
    /// Closest hit so far.
    pub best: Option<Hit>,
    // The node type: the stack capacity `C` is sized for its width.
    node: PhantomData<fn() -> N>,
}

impl<N: WideSlab, const C: usize, R: WideRay<N>> WideBvhTraversal<N, C, R> {
    /// Starts a ray at the root; an invalid ray is done at once.
    #[inline]
    pub fn new(ray: &Ray) -> WideBvhTraversal<N, C, R> {
        WideBvhTraversal {
            ray: R::for_ray(ray),
            t_min: ray.t_min,
            t_end: ray.t_max,
            current: (0, 0),
            stack: heapless::Vec::new(),
            done: !ray.is_valid(),
            best: None,
            node: PhantomData,
        }
    }

    /// Reads one inner node and moves to its nearest hit child (pushing the others), or
    /// reports the leaf the walk stands on.
    #[inline(always)]
    pub fn step<P: MemoryProbe>(&mut self, bvh: &WideBvhView<'_, N>, probe: &mut P) -> TreeEvent {
        if self.done {
            return TreeEvent::Done;
        }
        let (index, count) = self.current;
        if count > 0 {
            return TreeEvent::Leaf { first: index, count };
        }
        let node = bvh.node(index, probe);
        let mut tn = N::Dist::default();
        let mask = self.ray.slab(node, self.t_min, self.t_end, &mut tn);
        if mask == 0 {
            self.pop();
            return TreeEvent::Inner;
        }
        self.current = descend(node, &tn, mask, &mut self.stack);
        TreeEvent::Inner
    }

    /// After a leaf's triangles: nearer boxes only from now on, and on to the next entry.
    #[inline(always)]
    pub fn finish_leaf(&mut self) {
        self.t_end = self.best.map_or(self.t_end, |h| h.t);
        self.pop();
    }

    /// Pops the next entry that may still hold a closer hit, or ends the walk.
    #[inline(always)]
    fn pop(&mut self) {
        match pop_next(&mut self.stack, self.t_end) {
            Some(next) => self.current = next,
            None => self.done = true,
        }
    }
}

/// Moves on from `node`, whose hit slots are `mask` (non-empty) with entry distances
/// `t`: returns the nearest slot's `(child, count)` and pushes the others, farthest
/// first.
#[inline(always)]
fn descend<N: WideSlab, const C: usize>(node: &N, t: &N::Dist, mask: u32, stack: &mut Stack<C>) -> (u32, u32) {
    let first = mask.trailing_zeros() as usize & (N::WIDTH - 1);
    let rest = mask & (mask - 1);
    if rest == 0 {
        // One child hit (the common case for coherent rays): no sorting.
        return node.link(first);
    }
    if rest & (rest - 1) == 0 {
        // Two children: one comparison.
        let second = rest.trailing_zeros() as usize & (N::WIDTH - 1);
        let (near, far) = if t[second] < t[first] { (second, first) } else { (first, second) };
        let (c, n) = node.link(far);
        // Cannot be full: `parse` bounds the depth (see `stack_capacity`).
        let _ = stack.push((c, n, t[far]));
        return node.link(near);
    }
    // Three or more: pushed in slot order, then the new entries sorted farthest first,
    // ties in slot order (insertion sort: at most eight), and the nearest popped. (Sorting
    // 64-bit keys in registers first took fewer instructions but measured slower.)
    let base = stack.len();
    push_slots(node, t, mask, stack);
    let s = stack.get_mut(base..).unwrap_or_default();
    for i in 1..s.len() {
        let mut j = i;
        while j > 0 && s[j - 1].2 <= s[j].2 {
            s.swap(j - 1, j);
            j -= 1;
        }
    }
    let (c, n, _) = stack.pop().unwrap_or((0, 0, 0.0));
    (c, n)
}

/// [`descend`] for the any-hit query, which needs no order: the lowest hit slot next,
/// the others pushed in slot order (Embree's any-hit traversal does not sort either).
#[inline(always)]
fn descend_any<N: WideSlab, const C: usize>(node: &N, t: &N::Dist, mask: u32, stack: &mut Stack<C>) -> (u32, u32) {
    let first = mask.trailing_zeros() as usize & (N::WIDTH - 1);
    push_slots(node, t, mask & (mask - 1), stack);
    node.link(first)
}

/// Pushes the slots set in `mask` of `node` with their entry distances, in slot order.
#[inline(always)]
fn push_slots<N: WideSlab, const C: usize>(node: &N, t: &N::Dist, mask: u32, stack: &mut Stack<C>) {
    let mut m = mask;
    while m != 0 {
        let k = m.trailing_zeros() as usize & (N::WIDTH - 1);
        m &= m - 1;
        let (c, n) = node.link(k);
        // Cannot be full: `parse` bounds the depth (see `stack_capacity`).
        let _ = stack.push((c, n, t[k]));
    }
}

/// Pops the next entry whose entry distance is not beyond `t_end`.
#[inline(always)]
fn pop_next<const C: usize>(stack: &mut Stack<C>, t_end: f32) -> Option<(u32, u32)> {
    loop {
        let (c, n, t) = stack.pop()?;
        if t <= t_end {
            return Some((c, n));
        }
    }
}

impl<N: WideSlab, const C: usize, R: WideRay<N>> TreeWalk<WideBvhView<'_, N>> for WideBvhTraversal<N, C, R> {
    #[inline(always)]
    fn step<P: MemoryProbe>(&mut self, view: &WideBvhView<'_, N>, _ray: &Ray, probe: &mut P) -> TreeEvent {
        WideBvhTraversal::step(self, view, probe)
    }

    #[inline(always)]
    fn finish_leaf(&mut self) {
        WideBvhTraversal::finish_leaf(self)
    }

    #[inline(always)]
    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.best
    }
}

/// The closest hit of `ray` through a wide BVH.
///
/// The host's loop: the same walk as [`WideBvhTraversal::step`] (the same node test,
/// `descend` and `pop_next`), with its registers held in locals rather than in a
/// walk record, so that they stay in machine registers across nodes.
#[inline(always)]
pub fn trace_wide_bvh<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit>
where
    <I::Nodes as NodeTests>::Wide: WideRay<N>,
{
    search_wide_bvh::<N, C, I, P, false>(scene, bvh, ray, &mut LastOccluder::default(), probe, counters)
}

/// The any-hit query of `ray` through a wide BVH: the same walk as [`trace_wide_bvh`],
/// ended by the first leaf in which the ray hits something (the shadow ray's question,
/// Purcell 2002 §3.1.4). True exactly when the closest-hit query finds a hit.
#[inline(always)]
pub fn occluded_wide_bvh<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool
where
    <I::Nodes as NodeTests>::Wide: WideRay<N>,
{
    occluded_wide_bvh_cached::<N, C, I, P>(scene, bvh, ray, &mut LastOccluder::default(), probe, counters)
}

/// The any-hit query of `ray` through a wide BVH, the leaf of `cache` ([`last_occluder`])
/// tested before the root and the leaf that blocks the ray kept in it: the same answer as
/// [`occluded_wide_bvh`], for every ray and every cache.
#[inline(always)]
pub fn occluded_wide_bvh_cached<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool
where
    <I::Nodes as NodeTests>::Wide: WideRay<N>,
{
    search_wide_bvh::<N, C, I, P, true>(scene, bvh, ray, cache, probe, counters).is_some()
}

/// The walk of both queries; with `ANY` it returns the first hit found, not the closest,
/// testing `cache`'s leaf first and keeping in it the leaf where the walk found one.
#[inline(always)]
fn search_wide_bvh<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe, const ANY: bool>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit>
where
    <I::Nodes as NodeTests>::Wide: WideRay<N>,
{
    if !<I::Nodes as NodeTests>::FLOAT {
        // Another datapath's box test: the step walk with it (the loop below is the f32
        // tests' fast path).
        let walk = WideBvhTraversal::<N, C, <I::Nodes as NodeTests>::Wide>::new(ray);
        return trace_tree::<I, P, _, _>(scene, bvh, walk, ray, probe, counters);
    }
    if !ray.is_valid() {
        return None;
    }
    search_valid::<N, C, I, P, ANY>(scene, bvh, ray, cache, false, probe, counters)
}

/// [`search_wide_bvh`] for a valid ray with the `f32` node tests; `voted`: the ray has
/// tested the cached leaf already (and missed), so it walks at once.
#[inline(always)]
fn search_valid<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe, const ANY: bool>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    cache: &mut LastOccluder,
    voted: bool,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let mut tested = voted;
    if ANY && !voted && cache.to_test().is_some() {
        tested = true;
        if let Some(hit) = test_cached_leaf::<I, P, _>(scene, bvh, ray, cache, probe, counters) {
            return Some(hit);
        }
    }
    walk_octant::<N, C, I, P, ANY>(scene, bvh, ray, cache, tested, probe, counters)
}

/// The any-hit query of up to four rays (`rays`; `None` and invalid rays are free)
/// through a wide BVH, with the shadow cache: the cached leaf tested by the four rays at
/// once ([`last_occluder`]), the rays it does not block walking one by one. Bit `k` of
/// the result: ray `k` is blocked. The same answers as [`occluded_wide_bvh`].
#[inline(always)]
pub fn occluded_wide_bvh_cached4<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    rays: [Option<&Ray>; 4],
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> u32
where
    <I::Nodes as NodeTests>::Wide: WideRay<N>,
{
    let mut lanes = 0u32;
    for (k, r) in rays.iter().enumerate() {
        lanes |= (r.is_some_and(Ray::is_valid) as u32) << k;
    }
    let Some(&Some(any)) = rays.get(lanes.trailing_zeros() as usize) else {
        return 0;
    };
    let mut blocked = 0u32;
    if !<I::Nodes as NodeTests>::FLOAT {
        // Another datapath's box test: ray by ray.
        for (k, ray) in rays.iter().enumerate() {
            let hit = ray.and_then(|r| search_wide_bvh::<N, C, I, P, true>(scene, bvh, r, cache, probe, counters));
            blocked |= (hit.is_some() as u32) << k;
        }
        return blocked;
    }
    let (mut tested, mut found) = (0u32, 0u32);
    let group_leaf = cache.leaf();
    if lanes.count_ones() > 1 {
        // Lanes without a ray take one that has one, for the shared constants.
        let ray = |k: usize| if lanes & (1 << k) != 0 { rays[k].unwrap_or(any) } else { any };
        let four = [ray(0), ray(1), ray(2), ray(3)];
        (tested, found) = test_cached_leaf4::<I, P, _>(scene, bvh, &four, lanes, cache, probe, counters);
        blocked = found;
    }
    let mut rest = lanes & !found;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize & 3;
        rest &= rest - 1;
        let ray = rays[k].unwrap_or(any);
        // A ray that missed the group's leaf still tests the one a neighbour's walk has
        // put in its place: neighbours are blocked by neighbouring leaves.
        let voted = tested & (1 << k) != 0 && cache.leaf() == group_leaf;
        let hit = search_valid::<N, C, I, P, true>(scene, bvh, ray, cache, voted, probe, counters);
        blocked |= (hit.is_some() as u32) << k;
    }
    blocked
}

/// The walk of a valid ray with the `f32` node tests, in the form for its octant; with
/// `ANY`, `cache` keeps the leaf that blocks it (`tested`: the ray has tested the cached
/// leaf already, and voted).
#[inline(always)]
fn walk_octant<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe, const ANY: bool>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    cache: &mut LastOccluder,
    tested: bool,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let r = NodeRay::new(ray);
    // A walk per octant where the node test has forms for one octant: each reads its
    // near and far planes at fixed offsets (reading the ray's six offsets and masking
    // them took 12 of a node's 62 instructions on Sponza). Coherent rays keep to one or
    // two of the eight walks.
    let (best, leaf) = if N::OCTANT_FORMS && r.fma8.is_some() {
        match r.octant() {
            0 => walk::<N, C, I, P, 0, ANY>(scene, bvh, ray, &r, probe, counters),
            1 => walk::<N, C, I, P, 1, ANY>(scene, bvh, ray, &r, probe, counters),
            2 => walk::<N, C, I, P, 2, ANY>(scene, bvh, ray, &r, probe, counters),
            3 => walk::<N, C, I, P, 3, ANY>(scene, bvh, ray, &r, probe, counters),
            4 => walk::<N, C, I, P, 4, ANY>(scene, bvh, ray, &r, probe, counters),
            5 => walk::<N, C, I, P, 5, ANY>(scene, bvh, ray, &r, probe, counters),
            6 => walk::<N, C, I, P, 6, ANY>(scene, bvh, ray, &r, probe, counters),
            _ => walk::<N, C, I, P, 7, ANY>(scene, bvh, ray, &r, probe, counters),
        }
    } else {
        walk::<N, C, I, P, ANY_OCTANT, ANY>(scene, bvh, ray, &r, probe, counters)
    };
    if ANY {
        match best {
            Some(_) => cache.blocked_in(leaf.0, leaf.1, tested),
            None => cache.free(tested),
        }
    }
    best
}

/// `walk`'s octant parameter for a walk that takes the ray's octant from the ray.
const ANY_OCTANT: usize = 8;

/// [`trace_wide_bvh`]'s loop for a ray of octant `O` (`ANY_OCTANT`: any); with `ANY`,
/// ended by the first leaf that holds a hit, which it returns beside the hit.
#[inline(always)]
fn walk<N: WideSlab, const C: usize, I: Intersector, P: MemoryProbe, const O: usize, const ANY: bool>(
    scene: &SceneView<'_>,
    bvh: &WideBvhView<'_, N>,
    ray: &Ray,
    r: &NodeRay,
    probe: &mut P,
    counters: &mut RayCounters,
) -> (Option<Hit>, (u32, u32)) {
    let blocks = scene.has_tri_blocks();
    let mut prep = None;
    let mut best = None;
    let mut t_end = ray.t_max;
    let mut stack = Stack::<C>::new();
    let mut tn = N::Dist::default();
    let (mut index, mut count) = (0u32, 0u32);
    let (mut nodes, mut leaves, mut tests) = (0u32, 0u32, 0u32);
    loop {
        if count == 0 {
            nodes += 1;
            let node = bvh.node(index, probe);
            let mask = if O < 8 {
                node.slab_in::<O>(r, ray.t_min, t_end, &mut tn)
            } else {
                node.slab(r, ray.t_min, t_end, &mut tn)
            };
            if mask != 0 {
                (index, count) =
                    if ANY { descend_any(node, &tn, mask, &mut stack) } else { descend(node, &tn, mask, &mut stack) };
                continue;
            }
        } else {
            leaves += 1;
            // The watertight constants wait for the first leaf: many rays never reach one.
            // (Inline: a call here measured 11% slower on Sponza, though fewer instructions.)
            let prep = prep.get_or_insert_with(|| I::prepare(ray));
            test_wide_leaf::<I, P, _, ANY>(scene, bvh, prep, ray, (index, count), &mut best, blocks, probe);
            // Cannot overflow: a ray tests at most PRIM_LISTS' length (the parse bounds it).
            tests += count;
            t_end = best.map_or(t_end, |h: Hit| h.t);
            if ANY && best.is_some() {
                break;
            }
        }
        match pop_next(&mut stack, t_end) {
            Some(next) => (index, count) = next,
            None => break,
        }
    }
    counters.nodes = counters.nodes.saturating_add(nodes);
    counters.leaves = counters.leaves.saturating_add(leaves);
    counters.tri_tests = counters.tri_tests.saturating_add(tests);
    (best, (index, count))
}

/// A leaf's triangles against one ray, into `best`: four at a time from the image's leaf
/// blocks when it has them (`blocks`) and the test has a block form, else one by one.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn test_wide_leaf<I: Intersector, P: MemoryProbe, V: PrimLists, const ANY: bool>(
    scene: &SceneView<'_>,
    view: &V,
    prep: &I::Prepared,
    ray: &Ray,
    leaf: (u32, u32),
    best: &mut Option<Hit>,
    blocks: bool,
    probe: &mut P,
) {
    if I::BLOCKS && blocks {
        test_leaf_blocks::<I, P, _, ANY>(scene, view, prep, ray, leaf, best, probe);
    } else {
        test_leaf::<I, P, _>(scene, view, prep, ray, leaf, best, probe);
    }
}
