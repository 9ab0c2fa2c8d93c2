//! A packet in the shade pipeline: its reads, where it stands, and what it leaves when
//! done.

use raypipe_core::shade::ray_record::RayRecord;

use crate::memory::port::Fetch;

/// Where a shading job stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Stage {
    Fetching,
    Queued,
    Shading(u64),
}

/// A packet being shaded.
pub(super) struct ShadeJob {
    /// Packet number (for traces).
    pub(super) packet: u32,
    /// Cycle the packet was started, and the pixels its lanes belong to (cost images).
    pub(super) issued: u64,
    pub(super) pixels: Vec<u32>,
    /// Shading bytes the job reads.
    pub(super) bytes: u64,
    pub(super) fetch: Fetch,
    pub(super) stage: Stage,
    pub(super) data_at: u64,
    pub(super) primary: bool,
    /// Rays to shade (cycles in the datapath: `rays / shade_per_cycle`).
    pub(super) rays: u64,
    /// Records the shader emitted, released when the job is done.
    pub(super) emitted: Vec<RayRecord>,
    /// Framebuffer bytes written when done, at this address.
    pub(super) write: (u64, u32),
}
