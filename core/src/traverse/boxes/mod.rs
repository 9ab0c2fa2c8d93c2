//! Ray–box tests: clipping a ray to a box, the `f32` slab test of tree nodes, its
//! fixed-point form, and which of them goes with which triangle test.

pub mod box_test;
pub mod clip;
pub mod datapath;
pub mod fixed_slab;
pub mod slab;
pub mod wide_slab;
