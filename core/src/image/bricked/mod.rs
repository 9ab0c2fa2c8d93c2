//! Bricked scenes: a scene far larger than memory stored as many small, self-contained
//! scene images ("bricks", Wald & Slusallek 2001 §6.3's voxels) under a top-level BVH,
//! each brick compressed on its own so a driver loads only the bricks its rays reach.
//!
//! The file begins with an *index* — a 128-byte [`BrickedHeader`], one 64-byte
//! [`BrickRecord`] per brick, the top-level tree's [`crate::image::BvhNode`]s, the list
//! of brick ids its leaves index, and a small *globals* scene image (camera and lights,
//! no triangles) — followed by the bricks' stored bytes. Every offset and size in the
//! index is 64-bit, so a bricked scene may be far beyond 4 GiB; each brick is a flat
//! scene image of its own (below 4 GiB) whose TRIANGLE_IDS section maps its triangles to
//! scene-wide ids. [scene-format.md](https://github.com/raypipe/raypipe/blob/main/docs/scene-format.md)
//! documents the bytes.
//!
//! Core never decompresses: the driver reads a brick's stored bytes, decompresses them
//! with the codec the header names, and checks the result with
//! [`BrickedView::check_brick`] before passing its view to the two-level walk
//! ([`crate::traverse::two_level`]).

mod error;
mod layout;
mod view;

pub use error::BrickedError;
pub use layout::{BrickRecord, BrickedHeader, Codec, BRICKED_MAGIC, BRICKED_VERSION, INDEX_CHECKSUM_OFFSET};
pub use view::BrickedView;
