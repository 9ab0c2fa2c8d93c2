//! A DRAM timing model: channels of ranks of banks with one open row each, a shared data
//! bus per channel, the main JEDEC timings (tRCD, tRP, CL, CWL, tRAS, tWR, tRRD and tFAW
//! per rank, the write-to-read and read-to-write turnarounds, the rank-to-rank switch
//! tRTRS), periodic refresh (tREFI, tRFC; ranks refresh in turn, tREFI ÷ ranks apart, as
//! DRAMsim3's rank-staggered policy does) and an open or closed page policy. Requests are
//! timed burst by burst in the order the controller issues them
//! ([`crate::memory::dram_scheduler`]: FR-FCFS, or first come, first served); a request's
//! data is there when its last burst has crossed the bus.
//!
//! Address mapping (row : rank : bank : column : channel, high to low bits; DRAMsim3's
//! `rochrababgco` also puts the rank above the bank): bursts are interleaved over
//! channels, a channel's bytes fill a row of one bank before moving to the next bank, then
//! to the next rank, so a stream of sequential reads hits open rows. The model is checked
//! in its tests against what the DDR3-1600 datasheet timings give for a streaming and a
//! random-access micro-benchmark (docs/hw-model.md, "DRAM").

use crate::config::{DramConfig, PagePolicy};

/// One bank's state, in DRAM clock cycles.
#[derive(Clone, Copy, Debug, Default)]
struct Bank {
    open_row: Option<u64>,
    /// When the last ACTIVATE issued (for tRAS).
    activated: u64,
    /// Earliest cycle the bank takes its next command.
    ready: u64,
    /// Earliest cycle the bank may precharge: tWR after its last write's data.
    precharge_ok: u64,
    /// Refresh epoch the row was opened in (a refresh closes every row).
    epoch: u64,
    /// Row hits since the row opened (the scheduler's row-hit cap).
    hits: u32,
}

/// A column command: its cycle and its rank.
#[derive(Clone, Copy, Debug)]
struct Column {
    at: u64,
    rank: u32,
}

/// Where a burst lives.
#[derive(Clone, Copy, Debug)]
struct Place {
    channel: usize,
    rank: u32,
    /// The bank's index over all channels and ranks.
    bank: usize,
    row: u64,
}

/// What the scheduler sees of a request's bank.
#[derive(Clone, Copy, Debug)]
pub struct BankView {
    /// The bank's index over all channels and ranks.
    pub bank: usize,
    /// The request's row is open (and no refresh has closed it).
    pub open: bool,
    /// The chip cycle from which the bank takes its next command.
    pub free: u64,
    /// Row hits the bank has served since its row opened.
    pub hits: u32,
}

/// Per-bank counters.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct BankStats {
    /// Bursts served.
    pub accesses: u64,
    /// Bursts that found their row open.
    pub row_hits: u64,
    /// Bursts that found the bank closed (an ACTIVATE only).
    pub row_empty: u64,
    /// Bursts that found another row open (PRECHARGE and ACTIVATE).
    pub row_conflicts: u64,
}

/// The DRAM's state.
#[derive(Clone, Debug)]
pub struct Dram {
    cfg: DramConfig,
    /// Chip cycles per DRAM cycle.
    ratio: f64,
    banks: Vec<Bank>,
    /// Per channel: the data bus is free from this DRAM cycle.
    bus_free: Vec<u64>,
    /// Per rank, channel-major: its recent ACTIVATEs, in time order (tRRD, tFAW).
    acts: Vec<Vec<u64>>,
    /// Per channel: the last READ and WRITE column commands and their ranks (bus
    /// turnaround).
    last_read: Vec<Option<Column>>,
    last_write: Vec<Option<Column>>,
    /// Per channel: the rank whose burst the data bus carried last (tRTRS).
    bus_rank: Vec<Option<u32>>,
    /// Per bank, channel-major, then rank-major.
    pub stats: Vec<BankStats>,
    /// DRAM cycles the data buses carried data, all channels.
    pub bus_busy: u64,
}

impl Dram {
    /// Zeroes the statistics (open rows and timing state stay).
    pub fn reset_stats(&mut self) {
        self.stats.iter_mut().for_each(|b| *b = BankStats::default());
        self.bus_busy = 0;
    }

    /// An idle DRAM behind a chip clocked at `chip_mhz`.
    pub fn new(cfg: &DramConfig, chip_mhz: f64) -> Dram {
        let n = (cfg.channels * cfg.ranks * cfg.banks) as usize;
        let channels = cfg.channels as usize;
        Dram {
            cfg: *cfg,
            ratio: chip_mhz / cfg.clock_mhz,
            banks: vec![Bank::default(); n],
            bus_free: vec![0; channels],
            acts: vec![Vec::new(); channels * cfg.ranks as usize],
            last_read: vec![None; channels],
            last_write: vec![None; channels],
            bus_rank: vec![None; channels],
            stats: vec![BankStats::default(); n],
            bus_busy: 0,
        }
    }

    /// Channels.
    pub fn channels(&self) -> usize {
        self.cfg.channels as usize
    }

    /// The DRAM clock in MHz.
    pub fn clock_mhz(&self) -> f64 {
        self.cfg.clock_mhz
    }

    /// Bytes of one burst.
    pub fn burst_bytes(&self) -> u64 {
        (self.cfg.bus_bytes * self.cfg.burst_length) as u64
    }

    /// Bytes a request of `bytes` at `addr` moves over the bus: the whole bursts it
    /// touches.
    pub fn bytes_moved(&self, addr: u64, bytes: u32) -> u64 {
        let burst = self.burst_bytes();
        (addr + bytes.max(1) as u64).div_ceil(burst) * burst - addr / burst * burst
    }

    fn burst_cycles(&self) -> u64 {
        (self.cfg.burst_length / 2).max(1) as u64
    }

    /// The DRAM cycle at or after chip cycle `chip`.
    fn to_dram(&self, chip: u64) -> u64 {
        (chip as f64 / self.ratio).ceil() as u64
    }

    /// The chip cycle at or after DRAM cycle `dram`.
    fn to_chip(&self, dram: u64) -> u64 {
        (dram as f64 * self.ratio).ceil() as u64
    }

    /// An ACTIVATE wanted at `t` on the rank `rank` (channel-major index): the earliest
    /// cycle from `t` that keeps it tRRD from every other ACTIVATE of the rank and leaves
    /// at most four in any tFAW window (JEDEC sets both per rank). Banks are served in
    /// parallel, so ACTIVATEs need not come in request order. Returns when it issues, and
    /// records it.
    fn activate(&mut self, rank: usize, t: u64) -> u64 {
        let (rrd, faw) = (self.cfg.t_rrd as u64, self.cfg.t_faw as u64);
        let acts = &mut self.acts[rank];
        let mut at = t;
        // `acts` is in time order: only the ACTIVATEs within tRRD or tFAW of `at` can
        // constrain it. Each pass moves `at` past one conflict, forward, so it ends.
        'search: loop {
            let within = |d: u64| &acts[acts.partition_point(|&a| a + d <= at)..acts.partition_point(|&a| a < at + d)];
            if let Some(&a) = within(rrd).first() {
                at = a + rrd;
                continue 'search;
            }
            if faw > 0 {
                // Windows of tFAW cycles holding `at`: each may hold three others at most.
                let near = within(faw);
                for (i, &start) in near.iter().enumerate().take_while(|(_, &a)| a <= at) {
                    if near[i..].iter().take_while(|&&a| a < start + faw).count() >= 4 {
                        at = start + faw;
                        continue 'search;
                    }
                }
                for (i, &end) in near.iter().enumerate().skip_while(|(_, &a)| a <= at) {
                    let from = (end + 1).saturating_sub(faw);
                    if from <= at && near[..=i].iter().filter(|&&a| a >= from).count() >= 4 {
                        at = end + rrd.max(1);
                        continue 'search;
                    }
                }
            }
            break;
        }
        let pos = acts.partition_point(|&a| a <= at);
        acts.insert(pos, at);
        // Keep the ACTIVATEs that can still constrain one: requests arrive in order, so
        // none will want a cycle much before the latest arrival's.
        let horizon = at.saturating_sub(4 * (faw + rrd) + 1024);
        let old = acts.partition_point(|&a| a < horizon);
        if acts.len() > 256 {
            acts.drain(..old.max(acts.len() - 256));
        }
        at
    }

    /// Moves `t` out of any refresh window of `rank` (every `t_refi` cycles all its banks
    /// refresh for `t_rfc`); returns the time and its refresh epoch.
    fn after_refresh(&self, rank: u32, t: u64) -> (u64, u64) {
        let (refi, rfc) = (self.cfg.t_refi as u64, self.cfg.t_rfc as u64);
        if refi == 0 {
            return (t, 0);
        }
        // Ranks refresh in turn, one every tREFI ÷ ranks: rank r first at (r + 1) of those
        // intervals, then every tREFI. Shifted so that its refreshes fall on multiples of
        // tREFI, the refresh of epoch e occupies [e·tREFI, e·tREFI + tRFC) (none at 0).
        let shift = refi - (rank as u64 + 1) * (refi / self.cfg.ranks as u64);
        let s = t + shift;
        let (epoch, into) = (s / refi, s % refi);
        if epoch > 0 && into < rfc {
            (t - into + rfc, epoch)
        } else {
            (t, epoch)
        }
    }

    /// Where byte `addr` lives (row : rank : bank : column : channel, the module
    /// comment's mapping).
    fn locate(&self, addr: u64) -> Place {
        let c = &self.cfg;
        let (channels, ranks, banks, burst) = (c.channels as u64, c.ranks as u64, c.banks as u64, self.burst_bytes());
        let b = addr / burst;
        let channel = b % channels;
        let local = (b / channels) * burst;
        let bank_row = local / c.row_bytes as u64;
        let bank_in = bank_row % banks;
        let rank = bank_row / banks % ranks;
        let row = bank_row / (banks * ranks);
        Place {
            channel: channel as usize,
            rank: rank as u32,
            bank: ((channel * ranks + rank) * banks + bank_in) as usize,
            row,
        }
    }

    /// What a scheduler sees of the bank holding byte `addr` at chip cycle `t`.
    pub fn bank_view(&self, addr: u64, t: u64) -> BankView {
        let p = self.locate(addr);
        let bank = &self.banks[p.bank];
        let (_, epoch) = self.after_refresh(p.rank, self.to_dram(t).max(bank.ready));
        let open = bank.open_row == Some(p.row) && bank.epoch == epoch;
        BankView { bank: p.bank, open, free: self.to_chip(bank.ready), hits: bank.hits }
    }

    /// Serves a request of `bytes` at byte `addr` that reaches the DRAM at chip cycle
    /// `arrive`: returns the chip cycle its first command issued and the chip cycle its
    /// data has all crossed the bus (reads) or been written and recovered (writes).
    pub fn access(&mut self, arrive: u64, addr: u64, bytes: u32, write: bool) -> (u64, u64) {
        let c = self.cfg;
        let burst = self.burst_bytes();
        let first = addr / burst;
        let last = (addr + bytes.max(1) as u64 - 1) / burst;
        let mut start = u64::MAX;
        let mut done = 0;
        let t0 = self.to_dram(arrive);
        for b in first..=last {
            let Place { channel, rank, bank: k, row } = self.locate(b * burst);
            let (mut t, epoch) = self.after_refresh(rank, t0.max(self.banks[k].ready));
            let mut bank = self.banks[k];
            if bank.epoch != epoch {
                // A refresh closed every row since this bank was last used.
                bank.open_row = None;
                bank.epoch = epoch;
            }
            let stats = &mut self.stats[k];
            stats.accesses += 1;
            // The ACTIVATE the access needs (wanted at that cycle), if any.
            let column_at = match bank.open_row {
                Some(r) if r == row => {
                    stats.row_hits += 1;
                    bank.hits += 1;
                    None
                }
                Some(_) => {
                    stats.row_conflicts += 1;
                    // PRECHARGE no earlier than tRAS after the ACTIVATE and tWR after the
                    // last write's data, then ACTIVATE.
                    let pre = t.max(bank.activated + c.t_ras as u64).max(bank.precharge_ok);
                    t = pre;
                    Some(pre + c.t_rp as u64)
                }
                None => {
                    stats.row_empty += 1;
                    Some(t)
                }
            };
            let column_at = match column_at {
                Some(wanted) => {
                    let act = self.activate(channel * c.ranks as usize + rank as usize, wanted);
                    bank.activated = act;
                    bank.hits = 0;
                    act + c.t_rcd as u64
                }
                None => t,
            };
            let burst_clocks = self.burst_cycles();
            let column_at = self.turnaround(channel, rank, column_at, write);
            let last = if write { &mut self.last_write[channel] } else { &mut self.last_read[channel] };
            let at = last.map_or(column_at, |l| l.at.max(column_at));
            *last = Some(Column { at, rank });
            start = start.min(t);
            // Data follows the column command by CL (CWL for a write); the bus carries
            // one burst at a time, and idles tRTRS when the next comes from another rank.
            let switch = if self.bus_rank[channel].is_some_and(|r| r != rank) { c.t_rtrs as u64 } else { 0 };
            let latency = if write { c.t_cwl } else { c.t_cl } as u64;
            let data = (column_at + latency).max(self.bus_free[channel] + switch);
            let end = data + burst_clocks;
            self.bus_free[channel] = end;
            self.bus_rank[channel] = Some(rank);
            self.bus_busy += burst_clocks;
            // The next column command to this bank: one burst later. A write's data must
            // recover (tWR) before the row may close, not before the next column command.
            let mut next = column_at + burst_clocks;
            if write {
                bank.precharge_ok = end + c.t_wr as u64;
            }
            bank.open_row = Some(row);
            if c.page_policy == PagePolicy::Closed {
                let pre = next.max(bank.activated + c.t_ras as u64).max(bank.precharge_ok);
                bank.open_row = None;
                next = pre + c.t_rp as u64;
            }
            bank.ready = next;
            self.banks[k] = bank;
            done = done.max(end);
        }
        let ctrl = self.cfg.controller_latency as u64;
        (self.to_chip(start), self.to_chip(done) + ctrl)
    }

    /// The earliest cycle from `column_at` a column command of `rank` may issue after the
    /// channel's last command of the other direction: the bus turnarounds as JEDEC and
    /// DRAMsim3's timing table give them. Same rank: a READ waits CWL + the burst + tWTR
    /// after a WRITE; a WRITE waits CL + the burst − CWL + tRTRS after a READ. Another
    /// rank has its own write-to-read path, so a READ waits only until the write's data
    /// has left the bus (CWL + the burst + tRTRS − CL after it).
    fn turnaround(&self, channel: usize, rank: u32, column_at: u64, write: bool) -> u64 {
        let c = &self.cfg;
        let (cl, cwl, burst, rtrs) = (c.t_cl as u64, c.t_cwl as u64, self.burst_cycles(), c.t_rtrs as u64);
        if write {
            self.last_read[channel].map_or(column_at, |r| column_at.max((r.at + cl + burst + rtrs).saturating_sub(cwl)))
        } else {
            self.last_write[channel].map_or(column_at, |w| {
                let wait =
                    if w.rank == rank { cwl + burst + c.t_wtr as u64 } else { (cwl + burst + rtrs).saturating_sub(cl) };
                column_at.max(w.at + wait)
            })
        }
    }

    /// Row-buffer hit rate over all bursts.
    pub fn row_hit_rate(&self) -> f64 {
        let (hits, all) = self.stats.iter().fold((0, 0), |(h, a), s| (h + s.row_hits, a + s.accesses));
        if all == 0 {
            0.0
        } else {
            hits as f64 / all as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// DDR3-1600K (11-11-11) from the Micron MT41K256M16 datasheet, at the DRAM's own
    /// clock (ratio 1), no controller latency, one rank.
    fn ddr3() -> DramConfig {
        DramConfig { controller_latency: 0, ranks: 1, ..DramConfig::default() }
    }

    #[test]
    fn a_random_read_to_a_closed_bank_takes_trcd_cl_and_the_burst() {
        let mut d = Dram::new(&ddr3(), 800.0);
        let (start, done) = d.access(0, 0, 64, false);
        assert_eq!(start, 0);
        // ACTIVATE at 0, READ at tRCD = 11, data at 11 + CL = 22, four clocks of BL8.
        assert_eq!(done, 11 + 11 + 4);
        // A different row of the same bank: PRECHARGE waits for tRAS (28), then tRP,
        // tRCD, CL and the burst: 28 + 11 + 11 + 11 + 4 = 65 cycles = 81.25 ns, which is
        // the datasheet's tRC (48.75 ns) + tRCD + CL + burst (32.5 ns).
        let row = 8192 * 8;
        let (_, done2) = d.access(0, row, 64, false);
        assert_eq!(done2, 28 + 11 + 11 + 11 + 4);
    }

    #[test]
    fn streaming_reads_reach_the_datasheet_bandwidth_less_refresh() {
        // 64 MiB read in 64-byte bursts back to back: rows hit, the bus is the limit.
        // Peak: 8 bytes x 2 per clock = 16 bytes per DRAM cycle (12.8 GB/s at 800 MHz);
        // refresh takes tRFC / tREFI = 208 / 6240 = 3.3% of the time; each new row costs
        // a precharge and activate, hidden in part behind the other banks.
        let mut d = Dram::new(&ddr3(), 800.0);
        let bytes = 64u64 << 20;
        let mut done = 0;
        for k in 0..bytes / 64 {
            done = done.max(d.access(0, k * 64, 64, false).1);
        }
        let rate = bytes as f64 / done as f64;
        let peak = 16.0;
        let with_refresh = peak * (1.0 - 208.0 / 6240.0);
        assert!(rate <= peak, "{rate} bytes per cycle above the peak");
        assert!(rate >= 0.90 * with_refresh, "{rate} bytes per cycle, datasheet {with_refresh:.2} less row switches");
        assert!(d.row_hit_rate() > 0.95, "{}", d.row_hit_rate());
    }

    #[test]
    fn random_reads_to_one_bank_are_limited_by_trc() {
        // Every read to another row of bank 0, issued at once: each costs tRC at best
        // (tRAS + tRP = 39 cycles = 48.75 ns), as the datasheet's row cycle time says.
        let mut d = Dram::new(&ddr3(), 800.0);
        let n = 1000u64;
        let mut done = 0;
        for k in 0..n {
            done = done.max(d.access(0, k * 8192 * 8, 64, false).1);
        }
        let per = done as f64 / n as f64;
        assert!((39.0..=40.0).contains(&per), "{per} cycles per random access, tRC is 39");
        assert_eq!(d.row_hit_rate(), 0.0);
    }

    #[test]
    fn activates_keep_trrd_apart_and_four_to_a_tfaw_window() {
        // Eight reads to eight banks at once: ACTIVATEs at 0, 5, 10, 15 (tRRD = 5), the
        // fifth no sooner than tFAW = 24 after the first, then 29, 34, 39.
        let mut d = Dram::new(&ddr3(), 800.0);
        let row = 8192u64;
        let starts: Vec<u64> = (0..8).map(|b| d.access(0, b * row, 64, false).0).collect();
        assert_eq!(starts, vec![0; 8], "every access starts at once (its bank is idle)");
        let acts: Vec<u64> = d.banks.iter().map(|b| b.activated).collect();
        assert_eq!(acts, vec![0, 5, 10, 15, 24, 29, 34, 39]);
    }

    #[test]
    fn write_recovery_and_turnaround_follow_jedec() {
        let mut d = Dram::new(&ddr3(), 800.0);
        // A write to a closed bank: ACTIVATE, tRCD, CWL 8, the burst ends at 23.
        let (_, written) = d.access(0, 0, 64, true);
        assert_eq!(written, 11 + 8 + 4);
        // A read of the same row: the write-to-read turnaround (CWL + burst + tWTR after
        // the WRITE at 11), not tWR, holds it: READ at 29, data from 40 to 44.
        let (_, hit) = d.access(0, 64, 64, false);
        assert_eq!(hit, 11 + 8 + 4 + 6 + 11 + 4);
        // Another row of the bank: PRECHARGE waits for tWR after the write's data
        // (23 + 12 = 35; tRAS ends at 28), then tRP, ACTIVATE, tRCD, CL, the burst.
        let row = 8192 * 8;
        let (_, conflict) = d.access(0, row, 64, false);
        assert_eq!(conflict, 35 + 11 + 11 + 11 + 4);
        // A write after those reads waits CL + burst − CWL + 1 after the last READ (57).
        let mut e = Dram::new(&ddr3(), 800.0);
        e.access(0, 0, 64, false);
        let (_, w) = e.access(0, 64, 64, true);
        assert_eq!(w, 11 + (11 + 4 + 1 - 8) + 8 + 4);
    }

    #[test]
    fn the_closed_page_policy_pays_every_access_and_refresh_closes_rows() {
        let cfg = DramConfig { page_policy: PagePolicy::Closed, ..ddr3() };
        let mut d = Dram::new(&cfg, 800.0);
        d.access(0, 0, 64, false);
        let (_, done) = d.access(200, 64, 64, false);
        assert_eq!(done, 200 + 11 + 11 + 4, "same row, but it was closed");
        let mut d = Dram::new(&ddr3(), 800.0);
        d.access(0, 0, 64, false);
        // Inside the refresh at 6240: waits for its end, and the row is closed.
        let (start, done) = d.access(6250, 64, 64, false);
        assert_eq!(start, 6240 + 208);
        assert_eq!(done, 6240 + 208 + 11 + 11 + 4);
    }

    #[test]
    fn two_ranks_keep_their_own_activate_windows_and_refreshes() {
        let two = DramConfig { ranks: 2, ..ddr3() };
        // Rank 1 begins one rank's banks (8 × 8 KiB) up. Eight reads to four banks of
        // each rank at once: each rank keeps tRRD and its own tFAW window, so the eight
        // ACTIVATEs issue at 0, 5, 10, 15 in both ranks where one rank needs 39 cycles.
        let mut d = Dram::new(&two, 800.0);
        let row = 8192u64;
        for b in (0..4).chain(8..12) {
            d.access(0, b * row, 64, false);
        }
        let acts: Vec<u64> = d.banks.iter().map(|b| b.activated).collect();
        assert_eq!(acts, vec![0, 5, 10, 15, 0, 0, 0, 0, 0, 5, 10, 15, 0, 0, 0, 0]);
        assert!(d.stats[8..12].iter().all(|b| b.accesses == 1), "the second four went to rank 1");
        // Ranks refresh in turn, tREFI ÷ 2 = 3120 apart: rank 0 at 3120, rank 1 at 6240.
        let mut d = Dram::new(&two, 800.0);
        assert_eq!(d.access(3125, 0, 64, false).0, 3120 + 208, "rank 0 refreshes at 3120");
        assert_eq!(d.access(3125, 8 * row, 64, false).0, 3125, "rank 1 does not");
        assert_eq!(d.access(6245, 8 * row + 64, 64, false).0, 6240 + 208, "rank 1 refreshes at 6240");
    }

    #[test]
    fn a_rank_switch_idles_the_bus_trtrs() {
        let two = DramConfig { ranks: 2, ..ddr3() };
        let mut d = Dram::new(&two, 800.0);
        // Two reads to the open rows of bank 0 in each rank: the second burst follows the
        // first with tRTRS = 1 idle clock; within one rank they are back to back.
        let rank1 = 8 * 8192u64;
        d.access(0, 0, 64, false);
        d.access(0, rank1, 64, false);
        let (_, a) = d.access(100, 64, 64, false);
        let (_, b) = d.access(100, rank1 + 64, 64, false);
        assert_eq!((a, b), (100 + 11 + 4, 100 + 11 + 4 + 1 + 4));
        let (_, c) = d.access(100, rank1 + 128, 64, false);
        assert_eq!(c, b + 4, "same rank: back to back");
        // A read of another rank after a write waits for the write's data to leave the
        // bus, not for tWTR: WRITE at 200, data 208–212, READ at 200 + 8 + 4 + 1 − 11.
        let mut e = Dram::new(&two, 800.0);
        e.access(0, 0, 64, false);
        e.access(0, rank1, 64, false);
        e.access(200, 64, 64, true);
        let (_, r) = e.access(200, rank1 + 64, 64, false);
        assert_eq!(r, 213 + 4, "data after the write's burst and one idle clock");
    }
}
