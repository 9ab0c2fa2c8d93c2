//! # raypipe-core
//!
//! Fixed-layout scene image records and ray tracing kernels, `#![no_std]` and without
//! `alloc`. Everything here reads a compiled scene image *in place* from a byte slice
//! ([`SceneView::parse`]), validated once; after that no kernel can index out of bounds
//! or panic.
//!
//! The kernels are steps over plain data (see `../shared/DESIGN.md`), grouped by
//! Purcell's pipeline stages (generate → traverse → intersect → shade):
//!
//! * [`camera`]: pinhole eye rays and Purcell's scene-bounding-box test (generate);
//! * [`traverse`]: the 3D-DDA over Purcell's Figure 4 grid, the kd-tree and the BVHs as
//!   step kernels with fixed-capacity stacks, the robust ray/box tests, the any-hit query
//!   of shadow rays and the brute-force reference every structure must agree with;
//! * [`intersect`]: the ray–triangle interface and its watertight, Möller–Trumbore and
//!   Wald tests, and leaf triangle blocks;
//! * [`packet`]: ray packets, the lock-step driver and each structure's packet traversal;
//! * [`shade`]: Lambert shading, weighted ray records, Whitted's and the path tracer's
//!   shaders as stream kernels that emit rays, counter-based random numbers;
//! * at the root, the scene image ([`image`]) and the plain records: [`ray`], [`hit`],
//!   [`probe`] (the one access path of scene reads) and [`counters`].
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

pub mod camera;
pub mod counters;
pub mod cpu;
pub mod hit;
pub mod image;
pub mod intersect;
pub mod packet;
pub mod probe;
pub mod ray;
pub mod shade;
#[cfg(test)]
mod test_lcg;
pub mod traverse;

pub use camera::{Camera, CameraError};
pub use counters::RayCounters;
pub use hit::Hit;
pub use image::{SceneError, SceneView};
pub use intersect::triangle::{Intersector, MollerTrumbore, WaldProjection, Watertight};
pub use probe::{DataClass, MemoryProbe, NoProbe};
pub use ray::Ray;

pub use glam::{Vec3, Vec4};
