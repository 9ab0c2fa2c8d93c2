//! The limits of the format that every reader relies on: alignment of the buffer and of
//! its sections, and the deepest trees the traversal kernels' fixed stacks can walk.

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
