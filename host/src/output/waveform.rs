//! Waveforms as VCD (IEEE 1364 value change dump) through the `vcd` crate, for GTKWave
//! and Surfer: one time unit is one clock cycle; signals sit in scopes named after the
//! units (`raypipe.fifos.rays0.occupancy`, `raypipe.traversal0.threads.fetching`).

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
}

/// Starts a VCD at `path` (it appears when [`Streamed::commit`] is called after the run).
pub fn create(path: &Path, comment: String) -> Result<(Streamed, VcdSink)> {
    let mut file = Streamed::create(path)?;
    let handle = file.file().try_clone().map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let sink = VcdSink { writer: vcd::Writer::new(BufWriter::new(handle)), ids: Vec::new(), time: None, comment };
    Ok((file, sink))
}

fn io(e: std::io::Error) -> String {
    format!("cannot write the VCD: {e}")
}

impl WaveSink for VcdSink {
    fn define(&mut self, signals: &[Signal]) -> Result<(), String> {
        let w = &mut self.writer;
        w.comment(&self.comment).map_err(io)?;
        w.version(concat!("raypipe ", env!("CARGO_PKG_VERSION"))).map_err(io)?;
        w.timescale(1, TimescaleUnit::NS).map_err(io)?;
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
            self.writer.timestamp(cycle).map_err(io)?;
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
            self.writer.timestamp(cycle).map_err(io)?;
        }
        self.writer.flush().map_err(io)?;
        self.writer.writer().flush().map_err(io)
    }
}
