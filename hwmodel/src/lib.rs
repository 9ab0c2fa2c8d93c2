//! # raypipe-hw
//!
//! A cycle-level, RTL-style model of a ray tracing chip in the spirit of SaarCOR (Wald &
//! Slusallek 2001 §7.3): a ray generation & shading unit ([`rgs`]) feeds several traversal
//! units ([`traversal_unit`]), each coupled to a list & intersection unit
//! ([`intersection_unit`]) through bounded FIFOs ([`fifo`]); packets step in lock-step;
//! per-unit caches ([`cache`]) sit in front of the memory ([`memory`]: perfect, fixed or
//! DRAM ([`dram`]))
//! that accounts every byte by data class. Every unit has registered state and one
//! `tick`; FIFOs and the channel commit at the clock edge ([`simulator`]), so the tick
//! order cannot change any result.
//!
//! The model computes with raypipe-core's kernels — the structures' step kernels through
//! `raypipe_core::traverse::walk::Walk`, the intersection and shading kernels — and observes their
//! reads through `MemoryProbe`, so its image is the host's image bit for bit; it adds
//! cycles, stalls, occupancy and traffic ([`report`]). Parameters live in one
//! [`config::HwConfig`].
#![forbid(unsafe_code)]

pub mod chip;
pub mod config;
pub mod memory;
pub mod observe;
pub mod stream;

pub use chip::datapath::Datapath;
pub use chip::simulator::Simulator;
pub use config::HwConfig;
pub use observe::report::Report;

/// The set lanes of a mask, lowest first.
pub(crate) fn lane_iter(mask: u64) -> raypipe_core::packet::Lanes {
    raypipe_core::packet::Lanes(mask)
}
