//! A unit's memory port: its caches (one shared by all classes, one per class, or none),
//! `ports` lookups per cycle, and the requests it has sent to the memory.
//!
//! Timing follows data. A kernel runs at once when its work is issued (functional first)
//! and its scene reads are *recorded* ([`Recorder`], core's `MemoryProbe`), level by level:
//! a read that depends on data read before it (a list entry's triangle, a triangle's
//! vertices, a popped node's children — core marks them with `MemoryProbe::dependent`)
//! starts a new level. The port then replays the reads through its caches in time
//! ([`Fetch`]): a level's lookups start only once the previous level's data has arrived
//! (each dependent level is its own round trip), at most `ports` lookups per cycle, a miss
//! only with a free MSHR and room in the port's outgoing queue. The unit uses the work's
//! result no earlier than the cycle its last level's data arrived.

use std::collections::VecDeque;

use raypipe_core::{DataClass, MemoryProbe};

use crate::config::CacheConfig;
use crate::memory::cache::{Cache, Lookup};
use crate::memory::traffic::CLASSES;
use crate::observe::stall::Stall;

/// One recorded scene read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    /// Traffic class index.
    pub class: usize,
    /// Byte address in the chip's scene memory.
    pub addr: u64,
    /// Bytes read.
    pub bytes: u32,
}

/// The probe a unit hands to core's kernels: it records every read into its dependent
/// level.
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    /// Reads by level (level `k + 1` depends on level `k`).
    pub levels: Vec<Vec<Access>>,
    /// The level reads go to now.
    pub level: usize,
    /// Where the image the kernel reads lies in the chip's scene memory: its reads'
    /// addresses are offsets in that image (an instanced scene's bottoms and globals).
    pub base: u64,
}

impl Recorder {
    /// Reads from now on go to `level` (a new independent chain starts at its level).
    pub fn at_level(&mut self, level: usize) {
        self.level = level;
    }

    /// Every read of every level, for statistics.
    pub fn reads(&self) -> impl Iterator<Item = &Access> {
        self.levels.iter().flatten()
    }

    /// The recorded reads, without empty levels.
    pub fn into_levels(self) -> Vec<Vec<Access>> {
        self.levels.into_iter().filter(|l| !l.is_empty()).collect()
    }
}

impl MemoryProbe for Recorder {
    #[inline]
    fn read(&mut self, class: DataClass, addr: u32, bytes: u32) {
        while self.levels.len() <= self.level {
            self.levels.push(Vec::new());
        }
        self.levels[self.level].push(Access { class: class as usize, addr: self.base + addr as u64, bytes });
    }

    #[inline]
    fn dependent(&mut self) {
        self.level += 1;
    }
}

/// A request to the memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// Request number within its port.
    pub id: u32,
    /// Byte address (scene image; framebuffer writes use their own space).
    pub addr: u64,
    /// Bytes to transfer.
    pub bytes: u32,
    /// Traffic class index.
    pub class: usize,
    /// A posted write (nobody waits for it).
    pub write: bool,
    /// The cycle the unit made the request.
    pub issued: u64,
    /// The memory passed it over at an edge (its queue full, or the L2's lookups used):
    /// from then on, a unit waiting for it waits on the queue, not on data.
    pub refused: bool,
}

/// Ready cycle of a request the memory has not accepted yet.
pub const UNSCHEDULED: u64 = u64::MAX;

/// One lookup of a fetch: a cache line, or an uncached read.
#[derive(Clone, Copy, Debug)]
struct Lookup1 {
    class: usize,
    cache: Option<usize>,
    /// Line number (cached) or byte address (uncached).
    key: u64,
    bytes: u32,
}

/// The reads of one piece of work (a traversal step, a leaf job, a shading job), replayed
/// through the port level by level.
#[derive(Clone, Debug, Default)]
pub struct Fetch {
    levels: Vec<Vec<Access>>,
    level: usize,
    lookups: Vec<Lookup1>,
    next: usize,
    started: bool,
    /// Data of the current level's hits is there from this cycle.
    at: u64,
    /// Requests (misses and merges) of the current level.
    waits: Vec<u32>,
    /// Why the last cycle's lookups stopped (a port, an MSHR, the queue), if they did.
    pub blocked: Option<Stall>,
}

/// Where a fetch stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FetchState {
    /// Every level looked up; the last one's data is all there from this cycle.
    Done(u64),
    /// Waiting for data of the current level (arriving at the cycle, once known).
    Waiting(Option<u64>),
    /// Lookups left that could not be made this cycle.
    Blocked(Stall),
}

impl Fetch {
    /// The reads of `levels` (none: the work needs no data).
    pub fn new(levels: Vec<Vec<Access>>) -> Fetch {
        Fetch { levels, ..Fetch::default() }
    }

    /// How far the lookups have got (level, lookup, started): a change is progress.
    pub fn position(&self) -> (usize, usize, bool) {
        (self.level, self.next, self.started)
    }

    /// True if the work reads nothing.
    pub fn is_empty(&self) -> bool {
        self.levels.iter().all(Vec::is_empty)
    }
}

/// Latencies seen by the requests of one class: count, sum and a log2 histogram.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LatencyStats {
    /// Requests.
    pub count: u64,
    /// Sum of their latencies (cycles from request to data).
    pub sum: u64,
    /// `histogram[k]`: requests with a latency below `2^k` (and at least `2^(k-1)`).
    pub histogram: [u64; 32],
}

impl LatencyStats {
    /// Counts one request's latency.
    pub fn add(&mut self, cycles: u64) {
        self.count += 1;
        self.sum += cycles;
        let bin = (64 - cycles.leading_zeros()).min(31) as usize;
        self.histogram[bin] += 1;
    }
}

/// One unit's memory interface.
#[derive(Clone, Debug)]
pub struct MemPort {
    /// Name for reports.
    pub name: String,
    /// The caches: name and cache.
    pub caches: Vec<(String, Cache)>,
    /// For each traffic class, the cache its reads go through (`None`: uncached).
    route: [Option<usize>; CLASSES],
    /// Lookups per cycle.
    ports: u32,
    /// Lookups left this cycle.
    budget: u32,
    budget_cycle: u64,
    /// Ready cycle of every request, by id.
    ready: Vec<u64>,
    /// Requests made and not yet accepted by the memory (first in, first out).
    pub staged: VecDeque<Request>,
    /// Most requests waiting in `staged` before the port stops making new ones.
    pub staged_limit: usize,
    /// Reads of this cycle (address, bytes), for the distinct-data count.
    pub read_log: Vec<(u64, u32)>,
    /// Bytes requested from the memory, per class.
    pub requested: [u64; CLASSES],
    /// Bytes delivered to this port, per class.
    pub delivered: [u64; CLASSES],
    /// Latency of this port's read requests, per class.
    pub latency: [LatencyStats; CLASSES],
    /// Tracing: requests the memory took since the log was last taken (request, cycle
    /// its data arrives).
    pub log: Option<Vec<(Request, u64)>>,
}

impl MemPort {
    /// Zeroes the port's and its caches' statistics (lines, fills and requests stay).
    pub fn reset_stats(&mut self) {
        self.requested = [0; CLASSES];
        self.delivered = [0; CLASSES];
        self.latency = Default::default();
        for (_, c) in &mut self.caches {
            c.stats = Default::default();
        }
    }

    /// A port whose reads all go through one cache (`size_bytes = 0`: none).
    pub fn new(name: String, cache: &CacheConfig, staged_limit: u32) -> MemPort {
        MemPort::with_caches(name.clone(), &[(name, cache, &[0, 1, 2, 3, 4])], staged_limit)
    }

    /// A port with several caches, each named and serving the listed traffic classes
    /// (a class in no list, or whose cache has `size_bytes = 0`, is uncached). The port's
    /// width is the first cache configuration's `ports`.
    pub fn with_caches(name: String, caches: &[(String, &CacheConfig, &[usize])], staged_limit: u32) -> MemPort {
        let mut route = [None; CLASSES];
        let mut built = Vec::new();
        let ports = caches.first().map_or(1, |(_, c, _)| c.ports.max(1));
        for (cache_name, cfg, classes) in caches {
            if let Some(c) = Cache::new(cfg) {
                for &k in classes.iter() {
                    if let Some(r) = route.get_mut(k) {
                        *r = Some(built.len());
                    }
                }
                built.push((cache_name.clone(), c));
            }
        }
        MemPort {
            name,
            caches: built,
            route,
            ports,
            budget: ports,
            budget_cycle: u64::MAX,
            ready: Vec::new(),
            staged: VecDeque::new(),
            staged_limit: staged_limit.max(1) as usize,
            read_log: Vec::new(),
            requested: [0; CLASSES],
            delivered: [0; CLASSES],
            latency: Default::default(),
            log: None,
        }
    }

    fn request(&mut self, addr: u64, bytes: u32, class: usize, write: bool, now: u64) -> u32 {
        let id = self.ready.len() as u32;
        self.ready.push(UNSCHEDULED);
        self.staged.push_back(Request { id, addr, bytes, class, write, issued: now, refused: false });
        self.requested[class] += bytes as u64;
        id
    }

    /// A posted write (framebuffer): it costs memory bandwidth, nobody waits for it.
    pub fn write(&mut self, class: usize, addr: u64, bytes: u32, now: u64) {
        self.request(addr, bytes, class, true, now);
    }

    /// Called by the memory at the edge: request `id`'s data arrives at `cycle`.
    pub fn set_ready(&mut self, r: &Request, cycle: u64) {
        if let Some(log) = self.log.as_mut() {
            log.push((*r, cycle));
        }
        if let Some(slot) = self.ready.get_mut(r.id as usize) {
            *slot = cycle;
        }
        self.delivered[r.class] += r.bytes as u64;
        if !r.write {
            self.latency[r.class].add(cycle.saturating_sub(r.issued));
        }
    }

    fn ready_of(&self, id: u32) -> u64 {
        self.ready.get(id as usize).copied().unwrap_or(UNSCHEDULED)
    }

    /// The cycle the current level's data is all there, once every request it waits for
    /// has been accepted by the memory.
    fn level_ready(&self, f: &Fetch) -> Option<u64> {
        let mut at = f.at;
        for &id in &f.waits {
            let r = self.ready_of(id);
            if r == UNSCHEDULED {
                return None;
            }
            at = at.max(r);
        }
        Some(at)
    }

    fn start_level(&mut self, f: &mut Fetch) {
        f.lookups.clear();
        f.next = 0;
        f.at = 0;
        f.waits.clear();
        let Some(level) = f.levels.get(f.level) else { return };
        for a in level {
            self.read_log.push((a.addr, a.bytes));
            match self.route.get(a.class).copied().flatten() {
                Some(c) => {
                    let cache = &self.caches[c].1;
                    let first = cache.line_of(a.addr);
                    let last = cache.line_of(a.addr + a.bytes.max(1) as u64 - 1);
                    for line in first..=last {
                        // One lookup per line, however many reads of the level share it.
                        if !f.lookups.iter().any(|l| l.cache == Some(c) && l.key == line) {
                            f.lookups.push(Lookup1 {
                                class: a.class,
                                cache: Some(c),
                                key: line,
                                bytes: cache.line_bytes(),
                            });
                        }
                    }
                }
                None => f.lookups.push(Lookup1 { class: a.class, cache: None, key: a.addr, bytes: a.bytes }),
            }
        }
    }

    /// MSHRs of cache `c` busy at `now` (fills not yet arrived).
    fn mshrs_busy(&mut self, c: usize, now: u64) -> usize {
        let ready = &self.ready;
        let cache = &mut self.caches[c].1;
        cache.outstanding.retain(|&id| ready.get(id as usize).is_none_or(|&r| r > now));
        cache.outstanding.len()
    }

    /// Advances `f` at cycle `now`: lookups of the current level while the port has
    /// lookups left this cycle, then the next level once this one's data is there.
    pub fn advance(&mut self, f: &mut Fetch, now: u64) -> FetchState {
        if self.budget_cycle != now {
            self.budget_cycle = now;
            self.budget = self.ports;
        }
        f.blocked = None;
        if !f.started {
            f.started = true;
            self.start_level(f);
        }
        loop {
            if f.next >= f.lookups.len() {
                let Some(at) = self.level_ready(f) else { return FetchState::Waiting(None) };
                if f.level + 1 >= f.levels.len() {
                    return FetchState::Done(at);
                }
                if at > now {
                    return FetchState::Waiting(Some(at));
                }
                f.level += 1;
                self.start_level(f);
                continue;
            }
            if self.budget == 0 {
                f.blocked = Some(Stall::CachePort);
                return FetchState::Blocked(Stall::CachePort);
            }
            let l = f.lookups[f.next];
            match l.cache {
                Some(c) => {
                    let found = self.caches[c].1.lookup(l.key);
                    match found {
                        Lookup::Present { fill } => {
                            let r = self.ready_of(fill);
                            let cache = &mut self.caches[c].1;
                            if r <= now {
                                cache.stats.hits[l.class] += 1;
                                f.at = f.at.max(now + cache.hit_latency as u64);
                            } else {
                                cache.stats.merged[l.class] += 1;
                                // The tag lookup takes the hit latency whatever it finds.
                                f.at = f.at.max(now + cache.hit_latency as u64);
                                f.waits.push(fill);
                            }
                        }
                        Lookup::Absent => {
                            if self.mshrs_busy(c, now) >= self.caches[c].1.mshrs as usize {
                                f.blocked = Some(Stall::Mshr);
                                return FetchState::Blocked(Stall::Mshr);
                            }
                            if self.staged.len() >= self.staged_limit {
                                f.blocked = Some(Stall::MemoryQueue);
                                return FetchState::Blocked(Stall::MemoryQueue);
                            }
                            let line_bytes = self.caches[c].1.line_bytes() as u64;
                            let id = self.request(l.key * line_bytes, l.bytes, l.class, false, now);
                            let cache = &mut self.caches[c].1;
                            cache.stats.misses[l.class] += 1;
                            // A miss is known after the tag lookup: its data is never
                            // there sooner than a hit's, however fast the memory.
                            f.at = f.at.max(now + cache.hit_latency as u64);
                            cache.install(l.key, id);
                            cache.outstanding.push(id);
                            f.waits.push(id);
                        }
                    }
                }
                None => {
                    if self.staged.len() >= self.staged_limit {
                        f.blocked = Some(Stall::MemoryQueue);
                        return FetchState::Blocked(Stall::MemoryQueue);
                    }
                    let id = self.request(l.key, l.bytes, l.class, false, now);
                    f.waits.push(id);
                }
            }
            self.budget -= 1;
            f.next += 1;
        }
    }

    /// The earliest cycle after `now` at which a blocked or waiting fetch of this port
    /// can move on by time alone: a fill arriving (data, or a freed MSHR).
    pub fn next_arrival(&self, now: u64) -> Option<u64> {
        self.caches
            .iter()
            .flat_map(|(_, c)| c.outstanding.iter())
            .map(|&id| self.ready_of(id))
            .filter(|&r| r != UNSCHEDULED && r > now)
            .min()
    }

    /// The cycle from which `f`'s current level's data is there, if known and later than
    /// `now` (for the clock to skip to).
    pub fn wake_of(&self, f: &Fetch, now: u64) -> Option<u64> {
        if f.blocked == Some(Stall::CachePort) {
            return Some(now + 1);
        }
        if f.blocked == Some(Stall::Mshr) {
            return self.next_arrival(now);
        }
        self.level_ready(f).filter(|&t| t > now)
    }

    /// One cycle of `f` for a unit: returns whether its lookups moved on, and the cycle
    /// its data is all there once that is no later than `now`.
    pub fn step_fetch(&mut self, f: &mut Fetch, now: u64) -> (bool, Option<u64>) {
        let before = f.position();
        let state = self.advance(f, now);
        let moved = f.position() != before;
        match state {
            FetchState::Done(at) if at <= now => (moved, Some(at)),
            _ => (moved, None),
        }
    }

    /// Why a unit waiting on `f` stalls: what blocked its lookups, the memory queue, or
    /// its data (`data`: the class of data the unit waits for).
    pub fn stall_of(&self, f: &Fetch, data: Stall) -> Stall {
        match f.blocked {
            Some(b) => b,
            None if self.waits_on_queue(f) => Stall::MemoryQueue,
            None => data,
        }
    }

    /// Requests still staged (their fetches wait on the memory queue).
    pub fn has_staged(&self) -> bool {
        !self.staged.is_empty()
    }

    /// True if `f` waits for a request the memory passed over at an edge (one made this
    /// cycle is taken at the coming edge, if there is room: a wait for data, not the queue).
    pub fn waits_on_queue(&self, f: &Fetch) -> bool {
        self.staged.iter().any(|r| r.refused && f.waits.contains(&r.id))
    }
}
