//! Traversal: the structures' walks, one node or voxel per step — Purcell's uniform grid
//! with its 3D-DDA, the kd-tree, the binary, 4-wide and 8-wide BVHs — the robust ray/box
//! tests they share (in `f32` and in fixed point), the any-hit query of shadow rays, and the brute-force reference.

pub mod boxes;
pub mod brute_force;
pub mod bvh;
pub mod dda;
pub mod grid;
pub mod instanced;
pub mod kdtree;
pub mod occlusion;
pub mod tree_step;
pub mod two_level;
pub mod walk;
pub mod wide_bvh;
