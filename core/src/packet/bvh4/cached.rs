//! The packet's any-hit query with the shadow cache
//! ([`crate::traverse::wide_bvh::last_occluder`]): every ray first tests the leaf where
//! the last packet found a ray blocked, and only the rays it does not block take the
//! packet walk, which keeps in the cache a leaf where it found one.

use crate::counters::RayCounters;
use crate::image::{Bvh4View, SceneView};
use crate::intersect::triangle::Intersector;
use crate::packet::{LanesOf, PacketCounters, RayPacket};
use crate::probe::MemoryProbe;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::wide_bvh::last_occluder::{test_leaf_alone, LastOccluder};

use super::walk::occluded_packet_walk;

/// [`super::occluded_bvh4_packet`] with the shadow cache `cache`: bit `i` set when ray
/// `i` is blocked within its interval — the same bits for every packet and every cache.
pub fn occluded_bvh4_packet_cached<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut PacketCounters,
) -> u64 {
    let live = packet.live();
    let mut blocked = 0u64;
    let test = cache.to_test().filter(|_| <I::Nodes as NodeTests>::FLOAT);
    if let Some(leaf) = test {
        let mut c = RayCounters::default();
        // The single ray's leaf test, ray by ray: the one the walks end with, so a hit
        // here is a hit they would find (the structure is conservative).
        for i in LanesOf::<N>(live) {
            let ray = packet.ray(i);
            if ray.is_valid() {
                let hit = test_leaf_alone::<I, P, _>(scene, bvh, &ray, leaf, probe, &mut c);
                blocked |= u64::from(hit.is_some()) << i;
            }
        }
        counters.add_rays(&c);
    }
    // The packet votes once: for the leaf if it blocked half its rays or more, and such
    // a leaf stays whatever the walk finds.
    let tested = test.is_some();
    let good = tested && 2 * blocked.count_ones() >= live.count_ones().max(1);
    if tested {
        cache.tested(good);
    }
    let mut found = None;
    if live & !blocked != 0 {
        let mut rest = *packet;
        rest.active = live & !blocked;
        blocked |= occluded_packet_walk::<I, P, N>(scene, bvh, &rest, &mut found, probe, counters);
    }
    if !good {
        match found {
            Some((first, count)) => cache.blocked_in(first, count, tested),
            None => cache.free(tested),
        }
    }
    blocked
}
