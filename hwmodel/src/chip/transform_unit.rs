//! The transformation unit beside a traversal unit (SaarCOR's dynamic-scene prototype,
//! Schmittler et al. 2004; Wald & Slusallek 2001 §8.3): rays whose top-level walk handed
//! out an instance are carried into its object space — origin and direction through the
//! instance's world-to-object map — before they walk its bottom structure.
//!
//! A traversal thread's entering rays form one request. Requests are served oldest
//! first: a request of `n` rays enters the pipeline as `ceil(n / lanes_per_cycle)`
//! groups, one every `initiation_interval` cycles, and its last group's result leaves
//! `latency` cycles after that group entered. Only then may the thread step again.
//! The instance record the map comes from was read by the step that handed the instance
//! out, so the unit starts only once that step's data has arrived.
//!
//! Ports: requests in and results out, both inside the traversal unit (thread numbers).

use std::collections::VecDeque;

use serde::Serialize;

use crate::config::HwConfig;
use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

/// Counters of the transformation unit beyond activity.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TransformStats {
    /// Rays transformed.
    pub rays: u64,
    /// Requests (a thread's entering rays) served.
    pub requests: u64,
    /// Cycles × requests waiting for the unit (queued behind others).
    pub waiting_cycles: u64,
}

/// A transformation unit.
pub struct TransformUnit {
    /// Unit number (that of its traversal unit).
    pub id: usize,
    latency: u64,
    interval: u64,
    lanes_per_cycle: u64,
    packet_size: u64,
    /// Requests waiting, oldest first: (thread, rays).
    queue: VecDeque<(usize, u64)>,
    /// Requests in the pipeline: (thread, cycle the result leaves).
    pipeline: Vec<(usize, u64)>,
    /// Groups enter until this cycle (exclusive).
    busy_until: u64,
    /// Activity and lanes.
    pub stats: UnitStats,
    /// Rays, requests, waiting.
    pub tstats: TransformStats,
    last_waiting: u64,
}

impl TransformUnit {
    /// An idle unit with `cfg.transform`'s rates.
    pub fn new(id: usize, cfg: &HwConfig) -> TransformUnit {
        TransformUnit {
            id,
            latency: cfg.transform.latency as u64,
            interval: cfg.transform.initiation_interval.max(1) as u64,
            lanes_per_cycle: cfg.transform.lanes_per_cycle.max(1) as u64,
            packet_size: cfg.packet_size as u64,
            queue: VecDeque::new(),
            pipeline: Vec::new(),
            busy_until: 0,
            stats: UnitStats::default(),
            tstats: TransformStats::default(),
            last_waiting: 0,
        }
    }

    /// Thread `thread` asks for `rays` rays to be transformed (its step's data is there).
    pub fn request(&mut self, thread: usize, rays: u64) {
        self.queue.push_back((thread, rays.max(1)));
    }

    /// True if no request is in the unit.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty() && self.pipeline.is_empty()
    }

    /// The first cycle after `now` at which time alone changes something.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        self.pipeline.iter().map(|&(_, at)| at).chain(Some(self.busy_until)).filter(|&w| w > now).min()
    }

    /// One cycle: a finished request leaves (its thread is returned), the oldest waiting
    /// one enters once the pipeline takes groups again. Returns the thread whose rays are
    /// in object space now, and whether anything moved.
    pub fn tick(&mut self, now: u64) -> (Option<usize>, bool) {
        let mut moved = false;
        let done = self.pipeline.iter().position(|&(_, at)| at <= now).map(|k| self.pipeline.remove(k).0);
        moved |= done.is_some();
        if self.busy_until <= now {
            if let Some((thread, rays)) = self.queue.pop_front() {
                let groups = rays.div_ceil(self.lanes_per_cycle);
                self.busy_until = now + groups * self.interval;
                self.pipeline.push((thread, now + (groups - 1) * self.interval + self.latency));
                self.stats.issue(rays, self.packet_size);
                self.tstats.rays += rays;
                self.tstats.requests += 1;
                moved = true;
            }
        }
        let activity = if self.busy_until > now {
            Activity::Busy
        } else if self.is_empty() {
            Activity::Idle
        } else {
            Activity::Stalled(Stall::PipelineLatency)
        };
        self.stats.cycle(activity);
        self.last_waiting = self.queue.len() as u64;
        self.tstats.waiting_cycles += self.last_waiting;
        (done, moved)
    }

    /// Requests waiting for the unit at the last tick (a waveform signal).
    pub fn waiting(&self) -> u64 {
        self.last_waiting
    }

    /// Zeroes the statistics (requests in flight stay).
    pub fn reset_stats(&mut self) {
        self.stats.reset();
        self.tstats = TransformStats::default();
    }

    /// Accounts `n` more cycles like the last one (the clock skipped them).
    pub fn repeat_last(&mut self, n: u64) {
        self.stats.repeat_last(n);
        self.tstats.waiting_cycles += n * self.last_waiting;
    }

    /// One line describing the unit (for the watchdog).
    pub fn describe(&self) -> String {
        format!("transform{}: {} requests waiting, {} in the pipeline", self.id, self.queue.len(), self.pipeline.len())
    }
}
