//! [`SceneView`]: the validated, zero-copy view of a scene image.

use core::fmt;

use bytemuck::Pod;
use glam::Vec3;

use super::crc32::Crc32;
use super::header::{
    AccelKind, Header, SectionEntry, SectionKind, CHECKSUM_OFFSET, FLAG_DEFAULT_LIGHT, FORMAT_VERSION, KNOWN_FLAGS,
    MAGIC,
};
use super::records::{
    Bvh4Node, Bvh8Node, BvhNode, CameraRecord, GridRecord, KdNode, LightAlias, LightRecord, MaterialRecord, Position,
    ShadingVertex, TextureRecord, TriBlock4, TriangleRecord, WaldTriangle, WideNode, NULL_INDEX,
};
use crate::probe::{DataClass, MemoryProbe};

/// Required alignment of the start of an image buffer, in bytes. Records need 4; 16
/// leaves room for SIMD-friendly records and matches what allocators return.
pub const IMAGE_ALIGN: usize = 16;
/// Every section starts at a multiple of this (one cache line).
pub const SECTION_ALIGN: u32 = 64;
/// Deepest binary tree (BVH or kd-tree) a scene image may hold: traversal kernels keep a
/// fixed-capacity stack of this many entries.
pub const MAX_TREE_DEPTH: u32 = 64;
/// Deepest wide (4- or 8-wide) BVH a scene image may hold. A wide walk's stack holds up
/// to `width − 1` entries per level, so this bounds its size: 100 entries (1.2 KB) for
/// the 4-wide BVH, where the binary trees' depth would take 196 (2.4 KB), over the
/// 2 KiB a firmware walk may use. Builders keep well inside it: the deepest wide BVH of
/// the shared scenes is 21 levels (the conference room's 4-wide), and a wide BVH
/// collapsed from a binary one is never deeper than that (`raypipe`'s builder rebuilds
/// the binary tree at most 31 deep in the rare case it would be).
pub const MAX_WIDE_DEPTH: u32 = 32;

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

/// The uniform grid of a scene image (Purcell 2002, Figure 4).
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a> {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
    /// Size of one cell.
    pub cell_size: Vec3,
    /// Cells per axis.
    pub dims: [u32; 3],
    cells: &'a [u32],
    lists: &'a [u32],
    cells_addr: u32,
    lists_addr: u32,
}

impl<'a> GridView<'a> {
    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    /// Number of primitive-list entries, terminators included.
    pub fn list_entry_count(&self) -> usize {
        self.lists.len()
    }

    /// Reads cell `index`: the offset of its list in PRIM_LISTS, or [`NULL_INDEX`].
    #[inline]
    pub fn cell<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::Nodes, self.cells_addr.wrapping_add(index.wrapping_mul(4)), 4);
        self.cells.get(index as usize).copied().unwrap_or(NULL_INDEX)
    }

    /// Reads primitive-list entry `pos`: a triangle index or [`NULL_INDEX`] (end of list).
    #[inline]
    pub fn list_entry<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.lists_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.lists.get(pos as usize).copied().unwrap_or(NULL_INDEX)
    }

    /// All cells, for statistics (not an observed kernel read).
    pub fn cells(&self) -> &'a [u32] {
        self.cells
    }
}

/// A bounding volume hierarchy of a scene image.
#[derive(Clone, Copy, Debug)]
pub struct BvhView<'a> {
    nodes: &'a [BvhNode],
    prims: &'a [u32],
    nodes_addr: u32,
    prims_addr: u32,
}

impl<'a> BvhView<'a> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// All nodes (for statistics; not an observed kernel read).
    pub fn nodes(&self) -> &'a [BvhNode] {
        self.nodes
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> BvhNode {
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.nodes.get(index as usize).copied().unwrap_or(BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 })
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

/// A wide (4- or 8-wide) BVH of a scene image.
#[derive(Clone, Copy, Debug)]
pub struct WideBvhView<'a, N: WideNode> {
    nodes: &'a [N],
    prims: &'a [u32],
    nodes_addr: u32,
    prims_addr: u32,
}

/// A 4-wide BVH of a scene image.
pub type Bvh4View<'a> = WideBvhView<'a, Bvh4Node>;
/// An 8-wide BVH of a scene image.
pub type Bvh8View<'a> = WideBvhView<'a, Bvh8Node>;

impl<'a, N: WideNode> WideBvhView<'a, N> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> &'a N {
        let size = core::mem::size_of::<N>() as u32;
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(size)), size);
        self.nodes.get(index as usize).unwrap_or_else(|| N::empty())
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

/// A kd-tree of a scene image; its root box is the scene bounds.
#[derive(Clone, Copy, Debug)]
pub struct KdTreeView<'a> {
    nodes: &'a [KdNode],
    prims: &'a [u32],
    nodes_addr: u32,
    prims_addr: u32,
    /// Lower corner of the root box.
    pub min: Vec3,
    /// Upper corner of the root box.
    pub max: Vec3,
}

impl<'a> KdTreeView<'a> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// All nodes (for statistics; not an observed kernel read).
    pub fn nodes(&self) -> &'a [KdNode] {
        self.nodes
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> KdNode {
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(8)), 8);
        self.nodes.get(index as usize).copied().unwrap_or(KdNode::leaf(0, 0))
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

impl crate::traverse::tree_step::PrimLists for BvhView<'_> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        BvhView::prim(self, pos, probe)
    }
}

impl<N: WideNode> crate::traverse::tree_step::PrimLists for WideBvhView<'_, N> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        WideBvhView::prim(self, pos, probe)
    }
}

impl crate::traverse::tree_step::PrimLists for KdTreeView<'_> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        KdTreeView::prim(self, pos, probe)
    }
}

/// The inner children of one tree node (at most eight: the 8-wide BVH).
type Children = heapless::Vec<u32, 8>;

/// Checks, with a fixed-capacity stack and no allocation, that `children(i)` describes a
/// tree rooted at node 0: every child comes after its parent and inside the section, no
/// path is `max_depth` nodes deep ([`MAX_TREE_DEPTH`] for binary trees, whose traversal
/// kernels' stacks hold one entry per level; [`MAX_WIDE_DEPTH`] for wide BVHs, seven
/// entries per level for the 8-wide one), and the walk visits exactly `n` nodes. `children(i)`
/// is `Err` for a malformed node, else the node's inner children (none for a leaf) and
/// the list entries its leaves hold; summed over every visit of the walk they may not
/// exceed `list_entries`.
///
/// That bounds the work of any ray on an accepted tree (docs/scene-format.md, "Work
/// bounds"): the walk visits each node at most once per path from the root, the paths
/// are exactly the visits counted here (at most `n`), so a ray takes at most `n` node
/// steps and tests at most `list_entries` list entries.
fn validate_tree(
    n: usize,
    section: SectionKind,
    max_depth: u32,
    list_entries: u64,
    mut children: impl FnMut(usize) -> Result<(Children, u64), ()>,
) -> Result<(), SceneError> {
    let bad = |node: usize| SceneError::BadTree { section, node: node as u32 };
    if n == 0 {
        return Err(bad(0));
    }
    // (node, depth); a depth-first walk pushes at most one more entry per level of a
    // binary tree, seven of an 8-wide one.
    const CAPACITY: usize = {
        let (binary, wide) = (MAX_TREE_DEPTH as usize + 1, 7 * MAX_WIDE_DEPTH as usize + 1);
        if binary > wide {
            binary
        } else {
            wide
        }
    };
    let mut stack: heapless::Vec<(u32, u32), CAPACITY> = heapless::Vec::new();
    let _ = stack.push((0, 0));
    let mut visited = 0usize;
    let mut leaf_entries = 0u64;
    while let Some((i, depth)) = stack.pop() {
        let i = i as usize;
        visited += 1;
        if visited > n || depth >= max_depth {
            return Err(bad(i));
        }
        let (inner, entries) = children(i).map_err(|_| bad(i))?;
        leaf_entries += entries;
        if leaf_entries > list_entries {
            return Err(bad(i));
        }
        for c in inner {
            if c as usize <= i || c as usize >= n || stack.push((c, depth + 1)).is_err() {
                return Err(bad(i));
            }
        }
    }
    if visited != n {
        return Err(bad(n - 1));
    }
    Ok(())
}

/// The two adjacent children `c` and `c + 1` of a binary inner node.
fn pair(c: u32) -> Children {
    Children::from_iter([c, c.wrapping_add(1)])
}

/// The scene bounds grown by a margin (1e-5 of the extent plus a few ulps of the
/// coordinates), as the builders grow their boxes: a box that a kernel's rounding cannot
/// make a hit fall outside of.
fn grow_bounds(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let pad = 1e-5 * (hi - lo).max_element() + 8.0 * f32::EPSILON * lo.abs().max(hi.abs()).max_element();
    (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
}

/// A validated scene image, borrowed in place. Cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct SceneView<'a> {
    header: &'a Header,
    bytes: &'a [u8],
    positions: &'a [Position],
    triangles: &'a [TriangleRecord],
    grid: Option<GridView<'a>>,
    bvh: Option<BvhView<'a>>,
    bvh4: Option<Bvh4View<'a>>,
    bvh8: Option<Bvh8View<'a>>,
    kd: Option<KdTreeView<'a>>,
    // Every tree keeps its leaves' triangle ids here (validated with the tree).
    prim_lists: &'a [u32],
    shading: &'a [ShadingVertex],
    wald: &'a [WaldTriangle],
    tri_blocks: &'a [TriBlock4],
    tri_materials: &'a [u32],
    materials: &'a [MaterialRecord],
    tri_objects: &'a [u32],
    textures: &'a [TextureRecord],
    texels: &'a [u32],
    lights: &'a [LightRecord],
    area_lights: u32,
    light_alias: &'a [LightAlias],
    camera: Option<&'a CameraRecord>,
    positions_addr: u32,
    triangles_addr: u32,
    shading_addr: u32,
    tri_materials_addr: u32,
    materials_addr: u32,
    texels_addr: u32,
    lights_addr: u32,
    light_alias_addr: u32,
    prim_lists_addr: u32,
    wald_addr: u32,
    tri_blocks_addr: u32,
}

struct Sections<'a> {
    entries: [Option<SectionEntry>; SectionKind::ALL.len()],
    bytes: &'a [u8],
}

impl<'a> Sections<'a> {
    fn entry(&self, kind: SectionKind) -> Option<SectionEntry> {
        self.entries[kind as usize - 1]
    }

    fn count(&self, kind: SectionKind) -> u32 {
        self.entry(kind).map_or(0, |e| e.count)
    }

    fn addr(&self, kind: SectionKind) -> u32 {
        self.entry(kind).map_or(0, |e| e.offset)
    }

    /// The records of a section, or an empty slice when it is absent.
    fn slice<T: Pod>(&self, kind: SectionKind) -> Result<&'a [T], SceneError> {
        let Some(e) = self.entry(kind) else { return Ok(&[]) };
        let start = e.offset as usize;
        let raw = self
            .bytes
            .get(start..start + e.size as usize)
            .ok_or(SceneError::Truncated { needed: start + e.size as usize, len: self.bytes.len() })?;
        bytemuck::try_cast_slice(raw).map_err(|_| SceneError::SectionMisaligned { section: kind, offset: e.offset })
    }

    fn required<T: Pod>(&self, kind: SectionKind) -> Result<&'a [T], SceneError> {
        if self.entry(kind).is_none() {
            return Err(SceneError::MissingSection(kind));
        }
        self.slice(kind)
    }
}

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

impl<'a> SceneView<'a> {
    /// Validates `bytes` once — magic, version, checksum, section bounds and alignment,
    /// counts, every offset and index — and returns a view that kernels can use without
    /// any further check. `bytes` may be longer than the image (e.g. a flash partition).
    pub fn parse(bytes: &'a [u8]) -> Result<SceneView<'a>, SceneError> {
        let head = bytes.get(..64).ok_or(SceneError::Truncated { needed: 64, len: bytes.len() })?;
        let misalign = bytes.as_ptr() as usize % IMAGE_ALIGN;
        if misalign != 0 {
            return Err(SceneError::Misaligned { offset: misalign, required: IMAGE_ALIGN });
        }
        let header: &Header = bytemuck::try_from_bytes(head)
            .map_err(|_| SceneError::Misaligned { offset: misalign, required: IMAGE_ALIGN })?;
        if header.magic != MAGIC {
            return Err(SceneError::BadMagic);
        }
        if header.version != FORMAT_VERSION {
            return Err(SceneError::UnsupportedVersion { found: header.version, supported: FORMAT_VERSION });
        }
        let total = header.total_size as usize;
        if bytes.len() < total || total < 64 {
            return Err(SceneError::Truncated { needed: total.max(64), len: bytes.len() });
        }
        let bytes = &bytes[..total];
        let mut crc = Crc32::default();
        crc.update(&bytes[..CHECKSUM_OFFSET]);
        crc.update(&[0; 4]);
        crc.update(&bytes[CHECKSUM_OFFSET + 4..]);
        let computed = crc.finish();
        if computed != header.checksum {
            return Err(SceneError::ChecksumMismatch { stored: header.checksum, computed });
        }
        if header.flags & !KNOWN_FLAGS != 0 {
            return Err(SceneError::UnknownFlags(header.flags & !KNOWN_FLAGS));
        }
        let accel = AccelKind::from_u32(header.accel).ok_or(SceneError::UnknownAccel(header.accel))?;

        let sections = Self::parse_table(header, bytes)?;
        Self::from_sections(header, bytes, &sections, accel)
    }

    fn parse_table(header: &Header, bytes: &'a [u8]) -> Result<Sections<'a>, SceneError> {
        // In u64 and then checked: `64 + 16 n` overflows a 32-bit usize for a crafted count.
        let table_end = 64 + 16 * header.section_count as u64;
        let table_end = usize::try_from(table_end).unwrap_or(usize::MAX);
        let table_bytes =
            bytes.get(64..table_end).ok_or(SceneError::Truncated { needed: table_end, len: bytes.len() })?;
        let table: &[SectionEntry] = bytemuck::try_cast_slice(table_bytes)
            .map_err(|_| SceneError::Misaligned { offset: 0, required: IMAGE_ALIGN })?;
        let mut entries = [None; SectionKind::ALL.len()];
        for e in table {
            let kind = SectionKind::from_u32(e.kind).ok_or(SceneError::UnknownSection(e.kind))?;
            let slot = &mut entries[kind as usize - 1];
            if slot.is_some() {
                return Err(SceneError::DuplicateSection(kind));
            }
            if e.offset % SECTION_ALIGN != 0 {
                return Err(SceneError::SectionMisaligned { section: kind, offset: e.offset });
            }
            let end = e.offset as u64 + e.size as u64;
            if (e.offset as usize) < table_end || end > bytes.len() as u64 {
                return Err(SceneError::SectionOutOfBounds {
                    section: kind,
                    offset: e.offset,
                    size: e.size,
                    image_size: bytes.len() as u32,
                });
            }
            if e.count as u64 * kind.record_size() as u64 != e.size as u64 {
                return Err(SceneError::SectionSize {
                    section: kind,
                    size: e.size,
                    count: e.count,
                    record_size: kind.record_size(),
                });
            }
            *slot = Some(*e);
        }
        // No two sections may share a byte.
        for (i, a) in entries.iter().enumerate() {
            for b in entries.iter().skip(i + 1) {
                if let (Some(a), Some(b)) = (a, b) {
                    let (a0, a1) = (a.offset as u64, a.offset as u64 + a.size as u64);
                    let (b0, b1) = (b.offset as u64, b.offset as u64 + b.size as u64);
                    if a.size > 0 && b.size > 0 && a0 < b1 && b0 < a1 {
                        let ka = SectionKind::from_u32(a.kind).unwrap_or(SectionKind::Positions);
                        let kb = SectionKind::from_u32(b.kind).unwrap_or(SectionKind::Positions);
                        return Err(SceneError::SectionsOverlap(ka, kb));
                    }
                }
            }
        }
        Ok(Sections { entries, bytes })
    }

    fn from_sections(
        header: &'a Header,
        bytes: &'a [u8],
        s: &Sections<'a>,
        accel: AccelKind,
    ) -> Result<SceneView<'a>, SceneError> {
        use SectionKind as K;
        let positions: &[Position] = s.required(K::Positions)?;
        let triangles: &[TriangleRecord] = s.required(K::Triangles)?;
        let nv = positions.len() as u32;
        let nt = triangles.len() as u32;
        if header.vertex_count != nv {
            return Err(SceneError::CountMismatch { section: K::Positions, expected: header.vertex_count, found: nv });
        }
        if header.triangle_count != nt {
            return Err(SceneError::CountMismatch {
                section: K::Triangles,
                expected: header.triangle_count,
                found: nt,
            });
        }

        // Geometry: finite, inside the declared bounds, indices in range.
        if !finite3(header.bounds_min) || !finite3(header.bounds_max) {
            return Err(SceneError::NonFinite { section: K::Positions, record: u32::MAX });
        }
        let (bmin, bmax) = (Vec3::from(header.bounds_min), Vec3::from(header.bounds_max));
        if nv > 0 && !bmin.cmple(bmax).all() {
            return Err(SceneError::OutOfBounds { section: K::Positions, record: u32::MAX });
        }
        for (i, p) in positions.iter().enumerate() {
            if !finite3(p.0) {
                return Err(SceneError::NonFinite { section: K::Positions, record: i as u32 });
            }
            let v = Vec3::from(p.0);
            if !(v.cmpge(bmin).all() && v.cmple(bmax).all()) {
                return Err(SceneError::OutOfBounds { section: K::Positions, record: i as u32 });
            }
        }
        for (i, t) in triangles.iter().enumerate() {
            if let Some(&bad) = t.0.iter().find(|&&x| x >= nv) {
                return Err(SceneError::IndexOutOfRange {
                    section: K::Triangles,
                    record: i as u32,
                    value: bad,
                    limit: nv,
                });
            }
        }

        let (mut grid, mut bvh, mut kd, mut bvh4, mut bvh8) = (None, None, None, None, None);
        match accel {
            AccelKind::None => {}
            AccelKind::Grid => grid = Some(Self::validate_grid(s, nt, bmin, bmax)?),
            AccelKind::Bvh => bvh = Some(Self::validate_bvh(s, nt)?),
            AccelKind::KdTree => kd = Some(Self::validate_kd(s, nt, bmin, bmax)?),
            AccelKind::Bvh4 => bvh4 = Some(Self::validate_wide(s, nt)?),
            AccelKind::Bvh8 => bvh8 = Some(Self::validate_wide(s, nt)?),
        }

        // Shading data: optional, but when present it must match the geometry.
        // An optional section with one record per vertex or triangle: absent, or all.
        let one_each = |section: SectionKind, found: usize, expected: u32| {
            if found != 0 && found as u32 != expected {
                return Err(SceneError::CountMismatch { section, expected, found: found as u32 });
            }
            Ok(())
        };
        let shading: &[ShadingVertex] = s.slice(K::ShadingVertices)?;
        one_each(K::ShadingVertices, shading.len(), nv)?;
        let materials: &[MaterialRecord] = s.slice(K::Materials)?;
        let tri_materials: &[u32] = s.slice(K::TriangleMaterials)?;
        one_each(K::TriangleMaterials, tri_materials.len(), nt)?;
        let nm = materials.len() as u32;
        for (i, &m) in tri_materials.iter().enumerate() {
            if m >= nm {
                return Err(SceneError::IndexOutOfRange {
                    section: K::TriangleMaterials,
                    record: i as u32,
                    value: m,
                    limit: nm,
                });
            }
        }
        let tri_objects: &[u32] = s.slice(K::TriangleObjects)?;
        one_each(K::TriangleObjects, tri_objects.len(), nt)?;
        let textures: &[TextureRecord] = s.slice(K::Textures)?;
        let texels: &[u32] = s.slice(K::Texels)?;
        for (i, t) in textures.iter().enumerate() {
            let levels_ok = t.levels >= 1 && t.levels <= TextureRecord::full_chain(t.width, t.height);
            let end = t.first as u64 + TextureRecord::chain_texels(t.width, t.height, t.levels);
            if t.width == 0 || t.height == 0 || !levels_ok || end > texels.len() as u64 || t.wrap > TextureRecord::CLAMP
            {
                return Err(SceneError::BadTexture { texture: i as u32 });
            }
        }
        for (i, m) in materials.iter().enumerate() {
            if m.texture != NULL_INDEX && m.texture >= textures.len() as u32 {
                return Err(SceneError::IndexOutOfRange {
                    section: K::Materials,
                    record: i as u32,
                    value: m.texture,
                    limit: textures.len() as u32,
                });
            }
        }
        let wald: &[WaldTriangle] = s.slice(K::WaldTriangles)?;
        if !wald.is_empty() && wald.len() as u32 != nt {
            return Err(SceneError::CountMismatch {
                section: K::WaldTriangles,
                expected: nt,
                found: wald.len() as u32,
            });
        }
        for (i, w) in wald.iter().enumerate() {
            let vals = [w.n_u, w.n_v, w.n_d, w.b_nu, w.b_nv, w.b_d, w.n_scale, w.c_nu, w.c_nv, w.c_d];
            if w.k > 3 || vals.iter().any(|v| !v.is_finite()) {
                return Err(SceneError::NonFinite { section: K::WaldTriangles, record: i as u32 });
            }
        }
        let prim_lists: &[u32] = s.slice(K::PrimLists)?;
        let tri_blocks: &[TriBlock4] = s.slice(K::TriBlocks)?;
        Self::validate_tri_blocks(tri_blocks, prim_lists, triangles, positions)?;
        let lights: &[LightRecord] = s.slice(K::Lights)?;
        let area_lights = lights.iter().filter(|l| l.kind == LightRecord::AREA).count() as u32;
        let bad_light = |record: usize| SceneError::BadLight { section: K::Lights, record: record as u32 };
        for (i, l) in lights.iter().enumerate() {
            if l.kind > LightRecord::MAX_KIND {
                return Err(SceneError::IndexOutOfRange {
                    section: K::Lights,
                    record: i as u32,
                    value: l.kind,
                    limit: LightRecord::MAX_KIND + 1,
                });
            }
            if l.kind == LightRecord::AREA && l.triangle >= nt {
                return Err(SceneError::IndexOutOfRange {
                    section: K::Lights,
                    record: i as u32,
                    value: l.triangle,
                    limit: nt,
                });
            }
            if !(l.position.iter().chain(&l.color).all(|v| v.is_finite())) {
                return Err(SceneError::NonFinite { section: K::Lights, record: i as u32 });
            }
            // The area lights are the tail: the point-light shaders stop before them.
            if l.kind != LightRecord::AREA && i >= lights.len() - area_lights as usize {
                return Err(bad_light(i));
            }
            if l.kind == LightRecord::DIRECTIONAL && l.position == [0.0; 3] {
                return Err(bad_light(i));
            }
        }
        let light_alias: &[LightAlias] = s.slice(K::LightAlias)?;
        if !light_alias.is_empty() && light_alias.len() != area_lights as usize {
            return Err(SceneError::CountMismatch {
                section: K::LightAlias,
                expected: area_lights,
                found: light_alias.len() as u32,
            });
        }
        for (i, a) in light_alias.iter().enumerate() {
            let probability = |p: f32| (0.0..=1.0).contains(&p);
            if !(probability(a.keep) && probability(a.pdf) && probability(a.alias_pdf)) || a.alias >= area_lights {
                return Err(SceneError::BadLight { section: K::LightAlias, record: i as u32 });
            }
        }
        let cameras: &[CameraRecord] = s.slice(K::Camera)?;
        if cameras.len() > 1 {
            return Err(SceneError::CountMismatch { section: K::Camera, expected: 1, found: cameras.len() as u32 });
        }

        Ok(SceneView {
            header,
            bytes,
            positions,
            triangles,
            grid,
            bvh,
            bvh4,
            bvh8,
            kd,
            prim_lists,
            shading,
            wald,
            tri_blocks,
            tri_materials,
            tri_objects,
            materials,
            textures,
            texels,
            lights,
            area_lights,
            light_alias,
            camera: cameras.first(),
            positions_addr: s.addr(K::Positions),
            triangles_addr: s.addr(K::Triangles),
            shading_addr: s.addr(K::ShadingVertices),
            tri_materials_addr: s.addr(K::TriangleMaterials),
            materials_addr: s.addr(K::Materials),
            texels_addr: s.addr(K::Texels),
            lights_addr: s.addr(K::Lights),
            light_alias_addr: s.addr(K::LightAlias),
            wald_addr: s.addr(K::WaldTriangles),
            tri_blocks_addr: s.addr(K::TriBlocks),
            prim_lists_addr: s.addr(K::PrimLists),
        })
    }

    /// TRI_BLOCKS, when present, covers PRIM_LISTS in blocks of four and holds exactly
    /// the vertices of the triangles listed there: a leaf tested from its blocks then
    /// gives the bits it gives tested through the lists (lanes past the lists' end are
    /// never tested).
    fn validate_tri_blocks(
        blocks: &[TriBlock4],
        prims: &[u32],
        triangles: &[TriangleRecord],
        positions: &[Position],
    ) -> Result<(), SceneError> {
        use SectionKind as K;
        if blocks.is_empty() {
            return Ok(());
        }
        const LANES: usize = TriBlock4::LANES;
        let expected = prims.len().div_ceil(LANES) as u32;
        if blocks.len() as u32 != expected {
            return Err(SceneError::CountMismatch { section: K::TriBlocks, expected, found: blocks.len() as u32 });
        }
        for (e, &prim) in prims.iter().enumerate() {
            let (record, lane) = (e / LANES, e % LANES);
            let stale = SceneError::StaleCopy { section: K::TriBlocks, record: record as u32 };
            let block = blocks.get(record).ok_or(stale)?;
            // A list terminator (grid lists): no triangle to copy.
            let Some(tri) = triangles.get(prim as usize) else { continue };
            let same = (0..3).all(|i| {
                let p = positions.get(tri.0[i] as usize).map_or([f32::NAN; 3], |p| p.0);
                (0..3).all(|a| block.v[i][a][lane].to_bits() == p[a].to_bits())
            });
            if !same {
                return Err(stale);
            }
        }
        Ok(())
    }

    fn validate_grid(s: &Sections<'a>, nt: u32, bmin: Vec3, bmax: Vec3) -> Result<GridView<'a>, SceneError> {
        use SectionKind as K;
        let rec: &[GridRecord] = s.required(K::Grid)?;
        let rec = rec.first().ok_or(SceneError::CountMismatch { section: K::Grid, expected: 1, found: 0 })?;
        if s.count(K::Grid) != 1 {
            return Err(SceneError::CountMismatch { section: K::Grid, expected: 1, found: s.count(K::Grid) });
        }
        if !finite3(rec.bounds_min) || !finite3(rec.bounds_max) || !finite3(rec.cell_size) {
            return Err(SceneError::NonFinite { section: K::Grid, record: 0 });
        }
        let cells_expected = rec.dims.iter().try_fold(1u32, |acc, &d| if d == 0 { None } else { acc.checked_mul(d) });
        let cell_count = match cells_expected {
            Some(c) if c == rec.cell_count && c < NULL_INDEX => c,
            _ => return Err(SceneError::BadGrid),
        };
        let (gmin, gmax, cs) = (Vec3::from(rec.bounds_min), Vec3::from(rec.bounds_max), Vec3::from(rec.cell_size));
        if !cs.cmpgt(Vec3::ZERO).all() || !gmin.cmplt(gmax).all() || rec.dims.iter().any(|&d| d > (1 << 24)) {
            return Err(SceneError::BadGrid);
        }
        if !(gmin.cmple(bmin).all() && gmax.cmpge(bmax).all()) {
            return Err(SceneError::OutOfBounds { section: K::Grid, record: 0 });
        }
        let cells: &[u32] = s.required(K::GridCells)?;
        if cells.len() as u32 != cell_count {
            return Err(SceneError::CountMismatch {
                section: K::GridCells,
                expected: cell_count,
                found: cells.len() as u32,
            });
        }
        let lists: &[u32] = s.required(K::PrimLists)?;
        let nl = lists.len() as u32;
        // Each full cell starts its own list: offsets grow from cell to cell and each one
        // follows a terminator (or is 0). So the lists a ray's cells hold are disjoint, and
        // a ray tests at most as many entries as the section holds (docs/scene-format.md,
        // "Work bounds").
        let mut next_free = 0u32;
        for (i, &c) in cells.iter().enumerate() {
            if c == NULL_INDEX {
                continue;
            }
            if c >= nl {
                return Err(SceneError::IndexOutOfRange {
                    section: K::GridCells,
                    record: i as u32,
                    value: c,
                    limit: nl,
                });
            }
            let starts_a_list = c == 0 || lists.get(c as usize - 1) == Some(&NULL_INDEX);
            if c < next_free || !starts_a_list {
                return Err(SceneError::SharedList { cell: i as u32 });
            }
            next_free = c + 1;
        }
        // A walk from any offset ends at a null entry inside the section because the last
        // entry is null; every other entry must name a triangle.
        if lists.last().is_some_and(|&l| l != NULL_INDEX) {
            return Err(SceneError::UnterminatedList);
        }
        for (i, &e) in lists.iter().enumerate() {
            if e != NULL_INDEX && e >= nt {
                return Err(SceneError::IndexOutOfRange {
                    section: K::PrimLists,
                    record: i as u32,
                    value: e,
                    limit: nt,
                });
            }
        }
        Ok(GridView {
            min: gmin,
            max: gmax,
            cell_size: cs,
            dims: rec.dims,
            cells,
            lists,
            cells_addr: s.addr(K::GridCells),
            lists_addr: s.addr(K::PrimLists),
        })
    }

    fn prim_list(s: &Sections<'a>, nt: u32) -> Result<&'a [u32], SceneError> {
        let prims: &[u32] = s.required(SectionKind::PrimLists)?;
        for (i, &e) in prims.iter().enumerate() {
            if e >= nt {
                return Err(SceneError::IndexOutOfRange {
                    section: SectionKind::PrimLists,
                    record: i as u32,
                    value: e,
                    limit: nt,
                });
            }
        }
        Ok(prims)
    }

    fn validate_bvh(s: &Sections<'a>, nt: u32) -> Result<BvhView<'a>, SceneError> {
        let nodes: &[BvhNode] = s.required(SectionKind::BvhNodes)?;
        let prims = Self::prim_list(s, nt)?;
        let np = prims.len() as u64;
        validate_tree(nodes.len(), SectionKind::BvhNodes, MAX_TREE_DEPTH, np, |i| {
            let n = nodes.get(i).ok_or(())?;
            let (lo, hi) = (Vec3::from(n.min), Vec3::from(n.max));
            if !(finite3(n.min) && finite3(n.max) && lo.cmple(hi).all()) {
                return Err(());
            }
            if n.count == 0 {
                Ok((pair(n.first), 0))
            } else if n.first as u64 + n.count as u64 <= np {
                Ok((Children::new(), n.count as u64))
            } else {
                Err(())
            }
        })?;
        Ok(BvhView {
            nodes,
            prims,
            nodes_addr: s.addr(SectionKind::BvhNodes),
            prims_addr: s.addr(SectionKind::PrimLists),
        })
    }

    fn validate_kd(s: &Sections<'a>, nt: u32, bmin: Vec3, bmax: Vec3) -> Result<KdTreeView<'a>, SceneError> {
        // The root box is the scene bounds grown like the builders grow their boxes, so a
        // hit that rounding puts a hair outside the bounds is not clipped away.
        let (rmin, rmax) = grow_bounds(bmin, bmax);
        let nodes: &[KdNode] = s.required(SectionKind::KdNodes)?;
        let prims = Self::prim_list(s, nt)?;
        let np = prims.len() as u64;
        validate_tree(nodes.len(), SectionKind::KdNodes, MAX_TREE_DEPTH, np, |i| {
            let n = nodes.get(i).ok_or(())?;
            if n.axis() == KdNode::LEAF {
                if n.index() as u64 + n.value as u64 <= np {
                    Ok((Children::new(), n.value as u64))
                } else {
                    Err(())
                }
            } else if n.split().is_finite() {
                Ok((pair(n.index()), 0))
            } else {
                Err(())
            }
        })?;
        Ok(KdTreeView {
            nodes,
            prims,
            nodes_addr: s.addr(SectionKind::KdNodes),
            prims_addr: s.addr(SectionKind::PrimLists),
            min: rmin,
            max: rmax,
        })
    }

    fn validate_wide<N: WideNode>(s: &Sections<'a>, nt: u32) -> Result<WideBvhView<'a, N>, SceneError> {
        let section = N::SECTION;
        let nodes: &[N] = s.required(section)?;
        let prims = Self::prim_list(s, nt)?;
        let np = prims.len() as u64;
        validate_tree(nodes.len(), section, MAX_WIDE_DEPTH, np, |i| {
            let node = nodes.get(i).ok_or(())?;
            let mut inner = Children::new();
            let mut entries = 0u64;
            for k in 0..N::WIDTH {
                let (lo, hi, c, count) = node.slot(k);
                if !(finite3(lo) && finite3(hi)) {
                    return Err(());
                }
                if c == NULL_INDEX {
                    // Empty slots are exactly the builder's encoding: the most inverted box
                    // (which no slab test accepts, however it grows a box) and no leaf. An
                    // almost-inverted box with a count would be entered as a leaf of up to
                    // 2^32 entries.
                    if lo != [f32::MAX; 3] || hi != [-f32::MAX; 3] || count != 0 {
                        return Err(());
                    }
                } else if !Vec3::from(lo).cmple(Vec3::from(hi)).all() {
                    return Err(());
                } else if count > 0 {
                    if c as u64 + count as u64 > np {
                        return Err(());
                    }
                    entries += count as u64;
                } else if inner.push(c).is_err() {
                    return Err(());
                }
            }
            Ok((inner, entries))
        })?;
        Ok(WideBvhView { nodes, prims, nodes_addr: s.addr(section), prims_addr: s.addr(SectionKind::PrimLists) })
    }

    /// Entries of PRIM_LISTS, the list the trees' leaves index (0 without a tree). A ray
    /// through any tree tests at most this many triangles (the parse bounds the leaves).
    pub fn prim_list_len(&self) -> usize {
        self.prim_lists.len()
    }

    /// The 8-wide BVH, if the image holds one.
    pub fn bvh8(&self) -> Option<&Bvh8View<'a>> {
        self.bvh8.as_ref()
    }

    /// The 4-wide BVH, if the image holds one.
    pub fn bvh4(&self) -> Option<&Bvh4View<'a>> {
        self.bvh4.as_ref()
    }

    /// The BVH, if the image holds one.
    pub fn bvh(&self) -> Option<&BvhView<'a>> {
        self.bvh.as_ref()
    }

    /// The kd-tree, if the image holds one.
    pub fn kdtree(&self) -> Option<&KdTreeView<'a>> {
        self.kd.as_ref()
    }

    /// The header.
    pub fn header(&self) -> &'a Header {
        self.header
    }

    /// The image's bytes (exactly `total_size` of them).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Which acceleration structure the image holds.
    pub fn accel(&self) -> AccelKind {
        AccelKind::from_u32(self.header.accel).unwrap_or(AccelKind::None)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> u32 {
        self.triangles.len() as u32
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> u32 {
        self.positions.len() as u32
    }

    /// Scene bounds from the header.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (Vec3::from(self.header.bounds_min), Vec3::from(self.header.bounds_max))
    }

    /// The scene bounds grown by the builders' margin: the box for Purcell's early
    /// bounding-box test, which must never end a ray that a kernel would report a hit for.
    pub fn test_bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.bounds();
        grow_bounds(lo, hi)
    }

    /// The uniform grid, if the image holds one.
    pub fn grid(&self) -> Option<&GridView<'a>> {
        self.grid.as_ref()
    }

    /// The default camera record, if the image holds one.
    pub fn camera(&self) -> Option<&'a CameraRecord> {
        self.camera
    }

    /// Number of lights.
    pub fn light_count(&self) -> u32 {
        self.lights.len() as u32
    }

    /// Number of area lights (emissive triangles), counted at parse. They are the last
    /// lights: area light `k` is light `shading_light_count() + k`.
    pub fn area_light_count(&self) -> u32 {
        self.area_lights
    }

    /// Number of lights before the area lights: all that ray casting, the shadow caster
    /// and Whitted's shader read (their cost does not grow with the emitters).
    pub fn shading_light_count(&self) -> u32 {
        self.lights.len() as u32 - self.area_lights
    }

    /// Picks an area light with probability proportional to its power from two uniform
    /// numbers in `[0, 1)` (one read of the alias table; uniformly without one): the
    /// area-light number and the probability it had. `None` without area lights.
    #[inline]
    pub fn pick_area_light<P: MemoryProbe>(&self, u: f32, v: f32, probe: &mut P) -> Option<(u32, f32)> {
        let n = self.area_lights;
        if n == 0 {
            return None;
        }
        let i = ((u * n as f32) as u32).min(n - 1);
        let Some(entry) = self.light_alias.get(i as usize) else {
            return Some((i, 1.0 / n as f32));
        };
        probe.read(DataClass::Shading, self.light_alias_addr.wrapping_add(i.wrapping_mul(16)), 16);
        Some(if v < entry.keep { (i, entry.pdf) } else { (entry.alias, entry.alias_pdf) })
    }

    /// Reads light `index` (a default black ambient light if out of range).
    #[inline]
    pub fn light<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> LightRecord {
        probe.read(DataClass::Shading, self.lights_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.lights.get(index as usize).copied().unwrap_or(LightRecord {
            position: [0.0; 3],
            kind: LightRecord::AMBIENT,
            color: [0.0; 3],
            triangle: 0,
        })
    }

    /// The materials.
    pub fn materials(&self) -> &'a [MaterialRecord] {
        self.materials
    }

    /// True when the image has shading vertices (normals, texture coordinates, colours).
    pub fn has_shading_vertices(&self) -> bool {
        !self.shading.is_empty()
    }

    /// True when the image's point light is raypipe's default, placed for the image's
    /// camera ([`FLAG_DEFAULT_LIGHT`]).
    pub fn has_default_light(&self) -> bool {
        self.header.flags & FLAG_DEFAULT_LIGHT != 0
    }

    /// Number of textures.
    pub fn texture_count(&self) -> u32 {
        self.textures.len() as u32
    }

    /// Texture `index` (validated: its texels lie inside TEXELS).
    pub fn texture(&self, index: u32) -> Option<TextureRecord> {
        self.textures.get(index as usize).copied()
    }

    /// Texel `(x, y)` of texture `t` as RGBA bytes (sRGB), `x`, `y` already wrapped.
    #[inline]
    pub fn texel<P: MemoryProbe>(&self, t: &TextureRecord, x: u32, y: u32, probe: &mut P) -> [u8; 4] {
        let i = t.first.wrapping_add(y.wrapping_mul(t.width)).wrapping_add(x);
        probe.read(DataClass::Shading, self.texels_addr.wrapping_add(i.wrapping_mul(4)), 4);
        self.texels.get(i as usize).copied().unwrap_or(0).to_le_bytes()
    }

    /// Reads PRIM_LISTS entry `pos` of a tree leaf (kd-tree, BVH, 4- or 8-wide BVH: all
    /// keep their leaves' triangle ids in that one section).
    #[inline]
    pub fn leaf_prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prim_lists_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prim_lists.get(pos as usize).copied().unwrap_or(0)
    }

    /// Reads triangle `prim` and its three vertex positions (intersection data).
    #[inline]
    pub fn triangle<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> [Vec3; 3] {
        probe.read(DataClass::Triangles, self.triangles_addr.wrapping_add(prim.wrapping_mul(12)), 12);
        let idx = self.triangles.get(prim as usize).map_or([0; 3], |t| t.0);
        // The vertices' addresses come from the record just read.
        probe.dependent();
        idx.map(|i| self.position(i, probe))
    }

    #[inline]
    fn position<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> Vec3 {
        probe.read(DataClass::Triangles, self.positions_addr.wrapping_add(index.wrapping_mul(12)), 12);
        self.positions.get(index as usize).map_or(Vec3::ZERO, |p| Vec3::from(p.0))
    }

    /// Reads triangle `prim`'s precomputed Wald record, if the image has that layout.
    #[inline]
    pub fn wald_triangle<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> Option<WaldTriangle> {
        if self.wald.is_empty() {
            return None;
        }
        probe.read(DataClass::Triangles, self.wald_addr.wrapping_add(prim.wrapping_mul(48)), 48);
        self.wald.get(prim as usize).copied()
    }

    /// Reads block `block` of TRI_BLOCKS (the triangles of PRIM_LISTS entries
    /// `4·block` to `4·block + 3`), if the image has that section and the block.
    #[inline(always)]
    pub fn tri_block<P: MemoryProbe>(&self, block: u32, probe: &mut P) -> Option<&'a TriBlock4> {
        const SIZE: u32 = core::mem::size_of::<TriBlock4>() as u32;
        probe.read(DataClass::Triangles, self.tri_blocks_addr.wrapping_add(block.wrapping_mul(SIZE)), SIZE);
        self.tri_blocks.get(block as usize)
    }

    /// True if the image stores its leaf triangles in blocks of four (TRI_BLOCKS).
    pub fn has_tri_blocks(&self) -> bool {
        !self.tri_blocks.is_empty()
    }

    /// True if the image stores Wald's precomputed triangles.
    pub fn has_wald_triangles(&self) -> bool {
        !self.wald.is_empty()
    }

    /// The vertex indices of triangle `prim` (not probed: shading re-reads them from its
    /// own copy of the index data in hardware; here they come with the shading fetch).
    #[inline]
    pub fn triangle_indices(&self, prim: u32) -> [u32; 3] {
        self.triangles.get(prim as usize).map_or([0; 3], |t| t.0)
    }

    /// Reads the shading data of vertex `index`, if the image has shading data.
    #[inline]
    pub fn shading_vertex<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> Option<ShadingVertex> {
        if self.shading.is_empty() {
            return None;
        }
        probe.read(DataClass::Shading, self.shading_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.shading.get(index as usize).copied()
    }

    /// The material number of triangle `prim` (`None` without materials).
    #[inline]
    pub fn material_id<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> Option<u32> {
        probe.read(DataClass::Shading, self.tri_materials_addr.wrapping_add(prim.wrapping_mul(4)), 4);
        self.tri_materials.get(prim as usize).copied()
    }

    /// The object triangle `prim` came from (0 without TRIANGLE_OBJECTS).
    pub fn object_of(&self, prim: u32) -> u32 {
        self.tri_objects.get(prim as usize).copied().unwrap_or(0)
    }

    /// The number of objects: one more than the largest object id (1 without
    /// TRIANGLE_OBJECTS: the whole scene is object 0).
    pub fn object_count(&self) -> u32 {
        self.tri_objects.iter().max().map_or(1, |&m| m.saturating_add(1))
    }

    /// Reads the material of triangle `prim` ([`MaterialRecord::DEFAULT`] if none).
    #[inline]
    pub fn material_of<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> MaterialRecord {
        if self.tri_materials.is_empty() {
            return MaterialRecord::DEFAULT;
        }
        probe.read(DataClass::Shading, self.tri_materials_addr.wrapping_add(prim.wrapping_mul(4)), 4);
        let id = self.tri_materials.get(prim as usize).copied().unwrap_or(NULL_INDEX);
        probe.read(DataClass::Shading, self.materials_addr.wrapping_add(id.wrapping_mul(64)), 64);
        self.materials.get(id as usize).copied().unwrap_or(MaterialRecord::DEFAULT)
    }
}
