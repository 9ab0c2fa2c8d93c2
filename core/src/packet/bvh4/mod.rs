//! Packet traversal of the 4-wide BVH: the packet visits a node if any of its rays may
//! hit one of the node's boxes, nearest child first; a leaf intersects its triangles with
//! exactly the rays that enter its box, in groups of four lanes (SIMD registers) for the
//! box test and, where the intersector has a four-ray form, for the triangles too. Rays
//! of one origin (a camera's) meet each triangle made ready once for it, eight lanes at a
//! time where the CPU has AVX (`simd::watertight8`).

mod apex;
mod cached;
pub(in crate::packet) mod frustum;
pub(crate) mod groups;
pub(in crate::packet) mod leaf;
mod many_origins;
pub(in crate::packet) mod prepared;
mod rays16;
pub(in crate::packet) mod walk;

pub use cached::occluded_bvh4_packet_cached;
#[cfg(target_arch = "x86_64")]
pub(crate) use groups::{Groups, GROUPS};
pub use walk::{occluded_bvh4_packet, takes_shadow_pyramid, trace_bvh4_packet};
