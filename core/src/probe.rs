//! The one access path through which kernels read the scene image.
//!
//! [design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md): "every scene read is visible". Each accessor of [`crate::SceneView`] that a
//! kernel uses reports the byte address, byte count and data class of the read to a
//! [`MemoryProbe`]. The host passes [`NoProbe`], which compiles to nothing; the hardware
//! model passes a probe that feeds its caches and memory channel.

/// What kind of scene data a read touches; the hardware model accounts traffic per class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum DataClass {
    /// Acceleration-structure nodes: grid cells, kd-tree and BVH nodes.
    Nodes = 0,
    /// Primitive lists: the triangle indices a cell or leaf references.
    PrimLists = 1,
    /// Intersection data: triangle records and vertex positions.
    Triangles = 2,
    /// Shading data: normals, colours, texture coordinates, materials, lights.
    Shading = 3,
}

impl DataClass {
    /// Every class, in a fixed order (for reports).
    pub const ALL: [DataClass; 4] = [DataClass::Nodes, DataClass::PrimLists, DataClass::Triangles, DataClass::Shading];

    /// A short lower-case name for reports.
    pub const fn name(self) -> &'static str {
        match self {
            DataClass::Nodes => "nodes",
            DataClass::PrimLists => "prim_lists",
            DataClass::Triangles => "triangles",
            DataClass::Shading => "shading",
        }
    }
}

/// Observer of scene reads: `addr` is the byte offset inside the scene image.
pub trait MemoryProbe {
    /// Called once for every record a kernel reads.
    fn read(&mut self, class: DataClass, addr: u32, bytes: u32);
    /// Marks that the reads after this point depend on data read before it (a triangle
    /// record's vertices, a popped node's children): a hardware model issues them as a
    /// separate round trip. Costs nothing on the host.
    #[inline(always)]
    fn dependent(&mut self) {}
}

/// The probe that observes nothing and costs nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProbe;

impl MemoryProbe for NoProbe {
    #[inline(always)]
    fn read(&mut self, _class: DataClass, _addr: u32, _bytes: u32) {}
}

/// A probe that only counts bytes per class (useful for statistics and tests).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ByteCounter {
    /// Bytes read, indexed by `DataClass as usize`.
    pub bytes: [u64; 4],
    /// Reads issued, indexed by `DataClass as usize`.
    pub reads: [u64; 4],
}

impl MemoryProbe for ByteCounter {
    #[inline]
    fn read(&mut self, class: DataClass, _addr: u32, bytes: u32) {
        self.bytes[class as usize] += bytes as u64;
        self.reads[class as usize] += 1;
    }
}
