//! What a run can be watched by, without changing it: waveforms (every FIFO's
//! occupancy, every unit's activity, traversal threads by state, the memory's queue,
//! requests and channel) sampled after each clock edge for a VCD writer, and a trace of
//! packet lifetimes and memory transactions for Chrome's trace-event format. Both only
//! read the chip's registers; the report is the same with or without them.

use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

/// One waveform signal.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Signal {
    /// Dotted name: its scopes, then the signal (`fifos.rays0.occupancy`).
    pub name: String,
    /// Width in bits.
    pub width: u32,
}

/// Where waveform changes go: a VCD writer, a test.
pub trait WaveSink {
    /// The signals, once, before any change.
    fn define(&mut self, signals: &[Signal]) -> Result<(), String>;
    /// Signal `index` has `value` from cycle `cycle` on.
    fn change(&mut self, cycle: u64, index: usize, value: u64) -> Result<(), String>;
    /// The run ended at `cycle` (exclusive).
    fn finish(&mut self, cycle: u64) -> Result<(), String>;
}

/// Whether `signal` is one of those `prefixes` select (all when there are none): the
/// VCD's `--vcd-units`, and the save file that lists the VCD's signals.
pub fn selected(signal: &Signal, prefixes: &[String]) -> bool {
    prefixes.is_empty() || prefixes.iter().any(|p| signal.name.starts_with(p.as_str()))
}

/// A unit's activity as a number: 0 idle, 1 busy, 2 + [`Stall`] index when stalled.
pub fn activity_code(stats: &UnitStats) -> u64 {
    match stats.last {
        None | Some(Activity::Idle) => 0,
        Some(Activity::Busy) => 1,
        Some(Activity::Stalled(s)) => 2 + Stall::ALL.iter().position(|r| *r == s).unwrap_or(0) as u64,
    }
}

/// The sampler: which signals are kept, their last values, the window.
pub struct Waves {
    sink: Box<dyn WaveSink>,
    /// Indices (into the simulator's full signal list) of the kept signals.
    keep: Vec<usize>,
    last: Vec<Option<u64>>,
    window: (u64, u64),
    /// Sample buffer (every signal).
    pub(crate) scratch: Vec<u64>,
    /// The first error of the sink (the run goes on; the caller reports it).
    pub error: Option<String>,
}

impl Waves {
    /// Keeps the signals whose names start with one of `prefixes` (all when empty), in
    /// cycles `window.0..window.1`.
    pub fn new(
        mut sink: Box<dyn WaveSink>,
        all: &[Signal],
        prefixes: &[String],
        window: (u64, u64),
    ) -> Result<Waves, String> {
        let keep: Vec<usize> = (0..all.len()).filter(|&i| selected(&all[i], prefixes)).collect();
        if keep.is_empty() {
            let some: Vec<&str> = all.iter().take(6).map(|s| s.name.as_str()).collect();
            return Err(format!(
                "--vcd-units {}: no signal starts with these (signals look like {})",
                prefixes.join(","),
                some.join(", ")
            ));
        }
        let kept: Vec<Signal> = keep.iter().map(|&i| all[i].clone()).collect();
        sink.define(&kept)?;
        Ok(Waves { sink, last: vec![None; keep.len()], keep, window, scratch: Vec::new(), error: None })
    }

    /// The values of cycle `cycle` (in `scratch`): changes go to the sink.
    pub(crate) fn sample(&mut self, cycle: u64) {
        if cycle < self.window.0 || cycle >= self.window.1 || self.error.is_some() {
            return;
        }
        for (k, &i) in self.keep.iter().enumerate() {
            let v = self.scratch[i];
            if self.last[k] != Some(v) {
                self.last[k] = Some(v);
                if let Err(e) = self.sink.change(cycle, k, v) {
                    self.error = Some(e);
                    return;
                }
            }
        }
    }

    /// The end of the run at `cycle`.
    pub fn finish(&mut self, cycle: u64) -> Result<(), String> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.sink.finish(cycle.clamp(self.window.0, self.window.1))
    }
}

/// One traced event.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TraceEvent {
    /// A packet entered (`push`) or left a FIFO at the edge of `cycle`.
    Fifo {
        /// Cycle.
        cycle: u64,
        /// The FIFO's name.
        fifo: String,
        /// Entered (true) or left.
        push: bool,
        /// Packet number.
        packet: u32,
    },
    /// The shading unit finished a packet (its framebuffer write or its released rays).
    Shaded {
        /// Cycle.
        cycle: u64,
        /// Packet number.
        packet: u32,
    },
    /// A memory request: from its issue to its data.
    Memory {
        /// The port.
        port: String,
        /// Cycle the unit asked.
        issued: u64,
        /// Cycle the data arrived (writes: the memory took it).
        ready: u64,
        /// Data class name.
        class: &'static str,
        /// Bytes.
        bytes: u32,
        /// A write.
        write: bool,
    },
}

/// The trace of a run: events in cycle order within each kind.
#[derive(Clone, Debug, Default)]
pub struct TraceLog {
    /// Events.
    pub events: Vec<TraceEvent>,
    /// Frame number of each event (walkthroughs; packets are numbered per frame).
    pub frames: Vec<u32>,
}
