//! The texture cache of Purcell 2002 §4.1 (after Hakura & Gupta 1997): every
//! random-access read, in the order the fragments are processed, goes through one cache
//! (default 64 KB, direct-mapped, 48-byte lines); per data type it counts hits and
//! misses, and the bandwidth with the cache (lines fetched) against without (words
//! read). Tags and replacement are [`crate::memory::cache::Cache`]'s; there is no timing here —
//! the stream machine is measured in passes, instructions and words.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::config::CacheConfig;
use crate::memory::cache::{Cache, Lookup};

/// Traffic classes: the scene's four data classes, then the state textures.
pub const CLASSES: usize = 5;
/// The class index of state-texture reads.
pub const STATE: usize = 4;
/// Names of the classes, by index.
pub const CLASS_NAMES: [&str; CLASSES] = ["grid_cells", "list_entries", "vertices", "shading", "state"];

/// Geometry of the texture cache; `size_bytes = 0` disables it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct TextureCacheConfig {
    /// Capacity in bytes.
    pub size_bytes: u32,
    /// Associativity (1: direct-mapped).
    pub ways: u32,
    /// Line size in bytes (a multiple of 4).
    pub line_bytes: u32,
}

impl Default for TextureCacheConfig {
    /// Purcell 2002 §4.1: 64 KB, direct-mapped, 48-byte lines (a 4×4 block of 24-bit
    /// texels, after Hakura & Gupta).
    fn default() -> Self {
        TextureCacheConfig { size_bytes: 64 * 1024, ways: 1, line_bytes: 48 }
    }
}

impl fmt::Display for TextureCacheConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.size_bytes == 0 {
            return write!(f, "off");
        }
        write!(f, "{} B, {}-way, {} B lines", self.size_bytes, self.ways, self.line_bytes)
    }
}

impl FromStr for TextureCacheConfig {
    type Err = String;

    /// `SIZE,WAYS,LINE` (SIZE in bytes, or with a K or M suffix), or `off`.
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "off" || s == "0" {
            return Ok(TextureCacheConfig { size_bytes: 0, ways: 1, line_bytes: 48 });
        }
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [size, ways, line] = parts.as_slice() else {
            return Err(format!("cache {s:?}: expected SIZE,WAYS,LINE (e.g. 64K,1,48) or off"));
        };
        let bytes = |p: &str| -> Result<u64, String> {
            let (num, mul) = match p.char_indices().last() {
                Some((i, 'K' | 'k')) => (&p[..i], 1024),
                Some((i, 'M' | 'm')) => (&p[..i], 1024 * 1024),
                _ => (p, 1),
            };
            num.parse::<u64>().map(|n| n.saturating_mul(mul)).map_err(|_| format!("cache {s:?}: '{p}' is not a size"))
        };
        let size = bytes(size)?;
        let ways: u64 = ways.parse().map_err(|_| format!("cache {s:?}: '{ways}' is not a number of ways"))?;
        let line = bytes(line)?;
        let cfg = TextureCacheConfig {
            size_bytes: u32::try_from(size).map_err(|_| format!("cache {s:?}: larger than 4 GB"))?,
            ways: u32::try_from(ways).map_err(|_| format!("cache {s:?}: too many ways"))?,
            line_bytes: u32::try_from(line).map_err(|_| format!("cache {s:?}: line too large"))?,
        };
        cfg.validate().map_err(|e| format!("cache {s:?}: {e}"))?;
        Ok(cfg)
    }
}

impl TextureCacheConfig {
    /// Checks the geometry.
    pub fn validate(&self) -> Result<(), String> {
        if self.size_bytes == 0 {
            return Ok(());
        }
        if self.line_bytes == 0 || !self.line_bytes.is_multiple_of(4) || self.line_bytes > 4096 {
            return Err(format!("line size {} B is not a multiple of 4 between 4 and 4096", self.line_bytes));
        }
        if self.size_bytes < self.line_bytes {
            return Err(format!("{} B holds no {}-byte line", self.size_bytes, self.line_bytes));
        }
        if self.size_bytes > 1 << 30 {
            return Err(format!("{} B is more than 1 GB", self.size_bytes));
        }
        let lines = self.size_bytes / self.line_bytes;
        if self.ways == 0 || self.ways > lines || !lines.is_multiple_of(self.ways) {
            return Err(format!("{} ways do not divide {lines} lines", self.ways));
        }
        Ok(())
    }
}

/// Per-class counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TextureCacheStats {
    /// Words requested (the bandwidth without a cache is 4 bytes each).
    pub words: [u64; CLASSES],
    /// Line accesses that hit.
    pub hits: [u64; CLASSES],
    /// Line accesses that missed (each fetches a line).
    pub misses: [u64; CLASSES],
}

impl TextureCacheStats {
    /// Hit rate of a class (accesses that hit), `None` without accesses.
    pub fn hit_rate(&self, class: usize) -> Option<f64> {
        let n = self.hits[class] + self.misses[class];
        (n > 0).then(|| self.hits[class] as f64 / n as f64)
    }
}

/// The cache and its counts.
#[derive(Clone, Debug)]
pub struct TextureCache {
    cache: Option<Cache>,
    line_bytes: u64,
    /// Counts so far.
    pub stats: TextureCacheStats,
}

impl TextureCache {
    /// A cache of the given geometry (disabled for size 0).
    pub fn new(cfg: &TextureCacheConfig) -> TextureCache {
        let c = CacheConfig {
            size_bytes: cfg.size_bytes,
            line_bytes: cfg.line_bytes,
            ways: cfg.ways,
            hit_latency: 0,
            ports: 1,
            mshrs: 1,
        };
        TextureCache { cache: Cache::new(&c), line_bytes: cfg.line_bytes.max(4) as u64, stats: Default::default() }
    }

    /// True if there is a cache.
    pub fn enabled(&self) -> bool {
        self.cache.is_some()
    }

    /// One read of `bytes` at byte address `addr`, of traffic class `class`.
    pub fn read(&mut self, class: usize, addr: u64, bytes: u32) {
        let class = class.min(CLASSES - 1);
        self.stats.words[class] += (bytes as u64).div_ceil(4);
        let Some(cache) = self.cache.as_mut() else { return };
        if bytes == 0 {
            return;
        }
        let (first, last) = (addr / self.line_bytes, (addr + bytes as u64 - 1) / self.line_bytes);
        for line in first..=last {
            match cache.lookup(line) {
                Lookup::Present { .. } => self.stats.hits[class] += 1,
                Lookup::Absent => {
                    self.stats.misses[class] += 1;
                    cache.install(line, 0);
                }
            }
        }
    }

    /// Bytes fetched from memory for a class: lines missed with a cache, words read
    /// without.
    pub fn bytes_fetched(&self, class: usize) -> u64 {
        match self.cache {
            Some(_) => self.stats.misses[class] * self.line_bytes,
            None => self.stats.words[class] * 4,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A direct-mapped cache written the obvious way, as the reference.
    struct Reference {
        tags: Vec<Option<u64>>,
        line: u64,
    }

    impl Reference {
        fn access(&mut self, addr: u64) -> bool {
            let l = addr / self.line;
            let set = (l % self.tags.len() as u64) as usize;
            let hit = self.tags[set] == Some(l);
            self.tags[set] = Some(l);
            hit
        }
    }

    #[test]
    fn direct_mapped_48_byte_lines_match_a_reference_on_a_synthetic_trace() {
        let cfg = TextureCacheConfig::default();
        let mut c = TextureCache::new(&cfg);
        let mut r = Reference { tags: vec![None; (64 * 1024 / 48) as usize], line: 48 };
        // A trace with reuse, strides that alias in a direct-mapped cache, and
        // word-sized reads that never straddle a 48-byte line (4 divides 48).
        let mut x = 12345u64;
        let (mut hits, mut misses) = (0, 0);
        for i in 0..200_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let addr = match i % 4 {
                0 => ((x >> 33) % (1 << 20)) & !3,
                1 => (i * 48 * 1365) % (1 << 22),
                2 => (i % 512) * 4,
                _ => ((x >> 40) % 4096) & !3,
            };
            if r.access(addr) {
                hits += 1
            } else {
                misses += 1
            }
            c.read(2, addr, 4);
        }
        assert_eq!((c.stats.hits[2], c.stats.misses[2]), (hits, misses));
        assert!(hits > 10_000 && misses > 10_000, "{hits} {misses}");
        assert_eq!(c.bytes_fetched(2), misses * 48);
        assert_eq!(c.stats.words[2], 200_000);
    }

    #[test]
    fn without_a_cache_bandwidth_is_the_words_read_and_reads_split_across_lines() {
        let mut off = TextureCache::new(&"off".parse().unwrap());
        off.read(0, 100, 12);
        assert_eq!((off.bytes_fetched(0), off.stats.words[0]), (12, 3));
        let mut c = TextureCache::new(&TextureCacheConfig::default());
        c.read(1, 44, 8); // bytes 44..52 straddle lines 0 and 1
        assert_eq!(c.stats.misses[1], 2);
        c.read(1, 40, 4);
        assert_eq!(c.stats.hits[1], 1);
    }

    #[test]
    fn parsing_checks_the_geometry() {
        assert_eq!("64K,1,48".parse::<TextureCacheConfig>(), Ok(TextureCacheConfig::default()));
        assert_eq!("16384,4,64".parse::<TextureCacheConfig>().unwrap().ways, 4);
        for bad in ["64K,1", "64K,0,48", "64K,1,50", "32,1,48", "64K,2,48", "2G,1,48", "x,1,48"] {
            assert!(bad.parse::<TextureCacheConfig>().is_err(), "{bad}");
        }
    }
}
