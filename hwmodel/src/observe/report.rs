//! The report of a run, gathered in one place from the units' counters: a JSON document
//! (schema `raypipe-hw-report/2`, documented in docs/hw-model.md) and a human summary.

use std::collections::BTreeMap;

use serde::Serialize;

use raypipe_core::shade::ray_record::RayKind;

use crate::chip::fifo::FifoStats;
use crate::chip::transform_unit::TransformStats;
use crate::chip::traversal_unit::{TraversalStats, STATE_NAMES};
use crate::config::HwConfig;
use crate::memory::cache::Cache;
use crate::memory::port::LatencyStats;
use crate::memory::traffic::{CLASSES, CLASS_NAMES, FRAMEBUFFER};
use crate::memory::ChannelStats;
use crate::observe::stall::Stall;
use crate::observe::unit_stats::UnitStats;

/// Schema name and version of the JSON report.
pub const SCHEMA: &str = "raypipe-hw-report/2";

/// One unit's line of the report.
#[derive(Clone, Debug, Serialize)]
pub struct UnitReport {
    /// Unit name (`rgs.generate`, `rgs.shade`, `traversal0`, `intersection0`, …).
    pub name: String,
    /// Cycles doing work.
    pub busy_cycles: u64,
    /// Cycles with work waiting (memory, latency, a full FIFO).
    pub stall_cycles: u64,
    /// Cycles without work.
    pub idle_cycles: u64,
    /// Packet operations issued.
    pub issues: u64,
    /// Active lanes over lane slots of those issues.
    pub simd_efficiency: f64,
    /// Lanes that took part, summed over issues (ray–node tests, ray–triangle tests in
    /// leaf jobs, rays generated or shaded).
    pub active_lanes: u64,
    /// Stall cycles by reason; they sum to `stall_cycles`.
    pub stall_reasons: BTreeMap<String, u64>,
    /// Traversal units: node records read per packet step (1 for a packet's shared walk).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node_reads_per_step: Option<f64>,
    /// Traversal units: mean threads in each state over the frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thread_states: Option<BTreeMap<String, f64>>,
    /// Transformation units: rays transformed, requests served, and cycles × requests
    /// waiting behind others.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transform: Option<TransformStats>,
    /// Bytes delivered to the unit's memory port.
    pub bytes: u64,
}

/// One FIFO's line.
#[derive(Clone, Debug, Serialize)]
pub struct FifoReport {
    /// FIFO name (`rays0`, `leaves0`, `results0`, `hits0`, …).
    pub name: String,
    /// Configured depth.
    pub depth: usize,
    /// Mean committed occupancy.
    pub mean_occupancy: f64,
    /// Counters and the occupancy histogram (`occupancy[k]`: cycles with `k` entries).
    #[serde(flatten)]
    pub stats: FifoStats,
}

/// One class's counts in one cache.
#[derive(Clone, Debug, Serialize)]
pub struct CacheClassReport {
    /// Line accesses that hit.
    pub hits: u64,
    /// Line accesses that joined a fill in flight.
    pub merged: u64,
    /// Line accesses that missed.
    pub misses: u64,
    /// `hits / (hits + merged + misses)`.
    pub hit_rate: f64,
}

/// One cache's line.
#[derive(Clone, Debug, Serialize)]
pub struct CacheReport {
    /// Cache name (that of its port).
    pub name: String,
    /// Capacity in bytes.
    pub size_bytes: u32,
    /// Line size in bytes.
    pub line_bytes: u32,
    /// Per data class with any access.
    pub classes: BTreeMap<String, CacheClassReport>,
}

/// The memory channel.
#[derive(Clone, Debug, Serialize)]
pub struct MemoryReport {
    /// Bytes transferred per class.
    pub bytes: BTreeMap<String, u64>,
    /// Total bytes transferred.
    pub total_bytes: u64,
    /// Total bytes per traced ray.
    pub bytes_per_ray: f64,
    /// Requests served.
    pub requests: u64,
    /// Fraction of cycles the channel was transferring.
    pub utilization: f64,
    /// Distinct scene bytes the kernels read (the compulsory traffic).
    pub distinct_scene_bytes: u64,
    /// Scene bytes transferred over distinct scene bytes read (1.0 is the floor).
    pub traffic_over_compulsory: f64,
    /// `"perfect"`, `"fixed"`, `"dram"` or `"dramsim3"`.
    pub model: String,
    /// Read latency (cycles from a unit's request to its data) per class: mean, count and
    /// a log2 histogram (`"<N"`: requests below N cycles).
    pub latency: BTreeMap<String, LatencyReport>,
    /// Shared L2: hits, merges and misses (line lookups).
    pub l2: BTreeMap<String, u64>,
    /// DRAM: row-buffer hit rate and per-bank counters (absent for other models).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dram: Option<DramReport>,
    /// DRAMsim3: bandwidth, latency, row hits, commands, energy (absent for other models).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dramsim3: Option<super::dramsim3_report::Dramsim3Report>,
}

/// Latencies of one data class.
#[derive(Clone, Debug, Serialize)]
pub struct LatencyReport {
    /// Requests.
    pub count: u64,
    /// Mean cycles from request to data.
    pub mean: f64,
    /// Requests by latency bin.
    pub histogram: BTreeMap<String, u64>,
}

/// The DRAM's statistics.
#[derive(Clone, Debug, Serialize)]
pub struct DramReport {
    /// Bursts that found their row open.
    pub row_hit_rate: f64,
    /// Per bank, channel-major.
    pub banks: Vec<crate::memory::dram::BankStats>,
}

/// What produced a report: the scene, view, algorithm and program.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RunIdentity {
    /// The scene argument (a path, or the built-in default).
    pub scene: String,
    /// FNV-1a 64 of the scene image bytes, hex.
    pub scene_hash: String,
    /// Acceleration structure.
    pub structure: String,
    /// Shading algorithm.
    pub algorithm: String,
    /// Intersection test.
    pub intersector: String,
    /// Camera: eye, look-at, up, vertical field of view.
    pub camera: String,
    /// raypipe's version.
    pub raypipe_version: String,
}

/// FNV-1a, 64 bits (a scene image's fingerprint in reports).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Checks that must hold for every run.
#[derive(Clone, Debug, Serialize)]
pub struct Conservation {
    /// Rays sent to traversal.
    pub rays_issued: u64,
    /// Rays shaded after traversal.
    pub rays_retired: u64,
    /// Bytes the ports requested.
    pub bytes_requested: u64,
    /// Bytes the channel delivered.
    pub bytes_delivered: u64,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Schema name and version.
    pub schema: &'static str,
    /// The configuration simulated.
    pub config: HwConfig,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Rays traced (primary rays that passed the scene-bounds test).
    pub rays: u64,
    /// Cycles for the frame.
    pub cycles: u64,
    /// Frames per second at `config.clock_mhz`.
    pub frames_per_second: f64,
    /// Traced rays per second at `config.clock_mhz`.
    pub rays_per_second: f64,
    /// Rays traced, by kind (primary, shadow, reflection, refraction, path).
    pub rays_by_kind: BTreeMap<String, u64>,
    /// Most shadow and secondary ray records waiting in the shading unit at once.
    pub ray_stream_peak: usize,
    /// Traversal steps issued (packet steps: a 64-ray packet's step counts once, so
    /// chips of different packet sizes compare on `ray_steps`, not on this).
    pub traversal_steps: u64,
    /// Ray steps: the rays that took part in each traversal step, summed (a packet step
    /// of 40 active rays counts 40).
    pub ray_steps: u64,
    /// Ray steps per traced ray.
    pub steps_per_ray: f64,
    /// Ray–triangle tests run.
    pub triangle_tests: u64,
    /// Ray–triangle tests per traced ray.
    pub tests_per_ray: f64,
    /// Active lanes over lane slots of the traversal units' issues (1 for single rays).
    pub traversal_simd_efficiency: f64,
    /// What produced the report (set by the command line).
    pub run: RunIdentity,
    /// The one-line verdict: what bounds the frame.
    pub bottleneck: String,
    /// Per unit.
    pub units: Vec<UnitReport>,
    /// Per FIFO.
    pub fifos: Vec<FifoReport>,
    /// Per cache.
    pub caches: Vec<CacheReport>,
    /// The memory channel.
    pub memory: MemoryReport,
    /// The frame's closed-form lower bounds and the achieved cycles over the largest.
    pub bounds: super::bounds::Bounds,
    /// Conservation checks.
    pub conservation: Conservation,
    /// Energy and area estimates (`config.energy`'s figures over the counters).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergyReport>,
}

/// Energy per frame by part, and area by part.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct EnergyReport {
    /// Process node of the figures (nm).
    pub process_nm: f64,
    /// Joules for the frame (the report's cycles).
    pub joules_per_frame: f64,
    /// Joules per traced ray.
    pub joules_per_ray: f64,
    /// Average power at the clock, running frame after frame (W).
    pub watts: f64,
    /// Chip area (mm²).
    pub area_mm2: f64,
    /// Joules by part: traversal, intersection, shading datapaths, caches, l2, dram,
    /// leakage.
    pub joules: std::collections::BTreeMap<String, f64>,
    /// mm² by part: the datapaths, caches, thread and FIFO registers.
    pub area: std::collections::BTreeMap<String, f64>,
}

/// Everything [`Report::gather`] reads.
pub struct Sources<'a> {
    /// The configuration.
    pub cfg: &'a HwConfig,
    /// Image size.
    pub size: (u32, u32),
    /// Frame cycles.
    pub cycles: u64,
    /// Units by name.
    pub units: Vec<(String, &'a UnitStats)>,
    /// Traversal units' own counters, by unit name.
    pub traversal: Vec<(String, &'a TraversalStats)>,
    /// Transformation units' own counters, by unit name (two-level scenes).
    pub transform: Vec<(String, &'a TransformStats)>,
    /// Bytes delivered per unit port, by unit name.
    pub port_bytes: Vec<(String, u64)>,
    /// Read latencies per class over all ports.
    pub latency: Vec<LatencyStats>,
    /// Memory utilization.
    pub utilization: f64,
    /// Bytes delivered to the ports.
    pub delivered: u64,
    /// The DRAM, if that is the model.
    pub dram: Option<&'a crate::memory::dram::Dram>,
    /// DRAMsim3's report, if that is the model.
    pub dramsim3: Option<super::dramsim3_report::Dramsim3Report>,
    /// FIFOs: name, depth, counters.
    pub fifos: Vec<(String, usize, &'a FifoStats)>,
    /// Caches by port name.
    pub caches: Vec<(String, &'a Cache)>,
    /// The channel.
    pub channel: &'a ChannelStats,
    /// Bytes requested by all ports.
    pub requested: u64,
    /// Distinct scene bytes read.
    pub distinct: u64,
    /// Rays issued, rays retired.
    pub rays: (u64, u64),
    /// Ray–triangle tests.
    pub tests: u64,
    /// Rays by kind, in `RayKind::ALL` order.
    pub rays_by_kind: [u64; RayKind::COUNT],
    /// Peak of the shading unit's ray stream.
    pub queue_peak: usize,
}

fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

impl Report {
    /// Gathers the report.
    pub fn gather(s: Sources<'_>) -> Report {
        let cycles = s.cycles.max(1);
        let seconds = cycles as f64 / (s.cfg.clock_mhz * 1e6);
        let rays = s.rays.0;
        let units = unit_reports(&s);
        let traversal_steps =
            s.units.iter().filter(|(n, _)| n.starts_with("traversal")).map(|(_, u)| u.issues).sum::<u64>();
        let ray_steps = units.iter().filter(|u| u.name.starts_with("traversal")).map(|u| u.active_lanes).sum::<u64>();
        let lane_slots = traversal_steps.saturating_mul(s.cfg.packet_size as u64);
        let traversal_simd_efficiency = if lane_slots == 0 { 1.0 } else { ray_steps as f64 / lane_slots as f64 };
        let fifos = fifo_reports(&s);
        let caches = cache_reports(&s);
        let memory = memory_report(&s, rays);
        let bottleneck = crate::observe::verdict::verdict(&units, memory.utilization);
        let bounds = super::bounds::bounds(s.cfg, s.cycles, &units, s.tests, &memory);
        Report {
            schema: SCHEMA,
            config: s.cfg.clone(),
            width: s.size.0,
            height: s.size.1,
            rays,
            cycles: s.cycles,
            frames_per_second: 1.0 / seconds,
            rays_per_second: rays as f64 / seconds,
            rays_by_kind: RayKind::ALL.iter().map(|k| (k.name().to_string(), s.rays_by_kind[*k as usize])).collect(),
            ray_stream_peak: s.queue_peak,
            run: RunIdentity::default(),
            bottleneck,
            traversal_steps,
            ray_steps,
            steps_per_ray: ray_steps as f64 / rays.max(1) as f64,
            triangle_tests: s.tests,
            tests_per_ray: s.tests as f64 / rays.max(1) as f64,
            traversal_simd_efficiency,
            units,
            fifos,
            caches,
            memory,
            bounds,
            conservation: Conservation {
                rays_issued: s.rays.0,
                rays_retired: s.rays.1,
                bytes_requested: s.requested,
                bytes_delivered: s.delivered,
            },
            energy: None,
        }
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}

/// Each unit's line: activity, stall reasons, SIMD efficiency, threads by state, bytes.
fn unit_reports(s: &Sources<'_>) -> Vec<UnitReport> {
    s.units
        .iter()
        .map(|(name, u)| {
            let tr = s.traversal.iter().find(|(n, _)| n == name).map(|(_, t)| *t);
            let ticked = (u.busy_cycles + u.stall_cycles + u.idle_cycles).max(1) as f64;
            UnitReport {
                name: name.clone(),
                busy_cycles: u.busy_cycles,
                stall_cycles: u.stall_cycles,
                idle_cycles: u.idle_cycles,
                issues: u.issues,
                simd_efficiency: u.simd_efficiency(),
                active_lanes: u.active_lanes,
                stall_reasons: Stall::ALL
                    .iter()
                    .map(|r| (r.name().to_string(), u.stall_reasons[*r as usize]))
                    .collect(),
                node_reads_per_step: tr.map(|t| ratio(t.node_reads as f64, t.steps as f64)),
                thread_states: tr.map(|t| {
                    STATE_NAMES
                        .iter()
                        .zip(t.thread_state_cycles.iter())
                        .map(|(n, c)| (n.to_string(), *c as f64 / ticked))
                        .collect()
                }),
                transform: s.transform.iter().find(|(n, _)| n == name).map(|(_, t)| (*t).clone()),
                bytes: s.port_bytes.iter().find(|(n, _)| n == name).map_or(0, |(_, b)| *b),
            }
        })
        .collect::<Vec<_>>()
}

/// Each FIFO's line, with its mean occupancy.
fn fifo_reports(s: &Sources<'_>) -> Vec<FifoReport> {
    s.fifos
        .iter()
        .map(|(name, depth, st)| {
            let total: u64 = st.occupancy.iter().sum();
            let weighted: u64 = st.occupancy.iter().enumerate().map(|(k, c)| k as u64 * c).sum();
            FifoReport {
                name: name.clone(),
                depth: *depth,
                mean_occupancy: ratio(weighted as f64, total as f64),
                stats: (*st).clone(),
            }
        })
        .collect()
}

/// Each cache's hits, merges and misses by data class.
fn cache_reports(s: &Sources<'_>) -> Vec<CacheReport> {
    s.caches
        .iter()
        .map(|(name, cache)| (name, &cache.stats, cache))
        .map(|(name, c, cache)| CacheReport {
            name: name.clone(),
            size_bytes: cache.size_bytes(),
            line_bytes: cache.line_bytes(),
            classes: (0..CLASSES)
                .filter(|&k| c.hits[k] + c.merged[k] + c.misses[k] > 0)
                .map(|k| {
                    let all = (c.hits[k] + c.merged[k] + c.misses[k]) as f64;
                    let r = CacheClassReport {
                        hits: c.hits[k],
                        merged: c.merged[k],
                        misses: c.misses[k],
                        hit_rate: ratio(c.hits[k] as f64, all),
                    };
                    (CLASS_NAMES[k].to_string(), r)
                })
                .collect(),
        })
        .collect()
}

/// The memory channel: bytes by class and per ray, requests, utilization, traffic over
/// the compulsory floor, read latencies, the L2 and the DRAM's rows.
fn memory_report(s: &Sources<'_>, rays: u64) -> MemoryReport {
    let total_bytes: u64 = s.channel.bytes.iter().sum();
    let scene_bytes = total_bytes - s.channel.bytes[FRAMEBUFFER];
    MemoryReport {
        bytes: (0..CLASSES).map(|k| (CLASS_NAMES[k].to_string(), s.channel.bytes[k])).collect(),
        total_bytes,
        bytes_per_ray: ratio(total_bytes as f64, rays as f64),
        requests: s.channel.requests.iter().sum(),
        utilization: s.utilization,
        distinct_scene_bytes: s.distinct,
        traffic_over_compulsory: ratio(scene_bytes as f64, s.distinct as f64),
        model: format!("{:?}", s.cfg.memory.model).to_lowercase(),
        latency: (0..CLASSES)
            .filter(|&k| s.latency[k].count > 0)
            .map(|k| {
                let l = &s.latency[k];
                let histogram = l
                    .histogram
                    .iter()
                    .enumerate()
                    .filter(|(_, &n)| n > 0)
                    .map(|(b, &n)| (format!("<{}", 1u64 << b), n))
                    .collect();
                let r = LatencyReport { count: l.count, mean: ratio(l.sum as f64, l.count as f64), histogram };
                (CLASS_NAMES[k].to_string(), r)
            })
            .collect(),
        l2: [("hits", s.channel.l2[0]), ("merged", s.channel.l2[1]), ("misses", s.channel.l2[2])]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        dram: s.dram.map(|d| DramReport { row_hit_rate: d.row_hit_rate(), banks: d.stats.clone() }),
        dramsim3: s.dramsim3.clone(),
    }
}
