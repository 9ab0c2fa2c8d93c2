//! The partition of a scene larger than memory (Wald & Slusallek 2001 §6.4): a part
//! that does not fit the memory budget is cut as [`mod@super::partition`] cuts one in
//! memory — a plane near the median of its keys, found with a histogram pass, then a
//! pass writing each record to its side's spill file (to both when it straddles) — and
//! each side is cut again, until a part fits; that part is read into memory,
//! partitioned there and its bricks are built in parallel. Every record is read and
//! written once per level: O(n log n) in all, as the paper's.

use std::path::Path;

use anyhow::Result;

use super::partition::{accepted_growth, widest, Part};
use super::region::{Region, Side};
use super::spill::{median_plane, SpillFile, SpillWriter};
use super::tri_record::{TriRecord, FULL_BYTES};

/// Receives each part that fits in memory, in order — its records, its region and its
/// growth allowance — and builds its bricks; returns the part's tree (its leaves are
/// the next bricks, in order).
pub type BuildPart<'a> = dyn FnMut(Vec<TriRecord>, Region, f64) -> Result<Part> + 'a;

/// How much memory a part's records may take, times their own size, to be partitioned
/// in memory: the records, and both halves of the first cut (with their shared
/// triangles) while it is made.
const IN_MEMORY_FACTOR: u64 = 3;

/// Partitions `file` (consumed) of `region` into bricks of at most `per_brick`
/// references within the growth `allowance`, holding at most `memory` bytes of records
/// at once; spill files go beside `file`.
pub fn partition_file(
    file: SpillFile,
    (region, allowance): (Region, f64),
    per_brick: usize,
    memory: u64,
    build: &mut BuildPart<'_>,
    progress: &indicatif::ProgressBar,
) -> Result<Part> {
    let bytes = file.count.saturating_mul(FULL_BYTES as u64).saturating_mul(IN_MEMORY_FACTOR);
    if bytes <= memory || file.count as usize <= per_brick {
        let mut records = file.load()?;
        file.remove();
        return build(std::mem::take(&mut records), region, allowance);
    }
    let (left, right, growth) = match spatial(&file, region, allowance, progress)? {
        Some(halves) => halves,
        None => object(&file, region, progress)?,
    };
    file.remove();
    let allowance = allowance / growth;
    let a = partition_file(left.0, (left.1, allowance), per_brick, memory, build, progress)?;
    let b = partition_file(right.0, (right.1, allowance), per_brick, memory, build, progress)?;
    Ok(Part::Inner(Box::new(a), Box::new(b)))
}

type Half = (SpillFile, Region);

/// The spatial cut at the keys' median, if it separates the records within the growth
/// `allowance`.
fn spatial(
    file: &SpillFile,
    region: Region,
    allowance: f64,
    progress: &indicatif::ProgressBar,
) -> Result<Option<(Half, Half, f64)>> {
    // The axis where the centroids spread most inside the region.
    let (lo, hi) = file.centroids;
    let inside = |a: usize| (lo[a].max(f64::from(region.lo[a])), hi[a].min(f64::from(region.hi[a])));
    let axis = widest([0, 1, 2].map(|a| inside(a).0), [0, 1, 2].map(|a| inside(a).1));
    let range = (f64::from(region.lo[axis]), f64::from(region.hi[axis]));
    let Some(plane) = median_plane(file, range, |r| region.key(r, axis))? else { return Ok(None) };
    let plane = plane as f32;
    if !region.splits_at(axis, plane) {
        return Ok(None);
    }
    let (left, right) = write_sides(file, progress, |r| region.side(r, axis, plane))?;
    let Some(growth) = accepted_growth(file.count, left.count, right.count, allowance) else {
        left.remove();
        right.remove();
        return Ok(None);
    };
    let (lr, rr) = region.halves(axis, plane);
    Ok(Some(((left, lr), (right, rr), growth)))
}

/// The object cut: each record to one side by its centroid (at the centroids' median,
/// or the file halved when they cannot be told apart); both halves keep the region.
fn object(file: &SpillFile, region: Region, progress: &indicatif::ProgressBar) -> Result<(Half, Half, f64)> {
    let (lo, hi) = file.centroids;
    let axis = widest(lo, hi);
    let at_plane = match median_plane(file, (lo[axis], hi[axis]), |r| r.centroid(axis))? {
        Some(p) => {
            let (l, r) = write_sides(file, progress, |r| if r.centroid(axis) < p { Side::Left } else { Side::Right })?;
            if l.count > 0 && r.count > 0 {
                Some((l, r))
            } else {
                l.remove();
                r.remove();
                None
            }
        }
        None => None,
    };
    let (left, right) = match at_plane {
        Some(halves) => halves,
        None => {
            // The plane left one side empty (centroids rounding onto it), or there was
            // none: halve the file.
            let (half, mut k) = (file.count / 2, 0u64);
            write_sides(file, progress, |_| {
                k += 1;
                if k <= half {
                    Side::Left
                } else {
                    Side::Right
                }
            })?
        }
    };
    Ok(((left, region), (right, region), 1.0))
}

/// Writes `file`'s records to two new spill files as `side` says.
fn write_sides(
    file: &SpillFile,
    progress: &indicatif::ProgressBar,
    mut side: impl FnMut(&TriRecord) -> Side,
) -> Result<(SpillFile, SpillFile)> {
    let base = file.path.display().to_string();
    let mut left = SpillWriter::create(Path::new(&format!("{base}0")), file.shading)?;
    let mut right = SpillWriter::create(Path::new(&format!("{base}1")), file.shading)?;
    file.for_each(|r| {
        progress.inc(1);
        match side(&r) {
            Side::Left => left.push(&r),
            Side::Right => right.push(&r),
            Side::Both => {
                left.push(&r)?;
                right.push(&r)
            }
        }
    })?;
    Ok((left.finish()?, right.finish()?))
}
