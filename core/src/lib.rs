//! # raypipe-core
//!
//! Fixed-layout scene image records and ray tracing kernels, `#![no_std]` and without
//! `alloc`. Everything here reads a compiled scene image *in place* from a byte slice
//! ([`SceneView::parse`]), validated once; after that no kernel can index out of bounds
//! or panic.
//!
//! The kernels are steps over plain data (see `../shared/DESIGN.md`):
//!
//! * [`camera`]: pinhole eye rays and Purcell's scene-bounding-box test;
//! * [`dda`]: the 3D-DDA of Amanatides & Woo, one voxel per step;
//! * [`grid`]: uniform-grid traversal over Purcell's Figure 4 layout;
//! * [`bvh`] and [`kdtree`]: tree traversal with a fixed-capacity stack;
//! * [`watertight`] and [`moller_trumbore`]: ray–triangle intersection;
//! * [`leaf_blocks`]: a leaf's triangles four at a time (optional TRI_BLOCKS);
//! * [`brute_force`]: the reference tracer every structure must agree with;
//! * [`shade`]: Lambert shading with one point light plus ambient;
//! * [`ray_record`], [`occlusion`], [`whitted`], [`path`] and [`shader`]: weighted ray
//!   records, the any-hit query of shadow rays, and Whitted's and the path tracer's
//!   shaders as stream kernels that emit rays ([`rng`]: counter-based random numbers).
//!
//! ```
//! use raypipe_core::{SceneView, SceneError};
//! // A buffer that is not a scene image is rejected with a typed error, never a panic.
//! let bytes = [0u8; 8];
//! assert!(matches!(SceneView::parse(&bytes), Err(SceneError::Truncated { .. })));
//! ```
#![no_std]
#![deny(missing_docs)]
// Safe code throughout, except the AVX forms of the 8-wide node test
// (`bvh8::slab8_avx`) and of the packets' leaf entry test (`bvh4_packet::leaf_entries_avx`),
// which run only once the host has reported AVX ([`cpu::assume_avx`]).
#![deny(unsafe_code)]

#[cfg(target_endian = "big")]
compile_error!("raypipe-core reads little-endian scene images in place and needs a little-endian target");

pub mod aabb;
pub mod brute_force;
pub mod bvh;
pub mod bvh4;
pub mod bvh4_packet;
pub mod bvh8;
pub mod bvh_packet;
pub mod camera;
pub mod color;
pub mod counters;
pub mod cpu;
pub mod dda;
pub mod grid;
pub mod grid_packet;
pub mod hit;
pub mod image;
pub mod kdtree;
pub mod kdtree_packet;
pub mod leaf_blocks;
pub mod lockstep;
pub mod moller_trumbore;
pub mod occlusion;
pub mod packet;
pub mod path;
pub mod probe;
pub mod radiance_sum;
pub mod raster;
pub mod ray;
pub mod ray_box;
pub mod ray_record;
pub mod rng;
pub mod shade;
pub mod shader;
pub mod specular;
pub mod surface;
#[cfg(test)]
mod test_lcg;
pub mod texture;
pub mod tree_step;
pub mod triangle;
pub mod wald;
pub mod walk;
pub mod watertight;
pub mod watertight8;
pub mod whitted;
pub mod wide_bvh;

pub use camera::{Camera, CameraError};
pub use counters::RayCounters;
pub use hit::Hit;
pub use image::{SceneError, SceneView};
pub use probe::{DataClass, MemoryProbe, NoProbe};
pub use ray::Ray;
pub use triangle::{Intersector, MollerTrumbore, WaldProjection, Watertight};

pub use glam::{Vec3, Vec4};
