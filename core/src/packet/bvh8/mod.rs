//! Packet traversal of the 8-wide BVH: the 4-wide packet walk's frustum, leaf test and
//! ray constants over nodes of eight children, so that a packet takes fewer, wider steps
//! (Embree's coherent packets walk its BVH8 so). Packets whose frustum does not cull go
//! ray by ray through the single-ray kernel.

mod walk;

pub use walk::trace_bvh8_packet;
