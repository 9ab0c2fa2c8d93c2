//! What the host machine offers the renderer: instruction sets, prefetch, huge pages, aligned buffers.

pub mod aligned;
pub mod huge_pages;
pub mod image_bytes;
pub mod isa;
pub mod memory;
pub mod prefetch;
pub mod thread_pools;
