//! What the stream machine counts, per pass and per kernel (Purcell 2002 §4, Tables 1–2,
//! Figures 7–8).

use serde::Serialize;

use crate::stream::cost_model::Kernel;
use crate::stream::stencil::StencilCounts;

/// The kind of a rendering pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PassKind {
    /// Eye-ray generation.
    Generate,
    /// Traversal setup.
    Setup,
    /// Traversal steps.
    Traverse,
    /// Triangle tests.
    Intersect,
    /// Shading (and the records it emits).
    Shade,
    /// Branching: every kernel fused in one pass.
    Fused,
}

/// One rendering pass.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PassRecord {
    /// Ray generation (0: eye rays) and screen of rays within it.
    pub wave: u32,
    /// Screen within the wave.
    pub screen: u32,
    /// What the pass ran.
    pub kind: Option<PassKind>,
    /// Rays that passed the stencil test and ran the kernel.
    pub processed: u64,
    /// Kernel iterations per processed ray (the unroll factor; 1 otherwise).
    pub iterations: u32,
    /// Iterations that did work: the ray was still in the kernel's stage.
    pub useful: u64,
    /// Iterations that ran on a ray already done with the kernel (unrolling).
    pub idle: u64,
    /// Stencil traffic.
    pub stencil: StencilCounts,
    /// State words read and written.
    pub state_read: u64,
    /// State words written.
    pub state_written: u64,
    /// Random-access words by class (grid cells, list entries, vertices, shading).
    pub random_words: [u64; 4],
    /// Instructions executed.
    pub instructions: u64,
    /// Rays still waiting to traverse or intersect after the pass.
    pub active_after: u64,
    /// Fragments the pass covered (the screen's rows that hold rays).
    pub covered: u64,
}

impl PassRecord {
    /// Purcell's SIMD efficiency of the pass (2002 §5.1, Table 2): the fraction of the
    /// pass's fragments — every ray of the screen — doing useful work, per iteration.
    pub fn screen_efficiency(&self) -> Option<f64> {
        let n = self.covered * self.iterations.max(1) as u64;
        (n > 0).then(|| self.useful as f64 / n as f64)
    }

    /// SIMD efficiency of the pass: useful iterations over iterations run.
    pub fn simd_efficiency(&self) -> Option<f64> {
        let n = self.useful + self.idle;
        (n > 0).then(|| self.useful as f64 / n as f64)
    }
}

/// One kernel's totals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct KernelTotals {
    /// Invocations (iterations, idle ones included).
    pub invocations: u64,
    /// Instructions.
    pub instructions: u64,
    /// State words read.
    pub state_read: u64,
    /// State words written.
    pub state_written: u64,
    /// Random-access words (measured, or the cost table's `m` per invocation).
    pub random_words: f64,
}

/// Totals by kernel, in [`Kernel::ALL`] order.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ByKernel(pub [KernelTotals; Kernel::COUNT]);

impl ByKernel {
    /// The totals of `k`.
    pub fn get_mut(&mut self, k: Kernel) -> &mut KernelTotals {
        &mut self.0[k as usize]
    }

    /// The totals of `k`.
    pub fn get(&self, k: Kernel) -> &KernelTotals {
        &self.0[k as usize]
    }

    /// Instructions of every kernel.
    pub fn instructions(&self) -> u64 {
        self.0.iter().map(|k| k.instructions).sum()
    }
}

/// Per-ray work, for Table 2's maxima and the optimal bound.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RayWork {
    /// Traversal steps.
    pub steps: u64,
    /// Triangle tests.
    pub intersections: u64,
    /// Traversal passes the ray needs at least (its runs of steps, each rounded up to
    /// the unroll factor).
    pub traverse_passes: u64,
    /// Intersection passes it needs at least.
    pub intersect_passes: u64,
}
