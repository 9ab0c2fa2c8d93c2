//! Clusters larger than this machine, by simulation: a distributed run's recording
//! (`render --mpi --mpi-record`) replayed on a modelled cluster of any size.

pub mod model;
pub mod recording;
