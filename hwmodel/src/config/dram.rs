//! The DRAM model's parameters (`memory.dram`): geometry, timings in DRAM clock cycles
//! as a datasheet gives them, the controller's policy, and their default memory.

use serde::{Deserialize, Serialize};

/// DRAM parameters (timings in DRAM clock cycles, as a datasheet gives them).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DramConfig {
    /// DRAM command clock in MHz (the data rate is twice this).
    pub clock_mhz: f64,
    /// Independent channels (addresses interleaved by burst).
    pub channels: u32,
    /// Ranks per channel: sets of devices that share the channel's buses, each with its
    /// own banks, ACTIVATE window and refresh.
    pub ranks: u32,
    /// Banks per rank.
    pub banks: u32,
    /// Bytes of one row (page) of one bank across the channel's width.
    pub row_bytes: u32,
    /// Data bus width per channel, in bytes.
    pub bus_bytes: u32,
    /// Burst length in transfers (a burst moves `bus_bytes × burst_length` bytes in
    /// `burst_length / 2` clocks).
    pub burst_length: u32,
    /// `"open"`: a row stays open after an access; `"closed"`: precharged at once.
    pub page_policy: PagePolicy,
    /// `"fr-fcfs"`: queued requests are issued row hits first, oldest first (Rixner et
    /// al. 2000); `"fcfs"`: in the order the memory accepted them.
    pub scheduler: DramScheduling,
    /// FR-FCFS: row hits a bank serves over an older waiting conflict before the conflict
    /// goes (a guard against starvation); 0: no cap.
    pub row_hit_cap: u32,
    /// ACTIVATE to READ/WRITE.
    pub t_rcd: u32,
    /// PRECHARGE to ACTIVATE.
    pub t_rp: u32,
    /// READ to first data (CAS latency).
    pub t_cl: u32,
    /// WRITE to first data (CAS write latency).
    pub t_cwl: u32,
    /// End of write data to a READ command of the channel (write-to-read turnaround).
    pub t_wtr: u32,
    /// ACTIVATE to PRECHARGE, at least.
    pub t_ras: u32,
    /// End of write data to PRECHARGE.
    pub t_wr: u32,
    /// Average refresh interval.
    pub t_refi: u32,
    /// Refresh cycle time (every bank of the channel is busy).
    pub t_rfc: u32,
    /// ACTIVATE to ACTIVATE of another bank of the rank, at least.
    pub t_rrd: u32,
    /// Four-activate window: at most four ACTIVATEs of a rank in any `t_faw` cycles.
    pub t_faw: u32,
    /// Rank-to-rank switch: idle data-bus cycles between bursts of two ranks.
    pub t_rtrs: u32,
    /// Chip cycles through the memory controller, each way together.
    pub controller_latency: u32,
}

/// How the DRAM controller orders the requests in its queue.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DramScheduling {
    /// First ready, first come first served: row hits before older requests.
    #[default]
    #[serde(rename = "fr-fcfs")]
    FrFcfs,
    /// First come, first served.
    #[serde(rename = "fcfs")]
    Fcfs,
}

/// DRAM page policy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PagePolicy {
    /// Rows stay open (row hits are cheap, conflicts pay a precharge).
    Open,
    /// Rows are precharged after every access.
    Closed,
}

impl Default for DramConfig {
    /// DDR3-1600 11-11-11 (JEDEC JESD79-3F speed bin DDR3-1600K; e.g. Micron
    /// MT41K512M8 datasheet): 800 MHz, tRCD = tRP = CL = 13.75 ns, CWL = 8 clocks,
    /// tWTR = 7.5 ns (6 clocks), tRAS = 35 ns,
    /// tWR = 15 ns, tREFI = 7.8 µs, tRFC = 260 ns (4 Gb), tRRD = 6 ns and tFAW = 30 ns
    /// (1 KB pages); one 64-bit channel of two ranks of eight x8 devices (8 GB): 8 banks
    /// per rank with 8 KiB rows, BL8; a rank switch idles the bus tRTRS = 1 clock (JEDEC
    /// leaves it to the controller; DRAMsim3's value). DRAMsim3's `DDR3_4Gb_x8_1600.ini`
    /// describes the same memory (its `channel_size` of 8192 MB is two 4 GB ranks).
    /// Row hits are not capped: DRAMsim3 caps them at 4 over a waiting conflict, but
    /// only once the conflict's PRECHARGE is ready, which back-to-back hits (tRTP 6 >
    /// the burst's 4 clocks) keep it from; this model has no per-command readiness, and
    /// a cap of 4 cut its row hits below DRAMsim3's (docs/hw-model.md).
    fn default() -> Self {
        DramConfig {
            clock_mhz: 800.0,
            channels: 1,
            ranks: 2,
            banks: 8,
            row_bytes: 8192,
            bus_bytes: 8,
            burst_length: 8,
            page_policy: PagePolicy::Open,
            scheduler: DramScheduling::FrFcfs,
            row_hit_cap: 0,
            t_rcd: 11,
            t_rp: 11,
            t_cl: 11,
            t_cwl: 8,
            t_wtr: 6,
            t_ras: 28,
            t_wr: 12,
            t_refi: 6240,
            t_rfc: 208,
            t_rrd: 5,
            t_faw: 24,
            t_rtrs: 1,
            controller_latency: 10,
        }
    }
}
