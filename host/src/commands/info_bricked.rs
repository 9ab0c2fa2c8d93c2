//! `raypipe info` of a bricked scene: its index, its bricks' sizes, and (`--codecs`) what
//! each codec would make of them — the measurement the default codec was chosen by.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use raypipe_core::image::bricked::Codec;

use super::fmt_bytes;
use crate::input::bricked::codec::{compress, decompress};
use crate::input::bricked::BrickedScene;
use crate::platform::aligned::AlignedBytes;

/// Prints the bricked scene at `path`; measures the codecs when asked.
pub(crate) fn cmd_info_bricked(path: &Path, codecs: bool) -> Result<()> {
    let open = Instant::now();
    let scene = BrickedScene::open(path)?;
    let opened = open.elapsed().as_secs_f64();
    let index = scene.view();
    let h = index.header();
    let bricks = index.bricks();
    let images: u64 = bricks.iter().map(|b| b.image_size).sum();
    let stored: u64 = bricks.iter().map(|b| b.stored_size).sum();
    let per = |b: u64| b as f64 / h.triangle_count.max(1) as f64;
    println!("scene       {} (bricked, format version {})", scene.name, h.version);
    println!("file        {} bytes ({}), index {} bytes", h.total_size, fmt_bytes(h.total_size as usize), h.index_size);
    println!(
        "bounds      ({}, {}, {}) .. ({}, {}, {})",
        h.bounds_min[0], h.bounds_min[1], h.bounds_min[2], h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]
    );
    println!(
        "triangles   {} ({} in bricks, {:.3} per triangle; {} vertices stored in bricks)",
        h.triangle_count,
        h.reference_count,
        h.reference_count as f64 / h.triangle_count.max(1) as f64,
        h.vertex_count
    );
    println!(
        "bricks      {}, top-level BVH of {} nodes; images {} ({:.1} bytes/triangle), largest {}",
        bricks.len(),
        h.node_count,
        fmt_bytes(images as usize),
        per(images),
        fmt_bytes(h.max_brick_size as usize)
    );
    println!(
        "stored      {} with {} ({:.2}:1, {:.1} bytes/triangle)",
        fmt_bytes(stored as usize),
        index.codec().name(),
        images as f64 / stored.max(1) as f64,
        per(stored)
    );
    let (first, _) = scene.load(0)?;
    println!("brick 0     {} triangles, {}", first.view().triangle_count(), super::structure_summary(first.view()));
    drop(first);
    println!("open        {:.4} s (index mapped and validated)", opened);
    if codecs {
        measure(&scene)?;
    }
    Ok(())
}

/// Each codec on up to 64 bricks spread over the scene: ratio, compression and
/// decompression rates (decompressed bytes per second, one thread).
fn measure(scene: &BrickedScene) -> Result<()> {
    let n = scene.view().brick_count();
    let step = (n / 64).max(1);
    let sample: Vec<AlignedBytes> = (0..n)
        .step_by(step as usize)
        .take(64)
        .map(|b| scene.load(b).map(|(r, _)| AlignedBytes::from_slice(r.image())))
        .collect::<Result<_>>()?;
    let total: u64 = sample.iter().map(|s| s.len() as u64).sum();
    println!("codecs      on {} bricks, {}:", sample.len(), fmt_bytes(total as usize));
    println!("  codec   ratio   compress MB/s   decompress MB/s");
    for codec in [Codec::Lz4, Codec::Zstd] {
        let t = Instant::now();
        let packed: Vec<Vec<u8>> = sample.iter().map(|s| compress(codec, s)).collect::<Result<_>>()?;
        let c_secs = t.elapsed().as_secs_f64();
        let stored: u64 = packed.iter().map(|p| p.len() as u64).sum();
        // Decompression timed over several rounds: the median of five.
        let mut rounds = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            for (p, s) in packed.iter().zip(&sample) {
                let mut out = AlignedBytes::zeroed(s.len());
                decompress(codec, p, &mut out)?;
            }
            rounds.push(t.elapsed().as_secs_f64());
        }
        rounds.sort_by(f64::total_cmp);
        println!(
            "  {:<6} {:>6.2}   {:>13.0}   {:>15.0}",
            codec.name(),
            total as f64 / stored.max(1) as f64,
            total as f64 / c_secs.max(1e-9) / 1e6,
            total as f64 / rounds[2].max(1e-9) / 1e6
        );
    }
    Ok(())
}
