//! The fixed-layout records of an instanced scene file.

use bytemuck::{Pod, Zeroable};

/// First eight bytes of an instanced scene file.
pub const INSTANCED_MAGIC: [u8; 8] = *b"RPINSTC\0";
/// The instanced format version this crate reads.
pub const INSTANCED_VERSION: u32 = 1;
/// Byte offset of [`InstancedHeader::index_checksum`].
pub const INSTANCED_CHECKSUM_OFFSET: usize = 28;

/// The 128-byte header of an instanced scene file (offset 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct InstancedHeader {
    /// [`INSTANCED_MAGIC`].
    pub magic: [u8; 8],
    /// [`INSTANCED_VERSION`].
    pub version: u32,
    /// No flags are defined: 0.
    pub flags: u32,
    /// Instance records (and top-level list entries).
    pub instance_count: u32,
    /// Bottom-level images.
    pub bottom_count: u32,
    /// Nodes of the top-level BVH.
    pub node_count: u32,
    /// CRC-32 of the index (`0 .. index_size`) with these four bytes taken as zero.
    /// Each bottom image carries its own checksum.
    pub index_checksum: u32,
    /// Bytes of the index: header, instances, bottom directory, nodes, list and the
    /// globals image, a multiple of 64. The bottom images follow.
    pub index_size: u64,
    /// Bytes of the whole file.
    pub total_size: u64,
    /// Start of the globals scene image (a multiple of 64).
    pub globals_offset: u64,
    /// Bytes of the globals scene image.
    pub globals_size: u64,
    /// Lower corner of the world bounds (every instance's box lies inside).
    pub bounds_min: [f32; 3],
    /// Upper corner.
    pub bounds_max: [f32; 3],
    /// Triangles of the scene as drawn: each instance counts its bottom's triangles.
    pub triangle_count: u64,
    /// Triangles the bottom images store, summed (each once, however often instanced).
    pub stored_triangles: u64,
    /// Zero.
    pub reserved: [u32; 6],
}
const _: () = assert!(core::mem::size_of::<InstancedHeader>() == 128);
const _: () = assert!(core::mem::offset_of!(InstancedHeader, index_checksum) == INSTANCED_CHECKSUM_OFFSET);

/// One instance (128 bytes): a bottom-level image placed in the world by an affine map.
///
/// A transform is a 3×4 matrix in row-major order, `[m00 m01 m02 t0, m10 … t1, m20 … t2]`,
/// mapping `p` to `M p + t`. Rays enter the instance through `to_object`, so the hit's
/// parameter `t` is the same in both spaces ([`crate::math::affine`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct InstanceRecord {
    /// Object space to world space.
    pub to_world: [f32; 12],
    /// World space to object space: `to_world`'s inverse.
    pub to_object: [f32; 12],
    /// The bottom-level image this instance draws.
    pub bottom: u32,
    /// A material of the globals image that replaces the bottom's own on every
    /// triangle, or [`crate::image::NULL_INDEX`] for none.
    pub material: u32,
    /// Lower corner of the instance's world box (the bottom's bounds mapped to the world
    /// and rounded outward), which the top-level tree encloses.
    pub bounds_min: [f32; 3],
    /// Upper corner.
    pub bounds_max: [f32; 3],
}
const _: () = assert!(core::mem::size_of::<InstanceRecord>() == 128);

/// One bottom-level image of the directory (64 bytes): where its bytes are.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BottomRecord {
    /// Start of the image in the file (a multiple of 64, after the index).
    pub offset: u64,
    /// Bytes of the image.
    pub size: u64,
    /// Lower corner of the image's vertices, in object space.
    pub bounds_min: [f32; 3],
    /// Upper corner.
    pub bounds_max: [f32; 3],
    /// The image's triangles.
    pub triangle_count: u32,
    /// The image's vertices.
    pub vertex_count: u32,
    /// The image's structure ([`crate::image::AccelKind`] as a number).
    pub accel: u32,
    /// Zero.
    pub reserved: [u32; 3],
}
const _: () = assert!(core::mem::size_of::<BottomRecord>() == 64);

/// Where the index's parts lie for `instances` instances, `bottoms` bottom images and
/// `nodes` top-level nodes: the byte offsets of the instance records, the nodes and the
/// list, and the list's end (the globals image starts at the next 64-byte boundary). The
/// file's layout, and the addresses a driver holding a top level in memory reports its
/// reads at, so that a model sees the same memory either way.
pub const fn index_layout(instances: u32, bottoms: u32, nodes: u32) -> ([u32; 3], u64) {
    let dir_at = 128 + 128 * instances as u64;
    let nodes_at = dir_at + 64 * bottoms as u64;
    let list_at = nodes_at + 32 * nodes as u64;
    let list_end = list_at + 4 * instances as u64;
    // Labels past 4 GiB wrap (the index of a file that parses is far smaller).
    ([128, nodes_at as u32, list_at as u32], list_end)
}
