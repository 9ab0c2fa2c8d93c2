//! Why an instanced scene, its top level or one of its bottom images was refused.

use core::fmt;

use crate::image::SceneError;

/// A malformed instanced scene. Every variant names what to look at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstancedError {
    /// The buffer is shorter than the file says.
    Truncated {
        /// Bytes needed.
        needed: u64,
        /// Bytes present.
        len: u64,
    },
    /// The buffer does not start on a 64-byte boundary.
    Misaligned,
    /// Not an instanced scene file.
    BadMagic,
    /// A version this crate does not read.
    UnsupportedVersion(u32),
    /// Unknown header flags or a nonzero reserved field.
    Reserved,
    /// The index checksum does not match.
    ChecksumMismatch {
        /// Stored value.
        stored: u32,
        /// Computed value.
        computed: u32,
    },
    /// The index's parts (instances, directory, nodes, list, globals) are out of place.
    BadLayout,
    /// A bottom image lies outside the file, inside the index, off a 64-byte boundary,
    /// or overlaps the one before it (the directory is in file order).
    BottomOutOfPlace {
        /// The bottom image.
        bottom: u32,
    },
    /// A bottom image's directory record is impossible (empty, too large, bounds that
    /// are not finite and ordered).
    BadBottom {
        /// The bottom image.
        bottom: u32,
    },
    /// An instance is impossible: a transform that is not finite or whose stored inverse
    /// does not undo it (a singular map has none), a bottom or material that does not
    /// exist, or a world box that does not hold its bottom's box.
    BadInstance {
        /// The instance.
        instance: u32,
    },
    /// The instances' triangle counts do not add up to the header's.
    CountMismatch,
    /// The top-level tree is malformed (child order, depth, NaN, a leaf naming an
    /// instance that does not exist or a box that does not hold its instances).
    BadTree {
        /// The node.
        node: u32,
    },
    /// The globals image is not a valid scene image without triangles.
    Globals(SceneError),
    /// A bottom image is not a valid scene image.
    BottomImage {
        /// The bottom image.
        bottom: u32,
        /// Why.
        error: SceneError,
    },
    /// A bottom image is valid but disagrees with its directory record.
    BottomMismatch {
        /// The bottom image.
        bottom: u32,
    },
}

impl fmt::Display for InstancedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use InstancedError::*;
        match *self {
            Truncated { needed, len } => write!(f, "truncated: {len} bytes, the file needs {needed}"),
            Misaligned => write!(f, "the buffer is not 64-byte aligned"),
            BadMagic => write!(f, "not an instanced scene (bad magic)"),
            UnsupportedVersion(v) => write!(f, "instanced format version {v} is not supported (this reads 1)"),
            Reserved => write!(f, "unknown flags or nonzero reserved fields in the header"),
            ChecksumMismatch { stored, computed } => {
                write!(f, "index checksum mismatch (stored {stored:#010x}, computed {computed:#010x})")
            }
            BadLayout => write!(f, "the index's instances, directory, nodes, list or globals image are out of place"),
            BottomOutOfPlace { bottom } => {
                write!(f, "bottom image {bottom} lies outside the file or overlaps the index or the image before it")
            }
            BadBottom { bottom } => write!(f, "bottom image {bottom}'s directory record is impossible"),
            BadInstance { instance } => write!(
                f,
                "instance {instance} is impossible (a singular or non-finite transform, a missing bottom image or material, or a box that does not hold it)"
            ),
            CountMismatch => write!(f, "the instances' triangle counts do not add up to the header's"),
            BadTree { node } => {
                write!(f, "top-level tree node {node} is malformed (order, depth, NaN, instance id or box)")
            }
            Globals(e) => write!(f, "globals image: {e}"),
            BottomImage { bottom, error } => write!(f, "bottom image {bottom}: {error}"),
            BottomMismatch { bottom } => write!(f, "bottom image {bottom} does not match its directory record"),
        }
    }
}
