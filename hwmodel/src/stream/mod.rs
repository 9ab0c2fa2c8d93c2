//! Purcell's programmable GPU as a stream processor (Purcell, Buck, Mark & Hanrahan,
//! *Ray Tracing on Programmable Graphics Hardware*, SIGGRAPH 2002): the same kernels as
//! the host — eye rays, the uniform grid's 3D-DDA, triangle tests, shading — run as
//! rendering passes over a screen-sized stream of rays, on the multipass architecture
//! (stencil-routed passes chosen by an oracle, optionally unrolled) or the branching
//! one (fused kernels, one pass), measured in passes, instructions and memory words,
//! with a texture cache in front of the scene data.
//!
//! The parts, named after the paper's concepts: [`config`] (architecture, oracle,
//! unrolling), [`stencil`], [`ray_state`] (the state textures), [`oracle`],
//! [`pass_loop`] (multipass), [`branching`], [`shading_pass`], [`cost_model`] (Table 1;
//! counts in [`scalar_counts`]),
//! [`texture_cache`] (§4.1), [`gpu`] (frame time), [`counters`] and [`report`];
//! [`frame`] runs a frame. The model's image is the host's image, bit for bit.

pub mod branching;
pub mod config;
pub mod cost_model;
pub mod counters;
pub mod frame;
pub mod gpu;
pub mod memory_probe;
pub mod oracle;
pub mod pass_loop;
pub mod ray_state;
pub mod report;
pub mod scalar_counts;
pub mod shading_pass;
pub mod stencil;
pub mod texture_cache;
pub mod vec4_counts;

pub use config::{Architecture, StreamConfig, Unroll};
pub use cost_model::{CostModel, Isa, Kernel};
pub use frame::StreamMachine;
pub use gpu::Machine;
pub use oracle::Oracle;
pub use report::StreamReport;
pub use texture_cache::TextureCacheConfig;
