//! Packets through the kd-tree in lock-step ([`crate::packet::lockstep`]): every ray keeps its
//! own traversal registers ([`KdTraversal`]), and a packet round is one node step of
//! each active ray.

use crate::hit::Hit;
use crate::image::{KdTreeView, SceneView};
use crate::intersect::triangle::Intersector;
use crate::packet::lockstep::{trace_lock_step, RayWalk};
use crate::packet::{PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::kdtree::KdTraversal;
use crate::traverse::tree_step::TreeEvent;

/// A ray's walk through the kd-tree.
struct KdWalk<'k> {
    kd: &'k KdTreeView<'k>,
    trav: KdTraversal,
}

impl RayWalk for KdWalk<'_> {
    #[inline]
    fn advance<P: MemoryProbe>(
        &mut self,
        ray: &Ray,
        probe: &mut P,
        test: &mut impl FnMut(&mut Self, u32, &mut P),
    ) -> bool {
        match self.trav.step(self.kd, ray, probe) {
            TreeEvent::Done => false,
            TreeEvent::Inner => true,
            TreeEvent::Leaf { first, count } => {
                for k in first..first.wrapping_add(count) {
                    let prim = self.kd.prim(k, probe);
                    test(self, prim, probe);
                }
                self.trav.finish_leaf();
                true
            }
        }
    }

    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.trav.best
    }
}

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_kdtree_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    kd: &KdTreeView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    trace_lock_step::<KdWalk<'_>, I, P, N>(scene, packet, hits, probe, counters, |ray| {
        Some(KdWalk { kd, trav: KdTraversal::new(kd, ray) })
    });
}
