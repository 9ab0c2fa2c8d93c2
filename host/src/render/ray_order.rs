//! The order in which a batch's single rays are traced. Incoherent rays (a diffuse
//! bounce's) come in pixel order with directions all over the sphere, so neighbours in
//! the batch walk different parts of the tree, and different octant forms of the walk.
//! Traced grouped by direction class instead (octant and dominant axis: 24 classes),
//! rays that follow each other touch the same nodes and triangles while they are still
//! in the cache. This is Pharr et al. 1997's ray reordering, with a key as cheap as a
//! counting sort. Within a class the batch's order is kept, so origins stay near their
//! neighbours'. Finer keys (directions on a cube map of 4×4 or 8×8 cells per face, or an
//! origin Morton code) traced no faster, and cost more to sort.
//!
//! Each ray's answer is the same, bit for bit, in any order: a closest-hit walk reads
//! nothing another ray wrote, and the shadow cache an any-hit ray may test first (the
//! leaf that blocked an earlier ray) changes its work, never its answer. The order
//! changes only when each ray is traced.

use std::mem::MaybeUninit;

use anyhow::Result;
use raypipe_core::{Ray, Vec3};

use crate::platform::huge_pages;
use crate::platform::thread_pools::for_each_claimed;

/// How a batch of single rays is ordered before it is traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RayOrder {
    /// By direction class when neighbouring rays mostly differ in it (incoherent rays);
    /// else as given.
    #[default]
    Auto,
    /// As given.
    Input,
    /// By direction class, whatever the batch.
    Direction,
}

/// Direction classes: eight octants times three dominant axes.
const CLASSES: usize = 24;

/// How many neighbouring pairs `Auto` looks at to judge a batch.
const SAMPLE_PAIRS: usize = 4096;

/// The share of sampled neighbours in different classes above which `Auto` reorders.
/// Eye rays and shadow rays to one light differ at a few boundaries (under 1% of the
/// pairs on the harness's scenes); a diffuse bounce's in about 90%.
const INCOHERENT_SHARE: f64 = 0.25;

/// Batches smaller than this are traced as given: the sort has nothing to win.
const MIN_RAYS: usize = 1024;

/// The fewest rays a part of the sort takes on a thread of its own.
const MIN_PART: usize = 1 << 16;

/// The most parts the sort cuts a batch into (each keeps 24 output streams open).
const MAX_PARTS: usize = 16;

/// Rays per task when the hits are put back.
const RESTORE_CHUNK: usize = 1 << 16;

/// The direction class of `d`: its octant (the signs of its components) and its
/// dominant axis.
#[inline]
fn class(d: Vec3) -> usize {
    let octant = (d.x < 0.0) as usize | ((d.y < 0.0) as usize) << 1 | ((d.z < 0.0) as usize) << 2;
    let a = d.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    octant * 3 + axis
}

/// True when most of the sampled neighbouring rays of `rays` differ in direction class.
fn incoherent(rays: &[Ray]) -> bool {
    let pairs = rays.len().saturating_sub(1);
    if pairs == 0 {
        return false;
    }
    let step = pairs.div_ceil(SAMPLE_PAIRS).max(1);
    let (mut sampled, mut differ) = (0usize, 0usize);
    for w in rays.windows(2).step_by(step) {
        sampled += 1;
        differ += (class(w[0].dir) != class(w[1].dir)) as usize;
    }
    differ as f64 > INCOHERENT_SHARE * sampled as f64
}

/// A batch's rays in tracing order, and where each went: ray `i` of the batch is ray
/// `pos[i]` here. The rays are moved, not indexed: traced through an index, each ray's
/// record and each hit's lay on a cache line of its own (the hits written a line at a
/// time, each line read first), and the batch traced at 0.83–0.95× its speed in the
/// given order; moved by the counting sort, the reads and writes are 24 sequential
/// streams. The buffers are kept from batch to batch, as a batch's output is: fresh
/// ones for a million rays cost a few milliseconds of page faults, a third of the sort.
#[derive(Debug, Default)]
pub struct Reordered {
    rays: Vec<Ray>,
    // Empty, or a permutation of `0 .. rays.len()`: only a sort that checked every range
    // full leaves it filled (`by_class`), and `restore` relies on that.
    pos: Vec<u32>,
    classes: Vec<u8>,
}

impl Reordered {
    /// Sorts `rays` into this workspace in the order `order` makes, on `threads`
    /// threads (all cores when `None`); false when they are to be traced as given (and
    /// the workspace holds no batch).
    pub fn sort(&mut self, rays: &[Ray], order: RayOrder, threads: Option<usize>) -> Result<bool> {
        self.rays.clear();
        self.pos.clear();
        let sort = match order {
            RayOrder::Input => false,
            RayOrder::Direction => true,
            RayOrder::Auto => rays.len() >= MIN_RAYS && incoherent(rays),
        };
        // Positions are `u32` (half the bytes of `usize` to stream); a batch this large
        // is traced as given.
        if !sort || rays.len() > u32::MAX as usize {
            return Ok(false);
        }
        self.by_class(rays, threads)
    }

    /// A stable counting sort of `rays` by direction class, the batch cut into one part
    /// per thread: each part counts its classes, then moves its rays into its own range
    /// of each class's (part 0's rays of a class first, then part 1's, …). False if it
    /// failed (it cannot: see the end).
    fn by_class(&mut self, rays: &[Ray], threads: Option<usize>) -> Result<bool> {
        let n = rays.len();
        let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |t| t.get()));
        let parts = if n < MIN_PART * 2 { 1 } else { threads.clamp(1, MAX_PARTS) };
        let part = n.div_ceil(parts).max(1);
        reserve(&mut self.classes, n);
        self.classes.resize(n, 0);
        let mut counts = vec![[0usize; CLASSES]; parts];
        let work = self.classes.chunks_mut(part).zip(rays.chunks(part)).zip(counts.iter_mut());
        for_each_claimed(Some(parts), work, |((classes, rays), count)| {
            for (c, r) in classes.iter_mut().zip(rays) {
                *c = class(r.dir) as u8;
                count[*c as usize] += 1;
            }
        })?;
        // Each part's first position in each class.
        let mut start = vec![[0usize; CLASSES]; parts];
        let mut sum = 0;
        for c in 0..CLASSES {
            for (s, count) in start.iter_mut().zip(&counts) {
                (s[c], sum) = (sum, sum + count[c]);
            }
        }
        reserve(&mut self.pos, n);
        self.pos.resize(n, 0);
        reserve(&mut self.rays, n);
        // The spare capacity cut into each part's range of each class, in position order.
        let mut rest = &mut self.rays.spare_capacity_mut()[..n];
        let mut ranges: Vec<Vec<&mut [MaybeUninit<Ray>]>> = (0..parts).map(|_| Vec::with_capacity(CLASSES)).collect();
        for c in 0..CLASSES {
            for (range, count) in ranges.iter_mut().zip(&counts) {
                let len = count[c].min(rest.len());
                let (this, after) = std::mem::take(&mut rest).split_at_mut(len);
                range.push(this);
                rest = after;
            }
        }
        let mut filled = vec![[0usize; CLASSES]; parts];
        let work = ranges
            .into_iter()
            .zip(rays.chunks(part).zip(self.classes.chunks(part)))
            .zip(self.pos.chunks_mut(part).zip(&start))
            .zip(filled.iter_mut());
        let moved = for_each_claimed(Some(parts), work, |(((mut ranges, (rays, classes)), (pos, start)), fill)| {
            for ((r, &c), p) in rays.iter().zip(classes).zip(pos) {
                let c = c as usize % CLASSES;
                *p = (start[c] + fill[c]) as u32;
                // Counted only when written: the count is what proves the range full.
                if let Some(slot) = ranges.get_mut(c).and_then(|range| range.get_mut(fill[c])) {
                    slot.write(*r);
                    fill[c] += 1;
                }
            }
        });
        // Each part wrote as many rays of each class as its range holds, and the ranges
        // tile `0 .. n`; else (or if the threads did not run) no permutation is kept.
        if moved.is_err() || filled != counts || sum != n || !rest.is_empty() {
            self.pos.clear();
            return moved.map(|()| false);
        }
        // SAFETY: the capacity is at least `n` (reserved above), and the first `n` slots
        // are written: the ranges tile them, and each was filled to its length.
        unsafe { self.rays.set_len(n) };
        Ok(true)
    }

    /// The rays in tracing order.
    pub fn rays(&self) -> &[Ray] {
        &self.rays
    }

    /// `items` (one per ray of the batch) in tracing order; empty when their number is
    /// not the batch's.
    pub fn apply<T: Copy>(&self, items: &[T]) -> Vec<T> {
        let Some(&first) = items.first().filter(|_| items.len() == self.pos.len()) else {
            return Vec::new();
        };
        let mut out = huge_pages::filled_vec(items.len(), first);
        for (&p, x) in self.pos.iter().zip(items) {
            if let Some(o) = out.get_mut(p as usize) {
                *o = *x;
            }
        }
        out
    }

    /// `traced` (one per ray, in tracing order) back in the batch's order, into `out`,
    /// replacing its contents (and keeping its memory where it is large enough), on
    /// `threads` threads; empty when `traced` is not one per ray.
    pub fn restore<T: Copy + Send + Sync>(&self, traced: &[T], out: &mut Vec<T>, threads: Option<usize>) -> Result<()> {
        out.clear();
        let n = self.pos.len();
        if traced.len() != n {
            return Ok(());
        }
        reserve(out, n);
        let work = out.spare_capacity_mut()[..n].chunks_mut(RESTORE_CHUNK).zip(self.pos.chunks(RESTORE_CHUNK));
        for_each_claimed(threads, work, |(out, pos)| {
            for (o, &p) in out.iter_mut().zip(pos) {
                if let Some(t) = traced.get(p as usize) {
                    o.write(*t);
                }
            }
        })?;
        // SAFETY: the capacity is at least `n`, and each of the first `n` slots is written:
        // the output's chunks pair with the positions' chunks of the same lengths, and
        // every position is below `n` (`pos` holds a permutation of `0 .. n`, see its
        // field), so `traced.get` finds each.
        unsafe { out.set_len(n) };
        Ok(())
    }
}

/// Makes room in `v` (empty) for `n` elements, asking for huge pages for a new buffer.
fn reserve<T>(v: &mut Vec<T>, n: usize) {
    v.clear();
    if v.capacity() < n {
        *v = huge_pages::empty_vec(n);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(dir: Vec3) -> Ray {
        Ray { origin: Vec3::ZERO, dir, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// A reproducible spread of directions over the sphere.
    fn scattered(n: usize) -> Vec<Ray> {
        let mut s = 0x2545_f491u32;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        (0..n).map(|_| ray(Vec3::new(next(), next(), next()))).collect()
    }

    #[test]
    fn classes_are_octant_and_dominant_axis() {
        assert_eq!(class(Vec3::new(1.0, 0.5, 0.25)), 0);
        assert_eq!(class(Vec3::new(0.5, 1.0, 0.25)), 1);
        assert_eq!(class(Vec3::new(0.5, 0.25, -1.0)), 4 * 3 + 2);
        assert_eq!(class(Vec3::new(-0.5, -2.0, -1.0)), 7 * 3 + 1);
    }

    #[test]
    fn the_order_is_a_stable_permutation_by_class() {
        let rays = scattered(5000);
        let mut r = Reordered::default();
        assert!(r.sort(&rays, RayOrder::Direction, Some(1)).unwrap(), "sorted on request");
        let mut seen = vec![false; rays.len()];
        for (i, &p) in r.pos.iter().enumerate() {
            assert!(!seen[p as usize], "position {p} twice");
            seen[p as usize] = true;
            assert_eq!(r.rays()[p as usize], rays[i]);
        }
        assert!(seen.iter().all(|s| *s));
        // Classes ascend along the order; within a class, the batch's order is kept.
        let mut from = vec![0usize; rays.len()];
        for (i, &p) in r.pos.iter().enumerate() {
            from[p as usize] = i;
        }
        for w in from.windows(2) {
            let (a, b) = (class(rays[w[0]].dir), class(rays[w[1]].dir));
            assert!(a < b || (a == b && w[0] < w[1]), "{w:?}: classes {a}, {b}");
        }
        // Results in tracing order come back in the batch's order.
        let ids: Vec<usize> = (0..rays.len()).collect();
        let traced = r.apply(&ids);
        let mut back = vec![usize::MAX; 3];
        r.restore(&traced, &mut back, Some(1)).unwrap();
        assert_eq!(back, ids);
        assert!(r.apply(&ids[1..]).is_empty(), "a list of another length");
        r.restore(&traced[1..], &mut back, Some(1)).unwrap();
        assert!(back.is_empty(), "results of another length");
        // The workspace sorts the next batch the same, from its kept buffers.
        let again = scattered(4000);
        assert!(r.sort(&again, RayOrder::Direction, Some(1)).unwrap());
        let mut fresh = Reordered::default();
        assert!(fresh.sort(&again, RayOrder::Direction, Some(1)).unwrap());
        assert_eq!((r.rays(), &r.pos), (fresh.rays(), &fresh.pos));
    }

    #[test]
    fn every_part_count_sorts_alike() {
        // Parts of at least `MIN_PART` rays each: one, two and three threads.
        let rays = scattered(3 * MIN_PART + 17);
        let mut one = Reordered::default();
        assert!(one.sort(&rays, RayOrder::Direction, Some(1)).unwrap());
        for threads in [2, 3] {
            let mut more = Reordered::default();
            assert!(more.sort(&rays, RayOrder::Direction, Some(threads)).unwrap());
            assert!(more.rays() == one.rays() && more.pos == one.pos, "{threads} threads");
            let ids: Vec<u32> = (0..rays.len() as u32).collect();
            let mut back = Vec::new();
            more.restore(&more.apply(&ids), &mut back, Some(threads)).unwrap();
            assert_eq!(back, ids);
        }
    }

    #[test]
    fn auto_sorts_scattered_rays_only() {
        let rays = scattered(5000);
        let mut r = Reordered::default();
        assert!(r.sort(&rays, RayOrder::Auto, None).unwrap());
        assert!(!r.sort(&rays, RayOrder::Input, None).unwrap());
        assert!(r.rays().is_empty(), "no batch held when traced as given");
        assert!(!r.sort(&rays[..100], RayOrder::Auto, None).unwrap(), "a small batch");
        // A camera's rays: directions sweep smoothly, crossing a class boundary rarely.
        let eye: Vec<Ray> = (0..5000)
            .map(|i| ray(Vec3::new((i % 100) as f32 / 50.0 - 1.0, (i / 100) as f32 / 25.0 - 1.0, -1.0)))
            .collect();
        assert!(!r.sort(&eye, RayOrder::Auto, None).unwrap());
    }
}
