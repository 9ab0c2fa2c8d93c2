//! # raypipe-hw
//!
//! The cycle-level, RTL-style model of a ray tracing chip (issue 4): ray generation and
//! shading units feeding traversal units coupled to intersection units through bounded
//! FIFOs, with caches and a memory channel that account every byte. It will be built
//! from `raypipe-core`'s kernels — the grid traversal is already a step kernel
//! (`raypipe_core::grid::GridTraversal::step`) and every scene read already goes through
//! `raypipe_core::MemoryProbe` — so that its images equal the host's bit for bit.
//!
//! Nothing is modelled yet; this crate only fixes the workspace layout.
#![forbid(unsafe_code)]
