//! The chip's units and their clock: ray generation & shading, traversal and intersection units, the FIFOs between them, and the simulator that ticks them.

pub mod datapath;
pub mod fifo;
pub mod intersection_unit;
pub mod jobs;
pub mod rgs;
pub mod simulator;
pub mod traversal_unit;
