//! A binned-SAH BVH over boxes in `f32` (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies": centroids binned along the widest axis, the cheapest of
//! the bins' boundaries taken): the instanced scene's top level, rebuilt every frame of
//! an animation, and the dynamic bottom levels' fast rebuild. Node boxes are the exact
//! unions of their boxes (callers pass boxes already rounded outward), so a node holds
//! its children and a leaf its entries exactly as [`raypipe_core::image::instanced::TopLevel`]
//! checks.

use glam::Vec3A;
use raypipe_core::image::{BvhNode, MAX_TREE_DEPTH};

/// Bins per split.
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

    fn grow(&mut self, o: &Aabb) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// Builds the tree over `boxes` (`(lo, hi)` each), at most `max_leaf` boxes per leaf.
pub fn build_box_bvh(boxes: &[([f32; 3], [f32; 3])], max_leaf: usize) -> BoxBvh {
    let aabbs: Vec<Aabb> =
        boxes.iter().map(|(lo, hi)| Aabb { lo: Vec3A::from_array(*lo), hi: Vec3A::from_array(*hi) }).collect();
    let centroids: Vec<Vec3A> = aabbs.iter().map(|b| (b.lo + b.hi) * 0.5).collect();
    let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut out = BoxBvh { nodes: vec![node(Aabb::EMPTY, 0, 0)], list: Vec::with_capacity(boxes.len()), depth: 0 };
    let max_leaf = max_leaf.max(1);
    // (node, range of `ids`, depth)
    let mut todo = vec![(0usize, 0usize, ids.len(), 1u32)];
    while let Some((at, start, end, depth)) = todo.pop() {
        out.depth = out.depth.max(depth);
        let range = &mut ids[start..end];
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in range.iter() {
            bounds.grow(&aabbs[i as usize]);
            let c = centroids[i as usize];
            cbounds.grow(&Aabb { lo: c, hi: c });
        }
        let split = if range.len() <= 1 || depth + 1 >= MAX_TREE_DEPTH - 4 {
            None
        } else {
            best_split(range, &aabbs, &centroids, &cbounds, &bounds, max_leaf)
        };
        let Some(mid) = split.map(|s| start + partition(range, &centroids, s)) else {
            out.nodes[at] = node(bounds, out.list.len() as u32, range.len() as u32);
            out.list.extend_from_slice(range);
            continue;
        };
        let first = out.nodes.len();
        out.nodes.push(node(Aabb::EMPTY, 0, 0));
        out.nodes.push(node(Aabb::EMPTY, 0, 0));
        out.nodes[at] = node(bounds, first as u32, 0);
        todo.push((first + 1, mid, end, depth + 1));
        todo.push((first, start, mid, depth + 1));
    }
    out
}

fn node(b: Aabb, first: u32, count: u32) -> BvhNode {
    BvhNode { min: b.lo.to_array(), first, max: b.hi.to_array(), count }
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
    fn bin_of(&self, c: Vec3A) -> usize {
        (((c[self.axis] - self.lo) * self.scale) as usize).min(BINS - 1)
    }
}

/// The cheapest bin boundary over all three axes, or `None` when a leaf is cheaper
/// (and small enough) or the centroids cannot be told apart.
fn best_split(
    range: &[u32],
    aabbs: &[Aabb],
    centroids: &[Vec3A],
    cbounds: &Aabb,
    bounds: &Aabb,
    max_leaf: usize,
) -> Option<Split> {
    let extent = cbounds.hi - cbounds.lo;
    let mut best: Option<(f32, Split)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let split = Split { axis, bin: 0, lo: cbounds.lo[axis], scale: BINS as f32 / extent[axis] * 0.99999 };
        let mut counts = [0u32; BINS];
        let mut boxes = [Aabb::EMPTY; BINS];
        for &i in range {
            let b = split.bin_of(centroids[i as usize]);
            counts[b] += 1;
            boxes[b].grow(&aabbs[i as usize]);
        }
        // Sweep from the right, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut right_count = [0u32; BINS];
        let mut n = 0;
        for b in (1..BINS).rev() {
            acc.grow(&boxes[b]);
            n += counts[b];
            right_area[b] = acc.area();
            right_count[b] = n;
        }
        let mut left = Aabb::EMPTY;
        let mut ln = 0;
        for b in 1..BINS {
            left.grow(&boxes[b - 1]);
            ln += counts[b - 1];
            if ln == 0 || right_count[b] == 0 {
                continue;
            }
            let cost = left.area() * ln as f32 + right_area[b] * right_count[b] as f32;
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, Split { bin: b, ..split }));
            }
        }
    }
    let (cost, split) = best?;
    // Relative to one box test per entry of a leaf: a node costs about one test.
    let leaf_cost = range.len() as f32 * bounds.area();
    let split_cost = bounds.area() + cost;
    (range.len() > max_leaf || split_cost < leaf_cost).then_some(split)
}

/// Puts the ids whose centroid's bin is below the split first; returns how many.
fn partition(range: &mut [u32], centroids: &[Vec3A], s: Split) -> usize {
    let mut left = 0;
    for k in 0..range.len() {
        if s.bin_of(centroids[range[k] as usize]) < s.bin {
            range.swap(k, left);
            left += 1;
        }
    }
    left
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
