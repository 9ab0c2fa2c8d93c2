//! Rendering across processes with MPI (Wald & Slusallek 2001 §6.1–6.7): rank 0 is the
//! master — it hands out tiles from a [`tile_pool::TilePool`], gathers them and writes
//! the image — and every other rank a worker that renders the tiles it is given with
//! its own threads. The tile pool and the message layout are plain Rust; the transport
//! is rsmpi, behind the `mpi` cargo feature.

#[cfg(feature = "mpi")]
pub mod brick_service;
#[cfg(feature = "mpi")]
pub mod crew;
#[cfg(feature = "mpi")]
pub mod launcher_stop;
#[cfg(feature = "mpi")]
pub mod patient_receive;
pub mod protocol;
pub mod tile_pool;

#[cfg(feature = "mpi")]
pub mod mpi_master;
#[cfg(feature = "mpi")]
pub mod mpi_render;
#[cfg(feature = "mpi")]
pub mod mpi_sweep;
#[cfg(feature = "mpi")]
pub mod mpi_worker;

/// `raypipe render --mpi` in a raypipe built without MPI.
#[cfg(not(feature = "mpi"))]
pub fn cmd_render_mpi(_: &crate::commands::render::RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("--mpi: this raypipe was built without MPI; build it with `cargo build --release --features mpi`")
}

/// `raypipe sweep --mpi` in a raypipe built without MPI.
#[cfg(not(feature = "mpi"))]
pub fn cmd_sweep_mpi(_: &crate::commands::sweep::SweepArgs) -> anyhow::Result<()> {
    anyhow::bail!("--mpi: this raypipe was built without MPI; build it with `cargo build --release --features mpi`")
}

#[cfg(feature = "mpi")]
pub use mpi_render::cmd_render_mpi;
#[cfg(feature = "mpi")]
pub use mpi_sweep::cmd_sweep_mpi;

/// True in a process that an MPI launcher started as a rank other than 0 (OpenMPI,
/// MPICH and PMIx name it in the environment): such a rank leaves messages about the
/// command line to rank 0, so that a bad command line is one message, not one per rank.
pub fn is_secondary_rank() -> bool {
    ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"]
        .iter()
        .find_map(|k| std::env::var(k).ok())
        .is_some_and(|r| r.trim() != "0")
}
