//! DRAMsim3's part of the report: what its transactions saw (bandwidth, latency and its
//! tail, from the callbacks) and DRAMsim3's own counters (row hits, ACTIVATE, PRECHARGE
//! and REFRESH commands, energy), summed over its epochs.

use serde::Serialize;

/// DRAMsim3's statistics for the frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Dramsim3Report {
    /// The configuration file.
    pub config: String,
    /// Its protocol.
    pub protocol: String,
    /// Read and write transactions.
    pub reads: u64,
    /// Write transactions.
    pub writes: u64,
    /// Bytes the transactions moved.
    pub bytes: u64,
    /// Bytes READ commands moved over the bus (reads served from the write buffer or
    /// merged with another read to the same address cross it once or not at all).
    pub bus_read_bytes: u64,
    /// Bytes over the frame's time, GB/s.
    pub bandwidth_gb_s: f64,
    /// The channels' peak, GB/s.
    pub peak_gb_s: f64,
    /// Read latency inside DRAMsim3 (transaction added to its callback), ns: mean,
    /// median, 99th percentile and maximum.
    pub read_latency_ns: [f64; 4],
    /// Column commands that found their row open.
    pub row_hit_rate: f64,
    /// ACTIVATE commands.
    pub activates: u64,
    /// PRECHARGE commands.
    pub precharges: u64,
    /// REFRESH commands.
    pub refreshes: u64,
    /// DRAMsim3's energy estimate, nJ.
    pub energy_nj: f64,
    /// Memory cycles DRAMsim3's counters cover (whole epochs, the last closed idle at
    /// the frame's end).
    pub counted_cycles: u64,
}

/// Mean, median, 99th percentile and maximum of `cycles`, times `ns` per cycle.
pub fn latency_summary(cycles: &[u64], ns: f64) -> [f64; 4] {
    if cycles.is_empty() {
        return [0.0; 4];
    }
    let mut sorted = cycles.to_vec();
    sorted.sort_unstable();
    let at = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize] as f64 * ns;
    let mean = sorted.iter().map(|&c| c as f64).sum::<f64>() / sorted.len() as f64 * ns;
    [mean, at(0.5), at(0.99), at(1.0)]
}

#[cfg(feature = "dramsim3")]
impl Dramsim3Report {
    /// The report of `d` over a frame of `frame_ns`.
    pub fn of(d: &crate::memory::dramsim3::Dramsim3, frame_ns: f64) -> Dramsim3Report {
        let c = d.counters();
        let s = &d.stats;
        Dramsim3Report {
            config: d.path.display().to_string(),
            protocol: d.geometry.protocol.clone(),
            reads: s.transactions[0],
            writes: s.transactions[1],
            bytes: s.bytes,
            bus_read_bytes: c.read_commands * d.geometry.transaction_bytes(),
            bandwidth_gb_s: if frame_ns > 0.0 { s.bytes as f64 / frame_ns } else { 0.0 },
            peak_gb_s: d.geometry.peak_bytes_per_ns(),
            read_latency_ns: latency_summary(&s.read_latency, d.t_ck_ns()),
            row_hit_rate: if c.column_commands > 0 { c.row_hits as f64 / c.column_commands as f64 } else { 0.0 },
            activates: c.activates,
            precharges: c.precharges,
            refreshes: c.refreshes,
            energy_nj: c.energy_pj / 1e3,
            counted_cycles: c.cycles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_is_mean_median_tail_and_max() {
        let cycles: Vec<u64> = (1..=100).collect();
        let [mean, p50, p99, max] = latency_summary(&cycles, 2.0);
        assert_eq!(mean, 101.0);
        assert_eq!(p50, 102.0);
        assert_eq!(p99, 198.0);
        assert_eq!(max, 200.0);
        assert_eq!(latency_summary(&[], 1.0), [0.0; 4]);
    }
}
