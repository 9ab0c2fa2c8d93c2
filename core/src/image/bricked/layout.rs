//! The fixed-layout records of a bricked scene's index.

use bytemuck::{Pod, Zeroable};

/// First eight bytes of a bricked scene file.
pub const BRICKED_MAGIC: [u8; 8] = *b"RPBRICK\0";
/// The bricked format version this crate reads.
pub const BRICKED_VERSION: u32 = 2;
/// Byte offset of [`BrickedHeader::index_checksum`].
pub const INDEX_CHECKSUM_OFFSET: usize = 100;

/// How each brick's bytes are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Codec {
    /// As they are: a stored brick is its scene image.
    None = 0,
    /// LZ4 block format (a frame-less block of the whole image).
    Lz4 = 1,
    /// Zstandard frame.
    Zstd = 2,
}

impl Codec {
    /// The codec numbered `v`, if known.
    pub fn from_u32(v: u32) -> Option<Codec> {
        match v {
            0 => Some(Codec::None),
            1 => Some(Codec::Lz4),
            2 => Some(Codec::Zstd),
            _ => None,
        }
    }

    /// Its name in messages and on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Codec::None => "none",
            Codec::Lz4 => "lz4",
            Codec::Zstd => "zstd",
        }
    }
}

/// The 128-byte header of a bricked scene file (offset 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BrickedHeader {
    /// [`BRICKED_MAGIC`].
    pub magic: [u8; 8],
    /// [`BRICKED_VERSION`].
    pub version: u32,
    /// No flags are defined: 0.
    pub flags: u32,
    /// Bricks (directory records and top-level list entries).
    pub brick_count: u32,
    /// Nodes of the top-level BVH.
    pub node_count: u32,
    /// Bytes of the index: header, directory, nodes, list and globals image (a multiple
    /// of 64); the bricks' bytes follow it.
    pub index_size: u64,
    /// Bytes of the whole file.
    pub total_size: u64,
    /// Triangles of the scene, each counted once (scene-wide ids run below it).
    pub triangle_count: u64,
    /// Vertices the bricks store, summed (a vertex shared by two bricks counts twice).
    pub vertex_count: u64,
    /// Start of the globals scene image (a multiple of 64).
    pub globals_offset: u64,
    /// Bytes of the globals scene image.
    pub globals_size: u64,
    /// Lower corner of the scene's bounds (every brick's vertices lie inside).
    pub bounds_min: [f32; 3],
    /// Upper corner.
    pub bounds_max: [f32; 3],
    /// The [`Codec`] every brick is stored with.
    pub codec: u32,
    /// CRC-32 of the index's bytes with these four taken as zero.
    pub index_checksum: u32,
    /// The largest brick's image size: the smallest cache that can hold any brick.
    pub max_brick_size: u64,
    /// The bricks' triangle counts summed: a triangle reaching across a split of the
    /// partition is held by every brick whose region it reaches into.
    pub reference_count: u64,
    /// Zero.
    pub reserved: [u32; 2],
}
const _: () = assert!(core::mem::size_of::<BrickedHeader>() == 128);
const _: () = assert!(core::mem::offset_of!(BrickedHeader, index_checksum) == INDEX_CHECKSUM_OFFSET);

/// One brick of the directory (64 bytes, from offset 128, in increasing `offset`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BrickRecord {
    /// Start of the stored bytes in the file (at or after the index).
    pub offset: u64,
    /// Stored (compressed) bytes.
    pub stored_size: u64,
    /// Bytes of the brick's scene image once decompressed.
    pub image_size: u64,
    /// CRC-32 of the stored bytes (checked before decompressing).
    pub checksum: u32,
    /// The brick's triangles.
    pub triangle_count: u32,
    /// Lower corner of the brick's vertices.
    pub bounds_min: [f32; 3],
    /// Upper corner.
    pub bounds_max: [f32; 3],
    /// The brick's vertices.
    pub vertex_count: u32,
    /// Zero.
    pub reserved: u32,
}
const _: () = assert!(core::mem::size_of::<BrickRecord>() == 64);
