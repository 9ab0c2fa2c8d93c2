//! A packet through an instanced scene: the packet shares the top-level walk
//! ([`BvhPacketTraversal`] over the instances' world boxes, Wald, Boulos & Shirley 2007),
//! and at each instance its rays of the leaf's mask enter object space together and are
//! traced as one packet by the bottom image's own packet kernel. Each ray meets every
//! instance its single-ray walk meets, through the same object-space ray
//! ([`crate::math::affine::object_ray`]) with its interval ending at its own best hit,
//! so its hit is the single-ray walk's bit for bit ([`crate::traverse::instanced`]).

use crate::hit::Hit;
use crate::image::instanced::TopLevel;
use crate::image::SceneView;
use crate::math::affine;
use crate::packet::step::bvh::BvhPacketTraversal;
use crate::packet::step::{PacketEvent, PacketStep};
use crate::packet::{LanesOf, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::instanced::{bounded, keep_closest_instance, InstanceHit};
use crate::traverse::walk::Leaf;

/// The best hit of each ray of a packet in an instanced scene.
pub type InstancePacketHits<const N: usize> = [Option<InstanceHit>; N];

/// Traces the active rays of `packet` through the instanced scene; `hits[i]` receives
/// ray `i`'s closest hit, or for `any_hit` (shadow rays) some hit in range if there is
/// one. `bottom_packet` traces an object-space packet through a bottom image with that
/// image's packet kernel (for `any_hit`, any hit per ray will do).
#[allow(clippy::too_many_arguments)]
pub fn trace_instanced_packet<P: MemoryProbe, const N: usize>(
    top: &TopLevel<'_>,
    bottoms: &[SceneView<'_>],
    packet: &RayPacket<N>,
    any_hit: bool,
    hits: &mut InstancePacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
    mut bottom_packet: impl FnMut(&SceneView<'_>, &RayPacket<N>, &mut PacketHits<N>, &mut P, &mut PacketCounters),
) {
    *hits = [None; N];
    let rays: [Ray; N] = core::array::from_fn(|i| packet.ray(i));
    let mut walk = BvhPacketTraversal::<N>::new(&rays, packet.live());
    // Shadow rays that found a blocker take no further part.
    let mut blocked = 0u64;
    loop {
        match walk.step(top.tree(), probe) {
            PacketEvent::Node { lanes } => {
                counters.visits += 1;
                counters.active_lanes += lanes.count_ones() as u64;
            }
            PacketEvent::Leaf { leaf: Leaf::Range { first, count }, lanes } => {
                for k in 0..count {
                    let lanes = lanes & !blocked;
                    if lanes == 0 {
                        break;
                    }
                    let instance = top.list_instance(first.wrapping_add(k), probe);
                    probe.dependent();
                    let rec = top.instance(instance, probe);
                    let Some(view) = bottoms.get(rec.bottom as usize) else { continue };
                    let mut object = RayPacket::<N>::new();
                    for i in LanesOf::<N>(lanes) {
                        let r = bounded(&rays[i], hits[i]);
                        object.set(i, &affine::object_ray(&rec.to_object, &r));
                    }
                    let mut found: PacketHits<N> = [None; N];
                    bottom_packet(view, &object, &mut found, probe, counters);
                    for i in LanesOf::<N>(object.live()) {
                        let Some(hit) = found[i] else { continue };
                        keep_closest_instance(&mut hits[i], InstanceHit { hit, instance });
                        if let Some(best) = walk.best_mut(i) {
                            crate::hit::keep_closest(best, Hit { prim: 0, ..hit });
                        }
                        if any_hit {
                            blocked |= 1 << i;
                        }
                    }
                }
                walk.finish_leaf();
            }
            PacketEvent::Leaf { .. } => walk.finish_leaf(),
            PacketEvent::Done => return,
        }
    }
}
