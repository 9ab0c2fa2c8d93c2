//! The spatial partition of a bricked scene (Wald & Slusallek 2001 §6.4: a high-level
//! BSP over voxels): a part's region is cut by a plane at the median of its triangles'
//! keys (the centres of their boxes clipped to the region) along the axis where the
//! keys spread most; a triangle reaching across the plane is referenced from both
//! halves ([`super::region`]), so bricks answer for disjoint regions and their boxes
//! barely overlap. References may multiply only so far: along any path from the root,
//! the product of the splits' growth factors (references after ÷ before) stays within
//! the part's allowance, which bounds the whole scene's references by the root's
//! allowance times its triangles (the leaves' shares of each path sum to one). Where a
//! spatial cut would exceed it, or cannot separate the keys, the part is split as
//! objects instead — each triangle to one side by its centroid, both halves keeping the
//! region. The tree is built once, deterministically (ties broken by triangle id), and
//! is the top-level BVH.

use super::region::{Region, Side};
use super::tri_record::TriRecord;

/// How far references may multiply over the triangles of the whole scene. A safeguard
/// against scenes of long, crossing triangles rather than a tuning: the 2 M-triangle
/// power plant stand-in holds 1.088 references per triangle with this bound, with 1.2
/// and with 3 alike (docs/bricked-scenes.md).
pub const MAX_GROWTH: f64 = 1.5;

/// The partition tree; its leaves, left to right, are the bricks in id order.
#[derive(Debug)]
pub enum Part {
    /// A brick.
    Leaf,
    /// Two halves.
    Inner(Box<Part>, Box<Part>),
}

impl Part {
    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        match self {
            Part::Leaf => 1,
            Part::Inner(a, b) => a.leaf_count() + b.leaf_count(),
        }
    }
}

/// A brick to be: its triangles (each once) and the region it answers for.
#[derive(Debug)]
pub struct LeafPart {
    /// The triangles referenced in the region.
    pub records: Vec<TriRecord>,
    /// The region.
    pub region: Region,
}

/// A part's split: its two halves' triangles and regions.
pub struct Split {
    /// Below the plane (or the first half of an object split).
    pub left: (Vec<TriRecord>, Region),
    /// The rest.
    pub right: (Vec<TriRecord>, Region),
    /// References after ÷ before (1 for an object split).
    pub growth: f64,
}

/// The widest axis of the triangles' centroids' box.
pub fn widest_axis(tris: &[TriRecord]) -> usize {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in tris {
        for a in 0..3 {
            let c = t.centroid(a);
            lo[a] = lo[a].min(c);
            hi[a] = hi[a].max(c);
        }
    }
    widest(lo, hi)
}

/// The axis along which the box `lo..hi` is widest (the first of equals).
pub fn widest(lo: [f64; 3], hi: [f64; 3]) -> usize {
    (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0)
}

/// The growth of a spatial cut of `n` references into `left` and `right`, if the cut is
/// taken: both sides non-empty and smaller than the whole, the growth within `allowance`.
pub fn accepted_growth(n: u64, left: u64, right: u64, allowance: f64) -> Option<f64> {
    let growth = (left + right) as f64 / n as f64;
    (left > 0 && right > 0 && left < n && right < n && growth <= allowance).then_some(growth)
}

/// Splits `tris` of `region` in two: spatially if that keeps the growth within
/// `allowance`, as objects otherwise.
pub fn split(mut tris: Vec<TriRecord>, region: Region, allowance: f64) -> Split {
    let n = tris.len();
    if let Some(s) = spatial_split(&tris, region, allowance) {
        return s;
    }
    // An object split: centroid median on the centroids' widest axis, ties by id.
    let mid = n / 2;
    let axis = widest_axis(&tris);
    if mid > 0 && mid < n {
        tris.select_nth_unstable_by(mid, |a, b| a.centroid(axis).total_cmp(&b.centroid(axis)).then(a.id.cmp(&b.id)));
    }
    let right = tris.split_off(mid);
    Split { left: (tris, region), right: (right, region), growth: 1.0 }
}

/// The spatial split of `tris` at the median key, if it separates them and its growth
/// stays within `allowance`.
fn spatial_split(tris: &[TriRecord], region: Region, allowance: f64) -> Option<Split> {
    let n = tris.len();
    let (axis, spread) = region.widest_key_axis(tris);
    if spread <= 0.0 {
        return None;
    }
    let mut keys: Vec<f64> = tris.iter().map(|t| region.key(t, axis)).collect();
    let (_, median, _) = keys.select_nth_unstable_by(n / 2, f64::total_cmp);
    let plane = *median as f32;
    if !region.splits_at(axis, plane) {
        return None;
    }
    let (mut left, mut right) = (0usize, 0usize);
    for t in tris {
        match region.side(t, axis, plane) {
            Side::Left => left += 1,
            Side::Right => right += 1,
            Side::Both => (left, right) = (left + 1, right + 1),
        }
    }
    let growth = accepted_growth(n as u64, left as u64, right as u64, allowance)?;
    let (mut l, mut r) = (Vec::with_capacity(left), Vec::with_capacity(right));
    for t in tris {
        match region.side(t, axis, plane) {
            Side::Left => l.push(*t),
            Side::Right => r.push(*t),
            Side::Both => {
                l.push(*t);
                r.push(*t);
            }
        }
    }
    let (lr, rr) = region.halves(axis, plane);
    Some(Split { left: (l, lr), right: (r, rr), growth })
}

/// Partitions `tris` of `region` into bricks of at most `per_brick` references, within
/// the growth `allowance`; the bricks are appended to `out` left to right. Halves are
/// split in parallel.
pub fn partition(
    tris: Vec<TriRecord>,
    region: Region,
    per_brick: usize,
    allowance: f64,
    out: &mut Vec<LeafPart>,
) -> Part {
    let n = tris.len();
    if n <= per_brick.max(1) {
        out.push(LeafPart { records: tris, region });
        return Part::Leaf;
    }
    let s = split(tris, region, allowance);
    let allowance = allowance / s.growth;
    let ((l, lr), (r, rr)) = (s.left, s.right);
    let mut right_out = Vec::new();
    let (a, b) = if n > 100_000 {
        rayon::join(
            || partition(l, lr, per_brick, allowance, out),
            || partition(r, rr, per_brick, allowance, &mut right_out),
        )
    } else {
        (partition(l, lr, per_brick, allowance, out), partition(r, rr, per_brick, allowance, &mut right_out))
    };
    out.append(&mut right_out);
    Part::Inner(Box::new(a), Box::new(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tris(n: u32) -> Vec<TriRecord> {
        (0..n)
            .map(|i| {
                let x = (i * 7919 % n) as f32;
                TriRecord::plain([[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]], i)
            })
            .collect()
    }

    fn region(t: &[TriRecord]) -> Region {
        let mut r = Region { lo: [f32::INFINITY; 3], hi: [f32::NEG_INFINITY; 3] };
        for t in t {
            let (lo, hi) = super::super::region::tri_box(t);
            for a in 0..3 {
                r.lo[a] = r.lo[a].min(lo[a]);
                r.hi[a] = r.hi[a].max(hi[a]);
            }
        }
        r
    }

    #[test]
    fn parts_are_small_cover_every_triangle_and_regions_tile_space() {
        let t = tris(1000);
        let root = region(&t);
        let mut out = Vec::new();
        let part = partition(t, root, 64, MAX_GROWTH, &mut out);
        assert_eq!(part.leaf_count(), out.len());
        assert!(out.iter().all(|l| l.records.len() <= 64 && !l.records.is_empty()));
        let refs: usize = out.iter().map(|l| l.records.len()).sum();
        assert!(refs >= 1000 && refs as f64 <= 1000.0 * MAX_GROWTH, "{refs}");
        let mut ids: Vec<u32> = out.iter().flat_map(|l| l.records.iter().map(|r| r.id)).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids, (0..1000).collect::<Vec<_>>());
        // Each triangle lies in the union of the regions of the bricks that hold it.
        for l in &out {
            for r in &l.records {
                let (lo, hi) = l.region.clip(r);
                assert!((0..3).all(|a| lo[a] <= hi[a]), "a brick holds a triangle outside its region");
            }
        }
    }

    #[test]
    fn long_triangles_are_shared_not_stretched_over_every_brick() {
        // Small triangles along x and a few long ones spanning everything.
        let mut t = tris(2000);
        for i in 0..10 {
            t.push(TriRecord::plain([[0.0, 0.5, i as f32], [2000.0, 0.5, i as f32], [0.0, 0.6, i as f32]], 2000 + i));
        }
        let root = region(&t);
        let mut out = Vec::new();
        partition(t, root, 64, MAX_GROWTH, &mut out);
        // No brick's region covers the whole x range.
        assert!(out.iter().all(|l| l.region.hi[0] - l.region.lo[0] < 1000.0));
    }

    #[test]
    fn equal_keys_still_halve() {
        let t: Vec<TriRecord> =
            (0..300).map(|i| TriRecord::plain([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], i)).collect();
        let root = region(&t);
        let mut out = Vec::new();
        partition(t, root, 10, MAX_GROWTH, &mut out);
        assert!(out.iter().all(|l| l.records.len() <= 10));
        assert_eq!(out.len(), 32);
    }
}
