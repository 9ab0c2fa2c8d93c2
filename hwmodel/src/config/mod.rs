//! Every parameter of the modelled chip, declared once (gem5's `Params`, ChampSim's
//! configuration): unit counts, threads, FIFO depths, latencies, caches and the memory
//! channel. Loaded from TOML (a preset, a file, then `--set key=value` overrides); an
//! unknown key is an error, not silently ignored, and impossible values are rejected by
//! [`HwConfig::validate`] before anything is simulated.

use serde::{Deserialize, Serialize};

mod dram;
pub mod energy;
mod validate;

pub use dram::{DramConfig, DramScheduling, PagePolicy};

use crate::chip::datapath::Datapath;

/// Largest packet (the active mask is a `u64`).
pub const MAX_PACKET: u32 = 64;

/// Most simulator memory a configuration may ask for (a one-line error beyond).
pub const MAX_MODELLED_BYTES: u64 = 4 << 30;

/// Simulator bytes of one traversal thread's registers (rays, walks, shared stack).
const THREAD_BYTES: u64 = 48 * 1024;

/// Simulator bytes of one intersection job.
const JOB_BYTES: u64 = 8 * 1024;

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
    /// The arithmetic of the box and triangle tests: "f32" (default) or a fixed-point
    /// format ("q16.16", "q12.12", …; see [`Datapath`]). Fixed point needs a BVH scene.
    pub datapath: Datapath,
    /// Ray generation and shading.
    pub rgs: RgsConfig,
    /// Traversal units.
    pub traversal: TraversalConfig,
    /// List and intersection units (one per traversal unit).
    pub intersection: IntersectionConfig,
    /// Transformation units (one per traversal unit; instanced scenes).
    pub transform: TransformConfig,
    /// FIFO depths.
    pub fifo: FifoConfig,
    /// Caches.
    pub cache: CachesConfig,
    /// The memory channel.
    pub memory: MemoryConfig,
    /// Energy and area figures (docs/hw-model.md, "Energy and area").
    pub energy: energy::EnergyConfig,
    /// The acceleration structure the chip is built to traverse, used when the command
    /// line names none: "grid", "kd", "bvh", "bvh4", "bvh8" or "none".
    pub structure: String,
}

/// The structures a chip may name.
pub const STRUCTURES: [&str; 6] = ["grid", "kd", "bvh", "bvh4", "bvh8", "none"];

/// The ray generation & shading unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RgsConfig {
    /// Eye rays generated per cycle.
    pub rays_per_cycle: u32,
    /// Rays shaded per cycle.
    pub shade_per_cycle: u32,
    /// Packets being shaded at once (their shading-data reads overlap).
    pub shade_jobs: u32,
}

/// One traversal unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TraversalConfig {
    /// Number of traversal units (each with its own intersection unit).
    pub units: u32,
    /// Packets in flight per unit.
    pub threads: u32,
    /// Pipeline latency of one traversal step, in cycles, from its last ray–node test
    /// entering the datapath to its result.
    pub step_latency: u32,
    /// Ray–node tests the traversal datapath starts per cycle: a packet step of `n`
    /// active rays occupies it `ceil(n / lanes_per_cycle)` cycles.
    pub lanes_per_cycle: u32,
}

/// One list & intersection unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IntersectionConfig {
    /// Pipeline latency of a ray–triangle test, in cycles.
    pub latency: u32,
    /// Cycles between two groups of ray–triangle tests entering the pipeline.
    pub initiation_interval: u32,
    /// Ray–triangle tests per group (the datapath's width).
    pub lanes_per_cycle: u32,
    /// Leaf jobs in flight at once (fetching their lists and triangles, waiting for the
    /// datapath, in the pipeline).
    pub jobs: u32,
}

/// The transformation unit beside each traversal unit: a ray entering an instance is
/// carried into its object space (origin and direction through the instance's 3×4
/// world-to-object map, Wald & Slusallek 2001 §8.3), as SaarCOR's dynamic-scene prototype
/// does in its pipeline (Schmittler, Woop, Wagner, Paul & Slusallek, Graphics Hardware
/// 2004). A group of up to `lanes_per_cycle` rays enters every `initiation_interval`
/// cycles and leaves `latency` cycles later.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransformConfig {
    /// Pipeline latency of one ray's transformation, in cycles.
    pub latency: u32,
    /// Cycles between two groups entering the pipeline.
    pub initiation_interval: u32,
    /// Rays transformed per group (the datapath's width).
    pub lanes_per_cycle: u32,
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
    /// Line size in bytes (a multiple of 4).
    pub line_bytes: u32,
    /// Associativity.
    pub ways: u32,
    /// Hit latency in cycles.
    pub hit_latency: u32,
    /// Lookups per cycle (the port's width; also without a cache: requests per cycle).
    pub ports: u32,
    /// Misses outstanding at once (miss status holding registers); a miss without a free
    /// MSHR waits.
    pub mshrs: u32,
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
    /// A second-level cache shared by every unit, between their caches and the memory
    /// (`size_bytes = 0`: none); `ports` lookups per cycle for all units together.
    pub l2: CacheConfig,
}

/// Which memory sits behind the caches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MemoryModel {
    /// Every request is taken at the next edge and its data arrives the cycle after:
    /// no queue, no bandwidth limit, no L2 (the units' caches still take their hit
    /// latency): the compute bound.
    Perfect,
    /// One channel: `bytes_per_cycle`, then `latency` cycles.
    Fixed,
    /// DRAM with channels, banks, rows and their timing ([`DramConfig`]).
    Dram,
    /// DRAMsim3 itself, with one of its configuration files ([`Dramsim3Config`]);
    /// needs the `dramsim3` cargo feature.
    Dramsim3,
}

/// The error for `memory.model = "dramsim3"` in a build without DRAMsim3.
pub const NO_DRAMSIM3: &str = "memory.model = \"dramsim3\" needs raypipe built with the dramsim3 feature \
     (cargo install --features dramsim3; it builds DRAMsim3 with cmake)";

/// DRAMsim3's memory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dramsim3Config {
    /// One of DRAMsim3's shipped configurations by name (`DDR4_8Gb_x8_2400`), or the
    /// path of a DRAMsim3 `.ini` file.
    pub config: String,
}

impl Default for Dramsim3Config {
    /// DDR3-1600, 4 Gb x8 devices, one 64-bit channel with 8 KiB rows: the memory
    /// [`DramConfig`]'s defaults describe.
    fn default() -> Self {
        Dramsim3Config { config: "DDR3_4Gb_x8_1600".into() }
    }
}

/// The memory behind all caches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MemoryConfig {
    /// `"perfect"`, `"fixed"`, `"dram"` or `"dramsim3"`.
    pub model: MemoryModel,
    /// Fixed model: cycles from a transfer's end to its data arriving.
    pub latency: u32,
    /// Fixed model: bytes the channel transfers per cycle.
    pub bytes_per_cycle: u32,
    /// Requests accepted but not yet started that the memory holds; a unit whose request
    /// finds it full keeps the request and waits.
    pub queue_depth: u32,
    /// Fixed model: smallest transfer; a request moves a whole number of these bytes.
    pub min_burst_bytes: u32,
    /// The DRAM model's parameters.
    pub dram: DramConfig,
    /// DRAMsim3's configuration.
    pub dramsim3: Dramsim3Config,
}

impl MemoryConfig {
    /// Requests a unit's port may hold for the memory to take: `queue_depth`, except
    /// for perfect memory, which takes every request at the next edge and so has no
    /// queue to be full.
    pub fn port_staging(&self) -> u32 {
        match self.model {
            MemoryModel::Perfect => u32::MAX,
            _ => self.queue_depth,
        }
    }
}

impl Default for HwConfig {
    fn default() -> Self {
        HwConfig {
            clock_mhz: 200.0,
            packet_size: 16,
            watchdog_cycles: 100_000,
            datapath: Datapath::F32,
            rgs: RgsConfig::default(),
            traversal: TraversalConfig::default(),
            intersection: IntersectionConfig::default(),
            transform: TransformConfig::default(),
            fifo: FifoConfig::default(),
            cache: CachesConfig::default(),
            memory: MemoryConfig::default(),
            energy: energy::EnergyConfig::default(),
            // Purcell's uniform grid, the structure the project began with.
            structure: "grid".into(),
        }
    }
}

impl Default for RgsConfig {
    fn default() -> Self {
        RgsConfig { rays_per_cycle: 4, shade_per_cycle: 4, shade_jobs: 2 }
    }
}

impl Default for TraversalConfig {
    fn default() -> Self {
        TraversalConfig { units: 4, threads: 8, step_latency: 4, lanes_per_cycle: 4 }
    }
}

impl Default for IntersectionConfig {
    fn default() -> Self {
        IntersectionConfig { latency: 20, initiation_interval: 1, lanes_per_cycle: 1, jobs: 4 }
    }
}

impl Default for TransformConfig {
    /// One ray every two cycles: its origin (a point) and direction (a vector) pass one
    /// after the other through three 4-wide dot products (the 3×4 map's rows); the
    /// latency is a multiply and a two-level add tree at the depths of the intersection
    /// pipeline's float units. Derived from the arithmetic, not read off a chip.
    fn default() -> Self {
        TransformConfig { latency: 12, initiation_interval: 2, lanes_per_cycle: 1 }
    }
}

impl Default for FifoConfig {
    fn default() -> Self {
        FifoConfig { rays: 4, leaves: 4, results: 4, hits: 4 }
    }
}

impl Default for CacheConfig {
    fn default() -> Self {
        CacheConfig { size_bytes: 16 * 1024, line_bytes: 64, ways: 4, hit_latency: 1, ports: 1, mshrs: 8 }
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
            l2: CacheConfig { size_bytes: 0, line_bytes: 64, ways: 8, hit_latency: 10, ports: 2, mshrs: 32 },
        }
    }
}

impl Default for MemoryConfig {
    fn default() -> Self {
        MemoryConfig {
            model: MemoryModel::Fixed,
            latency: 100,
            bytes_per_cycle: 16,
            queue_depth: 16,
            min_burst_bytes: 32,
            dram: DramConfig::default(),
            dramsim3: Dramsim3Config::default(),
        }
    }
}

/// The presets shipped with the model (the files in `fixtures/hw/`).
pub const PRESETS: [(&str, &str); 2] = [
    ("saarcor", include_str!("../../../fixtures/hw/saarcor.toml")),
    ("minimal", include_str!("../../../fixtures/hw/minimal.toml")),
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
        // A bare word is a string (`memory.model=dram`), as a shell user writes it.
        let bare = !value.is_empty() && value.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        let parsed: toml::Value = toml::from_str::<toml::Table>(&format!("v = {value}"))
            .ok()
            .and_then(|mut t| t.remove("v"))
            .or_else(|| bare.then(|| toml::Value::String(value.to_string())))
            .ok_or_else(|| format!("--set {key}: {value:?} is not a number, boolean, word or quoted string"))?;
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

    /// Every cache configuration, named by its key.
    pub fn caches(&self) -> [(&'static str, &CacheConfig); 5] {
        [
            ("cache.nodes", &self.cache.nodes),
            ("cache.triangles", &self.cache.triangles),
            ("cache.lists", &self.cache.lists),
            ("cache.shading", &self.cache.shading),
            ("cache.l2", &self.cache.l2),
        ]
    }

    /// An estimate of the simulator memory the chip's state takes: cache tags, thread
    /// and job registers.
    pub fn modelled_bytes(&self) -> u64 {
        let units = self.traversal.units as u64;
        let cache = |c: &CacheConfig| (c.size_bytes as u64 / c.line_bytes.max(1) as u64) * 24;
        let per_unit = cache(&self.cache.nodes)
            + cache(&self.cache.triangles)
            + if self.cache.lists_share_triangle_cache { 0 } else { cache(&self.cache.lists) }
            + self.traversal.threads as u64 * THREAD_BYTES
            + self.intersection.jobs as u64 * JOB_BYTES;
        units * per_unit + cache(&self.cache.shading) + cache(&self.cache.l2)
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
        assert!(c.set("traversal.threads=many").is_err(), "a word is a string, not a number");
        c.set("memory.model=dram").unwrap();
        assert_eq!(c.memory.model, MemoryModel::Dram);
        c.set("fifo.rays=0").unwrap();
        assert!(c.validate().unwrap_err().contains("fifo.rays"));
        let mut c = HwConfig::default();
        c.set("cache.nodes.size_bytes=32").unwrap();
        assert!(c.validate().unwrap_err().contains("smaller than one"));
        let mut c = HwConfig::default();
        c.set("packet_size=128").unwrap();
        assert!(c.validate().is_err());
        let mut c = HwConfig::default();
        c.set("traversal.threads=65").unwrap();
        assert!(c.validate().unwrap_err().contains("traversal.threads"));
        let mut c = HwConfig::default();
        c.set("cache.nodes.line_bytes=48").unwrap();
        c.set("cache.nodes.size_bytes=6144").unwrap();
        c.validate().expect("48-byte lines (Purcell's texture cache) are fine");
        c.set("cache.nodes.line_bytes=50").unwrap();
        assert!(c.validate().unwrap_err().contains("multiple of 4"));
        let mut c = HwConfig::default();
        c.set("traversal.units=64").unwrap();
        c.set("traversal.threads=64").unwrap();
        for k in ["nodes", "triangles", "lists", "shading"] {
            c.set(&format!("cache.{k}.size_bytes=1073741824")).unwrap();
        }
        c.set("cache.lists_share_triangle_cache=false").unwrap();
        assert!(c.validate().unwrap_err().contains("GiB"), "64 units x 1 GiB caches");
        let mut c = HwConfig::default();
        c.set("memory.model=\"dram\"").unwrap();
        c.validate().unwrap();
        c.set("memory.model=\"hbm\"").unwrap_err();
    }
}
