//! Per-unit activity, gathered in one place (ChampSim's stats blocks): every cycle a unit
//! is exactly one of busy, stalled or idle, and SIMD lanes are counted per issue.

use serde::Serialize;

use crate::observe::stall::{Stall, STALLS};

/// What a unit did in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activity {
    /// Did work (issued a step, a test batch, generated or shaded).
    Busy,
    /// Had work but could not proceed, for the given reason.
    Stalled(Stall),
    /// Had nothing to do.
    Idle,
}

/// A unit's counters.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct UnitStats {
    /// Cycles with work done.
    pub busy_cycles: u64,
    /// Cycles with work waiting.
    pub stall_cycles: u64,
    /// Cycles without work.
    pub idle_cycles: u64,
    /// Packet operations issued (traversal steps, leaf jobs, packets generated/shaded).
    pub issues: u64,
    /// Lanes that took part, summed over issues.
    pub active_lanes: u64,
    /// Lanes available, summed over issues (issues × packet size).
    pub lane_slots: u64,
    /// Stall cycles by reason (`Stall as usize`); they sum to `stall_cycles`.
    pub stall_reasons: [u64; STALLS],
    /// The activity of the last cycle counted.
    #[serde(skip)]
    pub last: Option<Activity>,
}

impl UnitStats {
    /// Counts one cycle.
    pub fn cycle(&mut self, a: Activity) {
        self.cycles(a, 1);
        self.last = Some(a);
    }

    /// Counts `n` more cycles like the last one (the clock skipped cycles in which nothing
    /// could change).
    pub fn repeat_last(&mut self, n: u64) {
        if let Some(a) = self.last {
            self.cycles(a, n);
        }
    }

    /// Counts `n` cycles of the same activity.
    pub fn cycles(&mut self, a: Activity, n: u64) {
        match a {
            Activity::Busy => self.busy_cycles += n,
            Activity::Stalled(r) => {
                self.stall_cycles += n;
                self.stall_reasons[r as usize] += n;
            }
            Activity::Idle => self.idle_cycles += n,
        }
    }

    /// Zeroes the counters (the activity of the last cycle stays, for a skip that follows).
    pub fn reset(&mut self) {
        *self = UnitStats { last: self.last, ..UnitStats::default() };
    }

    /// Counts one issue with `active` of `slots` lanes.
    pub fn issue(&mut self, active: u64, slots: u64) {
        self.issues += 1;
        self.active_lanes += active;
        self.lane_slots += slots;
    }

    /// Fraction of lanes that did work.
    pub fn simd_efficiency(&self) -> f64 {
        if self.lane_slots == 0 {
            0.0
        } else {
            self.active_lanes as f64 / self.lane_slots as f64
        }
    }
}
