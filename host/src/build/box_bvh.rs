//! A binned-SAH BVH over boxes in `f32` (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies": centroids binned along all three axes in one pass, the
//! cheapest of the bins' boundaries taken): the instanced scene's top level, rebuilt
//! every frame of an animation, and the dynamic meshes' full rebuild. Primitives are
//! kept as 32-byte records and partitioned in place, each pass computing the children's
//! bounds for the next, so a node costs one binning pass and one partition pass. Node
//! boxes are the exact unions of their boxes (callers pass boxes already rounded
//! outward), so a node holds its children and a leaf its entries exactly as
//! [`raypipe_core::image::instanced::TopLevel`] checks. Nodes are laid out depth first,
//! each node's subtree finished before its sibling's starts (the refit relies on it).

use glam::Vec3A;
use raypipe_core::image::{BvhNode, MAX_TREE_DEPTH};

/// Bins per axis.
const BINS: usize = 16;

/// A built tree: nodes (0 is the root; an inner node's children are adjacent) and the
/// list its leaves index (entries are the caller's box ids).
#[derive(Clone, Debug, Default)]
pub struct BoxBvh {
    /// Nodes.
    pub nodes: Vec<BvhNode>,
    /// Box ids, leaf by leaf.
    pub list: Vec<u32>,
    /// Depth of the deepest leaf (root = 1).
    pub depth: u32,
}

#[derive(Clone, Copy)]
struct Aabb {
    lo: Vec3A,
    hi: Vec3A,
}

impl Aabb {
    const EMPTY: Aabb = Aabb { lo: Vec3A::splat(f32::INFINITY), hi: Vec3A::splat(f32::NEG_INFINITY) };

    #[inline]
    fn grow(&mut self, o: &Aabb) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    #[inline]
    fn grow_point(&mut self, p: Vec3A) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive: its box and id, 32 bytes (the top levels stream every primitive twice
/// per level; a 48-byte record of two 16-byte vectors cost a third more).
#[derive(Clone, Copy)]
struct Prim {
    lo: [f32; 3],
    id: u32,
    hi: [f32; 3],
    _pad: u32,
}

impl Prim {
    #[inline]
    fn aabb(&self) -> Aabb {
        Aabb { lo: Vec3A::from_array(self.lo), hi: Vec3A::from_array(self.hi) }
    }

    #[inline]
    fn centroid2(&self) -> Vec3A {
        // Twice the centroid: binning needs no halving.
        Vec3A::from_array(self.lo) + Vec3A::from_array(self.hi)
    }
}

/// A node's range with its bounds and (doubled) centroid bounds.
struct Range {
    at: usize,
    start: usize,
    end: usize,
    depth: u32,
    bounds: Aabb,
    cbounds: Aabb,
}

/// Builds the tree over `boxes` (`(lo, hi)` each): ranges of more than `max_leaf`
/// boxes are split where the SAH is least, the others are leaves (a range is a larger
/// leaf only where the centroids cannot be told apart or the tree is at its depth
/// limit).
pub fn build_box_bvh(boxes: &[([f32; 3], [f32; 3])], max_leaf: usize) -> BoxBvh {
    let mut prims: Vec<Prim> = Vec::with_capacity(boxes.len());
    let (mut bounds, mut cbounds) = (Aabb::EMPTY, Aabb::EMPTY);
    for (i, (lo, hi)) in boxes.iter().enumerate() {
        let p = Prim { lo: *lo, id: i as u32, hi: *hi, _pad: 0 };
        bounds.grow(&p.aabb());
        cbounds.grow_point(p.centroid2());
        prims.push(p);
    }
    let zero = BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 };
    let mut out = BoxBvh {
        nodes: Vec::with_capacity(2 * boxes.len() / max_leaf.max(1) + 1),
        list: Vec::with_capacity(boxes.len()),
        depth: 0,
    };
    out.nodes.push(zero);
    let max_leaf = max_leaf.max(1);
    let mut todo = vec![Range { at: 0, start: 0, end: prims.len(), depth: 1, bounds, cbounds }];
    while let Some(r) = todo.pop() {
        out.depth = out.depth.max(r.depth);
        let range = &mut prims[r.start..r.end];
        // A leaf of up to `max_leaf` boxes is tested as one block (four triangles, as
        // Embree's leaves; one instance at the top level): it is never split.
        let split = if range.len() <= max_leaf || r.depth + 1 >= MAX_TREE_DEPTH - 4 {
            None
        } else {
            best_split(range, &r.cbounds)
        };
        let node =
            |b: &Aabb, first: u32, count: u32| BvhNode { min: b.lo.to_array(), first, max: b.hi.to_array(), count };
        let Some(split) = split else {
            out.nodes[r.at] = node(&r.bounds, out.list.len() as u32, range.len() as u32);
            out.list.extend(range.iter().map(|p| p.id));
            continue;
        };
        let (left, right) = partition(range, split);
        let mid = r.start + left.count;
        let first = out.nodes.len();
        out.nodes.push(zero);
        out.nodes.push(zero);
        out.nodes[r.at] = node(&r.bounds, first as u32, 0);
        let depth = r.depth + 1;
        todo.push(Range { at: first + 1, start: mid, end: r.end, depth, bounds: right.bounds, cbounds: right.cbounds });
        todo.push(Range { at: first, start: r.start, end: mid, depth, bounds: left.bounds, cbounds: left.cbounds });
    }
    out
}

/// A split: the axis and the bin boundary (centroids in bins below it go left).
#[derive(Clone, Copy)]
struct Split {
    axis: usize,
    bin: usize,
    lo: f32,
    scale: f32,
}

impl Split {
    #[inline]
    fn bin_of(&self, c: Vec3A) -> usize {
        (((c[self.axis] - self.lo) * self.scale) as usize).min(BINS - 1)
    }
}

/// The bins' boundaries on all three axes of one pass, and the cheapest, or `None` when
/// the centroids cannot be told apart.
fn best_split(range: &[Prim], cbounds: &Aabb) -> Option<Split> {
    let extent = cbounds.hi - cbounds.lo;
    let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), Vec3A::splat(BINS as f32 * 0.99999) / extent, Vec3A::ZERO);
    let mut counts = [[0u32; BINS]; 3];
    let mut boxes = [[Aabb::EMPTY; BINS]; 3];
    let top = Vec3A::splat((BINS - 1) as f32);
    for p in range {
        let b_box = p.aabb();
        let b = ((p.centroid2() - cbounds.lo) * scale).min(top).to_array();
        for axis in 0..3 {
            let k = (b[axis] as usize).min(BINS - 1);
            counts[axis][k] += 1;
            boxes[axis][k].grow(&b_box);
        }
    }
    let mut best: Option<(f32, Split)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (counts, boxes) = (&counts[axis], &boxes[axis]);
        // Sweep from the right, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0u32; BINS];
        let (mut acc, mut n) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc.grow(&boxes[b]);
            n += counts[b];
            right_area[b] = acc.area();
            right_count[b] = n;
        }
        let (mut left, mut ln) = (Aabb::EMPTY, 0);
        for b in 1..BINS {
            left.grow(&boxes[b - 1]);
            ln += counts[b - 1];
            if ln == 0 || right_count[b] == 0 {
                continue;
            }
            let cost = left.area() * ln as f32 + right_area[b] * right_count[b] as f32;
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, Split { axis, bin: b, lo: cbounds.lo[axis], scale: scale[axis] }));
            }
        }
    }
    best.map(|(_, split)| split)
}

/// One side of a partition: its count, bounds and centroid bounds.
struct Side {
    count: usize,
    bounds: Aabb,
    cbounds: Aabb,
}

/// Puts the primitives whose centroid's bin is below the split first (two indices
/// moving inward, swapping only misplaced pairs); returns both sides with their bounds.
fn partition(range: &mut [Prim], s: Split) -> (Side, Side) {
    let mut left = Side { count: 0, bounds: Aabb::EMPTY, cbounds: Aabb::EMPTY };
    let mut right = Side { count: 0, bounds: Aabb::EMPTY, cbounds: Aabb::EMPTY };
    let goes_left = |p: &Prim| s.bin_of(p.centroid2()) < s.bin;
    let (mut i, mut j) = (0usize, range.len());
    loop {
        while i < j && goes_left(&range[i]) {
            left.bounds.grow(&range[i].aabb());
            left.cbounds.grow_point(range[i].centroid2());
            i += 1;
        }
        while i < j && !goes_left(&range[j - 1]) {
            right.bounds.grow(&range[j - 1].aabb());
            right.cbounds.grow_point(range[j - 1].centroid2());
            j -= 1;
        }
        if i >= j {
            break;
        }
        range.swap(i, j - 1);
    }
    left.count = i;
    right.count = range.len() - i;
    (left, right)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contains(n: &BvhNode, lo: [f32; 3], hi: [f32; 3]) -> bool {
        (0..3).all(|a| n.min[a] <= lo[a] && hi[a] <= n.max[a])
    }

    /// Every box reaches exactly one leaf, whose box and ancestors' boxes hold it;
    /// leaves respect the size limit once the SAH stops.
    #[test]
    fn every_box_sits_in_one_leaf_that_holds_it() {
        let mut g = 12345u64;
        let mut r = || {
            g = g.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (g >> 40) as f32 / (1u64 << 24) as f32
        };
        for n in [1usize, 2, 3, 17, 500] {
            let boxes: Vec<([f32; 3], [f32; 3])> = (0..n)
                .map(|_| {
                    let lo = [r() * 10.0, r() * 10.0, r() * 10.0];
                    (lo, [lo[0] + r(), lo[1] + r(), lo[2] + r()])
                })
                .collect();
            let t = build_box_bvh(&boxes, 2);
            let mut seen = vec![0; n];
            let mut stack = vec![(0usize, Vec::<usize>::new())];
            while let Some((i, ancestors)) = stack.pop() {
                let node = t.nodes[i];
                for &a in &ancestors {
                    assert!(contains(&t.nodes[a], node.min, node.max), "node {i} outside node {a}");
                }
                if node.count > 0 {
                    assert!(node.count <= 2, "leaf of {}", node.count);
                    for &e in &t.list[node.first as usize..(node.first + node.count) as usize] {
                        seen[e as usize] += 1;
                        let (lo, hi) = boxes[e as usize];
                        assert!(contains(&node, lo, hi));
                    }
                } else {
                    let mut a = ancestors.clone();
                    a.push(i);
                    stack.push((node.first as usize, a.clone()));
                    stack.push((node.first as usize + 1, a));
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "{n} boxes: {seen:?}");
        }
    }
}
