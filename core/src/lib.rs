//! # raypipe-core
//!
//! Fixed-layout scene image records and ray tracing kernels, `#![no_std]` and without
//! `alloc`. Everything here reads a compiled scene image *in place* from a byte slice
//! ([`SceneView::parse`]), validated once; after that no kernel can index out of bounds
//! or panic.
//!
//! The kernels are steps over plain data ([design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md), contract 3), grouped by
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
//! * [`math`]: sine, cosine, tangent, exp2 and log2 in f32 only, and the fixed-point
//!   numbers of the integer datapath; [`simd`]: the AVX forms of four kernels;
//! * at the root, the scene image ([`image`]) and the plain records: [`ray`], [`hit`],
//!   [`probe`] (the one access path of scene reads) and [`counters`], [`range`] (the
//!   scenes and rays for which every path gives the same hit).
//!
//! A board needs more than this crate: start-up code, a memory map, a linker script and
//! the right release profile. The [`guide`] takes you from nothing to a running
//! Cortex-M4F or RV32 firmware, and lists each feature's flash cost, each kernel's stack
//! and the trees' depth limits.
//!
//! ## Firmware in five steps
//!
//! Build an image on the host (`raypipe build scene.obj --accel bvh4 -o scene.rpsi`),
//! embed it, validate it once, and trace. Nothing below needs `std`, `alloc` or a heap,
//! and nothing can panic (the no_std proof in `nostd-proof/` checks that at link time and
//! runs this on an emulated Cortex-M4F and RV32).
//!
//! ```
//! use raypipe_core::camera::{Camera, EyeRays};
//! use raypipe_core::traverse::walk::trace_walk;
//! use raypipe_core::{NoProbe, Ray, SceneView, Vec3, Watertight};
//!
//! // 1. Embed the image, aligned as `parse` needs (flash, BRAM, or a mapped file).
//! static SCENE: &[u8] = raypipe_core::include_scene!("../../fixtures/tetra-bvh4.rpsi");
//!
//! // 2. Validate once: a typed error for a bad image, never a panic.
//! let view = SceneView::parse(SCENE).expect("a valid image");
//!
//! // 3. Rays: from the image's camera, or any origin and direction of your own.
//! let eye = EyeRays::new(&Camera::from(view.camera().expect("the image has a camera")))
//!     .expect("a usable camera");
//! let ray = eye.ray(eye.width / 2, eye.height - 1);
//!
//! // 4. Trace with the generic walk (it takes the image's structure, whichever it is;
//! //    `NoProbe` because nobody watches the memory reads here).
//! let hit = trace_walk::<Watertight, _>(&view, &ray, &mut NoProbe);
//!
//! // 5. Read the hit: distance, triangle, barycentrics.
//! let hit = hit.expect("the bottom row of the view sees the floor");
//! let point = ray.origin + ray.dir * hit.t;
//! assert!(hit.t > 0.0 && hit.prim < view.triangle_count() && point.is_finite());
//!
//! // An invalid ray (here: a zero direction) is no hit, not an error.
//! let nothing = Ray::new(Vec3::ZERO, Vec3::ZERO);
//! assert!(trace_walk::<Watertight, _>(&view, &nothing, &mut NoProbe).is_none());
//! ```
//!
//! ```
//! use raypipe_core::{SceneView, SceneError};
//! // A buffer that is not a scene image is rejected with a typed error, never a panic.
//! let bytes = [0u8; 8];
//! assert!(matches!(SceneView::parse(&bytes), Err(SceneError::Truncated { .. })));
//! ```
#![no_std]
#![deny(missing_docs)]
// Safe code throughout: every module but `simd` forbids `unsafe` (an `allow` cannot
// lift a `forbid`). `simd` holds the x86-64 AVX forms of four kernels, each reached by a
// safe function that takes an `Avx` token, which exists only once the host has reported
// AVX; each `unsafe` block there has its safety argument beside it. On other targets
// none of them is compiled.
#![deny(unsafe_code)]

#[cfg(target_endian = "big")]
compile_error!("raypipe-core reads little-endian scene images in place and needs a little-endian target");

#[forbid(unsafe_code)]
pub mod camera;
#[forbid(unsafe_code)]
pub mod counters;
#[forbid(unsafe_code)]
pub mod fixed_ray;
pub mod guide;
#[forbid(unsafe_code)]
pub mod hit;
#[forbid(unsafe_code)]
pub mod image;
#[forbid(unsafe_code)]
pub mod intersect;
pub mod math;
#[forbid(unsafe_code)]
pub mod packet;
#[forbid(unsafe_code)]
pub mod pixel_filter;
#[forbid(unsafe_code)]
pub mod probe;
#[forbid(unsafe_code)]
pub mod range;
#[forbid(unsafe_code)]
pub mod ray;
#[forbid(unsafe_code)]
pub mod shade;
pub mod simd;
#[cfg(test)]
#[forbid(unsafe_code)]
mod test_lcg;
#[forbid(unsafe_code)]
pub mod traverse;

pub use camera::{Camera, CameraError};
pub use counters::RayCounters;
pub use hit::Hit;
pub use image::{SceneError, SceneView};
pub use intersect::fixed_watertight::{FixedWatertight, Q12_12, Q16_16};
pub use intersect::moller_trumbore::MollerTrumbore;
pub use intersect::triangle::Intersector;
pub use intersect::wald::WaldProjection;
pub use intersect::watertight::Watertight;
pub use probe::{DataClass, MemoryProbe, NoProbe};
pub use ray::Ray;

pub use glam::{Vec3, Vec4};
