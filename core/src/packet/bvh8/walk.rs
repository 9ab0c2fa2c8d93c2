//! The packet's closest-hit walk through the 8-wide BVH: one node per step for the whole
//! packet, culled by its frustum, needed children nearest first, a leaf's triangles
//! tested by the rays that enter its box.

use crate::counters::RayCounters;
use crate::image::{Bvh8Node, Bvh8View, SceneView};
use crate::intersect::triangle::Intersector;
use crate::packet::bvh4::frustum::Frustum;
use crate::packet::bvh4::groups::Groups;
use crate::packet::bvh4::leaf::{leaf_entries, test_entered, LeafVisit};
use crate::packet::bvh4::prepared::Preps;
use crate::packet::bvh4::walk::nearest_first;
use crate::packet::{ray_by_ray, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::wide_bvh::node8::trace_bvh8;
use crate::traverse::wide_bvh::stack_capacity;

/// Stack entries: up to seven pushed per level of the tree (the single-ray walk's
/// capacity rule).
const STACK: usize = stack_capacity(8);

/// (child or first entry, leaf count or 0, entry bound, child box as min xyz, max xyz)
type Entry = (u32, u32, f32, [f32; 6]);

/// Traces all active rays of `packet` through the 8-wide BVH; `hits[i]` receives ray
/// `i`'s closest hit, bit for bit the single-ray walk's.
///
/// Inner nodes are tested once for the whole packet with its interval-arithmetic
/// frustum (conservative: a box it rejects, every ray rejects); at a leaf each ray tests
/// the leaf's box up to its own best hit and only the rays that enter it test the
/// triangles, as in the 4-wide packet walk. Packets without a frustum (a zero direction
/// component, rays of many origins in several octants) and trees of fixed-point nodes
/// are traced ray by ray.
pub fn trace_bvh8_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh8View<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    *hits = [None; N];
    let mask = packet.live();
    if mask == 0 {
        return;
    }
    let culls = <I::Nodes as NodeTests>::FLOAT && (packet.one_origin() || packet.one_octant());
    // Built in place, its lanes filled there: moved in whole, the walk's kilobytes of
    // lanes and constants were copied once more per packet.
    let mut walk = Walk::<I, N> { lanes: None, preps: Preps::new(), mask, t_end: 0.0, c: PacketCounters::default() };
    let frustum = culls.then(|| Frustum::of_packet(packet, mask, &mut walk.lanes));
    let Some((Some(frustum), t_end)) = frustum else {
        let walk = |r: &Ray, c: &mut RayCounters| trace_bvh8::<I, P>(scene, bvh, r, probe, c);
        return ray_by_ray(packet, hits, counters, walk);
    };
    walk.t_end = t_end;
    let mut stack: heapless::Vec<Entry, STACK> = heapless::Vec::new();
    let mut current: Entry = (0, 0, 0.0, [0.0; 6]);
    loop {
        let (index, count, leaf_t, leaf_box) = current;
        walk.c.visits += 1;
        if count == 0 {
            if let Some(next) = walk.inner(&frustum, bvh.node(index, probe), &mut stack) {
                current = next;
                continue;
            }
        } else {
            let leaf = LeafVisit { scene, bvh, packet, first: index, count };
            walk.leaf::<P>(&frustum, leaf, &leaf_box, leaf_t, hits, probe);
        }
        // The next entry whose bound is not beyond every ray's best hit.
        loop {
            let Some(entry) = stack.pop() else {
                counters.add(&walk.c);
                return;
            };
            if entry.2 <= walk.t_end {
                current = entry;
                break;
            }
        }
    }
}

/// The walk's state: the lanes in registers (made when a leaf first needs them), the
/// rays' intersection constants, how far any ray still looks, the counters.
struct Walk<I: Intersector, const N: usize> {
    lanes: Option<Groups>,
    preps: Preps<I, N>,
    mask: u64,
    t_end: f32,
    c: PacketCounters,
}

impl<I: Intersector, const N: usize> Walk<I, N> {
    /// Groups of four lanes in a packet of `N`.
    const GROUPS: usize = N.div_ceil(4);

    /// An inner node: its eight boxes culled by `frustum`, the needed children pushed
    /// farthest first but the nearest, which is returned as the next entry.
    #[inline(always)]
    fn inner(&mut self, frustum: &Frustum, node: &Bvh8Node, stack: &mut heapless::Vec<Entry, STACK>) -> Option<Entry> {
        self.c.active_lanes += self.mask.count_ones() as u64;
        let (child_t, needed) = frustum.slab8(node, self.t_end);
        let (order, n) = nearest_first(needed, &child_t);
        if n == 0 {
            return None;
        }
        let entry = |k: usize| {
            let k = k & 7;
            let b = [node.min_x[k], node.min_y[k], node.min_z[k], node.max_x[k], node.max_y[k], node.max_z[k]];
            (node.child[k], node.count[k], child_t[k], b)
        };
        for &k in order.get(1..n).unwrap_or_default().iter().rev() {
            // Cannot overflow: at most seven pushes per level of a tree of bounded depth.
            let _ = stack.push(entry(k));
        }
        Some(entry(order[0]))
    }

    /// A leaf (`leaf`, its box `leaf_box` entered at `leaf_t`): the rays that enter its
    /// box test its triangles, and the groups that did update their ends.
    #[inline(always)]
    fn leaf<P: MemoryProbe>(
        &mut self,
        frustum: &Frustum,
        leaf: LeafVisit<'_, '_, Bvh8Node, N>,
        leaf_box: &[f32; 6],
        leaf_t: f32,
        hits: &mut PacketHits<N>,
        probe: &mut P,
    ) {
        let (packet, mask, groups) = (leaf.packet, self.mask, Self::GROUPS);
        let q = match self.lanes {
            Some(ref mut q) => q,
            None => Groups::fill(&mut self.lanes, packet, groups, mask),
        };
        let origin = frustum.origin();
        let enter = leaf_entries(q, groups, mask, leaf_box, leaf_t, origin);
        self.c.active_lanes += enter.count_ones() as u64;
        if enter == 0 {
            return;
        }
        test_entered::<I, P, Bvh8Node, N>(&leaf, enter, (q, mask), origin, &mut self.preps, hits, probe);
        self.c.tri_tests += leaf.count as u64 * enter.count_ones() as u64;
        self.t_end = q.update_ends(enter, mask, hits, packet);
    }
}
