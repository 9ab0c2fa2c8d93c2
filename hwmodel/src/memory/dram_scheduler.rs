//! The DRAM controller's request queue and its FR-FCFS scheduler (Rixner, Dally,
//! Kapasi, Mattson & Owens 2000, *Memory Access Scheduling*, §4: "first-ready,
//! first-come first-serve"), the policy DRAMsim3 and most controllers use.
//!
//! Accepted requests wait in the queue (`memory.queue_depth` of them). A request is
//! *ready* once it has arrived and its bank can take a command. At each issue cycle the
//! scheduler issues, in turn, the oldest ready request whose row is open (a row hit),
//! else the oldest ready request, until none is ready — so row hits overtake an older
//! request that would close their row, and banks work in parallel. Each issued request
//! is timed by [`Dram::access`], which owns the banks, the bus, tRRD/tFAW and refresh.
//! A row hit overtakes an older conflict of its bank only while the bank has served
//! fewer than `row_hit_cap` hits since the row opened; then the conflict goes (DRAMsim3's
//! command queue caps them at 4 the same way, against starvation; 0: no cap, Rixner's
//! policy as published).

use crate::memory::dram::Dram;

/// A request waiting in the controller's queue.
#[derive(Clone, Copy, Debug)]
struct Queued {
    token: u32,
    arrive: u64,
    addr: u64,
    bytes: u32,
    write: bool,
}

/// The queue, oldest first.
#[derive(Clone, Debug, Default)]
pub struct DramScheduler {
    queue: Vec<Queued>,
    /// Row hits a bank may serve over an older conflict (0: no cap).
    row_hit_cap: u32,
}

impl DramScheduler {
    /// An empty queue whose row hits overtake an older conflict of their bank at most
    /// `row_hit_cap` times per opened row (0: always).
    pub fn new(row_hit_cap: u32) -> DramScheduler {
        DramScheduler { queue: Vec::new(), row_hit_cap }
    }

    /// Requests waiting.
    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    /// Queues a request (`token` names it in [`DramScheduler::issue`]'s answer) that
    /// reaches the controller at chip cycle `arrive`.
    pub fn submit(&mut self, token: u32, arrive: u64, addr: u64, bytes: u32, write: bool) {
        self.queue.push(Queued { token, arrive, addr, bytes, write });
    }

    /// Issues at chip cycle `t` every request that is ready, row hits first, each the
    /// oldest of its kind; returns each one's token and the chip cycle its data is there
    /// (reads) or written (writes).
    pub fn issue(&mut self, dram: &mut Dram, t: u64) -> Vec<(u32, u64)> {
        let mut done = Vec::new();
        loop {
            let mut pick: Option<(usize, bool)> = None;
            // Banks with an older ready conflict waiting: their hits are capped.
            let mut conflicted: Vec<usize> = Vec::new();
            for (i, q) in self.queue.iter().enumerate() {
                if q.arrive > t {
                    continue;
                }
                let v = dram.bank_view(q.addr, t);
                if v.free > t {
                    continue;
                }
                // Only a cap needs them: no list is kept on the default path.
                if !v.open && self.row_hit_cap > 0 {
                    conflicted.push(v.bank);
                }
                let capped = self.row_hit_cap > 0 && v.hits >= self.row_hit_cap && conflicted.contains(&v.bank);
                let open = v.open && !capped;
                // The queue is oldest first: the first hit, else the first ready one.
                match pick {
                    None => pick = Some((i, open)),
                    Some((_, false)) if open => pick = Some((i, true)),
                    _ => {}
                }
                if open {
                    break;
                }
            }
            let Some((i, _)) = pick else { break };
            let q = self.queue.remove(i);
            let (_, end) = dram.access(t, q.addr, q.bytes, q.write);
            done.push((q.token, end));
        }
        done
    }

    /// The first chip cycle after `now` at which a queued request may become ready (its
    /// arrival or its bank's next free cycle, whichever is later), if any waits.
    pub fn next_ready(&self, dram: &Dram, now: u64) -> Option<u64> {
        self.queue.iter().map(|q| q.arrive.max(dram.bank_view(q.addr, q.arrive).free)).min().map(|t| t.max(now + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DramConfig;

    fn dram() -> Dram {
        // DDR3-1600, one rank, behind a chip at the DRAM's clock: chip cycles are DRAM
        // cycles.
        Dram::new(&DramConfig { controller_latency: 0, t_refi: 0, ranks: 1, ..DramConfig::default() }, 800.0)
    }

    /// Runs the scheduler to empty, issuing every cycle from `t`; returns each token's
    /// end, by token.
    fn drain(s: &mut DramScheduler, d: &mut Dram, mut t: u64, n: usize) -> Vec<u64> {
        let mut ends = vec![0; n];
        while s.queued() > 0 {
            for (token, end) in s.issue(d, t) {
                ends[token as usize] = end;
            }
            t += 1;
        }
        ends
    }

    #[test]
    fn a_row_hit_overtakes_an_older_conflict_in_the_same_bank() {
        let row = 8192 * 8; // the next row of bank 0
        let (mut d, mut s) = (dram(), DramScheduler::default());
        // Open row 0 of bank 0.
        s.submit(0, 0, 0, 64, false);
        let first = drain(&mut s, &mut d, 0, 1)[0];
        // Queued together: a conflict (row 1), then a hit (row 0).
        s.submit(0, first, row, 64, false);
        s.submit(1, first, 64, 64, false);
        let ends = drain(&mut s, &mut d, first, 2);
        assert!(ends[1] < ends[0], "the hit finished first: {ends:?}");
        // First come, first served would have served the conflict first.
        let mut fcfs = dram();
        fcfs.access(0, 0, 64, false);
        let conflict = fcfs.access(first, row, 64, false).1;
        let hit_after = fcfs.access(first, 64, 64, false).1;
        assert!(ends[1] < hit_after && conflict < hit_after);
    }

    #[test]
    fn an_idle_controller_times_a_request_as_the_dram_does() {
        let (mut d, mut s) = (dram(), DramScheduler::default());
        s.submit(0, 5, 4096, 64, false);
        assert_eq!(s.next_ready(&d, 0), Some(5));
        assert!(s.issue(&mut d, 4).is_empty(), "not arrived yet");
        let got = s.issue(&mut d, 5);
        assert_eq!(got, vec![(0, dram().access(5, 4096, 64, false).1)]);
        assert_eq!(s.next_ready(&d, 5), None);
    }

    #[test]
    fn alternating_rows_of_one_bank_are_grouped_by_row() {
        // 16 requests alternating between two rows of bank 0, all queued at once: FR-FCFS
        // opens each row once or twice, FCFS once per request.
        let row = 8192 * 8;
        let (mut d, mut s) = (dram(), DramScheduler::default());
        for k in 0..16u64 {
            s.submit(k as u32, 0, (k % 2) * row + (k / 2) * 64, 64, false);
        }
        let ends = drain(&mut s, &mut d, 0, 16);
        let fr = ends.iter().max().copied().unwrap();
        let conflicts: u64 = d.stats.iter().map(|b| b.row_conflicts).sum();
        assert!(conflicts <= 2, "{conflicts} conflicts");
        let mut f = dram();
        let fcfs = (0..16u64).map(|k| f.access(0, (k % 2) * row + (k / 2) * 64, 64, false).1).max().unwrap();
        assert!(fr * 3 < fcfs, "FR-FCFS {fr} against FCFS {fcfs}");
    }

    #[test]
    fn a_row_hit_cap_lets_a_waiting_conflict_go() {
        // The same 16 requests with a cap of 4: row 0 opens and serves its first request
        // and 4 hits, row 1 then does the same, and so on: every fifth access opens a row.
        let row = 8192 * 8;
        let (mut d, mut s) = (dram(), DramScheduler::new(4));
        for k in 0..16u64 {
            s.submit(k as u32, 0, (k % 2) * row + (k / 2) * 64, 64, false);
        }
        drain(&mut s, &mut d, 0, 16);
        let (hits, conflicts) = d.stats.iter().fold((0, 0), |(h, c), b| (h + b.row_hits, c + b.row_conflicts));
        assert_eq!((hits, conflicts), (12, 3), "rows served 5, 5, 3 and 3 requests");
    }
}
