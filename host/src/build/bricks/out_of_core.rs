//! The partition of a scene larger than memory (Wald & Slusallek 2001 §6.4): the
//! records of a part that does not fit the memory budget are split at a plane near
//! their centroids' median — a histogram pass, then a pass writing each record to its
//! side's spill file — and each side is split again, until a part fits; that part is
//! read into memory, partitioned there and its bricks are built in parallel. Every
//! record is read and written once per level: O(n log n) in all, as the paper's.

use std::path::Path;

use anyhow::Result;

use super::partition::Part;
use super::spill::{median_plane, SpillFile, SpillWriter};
use super::tri_record::{TriRecord, FULL_BYTES};

/// Receives each part that fits in memory, in order, and builds its bricks; returns the
/// part's tree (its leaves are the next bricks, in order).
pub type BuildPart<'a> = dyn FnMut(Vec<TriRecord>) -> Result<Part> + 'a;

/// Partitions `file` (consumed) into bricks of at most `per_brick` triangles, holding at
/// most `memory` bytes of records at once; spill files go beside `file`.
pub fn partition_file(
    file: SpillFile,
    per_brick: usize,
    memory: u64,
    build: &mut BuildPart<'_>,
    progress: &indicatif::ProgressBar,
) -> Result<Part> {
    if file.count.saturating_mul(FULL_BYTES as u64) <= memory || file.count as usize <= per_brick {
        let mut records = file.load()?;
        file.remove();
        return build(std::mem::take(&mut records));
    }
    let (lo, hi) = file.centroids;
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
    let plane = median_plane(&file, axis)?;
    let (mut left, mut right) = split(&file, axis, plane, progress)?;
    if left.count == 0 || right.count == 0 {
        // The plane left one side empty (centroids rounding onto it): halve the file.
        left.remove();
        right.remove();
        (left, right) = split(&file, axis, None, progress)?;
    }
    file.remove();
    let a = partition_file(left, per_brick, memory, build, progress)?;
    let b = partition_file(right, per_brick, memory, build, progress)?;
    Ok(Part::Inner(Box::new(a), Box::new(b)))
}

/// Writes `file`'s records to two new spill files: those whose centroid on `axis` lies
/// below `plane`, and the others (without a plane, the first half and the rest).
fn split(
    file: &SpillFile,
    axis: usize,
    plane: Option<f64>,
    progress: &indicatif::ProgressBar,
) -> Result<(SpillFile, SpillFile)> {
    let base = file.path.display().to_string();
    let mut left = SpillWriter::create(Path::new(&format!("{base}0")), file.shading)?;
    let mut right = SpillWriter::create(Path::new(&format!("{base}1")), file.shading)?;
    let half = file.count / 2;
    let mut k = 0u64;
    file.for_each(|r| {
        let go_left = match plane {
            Some(p) => r.centroid(axis) < p,
            None => k < half,
        };
        k += 1;
        progress.inc(1);
        if go_left {
            left.push(&r)
        } else {
            right.push(&r)
        }
    })?;
    Ok((left.finish()?, right.finish()?))
}
