//! The spatial partition of a bricked scene: triangles split at the median of their
//! centroids along the widest axis of the centroids' box, recursively, until a part is
//! small enough to be a brick. Each triangle goes to exactly one side (an object split:
//! no triangle is referenced twice or clipped), so bricks' boxes may overlap where
//! triangles straddle a split; the top-level BVH over those boxes is the partition's own
//! tree, built once, deterministically (ties broken by triangle id).

use std::ops::Range;

use super::tri_record::TriRecord;

/// The partition tree over a slice of triangles.
#[derive(Debug)]
pub enum Part {
    /// A brick: these records of the slice.
    Leaf(Range<usize>),
    /// Two halves.
    Inner(Box<Part>, Box<Part>),
}

impl Part {
    /// The leaves' ranges, left to right: the bricks in id order.
    pub fn leaves(&self) -> Vec<Range<usize>> {
        let mut out = Vec::new();
        let mut stack = vec![self];
        while let Some(p) = stack.pop() {
            match p {
                Part::Leaf(r) => out.push(r.clone()),
                Part::Inner(a, b) => {
                    stack.push(b);
                    stack.push(a);
                }
            }
        }
        out
    }
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
    (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0)
}

/// Orders `tris` so that the first `mid` have the smallest centroids on `axis` (ties by
/// id): the median split.
pub fn split_at_median(tris: &mut [TriRecord], axis: usize, mid: usize) {
    if mid == 0 || mid >= tris.len() {
        return;
    }
    tris.select_nth_unstable_by(mid, |a, b| a.centroid(axis).total_cmp(&b.centroid(axis)).then(a.id.cmp(&b.id)));
}

/// Partitions `tris` (reordered in place) into parts of at most `per_brick` triangles;
/// ranges are offsets into `tris` from `base`. Halves are split in parallel.
pub fn partition(tris: &mut [TriRecord], per_brick: usize, base: usize) -> Part {
    let n = tris.len();
    if n <= per_brick.max(1) {
        return Part::Leaf(base..base + n);
    }
    let mid = n / 2;
    split_at_median(tris, widest_axis(tris), mid);
    let (left, right) = tris.split_at_mut(mid);
    let (a, b) = if n > 100_000 {
        rayon::join(|| partition(left, per_brick, base), || partition(right, per_brick, base + mid))
    } else {
        (partition(left, per_brick, base), partition(right, per_brick, base + mid))
    };
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

    #[test]
    fn parts_are_small_cover_every_triangle_once_and_split_space() {
        let mut t = tris(1000);
        let part = partition(&mut t, 64, 0);
        let leaves = part.leaves();
        assert!(leaves.iter().all(|r| r.len() <= 64 && !r.is_empty()));
        assert_eq!(leaves.iter().map(|r| r.len()).sum::<usize>(), 1000);
        assert_eq!(leaves.first().map(|r| r.start), Some(0));
        assert!(leaves.windows(2).all(|w| w[0].end == w[1].start));
        let mut ids: Vec<u32> = t.iter().map(|r| r.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..1000).collect::<Vec<_>>());
        // Along x, each brick's triangles lie left of the next brick's.
        for w in leaves.windows(2) {
            let max_a = t[w[0].clone()].iter().map(|r| r.p[0][0]).fold(f32::MIN, f32::max);
            let min_b = t[w[1].clone()].iter().map(|r| r.p[0][0]).fold(f32::MAX, f32::min);
            assert!(max_a <= min_b, "{max_a} > {min_b}");
        }
    }

    #[test]
    fn equal_centroids_still_halve() {
        let mut t: Vec<TriRecord> =
            (0..300).map(|i| TriRecord::plain([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], i)).collect();
        let leaves = partition(&mut t, 10, 0).leaves();
        assert!(leaves.iter().all(|r| r.len() <= 10));
        assert_eq!(leaves.len(), 32);
    }
}
