//! Builds a BVH by the binned surface area heuristic (Wald 2007, "On fast construction of
//! SAH-based bounding volume hierarchies"), writing 32-byte nodes whose children sit side
//! by side (`BvhNode`). Each node's box is grown outwards by a small margin, so that a
//! triangle lying on a box face is never culled by the rounding of the entry distance.

use glam::DVec3;
use raypipe_core::image::{BvhNode, WideNode, MAX_TREE_DEPTH, MAX_WIDE_DEPTH};

use crate::build::spatial_split::{find_spatial_split, split_references};
use crate::build::tri_clip::clipped_bounds;
use crate::input::mesh::Mesh;

/// The SAH cost constants and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhParams {
    /// Bins per axis.
    pub bins: usize,
    /// Cost of visiting a node, relative to one triangle test.
    pub traversal_cost: f64,
    /// Cost of one triangle test.
    pub intersection_cost: f64,
    /// Largest leaf (a larger one is split even if the SAH prefers not to).
    pub max_leaf: usize,
    /// Early split clipping (Ernst & Greiner 2007): a triangle whose box is longer than
    /// this fraction of the scene's extent is cut into pieces with tight boxes, so that
    /// large triangles (floors, walls) do not bloat the nodes they fall in. 0 disables.
    /// Spatial splits do the same where the SAH gains by it, but the two together took
    /// 5% fewer instructions per ray than spatial splits alone on the conference room
    /// (3% more on Sponza), averaged over four views of each.
    pub presplit_extent: f64,
    /// Spatial splits (Stich et al. 2009, "Spatial splits in bounding volume
    /// hierarchies"): tried at a node whose best object split leaves children overlapping
    /// by more than this fraction of the root's surface area. 0 disables.
    pub spatial_alpha: f64,
    /// At most this many references per triangle on average, whatever the splitting.
    pub max_refs_per_triangle: f64,
    /// Triangles a leaf tests at once (4 with TRI_BLOCKS): the SAH prices a leaf by its
    /// blocks, `ceil(n / leaf_block)`, as Embree does for its four-triangle leaves.
    pub leaf_block: usize,
    /// Deepest the binary tree may grow (root = 1): deeper, a node becomes a leaf.
    pub max_depth: u32,
}

impl Default for BvhParams {
    fn default() -> Self {
        BvhParams {
            bins: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            max_leaf: 8,
            presplit_extent: 1.0 / 32.0,
            spatial_alpha: 1e-5,
            max_refs_per_triangle: 3.0,
            leaf_block: 1,
            max_depth: MAX_TREE_DEPTH - 4,
        }
    }
}

/// A built BVH.
#[derive(Clone, Debug, Default)]
pub struct BuiltBvh {
    /// Nodes; 0 is the root.
    pub nodes: Vec<BvhNode>,
    /// Triangle ids referenced by the leaves.
    pub prims: Vec<u32>,
    /// Depth of the deepest leaf (root = 1).
    pub depth: u32,
}

/// An axis-aligned box in f64 (empty when `lo > hi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
}

impl Bounds {
    pub(crate) const EMPTY: Bounds = Bounds { lo: DVec3::splat(f64::INFINITY), hi: DVec3::splat(f64::NEG_INFINITY) };

    pub(crate) fn grow(&mut self, o: &Bounds) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    pub(crate) fn area(&self) -> f64 {
        let e = (self.hi - self.lo).max(DVec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// A node's f32 box.
    fn of_box(lo: [f32; 3], hi: [f32; 3]) -> Bounds {
        Bounds { lo: DVec3::from(lo.map(f64::from)), hi: DVec3::from(hi.map(f64::from)) }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }

    /// The axes along which the box has a positive extent: `(axis, lo, hi)`.
    pub(crate) fn extended_axes(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        (0..3).filter(|&a| self.hi[a] > self.lo[a]).map(|a| (a, self.lo[a], self.hi[a]))
    }

    fn intersection(&self, o: &Bounds) -> Bounds {
        Bounds { lo: self.lo.max(o.lo), hi: self.hi.min(o.hi) }
    }

    /// The box of the part of triangle `v` inside this box, if any.
    fn clip(&self, v: &[DVec3; 3]) -> Option<Bounds> {
        clipped_bounds(v, self.lo, self.hi).map(|(lo, hi)| Bounds { lo, hi })
    }
}

/// A build reference: a triangle, and the box of the part of it this reference stands
/// for (the whole triangle's box, or a piece's after a split).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ref {
    pub(crate) b: Bounds,
    pub(crate) tri: u32,
}

impl Ref {
    pub(crate) fn centroid(&self) -> DVec3 {
        (self.b.lo + self.b.hi) * 0.5
    }
}

/// Margin that node boxes are grown by: relative to the scene's size and magnitude.
pub fn box_margin(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (DVec3::from(lo.map(f64::from)), DVec3::from(hi.map(f64::from)));
    1e-5 * (hi - lo).max_element() + 8.0 * f64::from(f32::EPSILON) * lo.abs().max(hi.abs()).max_element()
}

/// Builds the BVH.
pub fn build_bvh(mesh: &Mesh, params: &BvhParams) -> BuiltBvh {
    let verts: Vec<[DVec3; 3]> =
        mesh.triangles.iter().map(|t| t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)))).collect();
    let budget = (params.max_refs_per_triangle * verts.len() as f64) as usize;
    let refs = presplit_references(mesh, &verts, params, budget);
    let mut spare = budget.saturating_sub(refs.len());
    let mut root = Bounds::EMPTY;
    for r in &refs {
        root.grow(&r.b);
    }
    // Spatial splits are tried only where the object split's children overlap by more
    // than this area (Stich et al. 2009, section 4.4: alpha of the root's area).
    let min_overlap = params.spatial_alpha * root.area();
    let margin = box_margin(mesh);
    let mut out =
        BuiltBvh { nodes: vec![BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 }], ..Default::default() };
    // (node, its references, depth)
    let mut todo = vec![(0usize, refs, 1u32)];
    let max_depth = params.max_depth.clamp(1, MAX_TREE_DEPTH - 4);
    while let Some((node, refs, depth)) = todo.pop() {
        out.depth = out.depth.max(depth);
        let mut bounds = Bounds::EMPTY;
        let mut cbounds = Bounds::EMPTY;
        for r in &refs {
            bounds.grow(&r.b);
            let c = r.centroid();
            cbounds.grow(&Bounds { lo: c, hi: c });
        }
        out.nodes[node].min = round_down(bounds.lo - DVec3::splat(margin));
        out.nodes[node].max = round_up(bounds.hi + DVec3::splat(margin));
        let count = refs.len();
        let split = if count <= 1 || depth >= max_depth {
            None
        } else {
            let object = find_split(&refs, &bounds, &cbounds, params);
            let spatial = match object {
                Some(o) if spare > 0 && min_overlap > 0.0 && o.overlap > min_overlap => {
                    find_spatial_split(&verts, &refs, &bounds, params)
                }
                _ => None,
            };
            match (object, spatial) {
                (Some(o), Some(s)) if s.cost < o.cost => Some(s),
                (o, _) => o,
            }
            .filter(|s| s.cost < leaf_cost(count, params) || count > params.max_leaf)
        };
        let (left, right) = match split {
            Some(Split { axis, pos, spatial: Some(sides), .. }) => {
                split_references(&verts, refs, axis, pos, &sides, params, &mut spare)
            }
            Some(s) => refs.into_iter().partition(|r| r.centroid()[s.axis] < s.pos),
            // Too many triangles for a leaf and no useful plane (e.g. equal centroids):
            // split the list in half.
            None if count > params.max_leaf && depth < max_depth => {
                let mut left = refs;
                let right = left.split_off(count / 2);
                (left, right)
            }
            None => (refs, Vec::new()),
        };
        if left.is_empty() || right.is_empty() {
            // A leaf: each triangle once, however many of its pieces arrived here.
            let mut tris: Vec<u32> = left.iter().chain(&right).map(|r| r.tri).collect();
            tris.sort_unstable();
            tris.dedup();
            out.nodes[node].first = out.prims.len() as u32;
            out.nodes[node].count = tris.len() as u32;
            out.prims.extend_from_slice(&tris);
        } else {
            let child = out.nodes.len();
            out.nodes.push(out.nodes[node]);
            out.nodes.push(out.nodes[node]);
            out.nodes[node].first = child as u32;
            out.nodes[node].count = 0;
            todo.push((child + 1, right, depth + 1));
            todo.push((child, left, depth + 1));
        }
    }
    out
}

/// A leaf's cost: its blocks of `leaf_block` triangles, each one intersection.
pub(crate) fn leaf_cost(n: usize, p: &BvhParams) -> f64 {
    p.intersection_cost * n.div_ceil(p.leaf_block.max(1)) as f64
}

/// The SAH cost of splitting a node of surface area `parent_area` into children of
/// `(area, references)` `left` and `right`: one traversal step, then each child's leaf
/// cost weighted by the chance a ray through the parent enters it.
pub(crate) fn split_cost(p: &BvhParams, parent_area: f64, left: (f64, usize), right: (f64, usize)) -> f64 {
    p.traversal_cost + children_cost(p, left, right) / parent_area
}

/// The area-weighted leaf costs of two children `(area, references)`.
pub(crate) fn children_cost(p: &BvhParams, (al, nl): (f64, usize), (ar, nr): (f64, usize)) -> f64 {
    al * leaf_cost(nl, p) + ar * leaf_cost(nr, p)
}

/// The build references: one box per triangle, or per piece of a large triangle cut by
/// early split clipping (at most `budget` references in all).
fn presplit_references(mesh: &Mesh, verts: &[[DVec3; 3]], params: &BvhParams, budget: usize) -> Vec<Ref> {
    let boxes: Vec<Bounds> =
        verts.iter().map(|v| Bounds { lo: v[0].min(v[1]).min(v[2]), hi: v[0].max(v[1]).max(v[2]) }).collect();
    let (lo, hi) = mesh.bounds();
    let extent = (DVec3::from(hi.map(f64::from)) - DVec3::from(lo.map(f64::from))).max_element();
    let limit = params.presplit_extent * extent;
    let mut refs = Vec::with_capacity(verts.len());
    // Largest triangles first get pieces while the budget lasts.
    let mut order: Vec<usize> = (0..verts.len()).collect();
    if limit > 0.0 {
        order.sort_by(|&a, &b| {
            let ea = (boxes[a].hi - boxes[a].lo).max_element();
            let eb = (boxes[b].hi - boxes[b].lo).max_element();
            eb.total_cmp(&ea)
        });
    }
    let mut spare = budget.saturating_sub(verts.len());
    let mut pieces = Vec::new();
    let mut split_of = vec![None; verts.len()];
    for &t in &order {
        if limit <= 0.0 || (boxes[t].hi - boxes[t].lo).max_element() <= limit || spare == 0 {
            continue;
        }
        pieces.clear();
        clip_split(&verts[t], boxes[t], limit, spare + 1, &mut pieces);
        if pieces.len() > 1 {
            spare = spare.saturating_sub(pieces.len() - 1);
            split_of[t] = Some(pieces.clone());
        }
    }
    for t in 0..verts.len() {
        match split_of[t].take() {
            Some(ps) => refs.extend(ps.into_iter().map(|b| Ref { b, tri: t as u32 })),
            None => refs.push(Ref { b: boxes[t], tri: t as u32 }),
        }
    }
    refs
}

/// Halves `b` along its longest axis while it is longer than `limit`, keeping the box of
/// the triangle's part in each half (at most `max` pieces in `out`, which has room for
/// one more on entry).
fn clip_split(v: &[DVec3; 3], b: Bounds, limit: f64, max: usize, out: &mut Vec<Bounds>) {
    let e = b.hi - b.lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    if e[axis] <= limit || out.len() + 2 > max {
        out.push(b);
        return;
    }
    let mid = 0.5 * (b.lo[axis] + b.hi[axis]);
    let (mut left, mut right) = (b, b);
    left.hi[axis] = mid;
    right.lo[axis] = mid;
    let halves: Vec<Bounds> = [left, right].iter().filter_map(|h| h.clip(v)).collect();
    for (i, &c) in halves.iter().enumerate() {
        // Each half ends as at least one piece: the first leaves room for the second.
        let reserve = halves.len() - 1 - i;
        clip_split(v, c, limit, max - reserve, out);
    }
}

/// A candidate split: the plane, its SAH cost, and (object splits) how much the two
/// children's boxes overlap.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Split {
    pub(crate) axis: usize,
    pub(crate) pos: f64,
    pub(crate) cost: f64,
    pub(crate) overlap: f64,
    /// A spatial split cuts the references that straddle the plane (`Some`: the
    /// children's boxes and reference counts as binned); an object split sends each
    /// reference to the side of its centroid.
    pub(crate) spatial: Option<Sides>,
}

/// A spatial split's two children as its binning saw them: box and reference count.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sides {
    pub(crate) left: (Bounds, usize),
    pub(crate) right: (Bounds, usize),
}

/// The best binned-SAH object split (Wald 2007): references binned by centroid.
fn find_split(refs: &[Ref], bounds: &Bounds, cbounds: &Bounds, p: &BvhParams) -> Option<Split> {
    let n = refs.len();
    let parent_area = bounds.area().max(f64::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    for (axis, lo, hi) in cbounds.extended_axes() {
        let scale = p.bins as f64 / (hi - lo);
        let mut bin_bounds = vec![Bounds::EMPTY; p.bins];
        let mut bin_count = vec![0usize; p.bins];
        for r in refs {
            let k = (((r.centroid()[axis] - lo) * scale) as usize).min(p.bins - 1);
            bin_bounds[k].grow(&r.b);
            bin_count[k] += 1;
        }
        // Sweep from the right, then from the left.
        let mut right_bounds = vec![Bounds::EMPTY; p.bins];
        let mut acc = Bounds::EMPTY;
        for k in (1..p.bins).rev() {
            acc.grow(&bin_bounds[k]);
            right_bounds[k] = acc;
        }
        let mut left = Bounds::EMPTY;
        let (mut nl, mut nr) = (0usize, n);
        for k in 1..p.bins {
            left.grow(&bin_bounds[k - 1]);
            nl += bin_count[k - 1];
            nr -= bin_count[k - 1];
            if nl == 0 || nr == 0 {
                continue;
            }
            let right = &right_bounds[k];
            let cost = split_cost(p, parent_area, (left.area(), nl), (right.area(), nr));
            if best.is_none_or(|b| cost < b.cost) {
                let overlap = left.intersection(right).area();
                best = Some(Split { axis, pos: lo + k as f64 / scale, cost, overlap, spatial: None });
            }
        }
    }
    best
}

fn round_down(v: DVec3) -> [f32; 3] {
    v.to_array().map(|c| {
        let f = c as f32;
        if f as f64 > c {
            f.next_down()
        } else {
            f
        }
    })
}

fn round_up(v: DVec3) -> [f32; 3] {
    v.to_array().map(|c| {
        let f = c as f32;
        if (f as f64) < c {
            f.next_up()
        } else {
            f
        }
    })
}

/// A built wide BVH (4- or 8-wide nodes).
#[derive(Clone, Debug, Default)]
pub struct BuiltWideBvh<N> {
    /// Nodes; 0 is the root.
    pub nodes: Vec<N>,
    /// Triangle ids referenced by the leaves.
    pub prims: Vec<u32>,
    /// Depth of the deepest node (root = 1).
    pub depth: u32,
}

/// Collapses a binary BVH into a wide one, choosing which binary nodes become wide nodes
/// by the SAH (Ylitie, Karras & Laine 2017, "Efficient incoherent ray traversal on GPUs
/// through compressed wide BVHs", section 3.1): bottom-up, the least cost of each binary
/// subtree spread over 1 to `WIDTH` slots of its parent, where a subtree in one slot is a
/// leaf (a binary leaf) or a wide node of its own (its children's subtrees spread over
/// its `WIDTH` slots). A wide node costs its area times the traversal cost, a leaf its
/// area times its blocks' intersection cost.
pub fn collapse_wide<N: WideNode>(bvh: &BuiltBvh, params: &BvhParams) -> BuiltWideBvh<N> {
    const MAX: usize = 8;
    let w = N::WIDTH.min(MAX);
    let area = |n: &BvhNode| Bounds::of_box(n.min, n.max).area();
    let nodes = &bvh.nodes;
    // cost[k][i - 1]: the least cost of node k's subtree in i slots; spread[k][i - 1]: how
    // (0: in i − 1 slots, or as one slot for i = 1; j: j slots to the left child's
    // subtree, i − j to the right's); own[k]: the left child's share of a wide node of k.
    let mut cost = vec![[0.0f64; MAX]; nodes.len()];
    let mut spread = vec![[0u8; MAX]; nodes.len()];
    let mut own = vec![0u8; nodes.len()];
    // Children come after their parent: a backward sweep meets them first.
    for k in (0..nodes.len()).rev() {
        let n = &nodes[k];
        if n.count > 0 {
            cost[k] = [area(n) * leaf_cost(n.count as usize, params); MAX];
            continue;
        }
        let (l, r) = (n.first as usize, n.first as usize + 1);
        let (Some(cl), Some(cr)) = (cost.get(l).copied(), cost.get(r).copied()) else { continue };
        // The children's subtrees sharing i slots.
        let mut share = [(f64::INFINITY, 0u8); MAX];
        for i in 2..=w {
            for j in 1..i {
                let c = cl[j - 1] + cr[i - j - 1];
                if c < share[i - 1].0 {
                    share[i - 1] = (c, j as u8);
                }
            }
        }
        own[k] = share[w - 1].1;
        cost[k][0] = area(n) * params.traversal_cost + share[w - 1].0;
        for i in 2..=w {
            (cost[k][i - 1], spread[k][i - 1]) =
                if share[i - 1].0 < cost[k][i - 2] { share[i - 1] } else { (cost[k][i - 2], 0) };
        }
    }
    // The binary nodes that fill `i` slots for node k's subtree.
    fn slots(nodes: &[BvhNode], spread: &[[u8; MAX]], k: usize, i: usize, out: &mut Vec<usize>) {
        let j = spread[k][i - 1] as usize;
        if i == 1 || nodes[k].count > 0 {
            out.push(k);
        } else if j == 0 {
            slots(nodes, spread, k, i - 1, out);
        } else {
            let l = nodes[k].first as usize;
            slots(nodes, spread, l, j, out);
            slots(nodes, spread, l + 1, i - j, out);
        }
    }
    let mut out = BuiltWideBvh { nodes: vec![*N::empty()], prims: bvh.prims.clone(), depth: 1 };
    // (binary node whose subtree fills wide node `target`, depth)
    let mut todo = vec![(0usize, 0usize, 1u32)];
    while let Some((src, target, depth)) = todo.pop() {
        out.depth = out.depth.max(depth);
        let root = &nodes[src];
        let mut filled = Vec::with_capacity(w);
        if root.count > 0 {
            filled.push(src); // a leaf root becomes a single leaf slot
        } else {
            let (l, j) = (root.first as usize, own[src] as usize);
            slots(nodes, &spread, l, j, &mut filled);
            slots(nodes, &spread, l + 1, w - j, &mut filled);
        }
        let mut node = *N::empty();
        for (k, &s) in filled.iter().enumerate() {
            let n = &nodes[s];
            if n.count > 0 {
                node.set_slot(k, n.min, n.max, n.first, n.count);
            } else {
                let child = out.nodes.len();
                out.nodes.push(*N::empty());
                node.set_slot(k, n.min, n.max, child as u32, 0);
                todo.push((s, child, depth + 1));
            }
        }
        out.nodes[target] = node;
    }
    out
}

/// Builds the binary BVH and collapses it into a wide one ([`collapse_wide`]) no deeper
/// than the image format allows ([`MAX_WIDE_DEPTH`]); see [`build_wide_bvh_within`].
pub fn build_wide_bvh<N: WideNode>(mesh: &Mesh, params: &BvhParams) -> BuiltWideBvh<N> {
    build_wide_bvh_within(mesh, params, MAX_WIDE_DEPTH)
}

/// [`build_wide_bvh`] at most `limit` levels deep (root = 1). Every wide level takes at
/// least one binary level, so where the collapse comes out deeper (no shared scene
/// does: the deepest is 21 against the format's 32), the binary tree is rebuilt at most
/// `limit − 1` deep, with larger leaves at the cut, and collapsed again.
pub fn build_wide_bvh_within<N: WideNode>(mesh: &Mesh, params: &BvhParams, limit: u32) -> BuiltWideBvh<N> {
    let wide = collapse_wide::<N>(&build_bvh(mesh, params), params);
    if wide.depth <= limit {
        return wide;
    }
    let shallow = BvhParams { max_depth: params.max_depth.min(limit.saturating_sub(1)), ..*params };
    collapse_wide::<N>(&build_bvh(mesh, &shallow), &shallow)
}

/// Starts every leaf's list on a multiple of `block` entries, so that a leaf of up to
/// `block` triangles is one TRI_BLOCKS record rather than straddling two. The gaps repeat
/// the entry before them (a valid id that no leaf's range includes).
pub fn align_leaves<N: WideNode>(bvh: &mut BuiltWideBvh<N>, block: usize) {
    let mut prims: Vec<u32> = Vec::with_capacity(bvh.prims.len() * 2);
    for node in &mut bvh.nodes {
        for k in 0..N::WIDTH {
            let (lo, hi, first, count) = node.slot(k);
            if count == 0 {
                continue;
            }
            while !prims.len().is_multiple_of(block) {
                prims.push(prims.last().copied().unwrap_or(0));
            }
            let start = prims.len() as u32;
            prims.extend_from_slice(&bvh.prims[first as usize..(first + count) as usize]);
            node.set_slot(k, lo, hi, start, count);
        }
    }
    bvh.prims = prims;
}

#[cfg(test)]
mod tests {
    use super::*;
    use raypipe_core::image::Bvh8Node;

    /// A strip of `n` thin triangles along x.
    fn strip(n: u32) -> Mesh {
        let positions = (0..=n).flat_map(|i| [[i as f32, 0.0, 0.0], [i as f32, 1.0, 0.0]]).collect();
        let triangles = (0..n).map(|i| [2 * i, 2 * i + 2, 2 * i + 1]).collect();
        Mesh { positions, triangles, ..Default::default() }
    }

    /// The leaves of a wide BVH, as `(first, count)` list ranges.
    fn leaves<N: WideNode>(bvh: &BuiltWideBvh<N>) -> Vec<(u32, u32)> {
        let slots = bvh.nodes.iter().flat_map(|n| (0..N::WIDTH).map(|k| n.link(k)));
        slots.filter(|&(_, count)| count > 0).collect()
    }

    /// `n` long slivers crossing the unit square diagonally, each offset a little along y:
    /// their boxes all overlap, the case spatial splits are for.
    fn slivers(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..n {
            let y = i as f32 / n as f32;
            positions.extend([[0.0, y, 0.0], [1.0, y + 1.0, 0.0], [1.0, y + 1.0, 0.01]]);
        }
        let triangles = (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        Mesh { positions, triangles, ..Default::default() }
    }

    /// The binary BVH's leaves: `(box, triangle ids)`.
    fn binary_leaves(bvh: &BuiltBvh) -> Vec<(BvhNode, &[u32])> {
        let leaves = bvh.nodes.iter().filter(|n| n.count > 0);
        leaves.map(|n| (*n, &bvh.prims[n.first as usize..(n.first + n.count) as usize])).collect()
    }

    #[test]
    fn split_references_keep_every_part_of_every_triangle_in_a_leaf_that_lists_it() {
        let mesh = slivers(64);
        // Spatial splits alone, then with presplitting (the default).
        let spatial = BvhParams { presplit_extent: 0.0, ..BvhParams::default() };
        for params in [spatial, BvhParams::default()] {
            let bvh = build_bvh(&mesh, &params);
            let leaves = binary_leaves(&bvh);
            // Split: some triangles are in more than one leaf, within the reference
            // budget, and no leaf lists a triangle twice.
            let refs: usize = leaves.iter().map(|(_, t)| t.len()).sum();
            assert!(refs > 64 && refs as f64 <= 64.0 * params.max_refs_per_triangle, "{refs} references");
            for (_, tris) in &leaves {
                assert!(tris.windows(2).all(|w| w[0] < w[1]), "{tris:?}");
            }
            // Every point of every triangle (on a barycentric lattice) is inside the box
            // of a leaf that lists the triangle.
            for (t, tri) in mesh.triangles.iter().enumerate() {
                let v = tri.map(|i| glam::Vec3::from(mesh.positions[i as usize]));
                for a in 0..=16 {
                    for b in 0..=16 - a {
                        let (u, w) = (a as f32 / 16.0, b as f32 / 16.0);
                        let p = v[0] * (1.0 - u - w) + v[1] * u + v[2] * w;
                        let held = leaves.iter().any(|(n, tris)| {
                            tris.contains(&(t as u32)) && (0..3).all(|k| n.min[k] <= p[k] && p[k] <= n.max[k])
                        });
                        assert!(held, "triangle {t}: point {p} is in no leaf listing it ({params:?})");
                    }
                }
            }
        }
        // Without either, each triangle is in exactly one leaf.
        let plain = build_bvh(&mesh, &BvhParams { spatial_alpha: 0.0, ..spatial });
        assert_eq!(binary_leaves(&plain).iter().map(|(_, t)| t.len()).sum::<usize>(), 64);
    }

    #[test]
    fn a_leaf_lists_a_presplit_triangle_once() {
        // Presplitting cuts the slivers into pieces; pieces that end in the same leaf are
        // one entry.
        let mesh = slivers(4);
        let params = BvhParams { presplit_extent: 1.0 / 64.0, spatial_alpha: 0.0, max_leaf: 64, ..Default::default() };
        let bvh = build_bvh(&mesh, &params);
        for (_, tris) in binary_leaves(&bvh) {
            assert!(tris.windows(2).all(|w| w[0] < w[1]), "{tris:?}");
        }
    }

    /// Random small triangles in a unit cube.
    fn scatter(n: u32, seed: u64) -> Mesh {
        let mut x = seed;
        let mut next = move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut positions = Vec::new();
        for _ in 0..n {
            let c = [next(), next(), next()];
            for _ in 0..3 {
                positions.push([c[0] + 0.05 * next(), c[1] + 0.05 * next(), c[2] + 0.05 * next()]);
            }
        }
        let triangles = (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        Mesh { positions, triangles, ..Default::default() }
    }

    /// The SAH cost of a wide BVH as the collapse prices it: each wide node its box's
    /// area times the traversal cost, each leaf its box's area times its blocks.
    fn wide_cost<N: WideNode>(bvh: &BuiltWideBvh<N>, p: &BvhParams) -> f64 {
        let mut cost = 0.0;
        for (i, node) in bvh.nodes.iter().enumerate() {
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for k in 0..N::WIDTH {
                let (l, h, _, count) = node.slot(k);
                if l[0] > h[0] {
                    continue; // empty slot
                }
                for a in 0..3 {
                    (lo[a], hi[a]) = (lo[a].min(l[a]), hi[a].max(h[a]));
                }
                if count > 0 {
                    cost += Bounds::of_box(l, h).area() * leaf_cost(count as usize, p);
                }
            }
            // The root's own test is the same for any collapse.
            if i > 0 {
                cost += Bounds::of_box(lo, hi).area() * p.traversal_cost;
            }
        }
        cost
    }

    /// The greedy collapse (Wald et al. 2008): open the largest inner child until the
    /// node is full. The reference the SAH collapse must never lose to.
    fn greedy<N: WideNode>(bvh: &BuiltBvh) -> BuiltWideBvh<N> {
        let area = |n: &BvhNode| Bounds::of_box(n.min, n.max).area();
        let mut out = BuiltWideBvh { nodes: vec![*N::empty()], prims: bvh.prims.clone(), depth: 1 };
        let mut todo = vec![(0usize, 0usize)];
        while let Some((src, target)) = todo.pop() {
            let root = &bvh.nodes[src];
            let mut slots = if root.count > 0 { vec![src] } else { vec![root.first as usize, root.first as usize + 1] };
            while slots.len() < N::WIDTH {
                let open = slots
                    .iter()
                    .enumerate()
                    .filter(|(_, &s)| bvh.nodes[s].count == 0)
                    .max_by(|a, b| area(&bvh.nodes[*a.1]).total_cmp(&area(&bvh.nodes[*b.1])));
                let Some((k, &s)) = open else { break };
                let f = bvh.nodes[s].first as usize;
                slots[k] = f;
                slots.push(f + 1);
            }
            let mut node = *N::empty();
            for (k, &s) in slots.iter().enumerate() {
                let n = &bvh.nodes[s];
                if n.count > 0 {
                    node.set_slot(k, n.min, n.max, n.first, n.count);
                } else {
                    out.nodes.push(*N::empty());
                    node.set_slot(k, n.min, n.max, out.nodes.len() as u32 - 1, 0);
                    todo.push((s, out.nodes.len() - 1));
                }
            }
            out.nodes[target] = node;
        }
        out
    }

    #[test]
    fn the_sah_collapse_keeps_the_leaves_and_never_costs_more_than_the_greedy_one() {
        for (seed, n) in [(1, 1), (2, 7), (3, 200), (4, 3000)] {
            let mesh = scatter(n, seed);
            for leaf_block in [1, 4] {
                let params = BvhParams { leaf_block, ..BvhParams::default() };
                let binary = build_bvh(&mesh, &params);
                let mut binary_leaves: Vec<(u32, u32)> =
                    binary.nodes.iter().filter(|n| n.count > 0).map(|n| (n.first, n.count)).collect();
                binary_leaves.sort_unstable();
                let wide = collapse_wide::<Bvh8Node>(&binary, &params);
                let mut wide_leaves = leaves(&wide);
                wide_leaves.sort_unstable();
                assert_eq!(wide_leaves, binary_leaves, "seed {seed}");
                let (sah, reference) = (wide_cost(&wide, &params), wide_cost(&greedy::<Bvh8Node>(&binary), &params));
                assert!(sah <= reference * (1.0 + 1e-9), "seed {seed}: {sah} > greedy {reference}");
                if n >= 200 {
                    assert!(sah < reference, "seed {seed}: no better than greedy");
                }
                let wide4 = collapse_wide::<raypipe_core::image::Bvh4Node>(&binary, &params);
                let mut leaves4 = leaves(&wide4);
                leaves4.sort_unstable();
                assert_eq!(leaves4, binary_leaves, "seed {seed}");
            }
        }
    }

    #[test]
    fn aligned_leaves_start_on_blocks_and_keep_their_triangles() {
        let mesh = strip(300);
        let params = BvhParams { leaf_block: 4, ..BvhParams::default() };
        let mut bvh = collapse_wide::<Bvh8Node>(&build_bvh(&mesh, &params), &params);
        let before: Vec<Vec<u32>> =
            leaves(&bvh).iter().map(|&(f, c)| bvh.prims[f as usize..(f + c) as usize].to_vec()).collect();
        align_leaves(&mut bvh, 4);
        let after = leaves(&bvh);
        assert!(after.iter().all(|&(first, _)| first % 4 == 0), "{after:?}");
        let lists: Vec<Vec<u32>> =
            after.iter().map(|&(f, c)| bvh.prims[f as usize..(f + c) as usize].to_vec()).collect();
        assert_eq!(lists, before);
        // Blocks priced by the SAH: leaves fill up to four triangles rather than stop at one.
        assert!(after.iter().any(|&(_, c)| c > 1));
    }
    /// A wide BVH deeper than its limit is rebuilt within it, keeping every triangle in
    /// exactly one leaf (here a limit of 6 on a scatter whose collapse is deeper), and
    /// the image made from it gives the brute-force hits.
    #[test]
    fn a_wide_bvh_deeper_than_its_limit_is_rebuilt_within_it() {
        use crate::build::image_writer::ImageWriter;
        use raypipe_core::traverse::brute_force::trace_brute_force;
        use raypipe_core::traverse::walk::trace_walk;
        use raypipe_core::{NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};
        let mesh = scatter(3000, 9);
        let params = BvhParams::default();
        let full = build_wide_bvh::<raypipe_core::image::Bvh4Node>(&mesh, &params);
        let limit = 6;
        assert!(full.depth > limit, "the scatter's 4-wide BVH is {} deep", full.depth);
        let bvh = build_wide_bvh_within::<raypipe_core::image::Bvh4Node>(&mesh, &params, limit);
        assert!(bvh.depth <= limit, "{} levels", bvh.depth);
        let mut listed: Vec<u32> =
            leaves(&bvh).iter().flat_map(|&(f, c)| bvh.prims[f as usize..(f + c) as usize].to_vec()).collect();
        listed.sort_unstable();
        listed.dedup();
        assert_eq!(listed.len(), mesh.triangles.len());
        let image = ImageWriter::new(&mesh).wide_bvh(&bvh).finish().unwrap();
        let view = SceneView::parse(&image).unwrap();
        let (lo, hi) = mesh.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let mut hits = 0;
        for i in 0..400 {
            let f = |k: u32| ((i * 7919 + k * 104729) % 1000) as f32 / 1000.0;
            let o = lo - (hi - lo) * 0.5 + (hi - lo) * Vec3::new(f(1), f(2), f(3)) * 2.0;
            let target = lo + (hi - lo) * Vec3::new(f(4), f(5), f(6));
            let ray = Ray::new(o, target - o);
            let want = trace_brute_force::<Watertight, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            assert_eq!(trace_walk::<Watertight, _>(&view, &ray, &mut NoProbe), want, "ray {i}");
            hits += want.is_some() as u32;
        }
        assert!(hits > 100, "{hits} of 400 rays hit");
    }
}
