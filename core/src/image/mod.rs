//! The scene image: a versioned, little-endian binary format read in place.
//!
//! The byte-level format is documented for RTL engineers in [scene-format.md](https://github.com/raypipe/raypipe/blob/main/docs/scene-format.md).
//! Layout: a 64-byte [`Header`], a table of 16-byte [`SectionEntry`] records, then the
//! sections, each starting on a 64-byte boundary. Every record is `#[repr(C)]` with its
//! size and alignment asserted at compile time.

pub mod bricked;
mod crc32;
mod embed;
mod error;
mod header;
pub mod instanced;
mod limits;
mod margin;
mod records;
mod sections;
mod structure_views;
mod validate;
mod view;

pub use crc32::{crc32, crc32_with_hole, Crc32};
pub use embed::Aligned64;
pub use error::SceneError;
pub use header::{
    AccelKind, Header, SectionEntry, SectionKind, FLAG_DEFAULT_LIGHT, FORMAT_VERSION, KNOWN_FLAGS, MAGIC,
};
pub use limits::{IMAGE_ALIGN, MAX_TREE_DEPTH, MAX_WIDE_DEPTH, SECTION_ALIGN};
pub use records::{
    Bvh4Node, Bvh8Node, BvhNode, CameraRecord, GridRecord, KdNode, LightAlias, LightRecord, MaterialRecord, Position,
    ShadingVertex, TextureRecord, TriBlock4, TriangleRecord, WaldTriangle, WideNode, NULL_INDEX,
};
pub use structure_views::{Bvh4View, Bvh8View, BvhView, GridView, GridWrap, KdTreeView, WideBvhView};
pub use view::{FrameGeometry, GridLevel, SceneView, MAX_LEVELS};
