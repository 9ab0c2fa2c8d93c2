//! The stream machine's report: Purcell 2002's Table 2 quantities, the kernel costs
//! (Table 1), totals by kernel (Figure 7) and by data type (Figure 8), the texture cache
//! (Figure 9), the frame time on the machine, and every pass.

use serde::Serialize;

use crate::stream::config::StreamConfig;
use crate::stream::cost_model::CostModel;
use crate::stream::counters::{KernelTotals, PassRecord, RayWork};
use crate::stream::gpu::FrameTime;
use crate::stream::texture_cache::TextureCacheStats;

/// Loop passes and the optimal bound, summed over every screen's loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LoopTotals {
    /// Traversal passes.
    pub traverse_passes: u64,
    /// Intersection passes.
    pub intersect_passes: u64,
    /// The optimal bound: per loop, the most traversal passes any ray needs plus the
    /// most intersection passes any ray needs (max steps + max intersections without
    /// unrolling).
    pub bound: u64,
    /// Loops run (screens traced on the multipass machine).
    pub loops: u64,
}

/// Table 2's row.
#[derive(Clone, Debug, Serialize)]
pub struct Table2 {
    /// Traversal passes.
    pub traverse_passes: u64,
    /// Intersection passes.
    pub intersect_passes: u64,
    /// Every other pass (eye rays, setup, shading; branching: its fused passes).
    pub other_passes: u64,
    /// All passes.
    pub total_passes: u64,
    /// The most traversal steps of any ray.
    pub max_steps: u64,
    /// The most triangle tests of any ray.
    pub max_intersections: u64,
    /// The optimal bound on loop passes.
    pub optimal_passes: u64,
    /// Loop passes over the bound (multipass).
    pub ratio_to_optimal: Option<f64>,
    /// SIMD efficiency of the traversal passes, the intersection passes and overall
    /// (useful kernel iterations over iterations run).
    pub simd_traverse: Option<f64>,
    /// Of the intersection passes.
    pub simd_intersect: Option<f64>,
    /// Of the traversal and intersection work together.
    pub simd_overall: Option<f64>,
    /// Purcell's SIMD efficiency (§5.1, Table 2's last column): the mean over the
    /// traversal and intersection passes of the fraction of the screen's rays doing
    /// useful work in the pass (multipass).
    pub simd_screen: Option<f64>,
}

/// One kernel's row: its costs per invocation and its totals.
#[derive(Clone, Debug, Serialize)]
pub struct KernelRow {
    /// Kernel name.
    pub kernel: &'static str,
    /// Instructions per invocation.
    pub instructions: u64,
    /// State words read per invocation (multipass).
    pub r: u64,
    /// State words written per invocation (multipass).
    pub w: u64,
    /// Random-access words per invocation: the table's, or measured (mean).
    pub m: f64,
    /// Totals.
    pub totals: KernelTotals,
}

/// One data type's traffic and cache behaviour.
#[derive(Clone, Debug, Serialize)]
pub struct ClassRow {
    /// Data type.
    pub class: &'static str,
    /// Words read.
    pub words: u64,
    /// Cache hit rate (line accesses).
    pub hit_rate: Option<f64>,
    /// Bytes from memory without the cache (4 per word).
    pub bytes_without_cache: u64,
    /// Bytes from memory with the cache (a line per miss).
    pub bytes_with_cache: u64,
}

/// Memory traffic of the frame in bytes.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Traffic {
    /// Random-access reads (through the cache when there is one).
    pub random: u64,
    /// Random-access reads without a cache.
    pub random_uncached: u64,
    /// State words read and written (4 bytes each; reads through the cache if so
    /// configured).
    pub state: u64,
    /// Stencil reads and writes (1 byte each).
    pub stencil: u64,
    /// Everything the frame moves.
    pub total: u64,
}

/// The report.
#[derive(Clone, Debug, Serialize)]
pub struct StreamReport {
    /// Image size.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The configuration.
    pub config: StreamConfig,
    /// The cost table used.
    pub costs: CostModel,
    /// Table 2.
    pub table2: Table2,
    /// Kernel rows (Table 1 and Figure 7).
    pub kernels: Vec<KernelRow>,
    /// Data types (Figures 8 and 9).
    pub classes: Vec<ClassRow>,
    /// Instructions in all.
    pub instructions: u64,
    /// State words read.
    pub state_read: u64,
    /// State words written.
    pub state_written: u64,
    /// Stencil reads.
    pub stencil_reads: u64,
    /// Stencil writes.
    pub stencil_writes: u64,
    /// Bytes moved.
    pub traffic: Traffic,
    /// Texture cache counts.
    pub cache: TextureCacheStats,
    /// Time on the machine.
    pub frame_time: FrameTime,
    /// Rays traced per wave (0: eye rays).
    pub rays_by_wave: Vec<u64>,
    /// Largest per-ray work.
    pub max_work: RayWork,
    /// Every pass.
    pub passes: Vec<PassRecord>,
}

pub(crate) fn ratio(a: u64, b: u64) -> Option<f64> {
    (b > 0).then(|| a as f64 / b as f64)
}

impl StreamReport {
    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}
