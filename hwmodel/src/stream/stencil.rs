//! The stencil buffer as the multipass machine's ray-state register (Purcell 2002 §3.2,
//! §4.1): one 8-bit value per fragment says which kernel the ray waits for. A pass sets
//! the stencil test to one stage, so only the fragments in that stage run the kernel
//! (early fragment kill) — but the test itself reads the stencil of every fragment the
//! pass covers, ray or no ray. A kernel that moves a ray to another stage writes its
//! stencil.

use serde::Serialize;

/// Which kernel a ray waits for (its stencil value).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[repr(u8)]
pub enum RayStage {
    /// No ray in this fragment (the eye ray missed the scene, or the stream is shorter
    /// than the screen).
    Inactive = 0,
    /// Waiting for a traversal step.
    Traverse = 1,
    /// Waiting to test the triangles of its voxel's list.
    Intersect = 2,
    /// Traversal is over (hit or miss): waiting for the shading kernel.
    Done = 3,
}

/// Stencil traffic of a pass or a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct StencilCounts {
    /// Stencil values read by the stencil test.
    pub reads: u64,
    /// Stencil values written (a ray changed stage).
    pub writes: u64,
}

impl StencilCounts {
    /// Adds another count.
    pub fn add(&mut self, o: &StencilCounts) {
        self.reads += o.reads;
        self.writes += o.writes;
    }
}

/// Fragments a pass over `rays` rays covers on a screen `width` wide: whole rows.
pub fn covered_fragments(rays: usize, width: u32) -> u64 {
    let w = width.max(1) as u64;
    (rays as u64).div_ceil(w) * w
}

/// The stencil buffer of one screen of the ray stream.
#[derive(Clone, Debug)]
pub struct Stencil {
    values: Vec<RayStage>,
    /// Fragments a pass covers (whole rows of the screen that hold rays).
    covered: u64,
    /// Traffic so far (taken by [`Stencil::take_counts`] after each pass).
    counts: StencilCounts,
}

impl Stencil {
    /// A stencil for `rays` fragments of a screen `width` wide: passes cover the rows
    /// that hold rays.
    pub fn new(rays: usize, width: u32) -> Stencil {
        Stencil {
            values: vec![RayStage::Inactive; rays],
            covered: covered_fragments(rays, width),
            counts: StencilCounts::default(),
        }
    }

    /// Fragments every pass covers.
    pub fn covered(&self) -> u64 {
        self.covered
    }

    /// The stencil test of one pass: reads every covered fragment's value.
    pub fn test_pass(&mut self) {
        self.counts.reads += self.covered;
    }

    /// The stage of fragment `i`.
    pub fn get(&self, i: usize) -> RayStage {
        self.values.get(i).copied().unwrap_or(RayStage::Inactive)
    }

    /// Moves fragment `i` to `stage`, writing the stencil if it changes.
    pub fn set(&mut self, i: usize, stage: RayStage) {
        if let Some(v) = self.values.get_mut(i) {
            if *v != stage {
                *v = stage;
                self.counts.writes += 1;
            }
        }
    }

    /// The traffic since the last call.
    pub fn take_counts(&mut self) -> StencilCounts {
        core::mem::take(&mut self.counts)
    }
}
