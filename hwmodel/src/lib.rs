//! # raypipe-hw
//!
//! A cycle-level, RTL-style model of a ray tracing chip in the spirit of SaarCOR (Wald &
//! Slusallek 2001 §7.3), and Purcell's programmable GPU as a stream processor
//! ([`stream`]). The parts, by folder:
//!
//! * [`chip`]: a ray generation & shading unit ([`chip::rgs`]) feeds several traversal
//!   units ([`chip::traversal_unit`]), each coupled to a list & intersection unit
//!   ([`chip::intersection_unit`]) through bounded FIFOs ([`chip::fifo`]); packets step
//!   in lock-step on a datapath of a configured width. Every unit has registered state
//!   and one `tick`; FIFOs and the channel commit at the clock edge
//!   ([`chip::simulator`]), so the tick order cannot change any result.
//! * [`memory`]: per-unit caches ([`memory::cache`]) behind ports ([`memory::port`]), an
//!   optional L2 and the memory — perfect, fixed or DRAM ([`memory::dram`]) — that
//!   accounts every byte by data class.
//! * [`observe`]: stall reasons, unit statistics, the report ([`observe::report`]), its
//!   counters and metrics, energy and area, waveform and trace signals — all reading the
//!   chip, none changing it.
//! * [`config`]: every parameter, declared once with its unit and source ([`HwConfig`]).
//!
//! The model computes with raypipe-core's kernels — the structures' step kernels through
//! `raypipe_core::traverse::walk::Walk`, the intersection and shading kernels — and
//! observes their reads through `MemoryProbe`, so its image is the host's image bit for
//! bit; it adds cycles, stalls, occupancy and traffic.
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
