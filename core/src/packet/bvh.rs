//! Packet traversal of the binary BVH (Wald, Boulos & Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies"): the packet enters a
//! child with the mask of its rays that hit the child's box, nearer child first.

use glam::Vec3A;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{BvhNode, BvhView, SceneView, MAX_TREE_DEPTH};
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::packet::{ray_by_ray, LanesOf, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::bvh::trace_bvh;

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_bvh_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &BvhView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    if !<I::Nodes as NodeTests>::FLOAT {
        let walk = |r: &Ray, c: &mut RayCounters| trace_bvh::<I, P>(scene, bvh, r, probe, c);
        return ray_by_ray(packet, hits, counters, walk);
    }
    let r = PacketRays::<I, N>::new(packet);
    *hits = [None; N];
    let mut stack: Stack = heapless::Vec::new();
    let mut c = PacketCounters::default();
    // The root box first.
    let root = bvh.node(0, probe);
    let mut mask = 0u64;
    for i in LanesOf::<N>(packet.live()) {
        let hit = r.boxes[i].entry(
            Vec3A::from_array(root.min),
            Vec3A::from_array(root.max),
            r.rays[i].t_min,
            r.rays[i].t_max,
        );
        if hit.is_some() {
            mask |= 1 << i;
        }
    }
    let mut node = root;
    if mask != 0 {
        loop {
            c.visits += 1;
            c.active_lanes += mask.count_ones() as u64;
            if node.count > 0 {
                test_leaf(scene, bvh, &node, &r, mask, hits, probe);
                c.tri_tests += node.count as u64 * mask.count_ones() as u64;
            } else if let Some((near, m)) = enter_children(bvh, &node, &r, mask, hits, &mut stack, probe) {
                node = near;
                mask = m;
                continue;
            }
            let Some((index, m)) = pop_next(&mut stack, &r, hits) else { break };
            node = bvh.node(index, probe);
            mask = m;
        }
    }
    counters.add(&c);
}

/// The walk's stack: (node, entry bound, the rays that entered it).
type Stack = heapless::Vec<(u32, f32, u64), { MAX_TREE_DEPTH as usize }>;

/// The packet's rays with their box-test and triangle-test constants, made once.
struct PacketRays<I: Intersector, const N: usize> {
    rays: [Ray; N],
    boxes: [RayBox; N],
    preps: [I::Prepared; N],
}

impl<I: Intersector, const N: usize> PacketRays<I, N> {
    #[inline(always)]
    fn new(packet: &RayPacket<N>) -> Self {
        let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
        let boxes: [RayBox; N] = core::array::from_fn(|i| RayBox::new(&rays[i]));
        let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
        PacketRays { rays, boxes, preps }
    }

    /// How far ray `i` still looks: its best hit so far, or its end.
    #[inline(always)]
    fn best_t(&self, hits: &PacketHits<N>, i: usize) -> f32 {
        hits[i].map_or(self.rays[i].t_max, |h: Hit| h.t)
    }
}

/// A leaf: its triangles, each read once, tested by the rays of `mask`.
#[inline(always)]
fn test_leaf<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &BvhView<'_>,
    node: &BvhNode,
    r: &PacketRays<I, N>,
    mask: u64,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) {
    for e in node.first..node.first.wrapping_add(node.count) {
        let prim = bvh.prim(e, probe);
        let verts = I::fetch(scene, prim, probe);
        for i in LanesOf::<N>(mask) {
            test_triangle::<I>(&r.preps[i], &r.rays[i], &verts, prim, &mut hits[i]);
        }
    }
}

/// An inner node: both children's boxes tested by the rays of `mask`; the packet enters
/// the child nearest to any of its rays (returned, with the rays that hit it) and pushes
/// the other with its rays. `None` when no ray enters either.
#[inline(always)]
fn enter_children<I: Intersector, P: MemoryProbe, const N: usize>(
    bvh: &BvhView<'_>,
    node: &BvhNode,
    r: &PacketRays<I, N>,
    mask: u64,
    hits: &PacketHits<N>,
    stack: &mut Stack,
    probe: &mut P,
) -> Option<(BvhNode, u64)> {
    let (ia, ib) = (node.first, node.first.wrapping_add(1));
    let a = bvh.node(ia, probe);
    let b = bvh.node(ib, probe);
    let (alo, ahi) = (Vec3A::from_array(a.min), Vec3A::from_array(a.max));
    let (blo, bhi) = (Vec3A::from_array(b.min), Vec3A::from_array(b.max));
    let (mut ma, mut mb) = (0u64, 0u64);
    let (mut ta, mut tb) = (f32::INFINITY, f32::INFINITY);
    for i in LanesOf::<N>(mask) {
        let end = r.best_t(hits, i);
        if let Some(t) = r.boxes[i].entry(alo, ahi, r.rays[i].t_min, end) {
            ma |= 1 << i;
            ta = ta.min(t);
        }
        if let Some(t) = r.boxes[i].entry(blo, bhi, r.rays[i].t_min, end) {
            mb |= 1 << i;
            tb = tb.min(t);
        }
    }
    match (ma != 0, mb != 0) {
        (true, true) => {
            let (near, nm, far, ft, fm) = if ta <= tb { (a, ma, ib, tb, mb) } else { (b, mb, ia, ta, ma) };
            let _ = stack.push((far, ft, fm));
            Some((near, nm))
        }
        (true, false) => Some((a, ma)),
        (false, true) => Some((b, mb)),
        (false, false) => None,
    }
}

/// The next entry of the stack that some of its rays still need (its entry bound not
/// beyond their best hits), with those rays.
#[inline(always)]
fn pop_next<I: Intersector, const N: usize>(
    stack: &mut Stack,
    r: &PacketRays<I, N>,
    hits: &PacketHits<N>,
) -> Option<(u32, u64)> {
    while let Some((index, t, m)) = stack.pop() {
        let mut still = 0u64;
        for i in LanesOf::<N>(m) {
            if t <= r.best_t(hits, i) {
                still |= 1 << i;
            }
        }
        if still != 0 {
            return Some((index, still));
        }
    }
    None
}
