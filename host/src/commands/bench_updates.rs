//! `raypipe bench-updates`: refit, linear-BVH and binned-SAH update times of an
//! animation's frames, in milliseconds per million triangles
//! ([`crate::study::update_bench`]), and the vertex buffers for Embree's harness.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;

use crate::input::aff::load_aff;
use crate::study::animation_report::percentile;
use crate::study::update_bench::{flatten_frames, time_updates, write_dump};

/// `raypipe bench-updates`.
#[derive(Args, Debug)]
pub struct BenchUpdatesArgs {
    /// The scene's entry AFF file.
    pub scene: PathBuf,
    /// Time every K-th frame.
    #[arg(long, value_name = "K", default_value_t = 8)]
    pub every: u32,
    /// Worker threads (the builders are single-threaded; this bounds the pool).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Write the sampled frames' flattened vertex buffers here for
    /// `bench/embree-updates.sh`.
    #[arg(long, value_name = "FILE")]
    pub dump: Option<PathBuf>,
}

pub(crate) fn cmd_bench_updates(a: BenchUpdatesArgs) -> Result<()> {
    if a.every == 0 {
        bail!("--every must be at least 1");
    }
    let aff = load_aff(&a.scene)?;
    crate::output::warnings::warnings(&aff.scene.name, &aff.scene.warnings);
    let flat = flatten_frames(&aff, (0..aff.frame_count()).step_by(a.every as usize));
    if let Some(path) = &a.dump {
        write_dump(path, &flat)?;
    }
    let [refit, lbvh, sah] = crate::render::in_pool(a.threads, || time_updates(&flat))?;
    println!(
        "scene    {}: {} triangles, {} frames sampled (every {})",
        aff.scene.name,
        flat.triangles.len(),
        flat.frames.len(),
        a.every
    );
    println!("update   ms per million triangles, median (p10 … p90); SAH cost over the binned SAH tree's, median and last frame");
    for (name, m) in [("refit", &refit), ("rebuild (LBVH)", &lbvh), ("full (binned SAH)", &sah)] {
        let last = m.cost_ratio.last().copied().unwrap_or(0.0);
        println!("{name:<18} {}   cost {:.3}, last {last:.3}", m.summary(), percentile(&m.cost_ratio, 50.0));
    }
    Ok(())
}
