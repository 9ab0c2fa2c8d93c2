//! DRAMsim3 (Li et al., IEEE CAL 2020) as the chip's memory, through the `dramsim3`
//! crate, which builds DRAMsim3 itself: the memory gem5 and GPGPU-Sim-based simulators
//! plug in, with its own controller (FR-FCFS scheduling, bank groups, tRRD/tFAW/tCCD,
//! read/write turnaround, refresh) and its power model.
//!
//! The two clocks cross exactly: the chip's edge ending cycle `n` is at time
//! `(n + 1) · T_chip`, and every memory cycle that ends by then is ticked before the
//! edge takes new requests. A transaction whose callback fires in memory cycle `d` has
//! its data at `(d + 1) · tCK`: the chip uses it from the first chip cycle starting
//! then, never before. A request is split into DRAMsim3's transactions (bus width ×
//! burst length bytes, aligned); it is done when its last transaction is. DRAMsim3 takes
//! a transaction only when `can_add` says so: the rest wait, in order, in the memory's
//! request queue (`memory.queue_depth` requests), which pushes back on the ports.
//!
//! DRAMsim3 reports its counters (row hits, ACT/PRE/REF commands, energy) only per
//! epoch, in a JSON file in its output folder; at the end of a frame the memory is ticked,
//! idle, to the next epoch boundary so that the counters cover the whole frame.

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;

use crate::config::Dramsim3Config;
use crate::memory::dramsim3_ini::{self, Dramsim3Geometry};

/// Memory cycles per epoch of DRAMsim3's counters (20 µs at 800 MHz): the idle tail
/// closing the last epoch is a small part of any real frame (its refreshes and standby
/// energy are counted), and a 100 ms frame writes some 5000 epochs (a few MB).
const EPOCH_CYCLES: u64 = 1 << 14;

/// Femtoseconds per ns.
const FS_PER_NS: f64 = 1e6;

/// DRAMsim3's counters and the chip's view of its transactions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dramsim3Stats {
    /// Transactions added (reads, writes).
    pub transactions: [u64; 2],
    /// Bytes the transactions moved.
    pub bytes: u64,
    /// Read latencies in memory cycles, add to callback, in completion order.
    pub read_latency: Vec<u64>,
}

/// DRAMsim3's counters summed over the epochs since the statistics were last zeroed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dramsim3Counters {
    /// Epochs (per channel) summed.
    pub epochs: u64,
    /// Memory cycles they cover (one channel's count).
    pub cycles: u64,
    /// Reads and writes done.
    pub reads: u64,
    /// Writes done.
    pub writes: u64,
    /// Read and write commands that found their row open.
    pub row_hits: u64,
    /// READ and WRITE commands.
    pub column_commands: u64,
    /// READ commands (each moves one transaction's bytes over the bus).
    pub read_commands: u64,
    /// ACTIVATE commands.
    pub activates: u64,
    /// PRECHARGE commands.
    pub precharges: u64,
    /// REFRESH commands (all-bank and per-bank).
    pub refreshes: u64,
    /// Energy in pJ, all parts (activate, read, write, refresh, background).
    pub energy_pj: f64,
}

/// The memory: DRAMsim3 and the transactions in flight.
pub struct Dramsim3 {
    sys: dramsim3::MemorySystem,
    /// DRAMsim3's output folder (removed on drop).
    dir: tempfile::TempDir,
    /// The configuration file used.
    pub path: PathBuf,
    /// Its geometry.
    pub geometry: Dramsim3Geometry,
    t_ck_fs: u64,
    chip_fs: u64,
    /// Memory cycles ticked.
    clk: u64,
    /// Transactions accepted and not yet added: token, address, write.
    issue: VecDeque<(u32, u64, bool)>,
    /// Requests with a transaction in `issue`.
    issuing: usize,
    /// Per token: transactions not yet done, and whether one is still in `issue`.
    remaining: HashMap<u32, (u32, u32)>,
    /// Added transactions not yet called back, by (address, write): token, cycle added.
    inflight: HashMap<(u64, bool), VecDeque<(u32, u64)>>,
    in_flight: usize,
    /// Requests done: token and the chip cycle their data is there from.
    done: Vec<(u32, u64)>,
    /// Epochs already counted when the statistics were last zeroed.
    epochs_skipped: u64,
    /// Statistics.
    pub stats: Dramsim3Stats,
}

impl std::fmt::Debug for Dramsim3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Dramsim3").field("path", &self.path).field("clk", &self.clk).finish_non_exhaustive()
    }
}

impl Dramsim3 {
    /// DRAMsim3 for `cfg` behind a chip clocked at `chip_mhz`.
    pub fn new(cfg: &Dramsim3Config, chip_mhz: f64) -> Result<Dramsim3, String> {
        let (path, mut ini, geometry) = dramsim3_ini::load(&cfg.config)?;
        let dir = tempfile::Builder::new()
            .prefix("raypipe-dramsim3-")
            .tempdir()
            .map_err(|e| format!("DRAMsim3's output folder: {e}"))?;
        ini.set("other", "epoch_period", &EPOCH_CYCLES.to_string());
        ini.set("other", "output_level", "1");
        ini.set("other", "output_prefix", "dramsim3");
        let copy = dir.path().join("config.ini");
        std::fs::write(&copy, ini.render()).map_err(|e| format!("{}: {e}", copy.display()))?;
        let sys = dramsim3::MemorySystem::new(&copy, dir.path())
            .map_err(|_| format!("{}: a path DRAMsim3 cannot take", path.display()))?;
        Ok(Dramsim3 {
            sys,
            dir,
            path,
            t_ck_fs: (geometry.t_ck_ns * FS_PER_NS).round() as u64,
            chip_fs: (1e9 / chip_mhz).round().max(1.0) as u64,
            geometry,
            clk: 0,
            issue: VecDeque::new(),
            issuing: 0,
            remaining: HashMap::new(),
            inflight: HashMap::new(),
            in_flight: 0,
            done: Vec::new(),
            epochs_skipped: 0,
            stats: Dramsim3Stats::default(),
        })
    }

    /// Requests accepted whose transactions are not all in DRAMsim3 yet.
    pub fn queued(&self) -> usize {
        self.issuing
    }

    /// True while a transaction waits to be added or for its callback.
    pub fn busy(&self) -> bool {
        !self.issue.is_empty() || self.in_flight > 0
    }

    /// Accepts request `token`: `bytes` at `addr`, as aligned transactions. Returns the
    /// bytes they move.
    pub fn submit(&mut self, token: u32, addr: u64, bytes: u32, write: bool) -> u64 {
        let size = self.geometry.transaction_bytes();
        let first = addr / size;
        let last = (addr + bytes.max(1) as u64 - 1) / size;
        let n = (last - first + 1) as u32;
        for t in first..=last {
            self.issue.push_back((token, t * size, write));
        }
        self.remaining.insert(token, (n, n));
        self.issuing += 1;
        n as u64 * size
    }

    /// The chip cycle from which data called back in memory cycle `clk` is there.
    fn chip_cycle_after(&self, clk: u64) -> u64 {
        ((clk + 1) * self.t_ck_fs).div_ceil(self.chip_fs)
    }

    /// The chip cycle the memory's clock has reached.
    pub fn chip_now(&self) -> u64 {
        (self.clk * self.t_ck_fs).div_ceil(self.chip_fs)
    }

    /// Adds waiting transactions while DRAMsim3 takes them, then ticks one memory cycle.
    fn tick(&mut self) {
        while let Some(&(token, addr, write)) = self.issue.front() {
            if !self.sys.can_add(addr, write) {
                break;
            }
            self.sys.add(addr, write);
            self.issue.pop_front();
            self.stats.transactions[write as usize] += 1;
            self.stats.bytes += self.geometry.transaction_bytes();
            self.inflight.entry((addr, write)).or_default().push_back((token, self.clk));
            self.in_flight += 1;
            if let Some(r) = self.remaining.get_mut(&token) {
                r.1 -= 1;
                if r.1 == 0 {
                    self.issuing -= 1;
                }
            }
        }
        let clk = self.clk;
        let mut called = Vec::new();
        self.sys.tick(|addr, write| called.push((addr, write)));
        for (addr, write) in called {
            let Some(q) = self.inflight.get_mut(&(addr, write)) else { continue };
            let Some((token, added)) = q.pop_front() else { continue };
            if q.is_empty() {
                self.inflight.remove(&(addr, write));
            }
            self.in_flight -= 1;
            if !write {
                self.stats.read_latency.push(clk - added);
            }
            let finished = self.remaining.get_mut(&token).map(|r| {
                r.0 -= 1;
                r.0 == 0
            });
            if finished == Some(true) {
                self.remaining.remove(&token);
                self.done.push((token, self.chip_cycle_after(clk)));
            }
        }
        self.clk += 1;
    }

    /// Ticks every memory cycle that ends by the edge ending chip cycle `now`.
    pub fn advance(&mut self, now: u64) {
        let edge = (now + 1) * self.chip_fs;
        while (self.clk + 1) * self.t_ck_fs <= edge {
            self.tick();
        }
    }

    /// Requests finished since the last call: token and the chip cycle their data is
    /// there from.
    pub fn take_done(&mut self) -> Vec<(u32, u64)> {
        std::mem::take(&mut self.done)
    }

    /// Ticks the idle memory to the end of its current epoch, so DRAMsim3's counters
    /// cover every cycle so far. Call only once nothing is in flight.
    pub fn close_epoch(&mut self) {
        while !self.clk.is_multiple_of(EPOCH_CYCLES) || self.clk == 0 {
            self.tick();
        }
    }

    /// Zeroes the statistics: DRAMsim3's counters from the epochs to come.
    pub fn reset_stats(&mut self) {
        self.stats = Dramsim3Stats::default();
        self.epochs_skipped = self.clk / EPOCH_CYCLES;
    }

    /// DRAMsim3's counters over the closed epochs since the statistics were zeroed.
    pub fn counters(&self) -> Dramsim3Counters {
        let file = self.dir.path().join("dramsim3epoch.json");
        let text = std::fs::read_to_string(file).unwrap_or_default();
        let mut c = Dramsim3Counters::default();
        let channels = self.geometry.channels.max(1) as u64;
        let objects = text.trim_start_matches('[').split(",\n").map(str::trim).filter(|s| !s.is_empty());
        for (k, obj) in objects.enumerate() {
            if (k as u64) < self.epochs_skipped * channels {
                continue;
            }
            let Ok(v) = serde_json::from_str::<serde_json::Value>(obj) else { continue };
            let u = |key: &str| v.get(key).and_then(serde_json::Value::as_u64).unwrap_or(0);
            c.epochs += 1;
            if (k as u64).is_multiple_of(channels) {
                c.cycles += u("num_cycles");
            }
            c.reads += u("num_reads_done");
            c.writes += u("num_writes_done");
            c.row_hits += u("num_read_row_hits") + u("num_write_row_hits");
            c.column_commands += u("num_read_cmds") + u("num_write_cmds");
            c.read_commands += u("num_read_cmds");
            c.activates += u("num_act_cmds");
            c.precharges += u("num_pre_cmds");
            c.refreshes += u("num_ref_cmds") + u("num_refb_cmds");
            c.energy_pj += v.get("total_energy").and_then(serde_json::Value::as_f64).unwrap_or(0.0);
        }
        c
    }

    /// The memory cycle period in ns.
    pub fn t_ck_ns(&self) -> f64 {
        self.geometry.t_ck_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ddr3(chip_mhz: f64) -> Dramsim3 {
        Dramsim3::new(&Dramsim3Config::default(), chip_mhz).expect("DRAMsim3's DDR3-1600 configuration")
    }

    /// Ticks chip cycles until every request is done; returns (token, ready) in order.
    fn drain(d: &mut Dramsim3, mut now: u64) -> Vec<(u32, u64)> {
        let mut done = Vec::new();
        while d.busy() {
            d.advance(now);
            done.extend(d.take_done());
            now += 1;
            assert!(now < 10_000_000, "DRAMsim3 never answered");
        }
        done
    }

    #[test]
    fn an_idle_read_costs_activate_cas_and_the_burst_and_crosses_clocks_up() {
        // DDR3-1600 11-11-11 at tCK = 1.25 ns behind a 200 MHz chip (5 ns): 4 memory
        // cycles per chip cycle.
        let mut d = ddr3(200.0);
        assert_eq!(d.submit(0, 4096, 64, false), 64);
        let done = drain(&mut d, 0);
        assert_eq!(done.len(), 1);
        let lat = d.stats.read_latency[0];
        // ACTIVATE, tRCD = 11, READ, CL = 11, BL8 = 4 cycles: 26, plus DRAMsim3's
        // command-queue cycles (at most a few).
        assert!((26..=30).contains(&lat), "{lat} memory cycles");
        // Its data is there from the first chip cycle starting after the callback's
        // memory cycle ends, never sooner.
        let (_, ready) = done[0];
        let added = 0; // the first tick, memory cycle 0, adds it
        let data_fs = (added + lat + 1) * d.t_ck_fs;
        assert_eq!(ready, data_fs.div_ceil(d.chip_fs));
    }

    #[test]
    fn a_request_spanning_transactions_is_done_with_its_last_and_the_queue_pushes_back() {
        let mut d = ddr3(800.0);
        // 200 bytes from byte 40: transactions at 0, 64, 128 and 192.
        assert_eq!(d.submit(7, 40, 200, false), 256);
        assert_eq!(d.queued(), 1);
        // Far more transactions than DRAMsim3's queue (32) holds: they wait, in order.
        for t in 8..208u32 {
            d.submit(t, t as u64 * 8192 * 8, 64, t % 3 == 0);
        }
        d.advance(0);
        assert!(d.queued() > 0, "DRAMsim3 took every transaction at once");
        let done = drain(&mut d, 1);
        assert_eq!(done.len(), 201, "every request answered once");
        assert_eq!(d.stats.transactions.iter().sum::<u64>(), 204);
        let c = d.counters();
        assert_eq!(c.reads + c.writes, 0, "no epoch closed yet");
        d.close_epoch();
        let c = d.counters();
        assert_eq!(c.reads, d.stats.transactions[0]);
        assert_eq!(c.writes, d.stats.transactions[1]);
        assert!(c.activates > 0 && c.energy_pj > 0.0 && c.cycles >= EPOCH_CYCLES, "{c:?}");
        d.reset_stats();
        assert_eq!(d.counters(), Dramsim3Counters::default());
    }

    #[test]
    fn a_missing_configuration_is_an_error_not_an_exit() {
        let cfg = Dramsim3Config { config: "DDR9_nothing".into() };
        let err = Dramsim3::new(&cfg, 500.0).unwrap_err();
        assert!(err.contains("DDR9_nothing"), "{err}");
    }
}
