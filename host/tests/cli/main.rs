//! The command line as a user meets it: defaults that work with no arguments, `--help`
//! everywhere, and bad input answered with one line on stderr, a non-zero exit, no panic
//! and no output file.

mod animate;
mod bad_input;
mod bricked;
mod build;
mod cluster;
mod common;
mod fixed_point;
mod info;
mod inputs;
mod instanced;
#[cfg(feature = "mpi")]
mod mpi;
mod outputs;
mod ray_log;
mod render;
mod report;
mod simulate;
mod simulate_instanced;
mod stats;
mod stream;
mod sweep;
mod trace;
