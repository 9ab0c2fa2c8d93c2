//! Per-ray work counters: Purcell 2002's scene statistics (his Table 2) come from these.

/// What one ray cost. Kernels count into a local copy and the driver adds it up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Grid voxels (or structure nodes) visited.
    pub voxels: u32,
    /// Voxels visited that held a non-empty triangle list.
    pub full_voxels: u32,
    /// Primitive-list entries read, including each list's null terminator.
    pub list_entries: u32,
    /// Ray–triangle intersection tests performed.
    pub tri_tests: u32,
}

impl RayCounters {
    /// Adds another ray's counters to these.
    pub fn add(&mut self, other: &RayCounters) {
        self.voxels += other.voxels;
        self.full_voxels += other.full_voxels;
        self.list_entries += other.list_entries;
        self.tri_tests += other.tri_tests;
    }
}
