//! The one memory channel behind every cache: requests are served in order, each
//! occupying the channel for `bytes / bytes_per_cycle` cycles, and their data arrives
//! `latency` cycles after the transfer. Requests are taken at the clock edge from the
//! ports in a fixed order (ray generation & shading, traversal units, intersection
//! units), so the schedule cannot depend on the order the units ticked in.

use serde::Serialize;

use crate::config::MemoryConfig;
use crate::mem_port::MemPort;
use crate::traffic::CLASSES;

/// What the channel carried.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ChannelStats {
    /// Bytes transferred, per class.
    pub bytes: [u64; CLASSES],
    /// Requests served, per class.
    pub requests: [u64; CLASSES],
    /// Cycles the channel was transferring.
    pub busy_cycles: u64,
}

/// The memory channel's registers.
#[derive(Clone, Debug)]
pub struct MemoryChannel {
    latency: u64,
    bytes_per_cycle: u64,
    busy_until: u64,
    /// Statistics.
    pub stats: ChannelStats,
}

impl MemoryChannel {
    /// An idle channel.
    pub fn new(cfg: &MemoryConfig) -> MemoryChannel {
        MemoryChannel {
            latency: cfg.latency as u64,
            bytes_per_cycle: cfg.bytes_per_cycle.max(1) as u64,
            busy_until: 0,
            stats: ChannelStats::default(),
        }
    }

    /// At the edge ending cycle `now`: schedules the port's staged requests.
    pub fn accept(&mut self, now: u64, port: &mut MemPort) {
        for k in 0..port.staged.len() {
            let r = port.staged[k];
            let start = self.busy_until.max(now + 1);
            let transfer = (r.bytes as u64).div_ceil(self.bytes_per_cycle).max(1);
            self.busy_until = start + transfer;
            self.stats.busy_cycles += transfer;
            self.stats.bytes[r.class] += r.bytes as u64;
            self.stats.requests[r.class] += 1;
            port.set_ready(r.id, start + transfer + self.latency);
        }
        port.staged.clear();
    }

    /// True while a transfer is under way after cycle `now`.
    pub fn busy_after(&self, now: u64) -> bool {
        self.busy_until > now + 1
    }

    /// The cycle the last accepted transfer's data arrives.
    pub fn drained_at(&self) -> u64 {
        if self.busy_until == 0 {
            0
        } else {
            self.busy_until + self.latency
        }
    }
}
