//! Random but valid hardware configurations for the hardware model's suites: the chip's
//! widths, latencies, FIFOs, caches and memories drawn, then mended where `validate`
//! would reject them.

use proptest::prelude::*;
use raypipe_hw::config::{DramScheduling, MemoryModel, PagePolicy};
use raypipe_hw::HwConfig;

/// A random but valid chip, with the datapath widths, jobs in flight, cache ports and
/// MSHRs, odd line sizes, an L2, the memory models and the DRAM's ranks, scheduler and
/// row-hit cap drawn too.
pub fn config() -> impl Strategy<Value = HwConfig> {
    (
        base_config(),
        (1u32..9, 1u32..5, 1u32..5, 1u32..3),
        (1u32..3, 1u32..5, any::<bool>(), memory_model()),
        (1u32..6, prop_oneof![Just(4u32), Just(32), Just(64)], any::<bool>(), any::<bool>(), any::<bool>()),
        (1u32..4, prop_oneof![Just(0u32), 1u32..5]),
    )
        .prop_map(
            |(
                mut c,
                (tl, il, jobs, sj),
                (ports, mshrs, l2, model),
                (queue, burst, odd, closed, fcfs),
                (ranks, cap),
            )| {
                c.traversal.lanes_per_cycle = tl;
                c.intersection.lanes_per_cycle = il;
                c.intersection.jobs = jobs;
                c.rgs.shade_jobs = sj;
                for cache in [&mut c.cache.nodes, &mut c.cache.triangles, &mut c.cache.lists, &mut c.cache.shading] {
                    cache.ports = ports;
                    cache.mshrs = mshrs;
                }
                if odd && c.cache.triangles.size_bytes > 0 {
                    // Purcell's 48-byte texture-cache lines, three sets.
                    c.cache.triangles.line_bytes = 48;
                    c.cache.triangles.size_bytes = 48 * 3 * c.cache.triangles.ways;
                }
                if l2 {
                    c.cache.l2.size_bytes = 4096;
                }
                c.memory.model = model.0;
                if let Some(name) = model.1 {
                    c.memory.dramsim3.config = name.to_string();
                }
                c.memory.queue_depth = queue;
                c.memory.min_burst_bytes = burst;
                if closed {
                    c.memory.dram.page_policy = PagePolicy::Closed;
                }
                if fcfs {
                    c.memory.dram.scheduler = DramScheduling::Fcfs;
                }
                c.memory.dram.ranks = ranks;
                c.memory.dram.row_hit_cap = cap;
                c.memory.dram.t_refi = 400;
                c.memory.dram.t_rfc = 30;
                ordered_hierarchy(&mut c);
                c
            },
        )
}

/// The memory models this build has: DRAMsim3 too with the `dramsim3` feature, on one
/// of four of its shipped memories (`None`: one of raypipe's own models).
pub fn memory_model() -> impl Strategy<Value = (MemoryModel, Option<&'static str>)> {
    let own = prop_oneof![Just(MemoryModel::Perfect), Just(MemoryModel::Fixed), Just(MemoryModel::Dram)];
    let own = own.prop_map(|m| (m, None));
    #[cfg(feature = "dramsim3")]
    let own = prop_oneof![
        3 => own,
        1 => prop::sample::select(vec!["DDR3_4Gb_x8_1600", "DDR4_8Gb_x8_2400", "LPDDR4_8Gb_x16_2400", "HBM2_8Gb_x128"])
            .prop_map(|c| (MemoryModel::Dramsim3, Some(c))),
    ];
    own
}

/// Makes each cache no slower than what is behind it, as `validate` demands: the L1s
/// no slower than the L2, and every cache no slower than the memory's fastest answer.
pub fn ordered_hierarchy(c: &mut HwConfig) {
    let fastest = c.memory_fastest_answer().map_or(u32::MAX, |f| f as u32);
    for cache in [&mut c.cache.nodes, &mut c.cache.triangles, &mut c.cache.lists, &mut c.cache.shading] {
        cache.hit_latency = cache.hit_latency.min(fastest);
    }
    let l1 = [&c.cache.nodes, &c.cache.triangles, &c.cache.lists, &c.cache.shading].map(|x| x.hit_latency);
    c.cache.l2.hit_latency = c.cache.l2.hit_latency.min(fastest).max(l1.into_iter().max().unwrap_or(0));
}

/// A random chip of the default's kind: units, threads, FIFOs, latencies, rates and
/// the four caches' geometry (a power-of-two number of sets), with an ideal memory of
/// random latency and width.
pub fn base_config() -> impl Strategy<Value = HwConfig> {
    let cache = || {
        (prop_oneof![Just(0u32), Just(256), Just(1024)], prop_oneof![Just(16u32), Just(32), Just(64)], 1u32..3, 0u32..4)
    };
    (
        (prop_oneof![Just(1u32), Just(4), Just(16), Just(64)], 1u32..4, 1u32..5, 1u32..6),
        ([1u32..4, 1u32..4, 1u32..4, 1u32..4], 1u32..40, 1u32..4, 1u32..3, 1u32..8),
        (cache(), cache(), cache(), cache(), any::<bool>()),
        (0u32..120, 1u32..33),
    )
        .prop_map(
            |((packet, units, threads, step), (fifos, ilat, ii, rpc, spc), (cn, ct, cs, cl, share), (mlat, bpc))| {
                let mut c = HwConfig { packet_size: packet, ..HwConfig::default() };
                c.traversal.units = units;
                c.traversal.threads = threads;
                c.traversal.step_latency = step;
                [c.fifo.rays, c.fifo.leaves, c.fifo.results, c.fifo.hits] = fifos;
                c.intersection.latency = ilat;
                c.intersection.initiation_interval = ii;
                c.rgs.rays_per_cycle = rpc;
                c.rgs.shade_per_cycle = spc;
                c.cache.lists_share_triangle_cache = share;
                for (slot, (size, line, ways, hit)) in [
                    (&mut c.cache.nodes, cn),
                    (&mut c.cache.triangles, ct),
                    (&mut c.cache.shading, cs),
                    (&mut c.cache.lists, cl),
                ] {
                    slot.size_bytes = size.max(if size > 0 { line * ways } else { 0 });
                    slot.line_bytes = line;
                    slot.ways = ways;
                    slot.hit_latency = hit;
                    // Keep the geometry legal: a power-of-two number of sets.
                    if size > 0 {
                        let sets = (slot.size_bytes / line / ways).next_power_of_two();
                        slot.size_bytes = sets * line * ways;
                    }
                }
                c.memory.latency = mlat;
                c.memory.bytes_per_cycle = bpc;
                c
            },
        )
}
