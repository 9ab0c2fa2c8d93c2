//! The host's drivers of the instanced walk: each instance's bottom image traced with
//! the kernel of its own structure (the per-structure fast paths of
//! [`crate::render::tracer`]), single rays, any-hit rays and packets.

use raypipe_core::packet::instanced::{trace_instanced_packet, InstancePacketHits};
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::instanced::{run_instanced, InstanceHit};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::{Hit, Intersector, NoProbe, Ray, RayCounters};

use super::Instances;
use crate::render::tracer::{trace, trace_packet};

/// The closest hit of `ray`.
#[inline]
pub fn trace_instance<I: Intersector>(s: &Instances<'_>, ray: &Ray, counters: &mut RayCounters) -> Option<InstanceHit> {
    run_instanced(&s.top, &s.bottoms, ray, false, &mut NoProbe, |view, r, p| trace::<I, _>(view, r, p, counters))
}

/// Whether anything lies on `ray` within its interval.
#[inline]
pub fn occluded_instance<I: Intersector>(s: &Instances<'_>, ray: &Ray, counters: &mut RayCounters) -> bool {
    let blocked = run_instanced(&s.top, &s.bottoms, ray, true, &mut NoProbe, |view, r, p| {
        occluded::<I, _>(view, r, p, counters).then_some(Hit { t: r.t_max, u: 0.0, v: 0.0, prim: 0 })
    });
    blocked.is_some()
}

/// The closest hits (any hits for `any_hit`) of a packet: the top level walked by the
/// packet, each bottom by its own packet kernel.
pub fn trace_instance_packet<I: Intersector, const N: usize>(
    s: &Instances<'_>,
    packet: &RayPacket<N>,
    any_hit: bool,
    hits: &mut InstancePacketHits<N>,
    counters: &mut PacketCounters,
) {
    trace_instanced_packet(
        &s.top,
        &s.bottoms,
        packet,
        any_hit,
        hits,
        &mut NoProbe,
        counters,
        |view, p, h, probe, c| trace_packet::<I, _, N>(view, p, h, probe, c),
    );
}
