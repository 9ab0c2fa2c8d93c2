//! Validating a scene image once, section by section, so that no kernel needs to check
//! anything again: one validator per section, each returning the typed records it
//! checked.

pub(in crate::image) mod bvh;
pub(in crate::image) mod geometry;
pub(in crate::image) mod grid;
pub(in crate::image) mod indices;
pub(in crate::image) mod kdtree;
pub(in crate::image) mod lights;
pub(in crate::image) mod prim_lists;
pub(in crate::image) mod shading;
pub(in crate::image) mod tree;
pub(in crate::image) mod tri_blocks;
pub(in crate::image) mod wald;
pub(in crate::image) mod wide_bvh;
