//! The chip's units and their clock: ray generation & shading, traversal units with their transformation units, intersection units, the FIFOs between them, and the simulator that ticks them.

pub mod datapath;
pub mod fifo;
pub mod instanced_lane;
pub mod intersection_unit;
pub mod jobs;
pub mod rgs;
pub mod scene;
pub mod simulator;
pub mod transform_unit;
pub mod traversal_thread;
pub mod traversal_unit;
