//! [`SceneError`]: why a byte slice is not a valid scene image.

use core::fmt;

use super::header::SectionKind;
#[cfg(doc)]
use super::limits::IMAGE_ALIGN;
use super::limits::{MAX_TREE_DEPTH, MAX_WIDE_DEPTH, SECTION_ALIGN};

/// Why a byte slice is not a valid scene image. Each variant carries the values a reader
/// needs to see what is wrong (expected and found).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// The buffer is shorter than the header or than the size the header declares.
    Truncated {
        /// Bytes needed.
        needed: usize,
        /// Bytes present.
        len: usize,
    },
    /// The buffer does not start on an [`IMAGE_ALIGN`]-byte boundary.
    Misaligned {
        /// Address modulo the required alignment.
        offset: usize,
        /// Required alignment.
        required: usize,
    },
    /// The first eight bytes are not `RPSCENE\0`.
    BadMagic,
    /// A version this crate does not read.
    UnsupportedVersion {
        /// Version in the image.
        found: u32,
        /// Version this crate reads.
        supported: u32,
    },
    /// Reserved flag bits are set.
    UnknownFlags(u32),
    /// The acceleration-structure kind is unknown.
    UnknownAccel(u32),
    /// The stored checksum does not match the bytes.
    ChecksumMismatch {
        /// Checksum in the header.
        stored: u32,
        /// Checksum of the bytes.
        computed: u32,
    },
    /// The section table names a kind this version does not define.
    UnknownSection(u32),
    /// A section kind appears twice.
    DuplicateSection(SectionKind),
    /// A required section is absent.
    MissingSection(SectionKind),
    /// A section does not start on a 64-byte boundary.
    SectionMisaligned {
        /// Which section.
        section: SectionKind,
        /// Its offset.
        offset: u32,
    },
    /// A section reaches outside the image or into the header/table.
    SectionOutOfBounds {
        /// Which section.
        section: SectionKind,
        /// Its offset.
        offset: u32,
        /// Its size.
        size: u32,
        /// Image size.
        image_size: u32,
    },
    /// Two sections share bytes.
    SectionsOverlap(SectionKind, SectionKind),
    /// A section's byte size is not `count × record size`.
    SectionSize {
        /// Which section.
        section: SectionKind,
        /// Declared size.
        size: u32,
        /// Declared count.
        count: u32,
        /// Record size of this kind.
        record_size: u32,
    },
    /// A count disagrees with another (e.g. header triangle count vs TRIANGLES).
    CountMismatch {
        /// Which section.
        section: SectionKind,
        /// Expected record count.
        expected: u32,
        /// Count found.
        found: u32,
    },
    /// A record holds an index outside its target section.
    IndexOutOfRange {
        /// Section holding the bad index.
        section: SectionKind,
        /// Record number inside that section.
        record: u32,
        /// The index.
        value: u32,
        /// Exclusive upper limit.
        limit: u32,
    },
    /// A coordinate or parameter is NaN or infinite.
    NonFinite {
        /// Section holding it (POSITIONS, GRID; header bounds are reported as POSITIONS).
        section: SectionKind,
        /// Record number.
        record: u32,
    },
    /// A vertex lies outside the header's scene bounds, or the scene bounds outside the grid.
    OutOfBounds {
        /// Section holding it.
        section: SectionKind,
        /// Record number.
        record: u32,
    },
    /// A light record is out of place or impossible: an area light before another kind,
    /// a direction of zero length, an alias-table entry whose probabilities are not
    /// probabilities.
    BadLight {
        /// LIGHTS or LIGHT_ALIAS.
        section: SectionKind,
        /// The record.
        record: u32,
    },
    /// The grid's dimensions, cell count or cell size are impossible.
    BadGrid,
    /// The last primitive list is not terminated by a null entry.
    UnterminatedList,
    /// A grid cell's list does not start a list of its own: it begins inside another list
    /// or at an offset an earlier cell already uses. Lists shared between cells would let
    /// a small image cost a ray far more tests than the image has list entries.
    SharedList {
        /// The cell.
        cell: u32,
    },
    /// A texture's size, mipmap levels or texel range is impossible, or its wrap mode
    /// unknown.
    BadTexture {
        /// The texture.
        texture: u32,
    },
    /// A list that must be strictly increasing (a brick's TRIANGLE_IDS) is not.
    NotIncreasing {
        /// Which section.
        section: SectionKind,
        /// The first record not above its predecessor.
        record: u32,
    },
    /// A section that copies other data (TRI_BLOCKS copies vertices) disagrees with it.
    StaleCopy {
        /// Which section.
        section: SectionKind,
        /// The record.
        record: u32,
    },
    /// A tree node is malformed: a child not after its parent, a node referenced twice or
    /// never, a tree deeper than [`MAX_TREE_DEPTH`], a leaf range outside PRIM_LISTS,
    /// leaves whose ranges add up to more than PRIM_LISTS holds, an empty wide-BVH slot
    /// that is not exactly the empty encoding, or a NaN box or split.
    BadTree {
        /// BVH_NODES or KD_NODES.
        section: SectionKind,
        /// The node.
        node: u32,
    },
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SceneError::*;
        match *self {
            Truncated { needed, len } => write!(f, "truncated scene image: needs {needed} bytes, has {len}"),
            Misaligned { offset, required } => write!(
                f,
                "scene image buffer is misaligned: starts {offset} bytes past a {required}-byte boundary (use include_scene! or an aligned buffer)"
            ),
            BadMagic => write!(f, "not a raypipe scene image (bad magic)"),
            UnsupportedVersion { found, supported } => {
                write!(f, "unsupported scene image version {found} (this build reads version {supported})")
            }
            UnknownFlags(v) => write!(f, "scene image has unknown flags 0x{v:08x}"),
            UnknownAccel(v) => write!(f, "scene image has unknown acceleration structure kind {v}"),
            ChecksumMismatch { stored, computed } => write!(
                f,
                "scene image is corrupted: checksum 0x{stored:08x} stored, 0x{computed:08x} computed"
            ),
            UnknownSection(v) => write!(f, "scene image has unknown section kind {v}"),
            StaleCopy { section, record } => write!(
                f,
                "section {} record {record} does not match the data it copies",
                section.name()
            ),
            BadTexture { texture } => write!(f, "scene image texture {texture} has an impossible size, mipmap levels, texel range or wrap mode"),
            DuplicateSection(s) => write!(f, "scene image has section {} twice", s.name()),
            MissingSection(s) => write!(f, "scene image lacks required section {}", s.name()),
            SectionMisaligned { section, offset } => write!(
                f,
                "section {} at offset {offset} is not aligned to {SECTION_ALIGN} bytes",
                section.name()
            ),
            SectionOutOfBounds { section, offset, size, image_size } => write!(
                f,
                "section {} (offset {offset}, {size} bytes) lies outside the image ({image_size} bytes)",
                section.name()
            ),
            SectionsOverlap(a, b) => write!(f, "sections {} and {} overlap", a.name(), b.name()),
            SectionSize { section, size, count, record_size } => write!(
                f,
                "section {} is {size} bytes but holds {count} records of {record_size} bytes",
                section.name()
            ),
            CountMismatch { section, expected, found } => write!(
                f,
                "section {} holds {found} records, expected {expected}",
                section.name()
            ),
            IndexOutOfRange { section, record, value, limit } => write!(
                f,
                "section {} record {record} holds index {value}, limit is {limit}",
                section.name()
            ),
            NonFinite { section, record } => {
                write!(f, "section {} record {record} holds a NaN or infinite value", section.name())
            }
            OutOfBounds { section, record } => write!(
                f,
                "section {} record {record} lies outside the declared bounds",
                section.name()
            ),
            BadLight { section, record } => write!(
                f,
                "section {} record {record} is an impossible light (area lights come last; directions are not zero; alias probabilities lie in [0, 1])",
                section.name()
            ),
            BadGrid => write!(f, "grid dimensions, cell count or cell size are invalid"),
            NotIncreasing { section, record } => {
                write!(f, "section {} record {record} is not above the record before it", section.name())
            }
            UnterminatedList => write!(f, "primitive list section does not end with a null entry"),
            SharedList { cell } => {
                write!(f, "grid cell {cell} shares a primitive list with another cell (each cell needs its own list)")
            }
            BadTree { section, node } => {
                let depth = match section {
                    SectionKind::Bvh4Nodes | SectionKind::Bvh8Nodes => MAX_WIDE_DEPTH,
                    _ => MAX_TREE_DEPTH,
                };
                write!(
                    f,
                    "section {} node {node} is malformed (child order, sharing, depth above {depth}, leaf range or NaN)",
                    section.name()
                )
            }
        }
    }
}
