//! The frame's closed-form lower bounds: no chip of this configuration can finish the
//! frame's work in fewer cycles than any of them, whatever its schedule.
//!
//! * memory: bytes through the channel ÷ its peak bytes per cycle (the fixed model's
//!   `bytes_per_cycle`; a DRAM's channels × bus × 2 transfers per memory clock; for
//!   DRAMsim3, whose write buffer drains after the frame, the bytes its READ commands
//!   moved);
//! * traversal: ray–node tests ÷ (`lanes_per_cycle` × units);
//! * intersection: the last group of `lanes_per_cycle` ray–triangle tests enters no
//!   sooner than (tests ÷ (`lanes_per_cycle` × units) − 1) × `initiation_interval`, and
//!   its results leave `latency` cycles later;
//! * generation: rays generated ÷ `rays_per_cycle`; shading: rays shaded ÷
//!   `shade_per_cycle`.
//!
//! The report gives each, the largest, and the achieved cycles as a multiple of it: 1.0
//! would be a chip that never waits on anything but its busiest resource.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::config::{HwConfig, MemoryModel};
use crate::observe::report::{MemoryReport, UnitReport};

/// The lower bounds, in cycles.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Bounds {
    /// Each bound by resource (`memory` absent for perfect memory).
    pub cycles: BTreeMap<String, f64>,
    /// The resource with the largest bound.
    pub largest: String,
    /// Achieved cycles over the largest bound (≥ 1 for a whole frame).
    pub achieved_over_largest: f64,
}

/// The channel's peak bytes per chip cycle, if the memory has one.
pub fn peak_bytes_per_cycle(cfg: &HwConfig, memory: &MemoryReport) -> Option<f64> {
    let m = &cfg.memory;
    match m.model {
        MemoryModel::Perfect => None,
        MemoryModel::Fixed => Some(m.bytes_per_cycle.max(1) as f64),
        MemoryModel::Dram => {
            let d = &m.dram;
            Some(d.channels as f64 * d.bus_bytes as f64 * 2.0 * d.clock_mhz / cfg.clock_mhz)
        }
        MemoryModel::Dramsim3 => memory.dramsim3.as_ref().map(|d| d.peak_gb_s * 1e3 / cfg.clock_mhz),
    }
}

/// The bounds of a frame of `cycles` with these units, ray–triangle tests and memory.
pub fn bounds(cfg: &HwConfig, cycles: u64, units: &[UnitReport], tests: u64, memory: &MemoryReport) -> Bounds {
    let lanes = |prefix: &str| units.iter().filter(|u| u.name.starts_with(prefix)).map(|u| u.active_lanes).sum::<u64>();
    let tu = cfg.traversal.units.max(1) as f64;
    let mut b = BTreeMap::new();
    if let Some(peak) = peak_bytes_per_cycle(cfg, memory) {
        // DRAMsim3 answers a write at once and drains its write buffer after, and serves
        // some reads without the bus: only its READ commands must cross it in the frame.
        let bytes = match &memory.dramsim3 {
            Some(d) => d.bus_read_bytes,
            None => memory.total_bytes,
        };
        b.insert("memory".to_string(), bytes as f64 / peak);
    }
    b.insert("traversal".into(), lanes("traversal") as f64 / (cfg.traversal.lanes_per_cycle.max(1) as f64 * tu));
    // The pipeline takes tests (a job's rays × its triangles), not lanes, per interval.
    let ii = cfg.intersection.initiation_interval.max(1) as f64;
    let groups = tests as f64 / (cfg.intersection.lanes_per_cycle.max(1) as f64 * tu);
    let last_in = (groups - 1.0).max(0.0) * ii;
    b.insert("intersection".into(), if tests > 0 { last_in + cfg.intersection.latency as f64 } else { 0.0 });
    b.insert("generation".into(), lanes("rgs.generate") as f64 / cfg.rgs.rays_per_cycle.max(1) as f64);
    b.insert("shading".into(), lanes("rgs.shade") as f64 / cfg.rgs.shade_per_cycle.max(1) as f64);
    let (largest, top) =
        b.iter().fold(("none".to_string(), 0.0f64), |(n, v), (k, &c)| if c > v { (k.clone(), c) } else { (n, v) });
    Bounds { cycles: b, largest, achieved_over_largest: if top > 0.0 { cycles as f64 / top } else { f64::NAN } }
}
