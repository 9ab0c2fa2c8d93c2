//! Rendering a bricked scene: a brick cache filled by loader threads, tracers that park
//! rays on missing bricks, and frames shaded from the bricks their hits lie in.

pub mod brick_cache;
pub mod brick_tracer;
pub mod frame;
