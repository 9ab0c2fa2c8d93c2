//! Per-ray work counters: Purcell 2002's scene statistics (his Table 2) come from these.

/// What one ray cost. Kernels count into a local copy and the driver adds it up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Structure nodes visited: grid voxels, kd-tree or BVH nodes.
    pub nodes: u32,
    /// Of those, the ones whose triangles were tested: non-empty voxels, leaves.
    pub leaves: u32,
    /// Primitive-list entries read, including each list's null terminator.
    pub list_entries: u32,
    /// Ray–triangle intersection tests performed.
    pub tri_tests: u32,
}

impl RayCounters {
    /// Adds another ray's counters to these.
    pub fn add(&mut self, other: &RayCounters) {
        self.nodes = self.nodes.saturating_add(other.nodes);
        self.leaves = self.leaves.saturating_add(other.leaves);
        self.list_entries = self.list_entries.saturating_add(other.list_entries);
        self.tri_tests = self.tri_tests.saturating_add(other.tri_tests);
    }
}
