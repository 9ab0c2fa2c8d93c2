//! Driving the hardware models from the command line: the chip simulator and Purcell's stream machine.

pub mod chip;
pub mod chip_summary;
pub mod frame_setup;
pub mod stream;
pub mod stream_charts;
