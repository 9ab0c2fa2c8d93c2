//! The packet's walk through the 4-wide BVH: one node per step for the whole packet,
//! culled by its frustum (or ray by ray), needed children nearest first, a leaf's
//! triangles tested by the rays that enter its box.

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView, MAX_WIDE_DEPTH};
use crate::intersect::triangle::Intersector;
use crate::packet::{
    occluded_lanes_ray_by_ray, ray_by_ray, LanesOf, PacketCounters, PacketHits, RayPacket, MAX_PACKET,
};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::wide_bvh::node4::slab4_exact;
use crate::traverse::wide_bvh::node4::{occluded_bvh4, trace_bvh4};
use glam::{BVec4A, Vec3A, Vec4};

use super::apex::Apex;
use super::frustum::Frustum;
use super::groups::Groups;
use super::leaf::{leaf_entries, test_entered, LeafVisit};
use super::many_origins::occluded_many_origins;
use super::prepared::Preps;

pub(in crate::packet) const STACK: usize = 3 * MAX_WIDE_DEPTH as usize + 4;

/// How the packet culls boxes: by its frustum, or ray by ray with each ray's exact box
/// test when some ray has a zero direction component (see [`RayBox`]).
// No heap in core to box the per-ray tests: they live on the stack for one packet, and
// are borrowed here, so that the frustum's packets (nearly all) do not move them (a
// copy of the whole record per packet was 2% of the bunny's packet time).
pub(super) enum Cull<'b, const N: usize> {
    Frustum(Frustum),
    /// Rays that end at one point, bounded by the pyramid from it.
    Apex(&'b mut Apex),
    Exact(&'b [RayBox; N]),
}

/// The slots set in `mask`, ordered by entry distance `t` (insertion sort: at most `W`,
/// four or eight), and how many there are.
#[inline(always)]
pub(in crate::packet) fn nearest_first<const W: usize>(mask: u32, t: &[f32; W]) -> ([usize; W], usize) {
    let mut order = [0usize; W];
    let mut m = 0;
    for k in 0..W {
        if mask & (1 << k) != 0 {
            let mut j = m;
            // Indices reduced modulo `W` (a power of two: a mask): the compiler sees them
            // in range (no panic path).
            while j > 0 && t[order[(j - 1) % W] % W] > t[k] {
                order[j % W] = order[(j - 1) % W];
                j -= 1;
            }
            order[j % W] = k;
            m += 1;
        }
    }
    (order, m)
}

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
///
/// Inner nodes are tested once for the whole packet with the interval-arithmetic
/// `Frustum`; at a leaf each ray tests the leaf's box (up to its own best hit) and only
/// the rays that enter it test the triangles (four rays against one triangle at once where
/// two or more of a group of four lanes enter). Since the frustum test is conservative,
/// every ray still tests every triangle its single-ray walk would. A packet whose rays
/// have a zero direction component falls back to one exact 4-box test per ray and node;
/// rays of many origins and several octants are traced one by one.
pub fn trace_bvh4_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    // Rays of many origins whose directions change sign on an axis (a diffuse bounce, a
    // path's secondaries) have no frustum that culls: the interval of their reciprocal
    // directions spans both signs, so the packet walked the whole tree (the conference
    // room's bounces: 0.1 Mrays/s in packets against 4 for single rays). They go ray by
    // ray, as Embree's packets switch to single rays when few lanes agree.
    if !<I::Nodes as NodeTests>::FLOAT || !(packet.one_origin() || packet.one_octant()) {
        let walk = |r: &Ray, c: &mut RayCounters| trace_bvh4::<I, P>(scene, bvh, r, probe, c);
        return ray_by_ray(packet, hits, counters, walk);
    }
    walk_packet::<I, P, N, false>(scene, bvh, packet, packet.live(), hits, None, &mut None, probe, counters);
}

/// The any-hit query for a packet: bit `i` of the result is set when ray `i` is blocked
/// within its interval — exactly [`crate::traverse::occlusion::occluded`] for each
/// active ray. Rays of one origin (a light's, a hemisphere from one point) take the
/// closest-hit packet walk, but a ray leaves the packet at the first leaf where it hits
/// something, its end no longer widens the packet's reach, and the packet stops as soon
/// as all its rays are blocked. Rays of many origins that end at one point (shadow rays
/// from a block of pixels' hits to a point light) take the packet walk culled by the
/// pyramid from that point (`Apex`), and shrink it as they leave. Other rays of many
/// origins take their own walk, SIMD across rays with no frustum: their frustum spans the
/// distance between the hits and the light, and a packet of 64 such rays culled by it
/// ran at a third of the single rays' rate on Sponza (1.9 against 5.7 Mrays/s; across
/// rays, 9.4 in packets of 16).
pub fn occluded_bvh4_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) -> u64 {
    occluded_packet_walk::<I, P, N>(scene, bvh, packet, packet.live(), &mut None, probe, counters)
}

/// [`occluded_bvh4_packet`]'s walks for the lanes of `live` (live lanes of `packet`: the
/// rays a caller still asks about, so that it need not copy the packet to narrow its
/// mask), which set `found` to the last leaf where they found a ray blocked.
#[inline(always)]
pub(super) fn occluded_packet_walk<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    live: u64,
    found: &mut Option<(u32, u32)>,
    probe: &mut P,
    counters: &mut PacketCounters,
) -> u64 {
    let live = live & packet.live();
    if !<I::Nodes as NodeTests>::FLOAT {
        let any = |r: &Ray, c: &mut RayCounters| occluded_bvh4::<I, P>(scene, bvh, r, probe, c);
        return occluded_lanes_ray_by_ray(packet, live, counters, any);
    }
    let mut apex = None;
    if !packet.one_origin_in(live) {
        apex = shadow_pyramid(scene, packet, live);
        if apex.is_none() {
            return occluded_many_origins::<I, P, N>(scene, bvh, packet, live, found, probe, counters);
        }
    }
    let mut hits = [None; N];
    walk_packet::<I, P, N, true>(scene, bvh, packet, live, &mut hits, apex.as_mut(), found, probe, counters);
    let mut blocked = 0u64;
    for (i, h) in hits.iter().enumerate() {
        blocked |= (h.is_some() as u64) << i;
    }
    blocked & live
}

/// The pyramid from the one point where the rays of `live` end, if they do, it is narrow
/// (see [`Apex::new`]) and the packet is of the largest size.
#[inline(always)]
fn shadow_pyramid<const N: usize>(scene: &SceneView<'_>, packet: &RayPacket<N>, live: u64) -> Option<Apex> {
    // Only the largest packets: in packets of 16 the many-origin walk tests four groups
    // of rays per box, and the pyramid measured 0.7–0.75× its rate on Sponza and Lost
    // Empire.
    if N < MAX_PACKET {
        return None;
    }
    Apex::new(packet, live, scene.bounds())
}

/// Whether [`occluded_bvh4_packet`] culls `packet` by the pyramid from its rays' one end:
/// for the equivalence suites, which must be seen to reach that walk.
#[doc(hidden)]
pub fn takes_shadow_pyramid<const N: usize>(scene: &SceneView<'_>, packet: &RayPacket<N>) -> bool {
    !packet.one_origin() && shadow_pyramid(scene, packet, packet.live()).is_some()
}

/// The packet walk; with `ANY`, a ray that hits something in a leaf leaves the packet
/// (its hit is then some hit, not the closest), and the walk ends when none is left.
/// `apex`: the pyramid that bounds rays ending at one point, to cull by; `found`: set to
/// the last leaf where a ray was found blocked.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn walk_packet<I: Intersector, P: MemoryProbe, const N: usize, const ANY: bool>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    mask: u64,
    hits: &mut PacketHits<N>,
    apex: Option<&mut Apex>,
    found: &mut Option<(u32, u32)>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    *hits = [None; N];
    if mask == 0 {
        return;
    }
    // Each ray's exact box test, where the frustum cannot serve.
    let mut boxes: Option<[RayBox; N]> = None;
    // The lanes and the ray constants live here, built in place: moved into the walk
    // record whole, their kilobytes were copied once more per packet.
    let (mut lanes, mut preps) = (None, Preps::<I, N>::new());
    let mut walk = PacketWalk::<I, N>::start(packet, mask, &mut boxes, apex, &mut lanes, &mut preps);
    // (child or first entry, leaf count or 0, entry bound, leaf box as min xyz, max xyz)
    let mut stack: heapless::Vec<(u32, u32, f32, [f32; 6]), STACK> = heapless::Vec::new();
    let mut current = (0u32, 0u32, [0f32; 6], 0f32);
    loop {
        let (index, count, leaf_box, leaf_t) = current;
        walk.c.visits += 1;
        if count == 0 {
            if let Some(next) = walk.inner(bvh.node(index, probe), packet, hits, &mut stack) {
                current = next;
                continue;
            }
        } else {
            let leaf = LeafVisit { scene, bvh, packet, first: index, count };
            let before = walk.mask;
            walk.leaf::<P, ANY>(leaf, &leaf_box, leaf_t, hits, probe);
            if ANY && walk.mask != before {
                *found = Some((index, count));
            }
            if ANY && walk.mask == 0 {
                counters.add(&walk.c);
                return;
            }
        }
        // Pop the next entry whose entry bound is not beyond every ray's best hit.
        loop {
            let Some((child, count, t, b)) = stack.pop() else {
                counters.add(&walk.c);
                return;
            };
            if t > walk.t_end {
                continue;
            }
            // A pyramid that shrank since the child was pushed may exclude it now.
            if let Cull::Apex(p) = &walk.cull {
                if p.shrunk() && !p.holds(&b) {
                    continue;
                }
            }
            current = (child, count, b, t);
            break;
        }
    }
}

/// The packet's walk state: how it culls, its lanes in registers (made when a leaf first
/// needs them), its rays' intersection constants, how far any ray still looks, and its
/// counters.
struct PacketWalk<'b, I: Intersector, const N: usize> {
    cull: Cull<'b, N>,
    lanes: &'b mut Option<Groups>,
    preps: &'b mut Preps<I, N>,
    mask: u64,
    /// How far any ray of the packet still looks.
    t_end: f32,
    c: PacketCounters,
}

impl<'b, I: Intersector, const N: usize> PacketWalk<'b, I, N> {
    /// Groups of four lanes in a packet of `N`.
    const GROUPS: usize = N.div_ceil(4);

    /// The walk of the rays of `mask`: culled by `apex` if given, else by the frustum
    /// where one bounds them, else ray by ray with the exact tests kept in `boxes`.
    #[inline(always)]
    fn start(
        packet: &RayPacket<N>,
        mask: u64,
        boxes: &'b mut Option<[RayBox; N]>,
        apex: Option<&'b mut Apex>,
        lanes: &'b mut Option<Groups>,
        preps: &'b mut Preps<I, N>,
    ) -> Self {
        let groups = Self::GROUPS;
        if let Some(apex) = apex {
            // Its rays have no zero direction component (see `Apex::new`).
            let t_end = Groups::fill(lanes, packet, groups, mask).largest_end();
            return PacketWalk { cull: Cull::Apex(apex), lanes, preps, mask, t_end, c: PacketCounters::default() };
        }
        // The lanes in SIMD registers with their reciprocals: computed when the first leaf
        // needs them, if the frustum can do without (see `Frustum::from_full_packet`).
        let (frustum, t_end) = Frustum::of_packet(packet, mask, lanes);
        let cull = match frustum {
            Some(f) => Cull::Frustum(f),
            None => Cull::Exact(boxes.insert(core::array::from_fn(|i| RayBox::new(&packet.ray(i))))),
        };
        // The watertight constants (`preps`) are computed the first time a ray enters a
        // leaf: most rays of a frame never do.
        PacketWalk { cull, lanes, preps, mask, t_end, c: PacketCounters::default() }
    }

    /// An inner node: its four boxes culled for the packet, the needed children pushed
    /// but the nearest, which is returned as the next entry (none if no child is needed).
    #[inline(always)]
    fn inner(
        &mut self,
        node: &Bvh4Node,
        packet: &RayPacket<N>,
        hits: &PacketHits<N>,
        stack: &mut heapless::Vec<(u32, u32, f32, [f32; 6]), STACK>,
    ) -> Option<(u32, u32, [f32; 6], f32)> {
        let mask = self.mask;
        let (tn, needed) = match &self.cull {
            Cull::Frustum(f) => {
                self.c.active_lanes += mask.count_ones() as u64;
                f.slab4(node, self.t_end)
            }
            Cull::Apex(p) => {
                self.c.active_lanes += mask.count_ones() as u64;
                // No entry distances: the children in slot order, none dropped by a hit.
                (Vec4::NEG_INFINITY, p.cull4(node))
            }
            Cull::Exact(boxes) => {
                let mut needed = 0u32;
                let mut t = Vec4::INFINITY;
                for i in LanesOf::<N>(mask) {
                    let end = hits[i].map_or(packet.t_max[i], |h: Hit| h.t);
                    let (tn, m) = slab4_exact(&boxes[i], node, packet.t_min[i], end);
                    if m != 0 {
                        self.c.active_lanes += 1;
                        needed |= m;
                        let hit = BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
                        t = t.min(Vec4::select(hit, tn, Vec4::INFINITY));
                    }
                }
                (t, needed)
            }
        };
        let child_t = tn.to_array();
        // Needed children, nearest first.
        let (order, n) = nearest_first(needed, &child_t);
        if n == 0 {
            return None;
        }
        let slot_box = |k: usize| {
            let k = k & 3;
            [node.min_x[k], node.min_y[k], node.min_z[k], node.max_x[k], node.max_y[k], node.max_z[k]]
        };
        for &k in order.get(1..n).unwrap_or_default().iter().rev() {
            let k = k & 3;
            let _ = stack.push((node.child[k], node.count[k], child_t[k], slot_box(k)));
        }
        let k = order[0] & 3;
        Some((node.child[k], node.count[k], slot_box(k), child_t[k]))
    }

    /// A leaf (`leaf`, its box `leaf_box` entered at `leaf_t`): the rays that enter its
    /// box test its triangles, and the groups that did update their ends. With `ANY`, the
    /// rays that hit leave the walk.
    #[inline(always)]
    fn leaf<P: MemoryProbe, const ANY: bool>(
        &mut self,
        leaf: LeafVisit<'_, '_, Bvh4Node, N>,
        leaf_box: &[f32; 6],
        leaf_t: f32,
        hits: &mut PacketHits<N>,
        probe: &mut P,
    ) {
        let (packet, mask, groups) = (leaf.packet, self.mask, Self::GROUPS);
        let q = match *self.lanes {
            Some(ref mut q) => q,
            None => Groups::fill(self.lanes, packet, groups, mask),
        };
        let enter = match &self.cull {
            Cull::Exact(boxes) => {
                let lo = Vec3A::new(leaf_box[0], leaf_box[1], leaf_box[2]);
                let hi = Vec3A::new(leaf_box[3], leaf_box[4], leaf_box[5]);
                let mut enter = 0u64;
                for i in LanesOf::<N>(mask) {
                    let end = hits[i].map_or(packet.t_max[i], |h: Hit| h.t);
                    if boxes[i].entry(lo, hi, packet.t_min[i], end).is_some() {
                        enter |= 1 << i;
                    }
                }
                enter
            }
            Cull::Frustum(f) => leaf_entries(q, groups, mask, leaf_box, leaf_t, f.origin()),
            Cull::Apex(_) => leaf_entries(q, groups, mask, leaf_box, leaf_t, None),
        };
        self.c.active_lanes += enter.count_ones() as u64;
        if enter == 0 {
            return;
        }
        let origin = match &self.cull {
            Cull::Frustum(f) => f.origin(),
            Cull::Apex(_) | Cull::Exact(_) => None,
        };
        test_entered::<I, P, Bvh4Node, N>(&leaf, enter, (q, mask), origin, self.preps, hits, probe);
        self.c.tri_tests += leaf.count as u64 * enter.count_ones() as u64;
        if ANY {
            for i in LanesOf::<N>(enter) {
                if hits[i].is_some() {
                    self.mask &= !(1 << i);
                }
            }
            if let Cull::Apex(p) = &mut self.cull {
                p.shrink(self.mask);
            }
        }
        self.t_end = q.update_ends(enter, self.mask, hits, packet);
    }
}
