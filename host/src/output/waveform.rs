//! Waveforms as VCD (IEEE 1364 value change dump) through the `vcd` crate, for GTKWave
//! and Surfer, in true time: `$timescale 1 ps` and each cycle at its clock edge (cycle
//! × the period, rounded to the picosecond), so a viewer's time axis reads the chip's
//! time. Signals sit in scopes named after the units (`raypipe.fifos.rays0.occupancy`,
//! `raypipe.traversal0.threads.fetching`). Beside the VCD go a GTKWave save file
//! (signals grouped by unit, activities decoded) and the translate filter file of the
//! activity code ([`activity_filter`]).

use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{anyhow, Result};
use raypipe_hw::observe::waves::{Signal, WaveSink};
use vcd::{IdCode, TimescaleUnit, Value};

use crate::output::Streamed;

/// A VCD file being written.
pub struct VcdSink {
    writer: vcd::Writer<BufWriter<std::fs::File>>,
    ids: Vec<(IdCode, u32)>,
    time: Option<u64>,
    comment: String,
    /// Picoseconds per clock cycle.
    ps_per_cycle: f64,
}

/// Starts a VCD at `path` of a chip clocked at `clock_mhz` (it appears when
/// [`Streamed::commit`] is called after the run).
pub fn create(path: &Path, comment: String, clock_mhz: f64) -> Result<(Streamed, VcdSink)> {
    let mut file = Streamed::create(path)?;
    let handle = file.file().try_clone().map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let writer = vcd::Writer::new(BufWriter::new(handle));
    let sink = VcdSink { writer, ids: Vec::new(), time: None, comment, ps_per_cycle: 1e6 / clock_mhz };
    Ok((file, sink))
}

impl VcdSink {
    /// The VCD time of cycle `cycle`'s edge, in picoseconds.
    fn at(&self, cycle: u64) -> u64 {
        (cycle as f64 * self.ps_per_cycle).round() as u64
    }
}

/// The activity code's names (`raypipe_hw::observe::waves::activity_code`: 0 idle,
/// 1 busy, 2 + the stall reason's index), as a GTKWave translate filter file.
pub fn activity_filter() -> String {
    let mut text = String::from("# raypipe unit activity\n0 idle\n1 busy\n");
    for (i, s) in raypipe_hw::observe::stall::Stall::ALL.iter().enumerate() {
        text += &format!("{} {}\n", i + 2, s.name());
    }
    text
}

/// A GTKWave save file for the VCD at `vcd` (absolute), showing `signals` grouped by
/// their first scope (the unit), each activity decimal through the filter at `filter`.
pub fn gtkw(vcd: &Path, filter: &Path, signals: &[Signal]) -> String {
    // Trace flags (GTKWave's TR_* bits): decimal 0x4, right-justified 0x20, translated
    // by a filter file 0x2000; a group's blank line opens 0x800200 or closes 0x1000200.
    let mut text = format!("[*] raypipe simulate\n[dumpfile] \"{}\"\n[timestart] 0\n", vcd.display());
    let mut group: Option<&str> = None;
    for s in signals {
        let unit = s.name.split('.').next().unwrap_or("");
        if group != Some(unit) {
            if let Some(g) = group {
                text += &format!("@1000200\n-{g}\n");
            }
            text += &format!("@800200\n-{unit}\n");
            group = Some(unit);
        }
        let name =
            if s.width > 1 { format!("raypipe.{}[{}:0]", s.name, s.width - 1) } else { format!("raypipe.{}", s.name) };
        if s.name.ends_with(".activity") {
            text += &format!("@2024\n^1 {}\n{name}\n", filter.display());
        } else {
            text += &format!("@24\n{name}\n");
        }
    }
    if let Some(g) = group {
        text += &format!("@1000200\n-{g}\n");
    }
    text
}

fn io(e: std::io::Error) -> String {
    format!("cannot write the VCD: {e}")
}

impl WaveSink for VcdSink {
    fn define(&mut self, signals: &[Signal]) -> Result<(), String> {
        let w = &mut self.writer;
        w.comment(&self.comment).map_err(io)?;
        w.version(concat!("raypipe ", env!("CARGO_PKG_VERSION"))).map_err(io)?;
        w.timescale(1, TimescaleUnit::PS).map_err(io)?;
        w.add_module("raypipe").map_err(io)?;
        let mut open: Vec<String> = Vec::new();
        for s in signals {
            let mut parts: Vec<&str> = s.name.split('.').collect();
            let var = parts.pop().unwrap_or("signal");
            let common = open.iter().zip(&parts).take_while(|(a, b)| a.as_str() == **b).count();
            while open.len() > common {
                w.upscope().map_err(io)?;
                open.pop();
            }
            for p in &parts[common..] {
                w.add_module(p).map_err(io)?;
                open.push(p.to_string());
            }
            let id = w.add_wire(s.width, var).map_err(io)?;
            self.ids.push((id, s.width));
        }
        for _ in 0..=open.len() {
            w.upscope().map_err(io)?;
        }
        w.enddefinitions().map_err(io)
    }

    fn change(&mut self, cycle: u64, index: usize, value: u64) -> Result<(), String> {
        if self.time != Some(cycle) {
            let t = self.at(cycle);
            self.writer.timestamp(t).map_err(io)?;
            self.time = Some(cycle);
        }
        let (id, width) = self.ids[index];
        if width == 1 {
            self.writer.change_scalar(id, Value::from(value & 1 == 1)).map_err(io)
        } else {
            let bits = (0..width).rev().map(|b| Value::from((value >> b) & 1 == 1));
            self.writer.change_vector(id, bits).map_err(io)
        }
    }

    fn finish(&mut self, cycle: u64) -> Result<(), String> {
        if self.time.is_none_or(|t| t < cycle) {
            let t = self.at(cycle);
            self.writer.timestamp(t).map_err(io)?;
        }
        self.writer.flush().map_err(io)?;
        self.writer.writer().flush().map_err(io)
    }
}
