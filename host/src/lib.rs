//! # raypipe (host)
//!
//! The `std` side of raypipe: loading OBJ/MTL scenes, building the uniform grid, writing
//! and reading scene images, the multithreaded tile renderer, Purcell's scene
//! statistics, benchmarks and the `raypipe` command line. Geometry kernels are never
//! re-implemented here: everything that touches a ray calls `raypipe-core`.

pub mod build;
pub mod cli;
pub mod commands;
pub mod distributed;
pub mod hw;
pub mod input;
pub mod output;
pub mod platform;
pub mod render;
pub mod scene;
pub mod study;
