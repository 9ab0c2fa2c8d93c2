//! One request stream, two memories: raypipe's own DRAM model ([`crate::memory::dram`])
//! and DRAMsim3 replay the same requests at the same cycles, open loop, and the same
//! figures are taken from both — mean and 99th-percentile latency, bandwidth, row-hit
//! rate — to validate the one against the other (`bench/dram_validate.sh`).
//!
//! Timing follows [`crate::memory::Memory`]: a request that arrives in cycle `t` is taken
//! at that cycle's edge; raypipe's model serves it from `t + 1`, DRAMsim3 adds it in the
//! first memory cycle after the edge. Latency is counted from `t` for both. The streams
//! are synthetic (sequential, random, strided, row conflicts, a read/write mix) or a
//! frame's requests recorded by `raypipe simulate --memory-trace`.

use serde::Serialize;

use crate::config::{DramConfig, DramScheduling};
use crate::memory::dram::Dram;
use crate::memory::dram_scheduler::DramScheduler;

/// One request of a stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamRequest {
    /// Cycle it reaches the memory.
    pub cycle: u64,
    /// Byte address.
    pub addr: u64,
    /// Bytes.
    pub bytes: u32,
    /// A write.
    pub write: bool,
}

/// What one memory made of a stream.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ReplayFigures {
    /// Requests.
    pub requests: u64,
    /// Mean latency, ns (arrival to data; writes to written).
    pub mean_ns: f64,
    /// 99th-percentile latency, ns.
    pub p99_ns: f64,
    /// Bytes over the time from the first arrival to the last completion, GB/s.
    pub bandwidth_gb_s: f64,
    /// Column accesses that found their row open.
    pub row_hit_rate: f64,
}

/// The synthetic streams: `n` requests of 64 bytes, one every `interval` cycles, on a
/// channel of `banks` banks over all its ranks with rows of `row_bytes`.
pub fn synthetic(kind: &str, n: u64, interval: u64, row_bytes: u64, banks: u64) -> Option<Vec<StreamRequest>> {
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut rand = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let req = |k: u64, addr: u64, write: bool| StreamRequest { cycle: k * interval, addr, bytes: 64, write };
    let stream = match kind {
        "sequential" => (0..n).map(|k| req(k, k * 64, false)).collect(),
        "random" => (0..n).map(|k| req(k, (rand() % (1 << 24)) * 64, false)).collect(),
        // One burst per row, walking the banks: every access opens a row.
        "strided" => (0..n).map(|k| req(k, k * row_bytes + (k % 7) * 64, false)).collect(),
        // Two rows of one bank, alternately: every access is a row conflict.
        "row-conflict" => (0..n).map(|k| req(k, (k % 2) * row_bytes * banks + (k / 2 % 64) * 64, false)).collect(),
        // Two reads to one write, sequential within three streams far apart.
        "read-write" => (0..n).map(|k| req(k, (k % 3) * (1 << 28) + (k / 3) * 64, k % 3 == 2)).collect(),
        _ => return None,
    };
    Some(stream)
}

/// The names of the synthetic streams.
pub const SYNTHETIC: [&str; 5] = ["sequential", "random", "strided", "row-conflict", "read-write"];

/// Parses a recorded stream: one request per line, `cycle addr bytes R|W`.
pub fn parse_trace(text: &str) -> Result<Vec<StreamRequest>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() || f[0].starts_with('#') {
            continue;
        }
        let bad = || format!("line {}: expected `cycle addr bytes R|W`", n + 1);
        if f.len() != 4 {
            return Err(bad());
        }
        let cycle = f[0].parse().map_err(|_| bad())?;
        let addr = f[1].parse().map_err(|_| bad())?;
        let bytes: u32 = f[2].parse().map_err(|_| bad())?;
        let write = match f[3] {
            "R" => false,
            "W" => true,
            _ => return Err(bad()),
        };
        if bytes == 0 || bytes > 1 << 20 {
            return Err(format!("line {}: {bytes} bytes is not a request size", n + 1));
        }
        if out.last().is_some_and(|r: &StreamRequest| r.cycle > cycle) {
            return Err(format!("line {}: cycle {cycle} is before the line above", n + 1));
        }
        out.push(StreamRequest { cycle, addr, bytes, write });
    }
    Ok(out)
}

/// Latency figures of `lat` (cycles) at `ns` per cycle, with bytes moved over `span`.
fn figures(lat: &[u64], ns: f64, bytes: u64, span: u64, row_hit_rate: f64) -> ReplayFigures {
    let [mean_ns, _, p99_ns, _] = crate::observe::dramsim3_report::latency_summary(lat, ns);
    ReplayFigures {
        requests: lat.len() as u64,
        mean_ns,
        p99_ns,
        bandwidth_gb_s: if span > 0 { bytes as f64 / (span as f64 * ns) } else { 0.0 },
        row_hit_rate,
    }
}

/// raypipe's DRAM model on `stream`, clocked at `mhz` (the stream's cycles).
pub fn replay_dram(cfg: &DramConfig, mhz: f64, stream: &[StreamRequest]) -> ReplayFigures {
    let mut d = Dram::new(cfg, mhz);
    let mut ready = vec![0u64; stream.len()];
    let bytes: u64 = stream.iter().map(|r| d.bytes_moved(r.addr, r.bytes)).sum();
    if cfg.scheduler == DramScheduling::Fcfs {
        for (r, at) in stream.iter().zip(ready.iter_mut()) {
            *at = d.access(r.cycle + 1, r.addr, r.bytes, r.write).1;
        }
    } else {
        // The controller's queue holds REPLAY_QUEUE requests, as DRAMsim3's
        // `trans_queue_size` does; a request that finds it full waits, and its latency
        // counts from its cycle in the stream.
        let mut q = DramScheduler::new(cfg.row_hit_cap);
        let (mut next, mut now) = (0, stream.first().map_or(0, |r| r.cycle));
        while next < stream.len() || q.queued() > 0 {
            while let Some(r) = stream.get(next).filter(|r| r.cycle <= now && q.queued() < REPLAY_QUEUE) {
                q.submit(next as u32, now + 1, r.addr, r.bytes, r.write);
                next += 1;
            }
            for (token, end) in q.issue(&mut d, now + 1) {
                ready[token as usize] = end;
            }
            // Skip to the next arrival or the cycle before a queued request is ready.
            let arrival = stream.get(next).map_or(u64::MAX, |r| r.cycle);
            let ready_at = q.next_ready(&d, now).map_or(u64::MAX, |t| t - 1);
            now = if q.queued() >= REPLAY_QUEUE { ready_at } else { arrival.min(ready_at) }.max(now + 1);
        }
    }
    let lat: Vec<u64> = stream.iter().zip(&ready).map(|(r, &at)| at - r.cycle).collect();
    let end = ready.iter().copied().max().unwrap_or(0);
    let start = stream.first().map_or(0, |r| r.cycle);
    figures(&lat, 1e3 / mhz, bytes, end.saturating_sub(start), d.row_hit_rate())
}

/// The FR-FCFS replay's queue: DRAMsim3's `trans_queue_size` in its DDR3 and DDR4 files.
const REPLAY_QUEUE: usize = 32;

/// DRAMsim3 on `stream`, clocked at `mhz` (the stream's cycles).
#[cfg(feature = "dramsim3")]
pub fn replay_dramsim3(
    cfg: &crate::config::Dramsim3Config,
    mhz: f64,
    stream: &[StreamRequest],
) -> Result<ReplayFigures, String> {
    let mut d = crate::memory::dramsim3::Dramsim3::new(cfg, mhz)?;
    let mut ready = vec![0u64; stream.len()];
    let mut next = 0;
    let mut now = stream.first().map_or(0, |r| r.cycle);
    while next < stream.len() || d.busy() {
        d.advance(now);
        for (token, at) in d.take_done() {
            ready[token as usize] = at;
        }
        while let Some(r) = stream.get(next).filter(|r| r.cycle <= now) {
            d.submit(next as u32, r.addr, r.bytes, r.write);
            next += 1;
        }
        now += 1;
    }
    d.close_epoch();
    let lat: Vec<u64> = stream.iter().zip(&ready).map(|(r, &at)| at - r.cycle).collect();
    let end = ready.iter().copied().max().unwrap_or(0);
    let c = d.counters();
    let hit_rate = if c.column_commands > 0 { c.row_hits as f64 / c.column_commands as f64 } else { 0.0 };
    let start = stream.first().map_or(0, |r| r.cycle);
    Ok(figures(&lat, 1e3 / mhz, d.stats.bytes, end.saturating_sub(start), hit_rate))
}

/// raypipe's DRAM model set to DRAMsim3's `DDR4_8Gb_x8_2400` file (JEDEC DDR4-2400,
/// 17-17-17 at tCK = 0.83 ns, CWL 12; 16 banks in 4 groups, which the model does not
/// tell apart, so tRRD, tCCD and tWTR are the same-group (long) ones for every pair;
/// tRFC 350 ns for 8 Gb; tREFI 7.8 µs; tFAW 21 ns), with no controller latency. The rest
/// is the default DDR3-1600's, which the file shares: one 64-bit channel of two ranks
/// (its `channel_size` of 16384 MB holds two of 8 GB), 8 KiB rows, BL8, tRTRS 1 clock,
/// open pages, FR-FCFS.
pub fn ddr4_2400() -> DramConfig {
    DramConfig {
        clock_mhz: 1200.0,
        banks: 16,
        t_rcd: 17,
        t_rp: 17,
        t_cl: 17,
        t_cwl: 12,
        t_wtr: 9,
        t_ras: 39,
        t_wr: 18,
        t_refi: 9360,
        t_rfc: 420,
        t_rrd: 6,
        t_faw: 26,
        controller_latency: 0,
        ..DramConfig::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn traces_parse_and_bad_lines_name_their_line() {
        let t = parse_trace("# cycle addr bytes R|W\n0 64 64 R\n3 128 32 W\n").unwrap();
        assert_eq!(
            t,
            vec![
                StreamRequest { cycle: 0, addr: 64, bytes: 64, write: false },
                StreamRequest { cycle: 3, addr: 128, bytes: 32, write: true },
            ]
        );
        for (text, want) in
            [("0 64 64 X\n", "line 1"), ("5 0 64 R\n4 0 64 R\n", "before"), ("0 0 0 R\n", "request size")]
        {
            assert!(parse_trace(text).unwrap_err().contains(want), "{text}");
        }
    }

    #[test]
    fn the_own_model_streams_at_its_bus_and_pays_conflicts() {
        let cfg = DramConfig { controller_latency: 0, ..DramConfig::default() };
        let seq = replay_dram(&cfg, 800.0, &synthetic("sequential", 20_000, 1, 8192, 16).unwrap());
        assert!(seq.bandwidth_gb_s > 11.0 && seq.bandwidth_gb_s <= 12.8, "{seq:?}");
        // Alternating rows of one bank, one request a cycle: first come, first served
        // pays a conflict for every request; FR-FCFS serves the queued requests of the
        // open row first.
        let stream = synthetic("row-conflict", 2000, 1, 8192, 16).unwrap();
        let fcfs = replay_dram(&DramConfig { scheduler: DramScheduling::Fcfs, ..cfg }, 800.0, &stream);
        assert_eq!(fcfs.row_hit_rate, 0.0);
        // With a cap of 4 hits over a waiting conflict, each row opened serves five.
        let capped = replay_dram(&DramConfig { row_hit_cap: 4, ..cfg }, 800.0, &stream);
        assert!((0.75..0.85).contains(&capped.row_hit_rate) && capped.mean_ns * 4.0 < fcfs.mean_ns, "{capped:?}");
        let fr = replay_dram(&cfg, 800.0, &stream);
        assert!(fr.row_hit_rate > 0.95 && fr.mean_ns * 10.0 < fcfs.mean_ns, "{fr:?} against {fcfs:?}");
        assert!(synthetic("zigzag", 1, 1, 8192, 8).is_none());
    }
}
