//! Packets through the kd-tree in lock-step: each ray keeps its own traversal registers
//! ([`KdTraversal`]), and each round every active ray takes one step; rays that reach a
//! leaf intersect it in the same round. Rays of a coherent packet walk the same nodes in
//! the same rounds, so node reads are shared in a cache, as in Wald & Slusallek 2001 §4;
//! the active fraction per round is the SIMD efficiency.

use crate::image::{KdTreeView, SceneView};
use crate::kdtree::{KdEvent, KdTraversal};
use crate::packet::{Lanes, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::triangle::{test_triangle, Intersector};

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_kdtree_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    kd: &KdTreeView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
    let mut trav: [KdTraversal; N] = core::array::from_fn(|i| KdTraversal::new(kd, &rays[i]));
    let mut active = packet.active;
    let mut c = PacketCounters::default();
    while active != 0 {
        c.visits += 1;
        c.active_lanes += active.count_ones() as u64;
        for i in Lanes(active) {
            match trav[i].step(kd, &rays[i], probe) {
                KdEvent::Done => active &= !(1 << i),
                KdEvent::Inner => {}
                KdEvent::Leaf { first, count } => {
                    for k in first..first.wrapping_add(count) {
                        let prim = kd.prim(k, probe);
                        let verts = I::fetch(scene, prim, probe);
                        test_triangle::<I>(&preps[i], &rays[i], &verts, prim, &mut trav[i].best);
                    }
                    c.tri_tests += count as u64;
                    trav[i].finish_leaf();
                }
            }
        }
    }
    for i in 0..N {
        hits[i] = if packet.active & (1 << i) != 0 { trav[i].best } else { None };
    }
    counters.add(&c);
}
