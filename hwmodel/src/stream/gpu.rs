//! The machine that turns a frame's totals into time: an instruction rate and a memory
//! bandwidth, overlapped (Purcell 2002 §4.4 reasons the same way: a frame takes as long
//! as the larger of its compute time and its memory time, and is bound by that one).
//!
//! Default: ATI's Radeon 9700 Pro (2002), the chip Purcell's §5 looks ahead to — 8
//! fragment pipelines at 325 MHz, one 4-wide instruction per pipeline per clock
//! (2.6 G instructions/s), and a 256-bit DDR memory at 310 MHz (19.84 GB/s) — from
//! ATI's published specifications. Each kernel instruction is charged as one fragment
//! instruction (the cost model counts scalar operations, so this is pessimistic for
//! code that would vectorise).

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

/// Rates of the machine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Machine {
    /// Fragment instructions per second.
    pub instr_per_s: f64,
    /// Memory bytes per second.
    pub bytes_per_s: f64,
}

impl Default for Machine {
    fn default() -> Self {
        Machine { instr_per_s: 8.0 * 325e6, bytes_per_s: 256.0 / 8.0 * 2.0 * 310e6 }
    }
}

impl fmt::Display for Machine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.3} G instr/s, {:.2} GB/s", self.instr_per_s / 1e9, self.bytes_per_s / 1e9)
    }
}

impl FromStr for Machine {
    type Err = String;

    /// `INSTR_PER_S,BYTES_PER_S`, e.g. `2.6e9,19.84e9`.
    fn from_str(s: &str) -> Result<Self, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|p| p.trim().parse::<f64>().map_err(|_| format!("machine {s:?}: '{}' is not a rate", p.trim())))
            .collect::<Result<_, _>>()?;
        let [i, b] = v.as_slice() else {
            return Err(format!("machine {s:?}: expected INSTR_PER_S,BYTES_PER_S"));
        };
        let ok = |x: f64| x.is_finite() && (1.0..=1e18).contains(&x);
        if !ok(*i) || !ok(*b) {
            return Err(format!("machine {s:?}: rates must be between 1 and 1e18 per second"));
        }
        Ok(Machine { instr_per_s: *i, bytes_per_s: *b })
    }
}

/// What bounds a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// Instructions take longer than memory traffic.
    Compute,
    /// Memory traffic takes longer than instructions.
    Bandwidth,
}

/// A frame's time on the machine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameTime {
    /// Seconds of instructions.
    pub compute_s: f64,
    /// Seconds of memory traffic.
    pub memory_s: f64,
    /// The frame: the larger of the two.
    pub frame_s: f64,
    /// Which one.
    pub bound: Bound,
}

impl Machine {
    /// The time of `instructions` and `bytes` on this machine.
    pub fn frame_time(&self, instructions: u64, bytes: u64) -> FrameTime {
        let compute_s = instructions as f64 / self.instr_per_s;
        let memory_s = bytes as f64 / self.bytes_per_s;
        let bound = if compute_s >= memory_s { Bound::Compute } else { Bound::Bandwidth };
        FrameTime { compute_s, memory_s, frame_s: compute_s.max(memory_s), bound }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slower_side_bounds_the_frame() {
        let m: Machine = "1e9,4e9".parse().unwrap();
        let t = m.frame_time(2_000_000_000, 4_000_000_000);
        assert_eq!((t.frame_s, t.bound), (2.0, Bound::Compute));
        let t = m.frame_time(1, 40_000_000_000);
        assert_eq!((t.frame_s, t.bound), (10.0, Bound::Bandwidth));
        assert!("1e9".parse::<Machine>().is_err() && "0,1".parse::<Machine>().is_err());
        assert!("nan,1e9".parse::<Machine>().is_err());
        assert_eq!(Machine::default().instr_per_s, 2.6e9);
    }
}
