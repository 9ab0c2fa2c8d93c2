//! Why a bricked scene's index or one of its bricks was refused.

use core::fmt;

use crate::image::SceneError;

/// A malformed bricked index or brick. Every variant names what to look at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrickedError {
    /// The buffer is shorter than the index (or the file shorter than it says).
    Truncated {
        /// Bytes needed.
        needed: u64,
        /// Bytes present.
        len: u64,
    },
    /// The buffer does not start on a 16-byte boundary.
    Misaligned,
    /// Not a bricked scene file.
    BadMagic,
    /// A version this crate does not read.
    UnsupportedVersion(u32),
    /// Unknown header flags or a nonzero reserved field.
    Reserved,
    /// An unknown codec.
    UnknownCodec(u32),
    /// The index checksum does not match.
    ChecksumMismatch {
        /// Stored value.
        stored: u32,
        /// Computed value.
        computed: u32,
    },
    /// The index's parts (directory, nodes, list, globals) are out of place.
    BadLayout,
    /// A brick's bytes lie outside the file, before the end of the index, or overlap
    /// the brick before it (the directory is in file order).
    BrickOutOfPlace {
        /// The brick.
        brick: u32,
    },
    /// A brick record is impossible: empty, larger than an image may be, or with
    /// bounds that are not finite and ordered.
    BadBrick {
        /// The brick.
        brick: u32,
    },
    /// The bricks' triangle counts do not add up to the header's.
    CountMismatch,
    /// The top-level tree is malformed (child order, depth, NaN, or a leaf naming a
    /// brick that does not exist).
    BadTree {
        /// The node.
        node: u32,
    },
    /// The globals image is not a valid scene image without triangles.
    Globals(SceneError),
    /// A brick's stored bytes fail their checksum.
    BrickChecksum {
        /// The brick.
        brick: u32,
    },
    /// A decompressed brick is not a valid scene image.
    BrickImage {
        /// The brick.
        brick: u32,
        /// Why.
        error: SceneError,
    },
    /// A decompressed brick is a valid image that disagrees with its directory record
    /// (size, triangle count, bounds) or has no scene-wide triangle ids in range.
    BrickMismatch {
        /// The brick.
        brick: u32,
    },
}

impl fmt::Display for BrickedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use BrickedError::*;
        match *self {
            Truncated { needed, len } => write!(f, "truncated: {len} bytes, the index needs {needed}"),
            Misaligned => write!(f, "the buffer is not 16-byte aligned"),
            BadMagic => write!(f, "not a bricked scene (bad magic)"),
            UnsupportedVersion(v) => write!(f, "bricked format version {v} is not supported (this reads 1)"),
            Reserved => write!(f, "unknown flags or nonzero reserved fields in the header"),
            UnknownCodec(c) => write!(f, "unknown codec {c}"),
            ChecksumMismatch { stored, computed } => {
                write!(f, "index checksum mismatch (stored {stored:#010x}, computed {computed:#010x})")
            }
            BadLayout => write!(f, "the index's directory, nodes, list or globals image are out of place"),
            BrickOutOfPlace { brick } => {
                write!(f, "brick {brick} lies outside the file or overlaps the index or the brick before it")
            }
            BadBrick { brick } => write!(f, "brick {brick}'s directory record is impossible"),
            CountMismatch => write!(f, "the bricks' triangle counts do not add up to the header's"),
            BadTree { node } => write!(f, "top-level tree node {node} is malformed (order, depth, NaN or brick id)"),
            Globals(e) => write!(f, "globals image: {e}"),
            BrickChecksum { brick } => write!(f, "brick {brick} fails its checksum"),
            BrickImage { brick, error } => write!(f, "brick {brick}: {error}"),
            BrickMismatch { brick } => write!(f, "brick {brick} does not match its directory record"),
        }
    }
}
