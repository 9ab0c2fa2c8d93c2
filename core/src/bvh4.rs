//! 4-wide BVH traversal: one node holds the boxes of four children, tested together by a
//! 4-lane slab test (SSE on x86-64 through glam's `Vec4`); hit children are visited
//! nearest first, the others pushed on a fixed-capacity stack (Wald, Benthin & Boulos
//! 2008; Embree's BVH4). Leaves are stack entries like nodes, so a leaf is intersected
//! only when it is the nearest thing left to visit.

use glam::{BVec4A, Vec3A, Vec4, Vec4Swizzles};

use crate::aabb::SLAB_GROWTH;
use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView, MAX_TREE_DEPTH};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::ray_box::RayBox;
use crate::tree_step::{test_leaf, TreeEvent, TreeWalk};
use crate::triangle::Intersector;

/// Stack capacity: at most three entries wait per level of a tree of [`MAX_TREE_DEPTH`].
const STACK: usize = 3 * MAX_TREE_DEPTH as usize + 4;

/// The ray as the 4-wide node test reads it: origin and reciprocal direction splatted
/// over four lanes, and per axis which of a box's two planes is entered first (the
/// ray's octant). Each axis then costs one subtraction and one product per plane and no
/// min/max (the sign trick of Williams et al. 2005, as in Embree's BVH4).
#[derive(Clone, Copy, Debug)]
pub struct NodeRay {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    // Per axis, the node row (see `rows`) of the near and the far plane.
    near: [usize; 3],
    far: [usize; 3],
    rb: RayBox,
}

impl NodeRay {
    /// Precomputes the splats and the octant.
    #[inline]
    pub fn new(ray: &Ray) -> NodeRay {
        let rb = RayBox::new(ray);
        let neg = rb.inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let (o, inv) = (Vec4::from((rb.origin, 0.0)), Vec4::from((rb.inv, 0.0)));
        NodeRay {
            org: [o.xxxx(), o.yyyy(), o.zzzz()],
            inv: [inv.xxxx(), inv.yyyy(), inv.zzzz()],
            near: core::array::from_fn(|a| a + 3 * ((neg >> a) & 1)),
            far: core::array::from_fn(|a| a + 3 * (!(neg >> a) & 1)),
            rb,
        }
    }
}

/// Entry distances of the ray into the four child boxes of `n`, within `[t0, t1]`, and
/// the bit mask of those it hits (empty slots, whose boxes are inverted, never).
#[inline(always)]
pub fn slab4(r: &NodeRay, n: &Bvh4Node, t0: f32, t1: f32) -> (Vec4, u32) {
    if r.rb.zero_axes != 0 {
        return slab4_exact(&r.rb, n, t0, t1);
    }
    // The node's planes as rows: min x, y, z, then max x, y, z (then children, counts).
    let rows: &[[f32; 4]; 8] = bytemuck::cast_ref(n);
    let near = |a: usize| (Vec4::from_array(rows[r.near[a] & 7]) - r.org[a]) * r.inv[a];
    let far = |a: usize| (Vec4::from_array(rows[r.far[a] & 7]) - r.org[a]) * r.inv[a];
    // The product is monotone in the plane, so these are the min and max of the two
    // planes' distances for a valid box; an inverted (empty) slot gets near > far on
    // every axis and fails the comparison.
    let tn = near(0).max(near(1)).max(near(2).max(Vec4::splat(t0)));
    let tf = (far(0).min(far(1)).min(far(2)) * SLAB_GROWTH).min(Vec4::splat(t1));
    (tn, tn.cmple(tf).bitmask())
}

/// [`slab4`] for any ray, including one with a zero direction component (whose axis is
/// tested as "origin inside the slab", see [`RayBox`]).
#[inline(always)]
pub fn slab4_exact(rb: &RayBox, n: &Bvh4Node, t0: f32, t1: f32) -> (Vec4, u32) {
    let (o, inv) = (rb.origin, rb.inv);
    let ax = (Vec4::from_array(n.min_x) - o.x) * inv.x;
    let bx = (Vec4::from_array(n.max_x) - o.x) * inv.x;
    let ay = (Vec4::from_array(n.min_y) - o.y) * inv.y;
    let by = (Vec4::from_array(n.max_y) - o.y) * inv.y;
    let az = (Vec4::from_array(n.min_z) - o.z) * inv.z;
    let bz = (Vec4::from_array(n.max_z) - o.z) * inv.z;
    // For a valid box the near plane's distance is the smaller; an empty slot's inverted
    // box becomes an interval too, so empty slots are masked by the sign test below.
    let (mut nx, mut fx) = (ax.min(bx), ax.max(bx));
    let (mut ny, mut fy) = (ay.min(by), ay.max(by));
    let (mut nz, mut fz) = (az.min(bz), az.max(bz));
    let mut inside = BVec4A::splat(true);
    if rb.zero_axes != 0 {
        // A direction component of zero: inside the slab or never (see `RayBox`).
        let axes = [
            (0, &mut nx, &mut fx, n.min_x, n.max_x, o.x),
            (1, &mut ny, &mut fy, n.min_y, n.max_y, o.y),
            (2, &mut nz, &mut fz, n.min_z, n.max_z, o.z),
        ];
        for (k, near, far, lo, hi, ok) in axes {
            if rb.zero_axes & (1 << k) != 0 {
                let o4 = Vec4::splat(ok);
                inside &= o4.cmpge(Vec4::from_array(lo)) & o4.cmple(Vec4::from_array(hi));
                *near = Vec4::NEG_INFINITY;
                *far = Vec4::INFINITY;
            }
        }
    }
    let tn = nx.max(ny).max(nz.max(Vec4::splat(t0)));
    let tf = (fx.min(fy).min(fz) * SLAB_GROWTH).min(Vec4::splat(t1));
    // Inverted (empty) slots: min > max on x.
    let real = Vec4::from_array(n.min_x).cmple(Vec4::from_array(n.max_x));
    (tn, (tn.cmple(tf) & inside & real).bitmask())
}

/// The traversal registers of one ray in the 4-wide BVH: the entry to visit next, a
/// fixed-capacity stack of `(child or first entry, leaf count or 0, entry distance)`, and
/// the best hit so far. One [`Bvh4Traversal::step`] reads one node.
#[derive(Clone, Debug)]
pub struct Bvh4Traversal {
    ray: NodeRay,
    t_min: f32,
    // The best hit's distance (or the ray's end): boxes entered beyond it are skipped.
    t_end: f32,
    current: (u32, u32),
    // heapless: fixed capacity, and nothing is written until pushed (no per-ray memset).
    stack: Stack,
    done: bool,
    /// Closest hit so far.
    pub best: Option<Hit>,
}

impl Bvh4Traversal {
    /// Starts a ray at the root; an invalid ray is done at once.
    #[inline]
    pub fn new(ray: &Ray) -> Bvh4Traversal {
        Bvh4Traversal {
            ray: NodeRay::new(ray),
            t_min: ray.t_min,
            t_end: ray.t_max,
            current: (0, 0),
            stack: heapless::Vec::new(),
            done: !ray.is_valid(),
            best: None,
        }
    }

    /// Reads one inner node and moves to its nearest hit child (pushing the others), or
    /// reports the leaf the walk stands on.
    #[inline(always)]
    pub fn step<P: MemoryProbe>(&mut self, bvh: &Bvh4View<'_>, probe: &mut P) -> TreeEvent {
        if self.done {
            return TreeEvent::Done;
        }
        let (index, count) = self.current;
        if count > 0 {
            return TreeEvent::Leaf { first: index, count };
        }
        let node = bvh.node(index, probe);
        let (tn, mask) = slab4(&self.ray, node, self.t_min, self.t_end);
        if mask == 0 {
            self.pop();
            return TreeEvent::Inner;
        }
        self.current = descend(node, tn, mask, &mut self.stack);
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

/// The traversal stack: `(child or first entry, leaf count or 0, entry distance)`.
type Stack = heapless::Vec<(u32, u32, f32), STACK>;

/// Moves on from `node`, whose hit slots are `mask` (non-empty) with entry distances
/// `tn`: returns the nearest slot's `(child, count)` and pushes the others, farthest
/// first.
#[inline(always)]
fn descend(node: &Bvh4Node, tn: Vec4, mask: u32, stack: &mut Stack) -> (u32, u32) {
    let t = tn.to_array();
    let first = mask.trailing_zeros() as usize & 3;
    let rest = mask & (mask - 1);
    if rest == 0 {
        // One child hit (the common case for coherent rays): no sorting.
        return (node.child[first], node.count[first]);
    }
    if rest & (rest - 1) == 0 {
        // Two children: one comparison.
        let second = rest.trailing_zeros() as usize & 3;
        let (near, far) = if t[second] < t[first] { (second, first) } else { (first, second) };
        // Cannot be full: `parse` bounds the depth (see `STACK`).
        let _ = stack.push((node.child[far], node.count[far], t[far]));
        return (node.child[near], node.count[near]);
    }
    // Three or four.
    let (order, m) = nearest_first(mask, &t);
    for &k in order[1..m].iter().rev() {
        let _ = stack.push((node.child[k], node.count[k], t[k]));
    }
    let k = order[0];
    (node.child[k], node.count[k])
}

/// Pops the next entry whose entry distance is not beyond `t_end`.
#[inline(always)]
fn pop_next(stack: &mut Stack, t_end: f32) -> Option<(u32, u32)> {
    loop {
        let (c, n, t) = stack.pop()?;
        if t <= t_end {
            return Some((c, n));
        }
    }
}

/// The slots set in `mask`, ordered by entry distance `t` (insertion sort: at most four),
/// and how many there are.
#[inline(always)]
pub fn nearest_first(mask: u32, t: &[f32; 4]) -> ([usize; 4], usize) {
    let mut order = [0usize; 4];
    let mut m = 0;
    for k in 0..4 {
        if mask & (1 << k) != 0 {
            let mut j = m;
            while j > 0 && t[order[j - 1]] > t[k] {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = k;
            m += 1;
        }
    }
    (order, m)
}

impl TreeWalk<Bvh4View<'_>> for Bvh4Traversal {
    #[inline(always)]
    fn step<P: MemoryProbe>(&mut self, view: &Bvh4View<'_>, _ray: &Ray, probe: &mut P) -> TreeEvent {
        Bvh4Traversal::step(self, view, probe)
    }

    #[inline(always)]
    fn finish_leaf(&mut self) {
        Bvh4Traversal::finish_leaf(self)
    }

    #[inline(always)]
    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.best
    }
}

/// The closest hit of `ray` through the 4-wide BVH.
///
/// The host's loop: the same walk as [`Bvh4Traversal::step`] (the same node test,
/// [`descend`] and [`pop_next`]), with its registers held in locals rather than in a
/// walk record, so that they stay in machine registers across nodes.
#[inline]
pub fn trace_bvh4<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    if !ray.is_valid() {
        return None;
    }
    let r = NodeRay::new(ray);
    // The watertight constants wait for the first leaf: many rays never reach one.
    let mut prep = None;
    let mut best = None;
    let mut t_end = ray.t_max;
    let mut stack = Stack::new();
    let (mut index, mut count) = (0u32, 0u32);
    let (mut nodes, mut leaves, mut tests) = (0u32, 0u32, 0u32);
    loop {
        if count == 0 {
            nodes += 1;
            let node = bvh.node(index, probe);
            let (tn, mask) = slab4(&r, node, ray.t_min, t_end);
            if mask != 0 {
                (index, count) = descend(node, tn, mask, &mut stack);
                continue;
            }
        } else {
            leaves += 1;
            let prep = prep.get_or_insert_with(|| I::prepare(ray));
            test_leaf::<I, P, _>(scene, bvh, prep, ray, (index, count), &mut best, probe);
            tests += count;
            t_end = best.map_or(t_end, |h: Hit| h.t);
        }
        match pop_next(&mut stack, t_end) {
            Some(next) => (index, count) = next,
            None => break,
        }
    }
    counters.nodes += nodes;
    counters.leaves += leaves;
    counters.tri_tests += tests;
    best
}
