//! The memory behind every unit's caches: an optional shared L2, then one of three
//! models (`memory.model`):
//!
//! * **perfect** — every request is taken at the next edge, whatever the queue depth,
//!   and its data arrives the cycle after, without a bandwidth limit and without the L2
//!   (the compute bound);
//! * **fixed** — one channel moving `bytes_per_cycle`, a request a whole number of
//!   `min_burst_bytes`, its data `latency` cycles after its transfer;
//! * **dram** — [`crate::memory::dram`]'s channels, banks and rows;
//! * **dramsim3** — DRAMsim3 itself (`memory::dramsim3`, with the `dramsim3`
//!   feature): its data arrives when DRAMsim3 calls back, not at a time known when the
//!   request is taken, so a request may wait *accepted but unscheduled* for several edges.
//!
//! Requests are taken at the clock edge from the ports in a fixed order (shading,
//! traversal units, intersection units), oldest first, while the request queue has room
//! (`queue_depth` requests accepted but not yet started); the rest stay in their port and
//! push back on its unit. So the schedule cannot depend on the order units ticked in.

pub mod cache;
pub mod dram;
pub mod dram_scheduler;
#[cfg(feature = "dramsim3")]
pub mod dramsim3;
pub mod dramsim3_ini;
pub mod port;
pub mod replay;
pub mod traffic;

use std::collections::VecDeque;

use serde::Serialize;

use crate::config::{DramScheduling, HwConfig, MemoryModel};
use crate::memory::cache::{Cache, Lookup};
use crate::memory::dram::Dram;
use crate::memory::dram_scheduler::DramScheduler;
use crate::memory::port::{MemPort, Request, UNSCHEDULED};
use crate::memory::traffic::CLASSES;

/// Marks every request still staged in `ports` as passed over at this edge.
fn refuse(ports: &mut [&mut MemPort]) {
    for port in ports.iter_mut() {
        port.staged.iter_mut().for_each(|r| r.refused = true);
    }
}

/// What the memory carried.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ChannelStats {
    /// Bytes moved by the memory (after the L2), per class.
    pub bytes: [u64; CLASSES],
    /// Requests served by the memory, per class.
    pub requests: [u64; CLASSES],
    /// Bytes the channel's bus could have moved in the cycles it was busy (fixed), or the
    /// DRAM data-bus cycles in chip cycles (dram).
    pub busy_cycles: u64,
    /// L2 lookups that hit, merged, missed (all classes).
    pub l2: [u64; 3],
}

/// The shared L2: its tags and the ready cycle of each fill.
#[derive(Clone, Debug)]
struct L2 {
    cache: Cache,
    ports: u32,
    fills: Vec<Ready>,
}

/// When a memory request's data is there: at a known cycle, or when the memory request
/// `token` (DRAMsim3's) is called back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ready {
    At(u64),
    Token(u32),
}

impl Ready {
    /// The cycle the data is there from at the earliest, and the DRAMsim3 requests (with
    /// cycles after each) it still waits for.
    fn waits(self) -> (u64, Vec<(u32, u64)>) {
        match self {
            Ready::At(t) => (t, Vec::new()),
            Ready::Token(t) => (0, vec![(t, 0)]),
        }
    }
}

/// A port's request whose data waits on DRAMsim3: no earlier than `at`, and `add` cycles
/// after each memory request it waits for (the L2's hit latency behind a fill).
#[derive(Clone, Debug)]
struct Pending {
    port: usize,
    request: Request,
    at: u64,
    on: Vec<(u32, u64)>,
}

/// The memory's registers.
#[derive(Debug)]
pub struct Memory {
    model: MemoryModel,
    latency: u64,
    bytes_per_cycle: u64,
    min_burst: u64,
    queue_depth: usize,
    /// Start cycles of accepted requests not yet started (the request queue).
    queue: VecDeque<u64>,
    /// Fixed model: the channel is busy up to this byte slot (`cycle × bytes_per_cycle`).
    busy_slot: u64,
    dram: Option<Dram>,
    /// The DRAM controller's queue, when it schedules FR-FCFS.
    dram_queue: Option<DramScheduler>,
    l2: Option<L2>,
    last_done: u64,
    /// DRAMsim3, when that is the model.
    #[cfg(feature = "dramsim3")]
    ds3: Option<Box<dramsim3::Dramsim3>>,
    /// The cycle each DRAMsim3 or FR-FCFS request's data is there from (`UNSCHEDULED`
    /// until known).
    tokens: Vec<u64>,
    /// Port requests waiting on DRAMsim3 or the FR-FCFS queue.
    pending: Vec<Pending>,
    /// When recording: every request the memory model served (after the L2), in order.
    pub stream: Option<Vec<replay::StreamRequest>>,
    /// Statistics.
    pub stats: ChannelStats,
}

impl Memory {
    /// An idle memory for `cfg` (an error if DRAMsim3 cannot be set up).
    pub fn new(cfg: &HwConfig) -> Result<Memory, String> {
        let m = &cfg.memory;
        #[cfg(feature = "dramsim3")]
        let ds3 = match m.model {
            MemoryModel::Dramsim3 => Some(Box::new(dramsim3::Dramsim3::new(&m.dramsim3, cfg.clock_mhz)?)),
            _ => None,
        };
        #[cfg(not(feature = "dramsim3"))]
        if m.model == MemoryModel::Dramsim3 {
            return Err(crate::config::NO_DRAMSIM3.into());
        }
        Ok(Memory {
            model: m.model,
            latency: m.latency as u64,
            bytes_per_cycle: m.bytes_per_cycle.max(1) as u64,
            min_burst: m.min_burst_bytes.max(1) as u64,
            queue_depth: m.queue_depth.max(1) as usize,
            queue: VecDeque::new(),
            busy_slot: 0,
            dram: (m.model == MemoryModel::Dram).then(|| Dram::new(&m.dram, cfg.clock_mhz)),
            dram_queue: (m.model == MemoryModel::Dram && m.dram.scheduler == DramScheduling::FrFcfs)
                .then(|| DramScheduler::new(m.dram.row_hit_cap)),
            l2: Cache::new(&cfg.cache.l2).map(|cache| L2 {
                cache,
                ports: cfg.cache.l2.ports.max(1),
                fills: Vec::new(),
            }),
            last_done: 0,
            #[cfg(feature = "dramsim3")]
            ds3,
            tokens: Vec::new(),
            pending: Vec::new(),
            stream: None,
            stats: ChannelStats::default(),
        })
    }

    /// Zeroes the statistics (queue, lines, rows and timing state stay).
    pub fn reset_stats(&mut self) {
        self.stats = ChannelStats::default();
        if let Some(d) = self.dram.as_mut() {
            d.reset_stats();
        }
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_mut() {
            d.reset_stats();
        }
    }

    /// Requests accepted and not yet started (as last updated at an edge).
    pub fn queue_len(&self) -> usize {
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_ref() {
            return d.queued();
        }
        if let Some(q) = self.dram_queue.as_ref() {
            return q.queued();
        }
        self.queue.len()
    }

    /// DRAMsim3, if that is the model.
    #[cfg(feature = "dramsim3")]
    pub fn dramsim3(&self) -> Option<&dramsim3::Dramsim3> {
        self.ds3.as_deref()
    }

    /// True once no request waits on the memory's callbacks or in the FR-FCFS queue.
    pub fn is_idle(&self) -> bool {
        if let Some(q) = self.dram_queue.as_ref() {
            return q.queued() == 0 && self.pending.is_empty();
        }
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_ref() {
            return !d.busy() && self.pending.is_empty();
        }
        true
    }

    /// At the end of a frame: DRAMsim3 ticks, idle, to the end of its counters' epoch.
    pub fn finish_frame(&mut self) {
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_mut() {
            d.close_epoch();
        }
    }

    /// The chip cycle from which the memory can take the next frame's requests (after
    /// DRAMsim3's closing epoch, whose idle cycles belong to no frame).
    pub fn resume_at(&self) -> u64 {
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_ref() {
            return self.last_done.max(d.chip_now());
        }
        self.last_done
    }

    /// At the edge ending `now`: DRAMsim3 ticks to the edge, the FR-FCFS queue issues
    /// what is ready in the next cycle, and the requests whose data is now known get
    /// their ready cycle.
    #[cfg_attr(not(feature = "dramsim3"), allow(unused_variables))]
    fn deliver(&mut self, now: u64, ports: &mut [&mut MemPort]) -> bool {
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_mut() {
            d.advance(now);
            for (token, cycle) in d.take_done() {
                if let Some(t) = self.tokens.get_mut(token as usize) {
                    *t = cycle;
                }
            }
        }
        if let (Some(q), Some(d)) = (self.dram_queue.as_mut(), self.dram.as_mut()) {
            for (token, end) in q.issue(d, now + 1) {
                if let Some(t) = self.tokens.get_mut(token as usize) {
                    *t = end;
                }
            }
        }
        let tokens = &self.tokens;
        let known = |p: &Pending| p.on.iter().all(|&(t, _)| tokens.get(t as usize).is_some_and(|&c| c != UNSCHEDULED));
        if !self.pending.iter().any(known) {
            return false;
        }
        let (ready, waiting): (Vec<Pending>, Vec<Pending>) =
            std::mem::take(&mut self.pending).into_iter().partition(known);
        self.pending = waiting;
        for p in ready {
            let at = p.on.iter().map(|&(t, add)| self.tokens[t as usize] + add).fold(p.at, u64::max);
            self.last_done = self.last_done.max(at);
            if let Some(port) = ports.get_mut(p.port) {
                port.set_ready(&p.request, at);
            }
        }
        true
    }

    /// True if the memory's request queue is full.
    fn queue_full(&self) -> bool {
        self.model != MemoryModel::Perfect && self.queue_len() >= self.queue_depth
    }

    /// The DRAM, if that is the model.
    pub fn dram(&self) -> Option<&Dram> {
        self.dram.as_ref()
    }

    /// At the edge ending cycle `now`: takes the ports' staged requests, in port order,
    /// while the queue has room. Returns whether it took any.
    pub fn accept(&mut self, now: u64, ports: &mut [&mut MemPort]) -> bool {
        while self.queue.front().is_some_and(|&s| s <= now) {
            self.queue.pop_front();
        }
        let mut took = self.deliver(now, ports);
        let mut l2_lookups = self.l2.as_ref().map_or(0, |l| l.ports);
        for p in 0..ports.len() {
            let port = &mut *ports[p];
            while let Some(r) = port.staged.front().copied() {
                if self.queue_full() {
                    refuse(&mut ports[p..]);
                    return took;
                }
                // Perfect memory is the compute bound: nothing behind the units' own caches
                // costs time, so it bypasses the L2 (whose ports and latency would bound
                // it, and whose fills would reorder it, making it no bound at all).
                let ready = if self.l2.is_some() && !r.write && self.model != MemoryModel::Perfect {
                    if l2_lookups == 0 {
                        refuse(&mut ports[p..]);
                        return took;
                    }
                    l2_lookups -= 1;
                    self.through_l2(now, &r)
                } else {
                    self.serve(now, r.addr, r.bytes, r.class, r.write).waits()
                };
                port.staged.pop_front();
                match ready {
                    (at, on) if on.is_empty() => port.set_ready(&r, at),
                    (at, on) => self.pending.push(Pending { port: p, request: r, at, on }),
                }
                took = true;
            }
        }
        // What was just taken may issue in the next cycle already.
        if self.dram_queue.as_ref().is_some_and(|q| q.queued() > 0) {
            self.deliver(now, ports);
        }
        took
    }

    /// A read through the L2: a hit after its latency, a line being filled when it
    /// arrives, a miss after the memory has served the L2 line. Returns the cycle its
    /// data is there from, or that cycle at the earliest and the DRAMsim3 requests it
    /// still waits for (with the hit latency after each).
    fn through_l2(&mut self, now: u64, r: &Request) -> (u64, Vec<(u32, u64)>) {
        let Some(mut l2) = self.l2.take() else { return self.serve(now, r.addr, r.bytes, r.class, false).waits() };
        let mut on = Vec::new();
        let line_bytes = l2.cache.line_bytes() as u64;
        let first = l2.cache.line_of(r.addr);
        let last = l2.cache.line_of(r.addr + r.bytes.max(1) as u64 - 1);
        let hit_at = now + 1 + l2.cache.hit_latency as u64;
        let mut ready = hit_at;
        for line in first..=last {
            match l2.cache.lookup(line) {
                Lookup::Present { fill } => {
                    let f = match l2.fills.get(fill as usize).copied().unwrap_or(Ready::At(0)) {
                        Ready::At(f) => f,
                        Ready::Token(t) => match self.tokens.get(t as usize).copied() {
                            Some(c) if c != UNSCHEDULED => c,
                            _ => {
                                // Its fill is still with DRAMsim3: a merge.
                                self.stats.l2[1] += 1;
                                on.push((t, l2.cache.hit_latency as u64));
                                continue;
                            }
                        },
                    };
                    if f <= now {
                        self.stats.l2[0] += 1;
                        ready = ready.max(hit_at);
                    } else {
                        self.stats.l2[1] += 1;
                        ready = ready.max(f + l2.cache.hit_latency as u64);
                    }
                }
                Lookup::Absent => {
                    self.stats.l2[2] += 1;
                    let f = self.serve(now, line * line_bytes, line_bytes as u32, r.class, false);
                    let id = l2.fills.len() as u32;
                    l2.fills.push(f);
                    l2.cache.install(line, id);
                    match f {
                        Ready::At(f) => ready = ready.max(f + l2.cache.hit_latency as u64),
                        Ready::Token(t) => on.push((t, l2.cache.hit_latency as u64)),
                    }
                }
            }
        }
        self.l2 = Some(l2);
        (ready, on)
    }

    /// The memory model serves `bytes` at `addr`: the cycle its data arrives, or the
    /// DRAMsim3 request that will tell.
    fn serve(&mut self, now: u64, addr: u64, bytes: u32, class: usize, write: bool) -> Ready {
        self.stats.requests[class] += 1;
        if let Some(log) = self.stream.as_mut() {
            log.push(replay::StreamRequest { cycle: now, addr, bytes, write });
        }
        let (start, done) = match self.model {
            MemoryModel::Perfect => {
                self.stats.bytes[class] += bytes as u64;
                (now + 1, now + 1)
            }
            MemoryModel::Fixed => {
                let moved = (bytes as u64).max(1).div_ceil(self.min_burst) * self.min_burst;
                self.stats.bytes[class] += moved;
                let bpc = self.bytes_per_cycle;
                let start_slot = self.busy_slot.max((now + 1) * bpc);
                let end_slot = start_slot + moved;
                self.busy_slot = end_slot;
                self.stats.busy_cycles += moved;
                (start_slot / bpc, end_slot.div_ceil(bpc) + self.latency)
            }
            MemoryModel::Dram => {
                let Some(d) = self.dram.as_mut() else { return Ready::At(now + 1) };
                self.stats.bytes[class] += d.bytes_moved(addr, bytes);
                if let Some(q) = self.dram_queue.as_mut() {
                    let token = self.tokens.len() as u32;
                    self.tokens.push(UNSCHEDULED);
                    q.submit(token, now + 1, addr, bytes, write);
                    return Ready::Token(token);
                }
                d.access(now + 1, addr, bytes, write)
            }
            MemoryModel::Dramsim3 => return self.serve_dramsim3(addr, bytes, class, write),
        };
        if start > now + 1 {
            self.queue.push_back(start);
        }
        self.last_done = self.last_done.max(done);
        Ready::At(done)
    }

    /// DRAMsim3 takes the request as transactions; its data's cycle comes with the last
    /// callback. (Without the feature, [`Memory::new`] builds no such memory.)
    #[cfg_attr(not(feature = "dramsim3"), allow(unused_variables))]
    fn serve_dramsim3(&mut self, addr: u64, bytes: u32, class: usize, write: bool) -> Ready {
        let token = self.tokens.len() as u32;
        self.tokens.push(UNSCHEDULED);
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.ds3.as_mut() {
            self.stats.bytes[class] += d.submit(token, addr, bytes, write);
        }
        Ready::Token(token)
    }

    /// The earliest cycle after `now` at which the queue frees a slot, if requests wait
    /// for one.
    pub fn next_wake(&self, now: u64, waiting: bool) -> Option<u64> {
        if let (Some(q), Some(d)) = (self.dram_queue.as_ref(), self.dram.as_ref()) {
            // Pending requests learn their cycle at the next edge; a queued one issues
            // in the cycle after the edge before it is ready.
            if !self.pending.is_empty() {
                return Some(now + 1);
            }
            if let Some(t) = q.next_ready(d, now) {
                return Some(t.saturating_sub(1).max(now + 1));
            }
        } else if !self.is_idle() {
            // DRAMsim3 does not say in advance when it will call back: tick every cycle.
            return Some(now + 1);
        }
        if !waiting {
            return None;
        }
        match self.queue.iter().copied().filter(|&s| s > now).min() {
            Some(t) => Some(t),
            // Room now (or an L2 port next cycle): the next edge takes them.
            None => Some(now + 1),
        }
    }

    /// The cycle the last accepted request's data arrives.
    pub fn drained_at(&self) -> u64 {
        self.last_done
    }

    /// Fraction of `cycles` the channel (fixed) or the DRAM data buses (dram) carried
    /// data.
    pub fn utilization(&self, cycles: u64, chip_mhz: f64) -> f64 {
        let cycles = cycles.max(1) as f64;
        match (self.model, &self.dram) {
            (MemoryModel::Fixed, _) => self.stats.busy_cycles as f64 / self.bytes_per_cycle as f64 / cycles,
            (MemoryModel::Dram, Some(d)) => {
                d.bus_busy as f64 / (cycles * d.clock_mhz() / chip_mhz * d.channels() as f64)
            }
            #[cfg(feature = "dramsim3")]
            (MemoryModel::Dramsim3, _) => self.ds3.as_ref().map_or(0.0, |d| {
                // Bytes moved over what the channels' peak could have moved in the time.
                let ns = cycles * 1e3 / chip_mhz;
                d.stats.bytes as f64 / (d.geometry.peak_bytes_per_ns() * ns)
            }),
            _ => 0.0,
        }
    }
}
