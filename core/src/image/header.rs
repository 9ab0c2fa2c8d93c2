//! The image header and the section table.

use bytemuck::{Pod, Zeroable};

/// The eight bytes every scene image starts with.
pub const MAGIC: [u8; 8] = *b"RPSCENE\0";
/// The format version this crate reads and writes.
pub const FORMAT_VERSION: u32 = 2;

/// Header flag: the image's point light is raypipe's default, placed for the image's
/// camera (not the author's); a driver rendering another view may place it again.
pub const FLAG_DEFAULT_LIGHT: u32 = 1;
/// Every flag this version defines.
pub const KNOWN_FLAGS: u32 = FLAG_DEFAULT_LIGHT;

/// Image header, 64 bytes at offset 0.
///
/// | offset | field |
/// |---|---|
/// | 0  | magic `"RPSCENE\0"` |
/// | 8  | version |
/// | 12 | flags ([`FLAG_DEFAULT_LIGHT`]; no other bit may be set) |
/// | 16 | acceleration structure kind |
/// | 20 | number of sections |
/// | 24 | total image size in bytes |
/// | 28 | CRC-32 of the image with this field read as zero |
/// | 32 | scene bounds min (3 × f32) |
/// | 44 | scene bounds max (3 × f32) |
/// | 56 | triangle count |
/// | 60 | vertex count |
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Header {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`FORMAT_VERSION`].
    pub version: u32,
    /// Feature flags: [`FLAG_DEFAULT_LIGHT`] or none.
    pub flags: u32,
    /// [`AccelKind`] as a number.
    pub accel: u32,
    /// Entries in the section table that follows the header.
    pub section_count: u32,
    /// Size of the whole image in bytes.
    pub total_size: u32,
    /// CRC-32 of the whole image with these four bytes read as zero.
    pub checksum: u32,
    /// Lower corner of the box around all vertices.
    pub bounds_min: [f32; 3],
    /// Upper corner of the box around all vertices.
    pub bounds_max: [f32; 3],
    /// Number of triangles (equals the TRIANGLES section count).
    pub triangle_count: u32,
    /// Number of vertices (equals the POSITIONS section count).
    pub vertex_count: u32,
}
const _: () = assert!(core::mem::size_of::<Header>() == 64);
const _: () = assert!(core::mem::align_of::<Header>() == 4);

/// Byte offset of [`Header::checksum`].
pub(crate) const CHECKSUM_OFFSET: usize = 28;

/// One entry of the section table, 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct SectionEntry {
    /// [`SectionKind`] as a number.
    pub kind: u32,
    /// Byte offset from the start of the image; a multiple of 64.
    pub offset: u32,
    /// Size in bytes: `count × record size`.
    pub size: u32,
    /// Number of records.
    pub count: u32,
}
const _: () = assert!(core::mem::size_of::<SectionEntry>() == 16);
const _: () = assert!(core::mem::align_of::<SectionEntry>() == 4);

/// Which acceleration structure the image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum AccelKind {
    /// No structure: only brute force can trace it.
    None = 0,
    /// Purcell's uniform grid (sections GRID, GRID_CELLS, PRIM_LISTS).
    Grid = 1,
    /// A bounding volume hierarchy (sections BVH_NODES, PRIM_LISTS).
    Bvh = 2,
    /// A kd-tree (sections KD_NODES, PRIM_LISTS).
    KdTree = 3,
    /// A 4-wide BVH (sections BVH4_NODES, PRIM_LISTS).
    Bvh4 = 4,
    /// An 8-wide BVH (sections BVH8_NODES, PRIM_LISTS).
    Bvh8 = 5,
}

impl AccelKind {
    /// Decodes the header field.
    pub fn from_u32(v: u32) -> Option<AccelKind> {
        match v {
            0 => Some(AccelKind::None),
            1 => Some(AccelKind::Grid),
            2 => Some(AccelKind::Bvh),
            3 => Some(AccelKind::KdTree),
            4 => Some(AccelKind::Bvh4),
            5 => Some(AccelKind::Bvh8),
            _ => None,
        }
    }
}

/// The kinds of section, with their record sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum SectionKind {
    /// Vertex positions, [`crate::image::Position`], 12 bytes each.
    Positions = 1,
    /// Triangles as three vertex indices, [`crate::image::TriangleRecord`], 12 bytes.
    Triangles = 2,
    /// The grid's parameters, one [`crate::image::GridRecord`], 64 bytes.
    Grid = 3,
    /// One `u32` per grid cell: first entry of its list in PRIM_LISTS, or null.
    GridCells = 4,
    /// `u32` triangle indices; each list ends with a null entry.
    PrimLists = 5,
    /// Per-vertex shading data, [`crate::image::ShadingVertex`], 32 bytes.
    ShadingVertices = 6,
    /// One `u32` material index per triangle.
    TriangleMaterials = 7,
    /// [`crate::image::MaterialRecord`], 64 bytes each.
    Materials = 8,
    /// [`crate::image::LightRecord`], 32 bytes each.
    Lights = 9,
    /// The default camera, one [`crate::image::CameraRecord`], 64 bytes.
    Camera = 10,
    /// BVH nodes, [`crate::image::BvhNode`], 32 bytes each; node 0 is the root.
    BvhNodes = 11,
    /// kd-tree nodes, [`crate::image::KdNode`], 8 bytes each; node 0 is the root.
    KdNodes = 12,
    /// 4-wide BVH nodes, [`crate::image::Bvh4Node`], 128 bytes each; node 0 is the root.
    Bvh4Nodes = 13,
    /// Wald's precomputed projection triangles, [`crate::image::WaldTriangle`], 48 bytes
    /// each, one per triangle (an optional intersection layout).
    WaldTriangles = 14,
    /// Diffuse textures, [`crate::image::TextureRecord`], 32 bytes each.
    Textures = 15,
    /// Texels of all textures, one `u32` each: RGBA, 8-bit sRGB, red in the low byte.
    Texels = 16,
    /// 8-wide BVH nodes, [`crate::image::Bvh8Node`], 256 bytes each; node 0 is the root.
    Bvh8Nodes = 17,
    /// Copies of the vertices of the trees' leaf triangles in blocks of four SIMD lanes,
    /// [`crate::image::TriBlock4`], 144 bytes each: block `j` holds the triangles of
    /// PRIM_LISTS entries `4j` to `4j + 3` (optional; single rays test a leaf's
    /// triangles four at a time from it).
    TriBlocks = 18,
    /// The area lights' power distribution as an alias table,
    /// [`crate::image::LightAlias`], 16 bytes each, one per area light in LIGHTS order
    /// (optional; without it the path tracer picks area lights uniformly).
    LightAlias = 19,
    /// The object each triangle came from (an OBJ `o`/`g` name, a glTF node, a scene
    /// file's mesh), u32 each, one per triangle (optional; hit queries report it).
    TriangleObjects = 20,
    /// A brick's triangles' ids in the whole scene, strictly increasing (one per
    /// triangle): the hit a brick reports carries the scene-wide id, so bricks order
    /// equal distances as the flat image does (Wald & Slusallek 2001, §6.3).
    TriangleIds = 21,
    /// A brick's whole scene's bounds (one record: min, max): shading offsets new rays
    /// in proportion to the scene's extent, which a brick must not change.
    SceneBounds = 22,
}

impl SectionKind {
    /// Every kind, in table order.
    pub const ALL: [SectionKind; 22] = [
        SectionKind::Positions,
        SectionKind::Triangles,
        SectionKind::Grid,
        SectionKind::GridCells,
        SectionKind::PrimLists,
        SectionKind::ShadingVertices,
        SectionKind::TriangleMaterials,
        SectionKind::Materials,
        SectionKind::Lights,
        SectionKind::Camera,
        SectionKind::BvhNodes,
        SectionKind::KdNodes,
        SectionKind::Bvh4Nodes,
        SectionKind::WaldTriangles,
        SectionKind::Textures,
        SectionKind::Texels,
        SectionKind::Bvh8Nodes,
        SectionKind::TriBlocks,
        SectionKind::LightAlias,
        SectionKind::TriangleObjects,
        SectionKind::TriangleIds,
        SectionKind::SceneBounds,
    ];

    /// Decodes a section-table kind.
    pub fn from_u32(v: u32) -> Option<SectionKind> {
        SectionKind::ALL.iter().copied().find(|k| *k as u32 == v)
    }

    /// Size in bytes of one record of this section.
    pub const fn record_size(self) -> u32 {
        match self {
            SectionKind::Positions | SectionKind::Triangles => 12,
            SectionKind::Grid | SectionKind::Materials | SectionKind::Camera => 64,
            SectionKind::GridCells
            | SectionKind::PrimLists
            | SectionKind::TriangleMaterials
            | SectionKind::Texels
            | SectionKind::TriangleObjects
            | SectionKind::TriangleIds => 4,
            SectionKind::Textures => 32,
            SectionKind::ShadingVertices | SectionKind::Lights | SectionKind::BvhNodes => 32,
            SectionKind::KdNodes => 8,
            SectionKind::Bvh4Nodes => 128,
            SectionKind::Bvh8Nodes => 256,
            SectionKind::WaldTriangles => 48,
            SectionKind::TriBlocks => 144,
            SectionKind::LightAlias => 16,
            SectionKind::SceneBounds => 24,
        }
    }

    /// Upper-case name used in documentation and error messages.
    pub const fn name(self) -> &'static str {
        match self {
            SectionKind::Positions => "POSITIONS",
            SectionKind::Triangles => "TRIANGLES",
            SectionKind::Grid => "GRID",
            SectionKind::GridCells => "GRID_CELLS",
            SectionKind::PrimLists => "PRIM_LISTS",
            SectionKind::ShadingVertices => "SHADING_VERTICES",
            SectionKind::TriangleMaterials => "TRIANGLE_MATERIALS",
            SectionKind::Materials => "MATERIALS",
            SectionKind::Lights => "LIGHTS",
            SectionKind::Camera => "CAMERA",
            SectionKind::BvhNodes => "BVH_NODES",
            SectionKind::KdNodes => "KD_NODES",
            SectionKind::Bvh4Nodes => "BVH4_NODES",
            SectionKind::Bvh8Nodes => "BVH8_NODES",
            SectionKind::WaldTriangles => "WALD_TRIANGLES",
            SectionKind::Textures => "TEXTURES",
            SectionKind::Texels => "TEXELS",
            SectionKind::TriBlocks => "TRI_BLOCKS",
            SectionKind::LightAlias => "LIGHT_ALIAS",
            SectionKind::TriangleObjects => "TRIANGLE_OBJECTS",
            SectionKind::TriangleIds => "TRIANGLE_IDS",
            SectionKind::SceneBounds => "SCENE_BOUNDS",
        }
    }
}
