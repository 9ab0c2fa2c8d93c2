//! Instanced scenes: bottom-level scene images (each with any structure raypipe builds)
//! placed in the world by affine instances under a top-level BVH over the instances'
//! world boxes (Wald & Slusallek 2001 §8.3: a scene of many copies stores each shape
//! once, and a moving object changes one transform, not the structure).
//!
//! The file begins with an *index* — a 128-byte [`InstancedHeader`], one 128-byte
//! [`InstanceRecord`] per instance, one 64-byte [`BottomRecord`] per bottom image, the
//! top-level tree's [`crate::image::BvhNode`]s, the list of instance ids its leaves
//! index, and a *globals* scene image (camera, lights and the override materials, no
//! triangles) — followed by the bottom images, each a flat scene image on a 64-byte
//! boundary. [scene-format.md](https://github.com/raypipe/raypipe/blob/main/docs/scene-format.md)
//! documents the bytes.
//!
//! The kernels take the top level ([`TopLevel`]) and the bottoms' views, so a host that
//! animates a scene can rebuild the top level in memory every frame and hand the same
//! kernels ([`crate::traverse::instanced`]) its own views.

mod error;
mod layout;
mod top_level;
mod view;

pub use error::InstancedError;
pub use layout::{
    index_layout, BottomRecord, InstanceRecord, InstancedHeader, INSTANCED_CHECKSUM_OFFSET, INSTANCED_MAGIC,
    INSTANCED_VERSION,
};
pub use top_level::{mapped_box, TopLevel, TopParts};
pub use view::InstancedView;
