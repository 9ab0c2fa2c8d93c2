//! A unit's memory port: its caches (one shared by all classes, or one per class, or
//! none) and the channel requests it has issued. The
//! kernels' scene reads arrive here through [`PortProbe`] (core's `MemoryProbe`), so the
//! model sees every byte the kernels read; misses become line requests that the memory
//! channel schedules at the clock edge, in a fixed order.

use raypipe_core::{DataClass, MemoryProbe};

use crate::cache::{Cache, Lookup};
use crate::config::CacheConfig;
use crate::traffic::CLASSES;

/// A request to the memory channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// Request number within its port.
    pub id: u32,
    /// Bytes to transfer.
    pub bytes: u32,
    /// Traffic class index.
    pub class: usize,
}

/// Ready cycle of a request the channel has not scheduled yet.
pub const UNSCHEDULED: u64 = u64::MAX;

/// The data a piece of work waits for: requests up to `last` (the channel serves a port's
/// requests in order, so the last one arrives last) and a fixed earliest cycle (hits).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Wait {
    /// Earliest cycle the data can be used, from cache hits.
    pub at: u64,
    /// The newest channel request waited for.
    pub last: Option<u32>,
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
    ready: Vec<u64>,
    /// Requests issued this cycle, taken by the channel at the edge.
    pub staged: Vec<Request>,
    /// Reads of this cycle (address, bytes), for the distinct-data count.
    pub read_log: Vec<(u32, u32)>,
    /// Bytes requested from the channel, per class.
    pub requested: [u64; CLASSES],
}

impl MemPort {
    /// A port whose reads all go through one cache (`size_bytes = 0`: none).
    pub fn new(name: String, cache: &CacheConfig) -> MemPort {
        MemPort::with_caches(name.clone(), &[(name, cache, &[0, 1, 2, 3, 4])])
    }

    /// A port with several caches, each named and serving the listed traffic classes
    /// (a class in no list, or whose cache has `size_bytes = 0`, is uncached).
    pub fn with_caches(name: String, caches: &[(String, &CacheConfig, &[usize])]) -> MemPort {
        let mut route = [None; CLASSES];
        let mut built = Vec::new();
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
            ready: Vec::new(),
            staged: Vec::new(),
            read_log: Vec::new(),
            requested: [0; CLASSES],
        }
    }

    fn request(&mut self, bytes: u32, class: usize) -> u32 {
        let id = self.ready.len() as u32;
        self.ready.push(UNSCHEDULED);
        self.staged.push(Request { id, bytes, class });
        self.requested[class] += bytes as u64;
        id
    }

    /// A read of `bytes` at `addr` at cycle `now`; `wait` collects what it waits for.
    pub fn read(&mut self, class: usize, addr: u32, bytes: u32, now: u64, wait: &mut Wait) {
        self.read_log.push((addr, bytes));
        let Some(c) = self.route.get(class).copied().flatten() else {
            let id = self.request(bytes, class);
            wait.last = wait.last.max(Some(id));
            return;
        };
        let cache = &self.caches[c].1;
        let first = cache.line_of(addr as u64);
        let last = cache.line_of(addr as u64 + bytes.max(1) as u64 - 1);
        let line_bytes = cache.line_bytes();
        for line in first..=last {
            let cache = &mut self.caches[c].1;
            match cache.lookup(line) {
                Lookup::Present { fill } => {
                    if self.ready.get(fill as usize).is_some_and(|&r| r <= now) {
                        cache.stats.hits[class] += 1;
                        wait.at = wait.at.max(now + cache.hit_latency as u64);
                    } else {
                        cache.stats.merged[class] += 1;
                        wait.last = wait.last.max(Some(fill));
                    }
                }
                Lookup::Absent => {
                    cache.stats.misses[class] += 1;
                    let id = self.request(line_bytes, class);
                    self.caches[c].1.install(line, id);
                    wait.last = wait.last.max(Some(id));
                }
            }
        }
    }

    /// A posted write (framebuffer): it costs channel bandwidth, nobody waits for it.
    pub fn write(&mut self, class: usize, bytes: u32) {
        self.request(bytes, class);
    }

    /// Called by the channel at the edge: request `id`'s data arrives at `cycle`.
    pub fn set_ready(&mut self, id: u32, cycle: u64) {
        if let Some(r) = self.ready.get_mut(id as usize) {
            *r = cycle;
        }
    }

    /// The cycle from which `wait`'s data is all there, once the channel has scheduled
    /// every request it needs (`None` before).
    pub fn resolve(&self, wait: &Wait) -> Option<u64> {
        match wait.last {
            None => Some(wait.at),
            Some(id) => match self.ready.get(id as usize) {
                Some(&r) if r != UNSCHEDULED => Some(wait.at.max(r)),
                _ => None,
            },
        }
    }
}

/// The probe a unit hands to core's kernels: every read goes to the port.
pub struct PortProbe<'p> {
    /// The unit's port.
    pub port: &'p mut MemPort,
    /// The current cycle.
    pub now: u64,
    /// What the work waits for.
    pub wait: Wait,
}

impl MemoryProbe for PortProbe<'_> {
    #[inline]
    fn read(&mut self, class: DataClass, addr: u32, bytes: u32) {
        self.port.read(class as usize, addr, bytes, self.now, &mut self.wait);
    }
}
