//! Intersection: the ray–triangle interface and its tests — watertight (Woop, Benthin &
//! Wald 2013, one ray and eight lanes; and in fixed point), Möller–Trumbore, Wald's
//! projection triangles —
//! and a leaf's triangles four at a time.

pub mod fixed_watertight;
pub mod leaf_blocks;
pub mod moller_trumbore;
pub mod triangle;
pub mod wald;
pub mod watertight;
