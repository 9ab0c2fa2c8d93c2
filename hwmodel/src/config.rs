//! Every parameter of the modelled chip, declared once (gem5's `Params`, ChampSim's
//! configuration): unit counts, threads, FIFO depths, latencies, caches and the memory
//! channel. Loaded from TOML (a preset, a file, then `--set key=value` overrides); an
//! unknown key is an error, not silently ignored, and impossible values are rejected by
//! [`HwConfig::validate`] before anything is simulated.

use serde::{Deserialize, Serialize};

use crate::fifo::MAX_FIFO_DEPTH;

/// Largest packet (the active mask is a `u64`).
pub const MAX_PACKET: u32 = 64;

/// The whole chip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HwConfig {
    /// Clock frequency in MHz (for frames and rays per second).
    pub clock_mhz: f64,
    /// Rays per packet: 1, 4, 16 or 64 (square pixel blocks of side 1, 2, 4, 8).
    pub packet_size: u32,
    /// Cycles without progress of any unit after which the run stops with an error.
    pub watchdog_cycles: u64,
    /// Ray generation and shading.
    pub rgs: RgsConfig,
    /// Traversal units.
    pub traversal: TraversalConfig,
    /// List and intersection units (one per traversal unit).
    pub intersection: IntersectionConfig,
    /// FIFO depths.
    pub fifo: FifoConfig,
    /// Caches.
    pub cache: CachesConfig,
    /// The memory channel.
    pub memory: MemoryConfig,
}

/// The ray generation & shading unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RgsConfig {
    /// Eye rays generated per cycle.
    pub rays_per_cycle: u32,
    /// Rays shaded per cycle.
    pub shade_per_cycle: u32,
}

/// One traversal unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TraversalConfig {
    /// Number of traversal units (each with its own intersection unit).
    pub units: u32,
    /// Packets in flight per unit.
    pub threads: u32,
    /// Pipeline latency of one traversal step, in cycles (one step issues per cycle).
    pub step_latency: u32,
}

/// One list & intersection unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IntersectionConfig {
    /// Pipeline latency of a ray–triangle test, in cycles.
    pub latency: u32,
    /// Cycles between two ray–triangle tests entering the pipeline.
    pub initiation_interval: u32,
}

/// Depth of each kind of FIFO (entries are whole packets).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FifoConfig {
    /// Ray generator → traversal unit.
    pub rays: u32,
    /// Traversal unit → intersection unit ("packet + leaf").
    pub leaves: u32,
    /// Intersection unit → traversal unit (the packet back).
    pub results: u32,
    /// Traversal unit → shading (finished packets).
    pub hits: u32,
}

/// One cache; `size_bytes = 0` means none (every read goes to the channel).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CacheConfig {
    /// Capacity in bytes (0: no cache).
    pub size_bytes: u32,
    /// Line size in bytes (a power of two).
    pub line_bytes: u32,
    /// Associativity.
    pub ways: u32,
    /// Hit latency in cycles.
    pub hit_latency: u32,
}

/// The caches: each traversal unit has a node cache, each intersection unit a cache for
/// triangles that primitive lists share (or their own), the shading unit one for shading
/// data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CachesConfig {
    /// Per traversal unit: nodes (grid cells, tree nodes).
    pub nodes: CacheConfig,
    /// Per intersection unit: triangles (and primitive lists, when they share it).
    pub triangles: CacheConfig,
    /// Primitive lists go through the triangle cache (true) or through `lists` (false).
    pub lists_share_triangle_cache: bool,
    /// Per intersection unit: primitive lists, when they do not share the triangle cache.
    pub lists: CacheConfig,
    /// The shading unit: materials, lights, shading vertices.
    pub shading: CacheConfig,
}

/// The one memory channel behind all caches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MemoryConfig {
    /// Cycles from a request leaving the channel to its data arriving.
    pub latency: u32,
    /// Bytes the channel transfers per cycle.
    pub bytes_per_cycle: u32,
}

impl Default for HwConfig {
    fn default() -> Self {
        HwConfig {
            clock_mhz: 200.0,
            packet_size: 16,
            watchdog_cycles: 100_000,
            rgs: RgsConfig::default(),
            traversal: TraversalConfig::default(),
            intersection: IntersectionConfig::default(),
            fifo: FifoConfig::default(),
            cache: CachesConfig::default(),
            memory: MemoryConfig::default(),
        }
    }
}

impl Default for RgsConfig {
    fn default() -> Self {
        RgsConfig { rays_per_cycle: 4, shade_per_cycle: 4 }
    }
}

impl Default for TraversalConfig {
    fn default() -> Self {
        TraversalConfig { units: 4, threads: 8, step_latency: 4 }
    }
}

impl Default for IntersectionConfig {
    fn default() -> Self {
        IntersectionConfig { latency: 20, initiation_interval: 1 }
    }
}

impl Default for FifoConfig {
    fn default() -> Self {
        FifoConfig { rays: 4, leaves: 4, results: 4, hits: 4 }
    }
}

impl Default for CacheConfig {
    fn default() -> Self {
        CacheConfig { size_bytes: 16 * 1024, line_bytes: 64, ways: 4, hit_latency: 1 }
    }
}

impl Default for CachesConfig {
    fn default() -> Self {
        CachesConfig {
            nodes: CacheConfig::default(),
            triangles: CacheConfig::default(),
            lists_share_triangle_cache: true,
            lists: CacheConfig { size_bytes: 4096, ..CacheConfig::default() },
            shading: CacheConfig::default(),
        }
    }
}

impl Default for MemoryConfig {
    fn default() -> Self {
        MemoryConfig { latency: 100, bytes_per_cycle: 16 }
    }
}

/// The presets shipped with the model (the files in `fixtures/hw/`).
pub const PRESETS: [(&str, &str); 2] = [
    ("saarcor", include_str!("../../fixtures/hw/saarcor.toml")),
    ("minimal", include_str!("../../fixtures/hw/minimal.toml")),
];

impl HwConfig {
    /// Parses a TOML document over the defaults; unknown keys are errors.
    pub fn from_toml(text: &str) -> Result<HwConfig, String> {
        toml::from_str(text).map_err(|e| one_line(&e.to_string()))
    }

    /// A shipped preset by name.
    pub fn preset(name: &str) -> Result<HwConfig, String> {
        match PRESETS.iter().find(|(n, _)| *n == name) {
            Some((_, text)) => HwConfig::from_toml(text).map_err(|e| format!("preset {name}: {e}")),
            None => {
                let names: Vec<&str> = PRESETS.iter().map(|(n, _)| *n).collect();
                Err(format!("unknown preset {name:?} (presets: {})", names.join(", ")))
            }
        }
    }

    /// Applies `key=value` (e.g. `traversal.threads=16`): the value is read as TOML (a
    /// number, boolean or quoted string); the key must name an existing parameter.
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let Some((key, value)) = assignment.split_once('=') else {
            return Err(format!("--set {assignment:?}: expected key=value"));
        };
        let (key, value) = (key.trim(), value.trim());
        let mut doc = toml::Table::try_from(&*self).map_err(|e| one_line(&e.to_string()))?;
        let parsed: toml::Value = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .ok_or_else(|| format!("--set {key}: {value:?} is not a number, boolean or quoted string"))?;
        let path: Vec<&str> = key.split('.').collect();
        let no_such = || format!("--set {key}: no such parameter");
        let Some((last, parents)) = path.split_last() else { return Err(no_such()) };
        let mut table = &mut doc;
        for part in parents {
            table = match table.get_mut(*part) {
                Some(toml::Value::Table(t)) => t,
                _ => return Err(no_such()),
            };
        }
        match table.get_mut(*last) {
            Some(slot) if !slot.is_table() => *slot = parsed,
            _ => return Err(no_such()),
        }
        *self = doc.try_into().map_err(|e: toml::de::Error| format!("--set {key}: {}", one_line(&e.to_string())))?;
        Ok(())
    }

    /// Rejects configurations that cannot be built or cannot work, with the reason.
    pub fn validate(&self) -> Result<(), String> {
        let err = |m: String| Err(m);
        if !(self.clock_mhz.is_finite() && self.clock_mhz > 0.0) {
            return err(format!("clock_mhz must be a positive number (got {})", self.clock_mhz));
        }
        if ![1, 4, 16, 64].contains(&self.packet_size) {
            return err(format!("packet_size must be 1, 4, 16 or 64 (got {})", self.packet_size));
        }
        if self.packet_size > MAX_PACKET {
            return err(format!("packet_size {} exceeds the {MAX_PACKET}-lane packet registers", self.packet_size));
        }
        let positive = [
            ("rgs.rays_per_cycle", self.rgs.rays_per_cycle),
            ("rgs.shade_per_cycle", self.rgs.shade_per_cycle),
            ("traversal.units", self.traversal.units),
            ("traversal.threads", self.traversal.threads),
            ("traversal.step_latency", self.traversal.step_latency),
            ("intersection.latency", self.intersection.latency),
            ("intersection.initiation_interval", self.intersection.initiation_interval),
            ("memory.bytes_per_cycle", self.memory.bytes_per_cycle),
        ];
        for (name, v) in positive {
            if v == 0 {
                return err(format!("{name} must be at least 1"));
            }
        }
        if self.traversal.units > 64 {
            return err(format!("traversal.units {} is more than the 64 the model supports", self.traversal.units));
        }
        if self.traversal.threads > 255 {
            return err(format!(
                "traversal.threads {} is more than the 255 a thread tag holds",
                self.traversal.threads
            ));
        }
        let fifos = [
            ("fifo.rays", self.fifo.rays),
            ("fifo.leaves", self.fifo.leaves),
            ("fifo.results", self.fifo.results),
            ("fifo.hits", self.fifo.hits),
        ];
        for (name, depth) in fifos {
            if depth == 0 {
                return err(format!("{name}: a FIFO needs a depth of at least 1"));
            }
            if depth as usize > MAX_FIFO_DEPTH {
                return err(format!("{name}: depth {depth} exceeds the {MAX_FIFO_DEPTH} entries a FIFO can hold"));
            }
        }
        for (name, c) in [
            ("cache.nodes", &self.cache.nodes),
            ("cache.triangles", &self.cache.triangles),
            ("cache.lists", &self.cache.lists),
            ("cache.shading", &self.cache.shading),
        ] {
            if !c.line_bytes.is_power_of_two() || c.line_bytes < 4 {
                return err(format!("{name}.line_bytes must be a power of two of at least 4 (got {})", c.line_bytes));
            }
            if c.size_bytes == 0 {
                continue;
            }
            if c.size_bytes < c.line_bytes {
                return err(format!("{name}: {} bytes is smaller than one {}-byte line", c.size_bytes, c.line_bytes));
            }
            if c.ways == 0 {
                return err(format!("{name}.ways must be at least 1"));
            }
            let lines = c.size_bytes / c.line_bytes;
            if c.size_bytes % c.line_bytes != 0 || lines % c.ways != 0 || !(lines / c.ways).is_power_of_two() {
                return err(format!(
                    "{name}: {} bytes in {}-byte lines and {} ways does not give a power-of-two number of sets",
                    c.size_bytes, c.line_bytes, c.ways
                ));
            }
        }
        // The watchdog must outlast the longest legitimate wait with nothing moving.
        let longest = self.memory.latency as u64
            + self.intersection.latency as u64
            + self.traversal.step_latency as u64
            + [&self.cache.nodes, &self.cache.triangles, &self.cache.lists, &self.cache.shading]
                .iter()
                .map(|c| c.hit_latency)
                .max()
                .unwrap_or(0) as u64;
        if self.watchdog_cycles <= longest {
            return err(format!(
                "watchdog_cycles {} must exceed the longest wait without progress ({longest} cycles)",
                self.watchdog_cycles
            ));
        }
        Ok(())
    }

    /// Side of the square pixel block of a packet.
    pub fn packet_side(&self) -> u32 {
        match self.packet_size {
            64 => 8,
            16 => 4,
            4 => 2,
            _ => 1,
        }
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_and_validate() {
        for (name, _) in PRESETS {
            let c = HwConfig::preset(name).unwrap();
            c.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        HwConfig::default().validate().unwrap();
    }

    #[test]
    fn unknown_keys_and_impossible_values_are_rejected() {
        let e = HwConfig::from_toml("[traversal]\nthreds = 4\n").unwrap_err();
        assert!(e.contains("threds"), "{e}");
        let mut c = HwConfig::default();
        assert!(c.set("traversal.thread=3").unwrap_err().contains("no such parameter"));
        assert!(c.set("nosuch=3").unwrap_err().contains("no such parameter"));
        assert!(c.set("traversal=3").unwrap_err().contains("no such parameter"));
        c.set("traversal.threads=16").unwrap();
        assert_eq!(c.traversal.threads, 16);
        assert!(c.set("traversal.threads=\"many\"").is_err());
        c.set("fifo.rays=0").unwrap();
        assert!(c.validate().unwrap_err().contains("fifo.rays"));
        let mut c = HwConfig::default();
        c.set("cache.nodes.size_bytes=32").unwrap();
        assert!(c.validate().unwrap_err().contains("smaller than one"));
        let mut c = HwConfig::default();
        c.set("packet_size=128").unwrap();
        assert!(c.validate().is_err());
        let mut c = HwConfig::default();
        c.set("watchdog_cycles=10").unwrap();
        assert!(c.validate().unwrap_err().contains("watchdog"));
    }
}
