//! A set-associative cache with LRU replacement, in front of one unit's memory port.
//! Lines remember which memory request fills them, so a read of a line still in flight
//! waits for that fill instead of asking again (an MSHR merge, counted apart from hits).
//! Misses in flight hold one of the cache's `mshrs` MSHRs until their data arrives.
//! Lines may be any multiple of 4 bytes (Purcell's texture cache has 48-byte lines), and
//! the number of sets any whole number (a line's set is its number modulo the sets).

use serde::Serialize;

use crate::config::CacheConfig;
use crate::memory::traffic::CLASSES;

/// Hits and misses per traffic class.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct CacheStats {
    /// Line accesses that found their data present.
    pub hits: [u64; CLASSES],
    /// Line accesses whose line was being filled (no new request).
    pub merged: [u64; CLASSES],
    /// Line accesses that requested the line from the channel.
    pub misses: [u64; CLASSES],
}

/// What a lookup found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lookup {
    /// The line is present or being filled by request `fill`.
    Present {
        /// The channel request that fills (or filled) the line.
        fill: u32,
    },
    /// Not present; the caller requests it and [`Cache::install`]s it.
    Absent,
}

/// The cache's tag and replacement state (data is read from the scene image itself).
#[derive(Clone, Debug)]
pub struct Cache {
    size_bytes: u32,
    line_bytes: u32,
    sets: u64,
    ways: usize,
    tags: Vec<u64>,
    last_use: Vec<u64>,
    fills: Vec<u32>,
    uses: u64,
    /// Hit latency in cycles.
    pub hit_latency: u32,
    /// MSHRs.
    pub mshrs: u32,
    /// The fills in flight (memory request ids), each holding an MSHR.
    pub outstanding: Vec<u32>,
    /// Statistics.
    pub stats: CacheStats,
}

const EMPTY: u64 = u64::MAX;

impl Cache {
    /// A cache of the configured geometry, or `None` for `size_bytes = 0` (the geometry
    /// was checked by `HwConfig::validate`).
    pub fn new(cfg: &CacheConfig) -> Option<Cache> {
        if cfg.size_bytes == 0 {
            return None;
        }
        let lines = (cfg.size_bytes / cfg.line_bytes.max(1)).max(1) as usize;
        let ways = (cfg.ways as usize).clamp(1, lines);
        let sets = (lines / ways).max(1);
        Some(Cache {
            size_bytes: cfg.size_bytes,
            line_bytes: cfg.line_bytes.max(4),
            sets: sets as u64,
            ways,
            tags: vec![EMPTY; sets * ways],
            last_use: vec![0; sets * ways],
            fills: vec![0; sets * ways],
            uses: 0,
            hit_latency: cfg.hit_latency,
            mshrs: cfg.mshrs.max(1),
            outstanding: Vec::new(),
            stats: CacheStats::default(),
        })
    }

    /// Capacity in bytes, as configured.
    pub fn size_bytes(&self) -> u32 {
        self.size_bytes
    }

    /// Line size in bytes.
    pub fn line_bytes(&self) -> u32 {
        self.line_bytes
    }

    /// The line number of a byte address.
    pub fn line_of(&self, addr: u64) -> u64 {
        addr / self.line_bytes as u64
    }

    fn set(&self, line: u64) -> std::ops::Range<usize> {
        let s = (line % self.sets) as usize * self.ways;
        s..s + self.ways
    }

    /// Looks `line` up, marking it most recently used if present.
    pub fn lookup(&mut self, line: u64) -> Lookup {
        self.uses += 1;
        for w in self.set(line) {
            if self.tags[w] == line {
                self.last_use[w] = self.uses;
                return Lookup::Present { fill: self.fills[w] };
            }
        }
        Lookup::Absent
    }

    /// Puts `line` in its set in place of the least recently used line.
    pub fn install(&mut self, line: u64, fill: u32) {
        let range = self.set(line);
        let victim = range.clone().min_by_key(|&w| (self.tags[w] != EMPTY, self.last_use[w])).unwrap_or(range.start);
        self.tags[victim] = line;
        self.last_use[victim] = self.uses;
        self.fills[victim] = fill;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lru_evicts_the_least_recently_used_way() {
        let cfg = CacheConfig { size_bytes: 128, line_bytes: 32, ways: 2, hit_latency: 1, ports: 1, mshrs: 1 };
        let mut c = Cache::new(&cfg).unwrap(); // 2 sets × 2 ways
        for (line, fill) in [(0, 1), (2, 2)] {
            assert_eq!(c.lookup(line), Lookup::Absent);
            c.install(line, fill);
        }
        assert_eq!(c.lookup(0), Lookup::Present { fill: 1 }); // 0 is now newer than 2
        assert_eq!(c.lookup(4), Lookup::Absent);
        c.install(4, 3); // evicts 2
        assert_eq!(c.lookup(2), Lookup::Absent);
        assert_eq!(c.lookup(0), Lookup::Present { fill: 1 });
        assert_eq!(c.lookup(1), Lookup::Absent, "odd lines live in the other set");
        assert_eq!(c.line_of(100), 3);
    }
}

#[cfg(test)]
mod odd_lines {
    use super::*;

    #[test]
    fn lines_of_48_bytes_and_three_sets() {
        let cfg = CacheConfig { size_bytes: 48 * 6, line_bytes: 48, ways: 2, hit_latency: 1, ports: 1, mshrs: 1 };
        let mut c = Cache::new(&cfg).unwrap(); // 3 sets x 2 ways
        assert_eq!(c.line_of(47), 0);
        assert_eq!(c.line_of(48), 1);
        for line in [0, 3, 6] {
            // All in set 0: the third evicts the first.
            assert_eq!(c.lookup(line), Lookup::Absent);
            c.install(line, line as u32);
        }
        assert_eq!(c.lookup(0), Lookup::Absent);
        assert_eq!(c.lookup(6), Lookup::Present { fill: 6 });
        assert_eq!(c.lookup(1), Lookup::Absent, "set 1 is untouched");
    }
}
