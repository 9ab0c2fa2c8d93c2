//! Driving the hardware models from the command line: the chip simulator and Purcell's stream machine.

pub mod chip;
pub mod stream;
pub mod stream_charts;
