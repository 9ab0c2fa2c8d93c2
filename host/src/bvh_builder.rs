//! Builds a BVH by the binned surface area heuristic (Wald 2007, "On fast construction of
//! SAH-based bounding volume hierarchies"), writing 32-byte nodes whose children sit side
//! by side (`BvhNode`). Each node's box is grown outwards by a small margin, so that a
//! triangle lying on a box face is never culled by the rounding of the entry distance.

use glam::DVec3;
use raypipe_core::image::{BvhNode, WideNode, MAX_TREE_DEPTH};

use crate::mesh::Mesh;

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
    pub presplit_extent: f64,
    /// At most this many references per triangle on average, whatever the splitting.
    pub max_refs_per_triangle: f64,
    /// Triangles a leaf tests at once (4 with TRI_BLOCKS): the SAH prices a leaf by its
    /// blocks, `ceil(n / leaf_block)`, as Embree does for its four-triangle leaves.
    pub leaf_block: usize,
}

impl Default for BvhParams {
    fn default() -> Self {
        BvhParams {
            bins: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            max_leaf: 8,
            presplit_extent: 1.0 / 32.0,
            max_refs_per_triangle: 3.0,
            leaf_block: 1,
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

#[derive(Clone, Copy)]
struct Bounds {
    lo: DVec3,
    hi: DVec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { lo: DVec3::splat(f64::INFINITY), hi: DVec3::splat(f64::NEG_INFINITY) };

    fn grow(&mut self, o: &Bounds) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    fn area(&self) -> f64 {
        let e = (self.hi - self.lo).max(DVec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
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
    let (tris, owner) = references(mesh, params);
    let mut idx: Vec<u32> = (0..tris.len() as u32).collect();
    let margin = box_margin(mesh);
    let mut out =
        BuiltBvh { nodes: vec![BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 }], ..Default::default() };
    // (node, start, end, depth)
    let mut todo = vec![(0usize, 0usize, tris.len(), 1u32)];
    let max_depth = MAX_TREE_DEPTH - 4;
    while let Some((node, start, end, depth)) = todo.pop() {
        out.depth = out.depth.max(depth);
        let mut bounds = Bounds::EMPTY;
        let mut cbounds = Bounds::EMPTY;
        for &i in &idx[start..end] {
            bounds.grow(&tris[i as usize].0);
            let c = tris[i as usize].1;
            cbounds.grow(&Bounds { lo: c, hi: c });
        }
        out.nodes[node].min = round_down(bounds.lo - DVec3::splat(margin));
        out.nodes[node].max = round_up(bounds.hi + DVec3::splat(margin));
        let count = end - start;
        let split = if count <= 1 || depth >= max_depth {
            None
        } else {
            find_split(&tris, &idx[start..end], &bounds, &cbounds, params)
        };
        let mid = match split {
            Some((axis, pos)) => {
                let slice = &mut idx[start..end];
                let mut left = 0;
                for k in 0..slice.len() {
                    if tris[slice[k] as usize].1[axis] < pos {
                        slice.swap(k, left);
                        left += 1;
                    }
                }
                Some(start + left)
            }
            // Too many triangles for a leaf and no useful plane (e.g. equal centroids):
            // split the list in half.
            None if count > params.max_leaf && depth < max_depth => Some(start + count / 2),
            None => None,
        };
        match mid {
            Some(mid) if mid > start && mid < end => {
                let child = out.nodes.len();
                out.nodes.push(out.nodes[node]);
                out.nodes.push(out.nodes[node]);
                out.nodes[node].first = child as u32;
                out.nodes[node].count = 0;
                todo.push((child + 1, mid, end, depth + 1));
                todo.push((child, start, mid, depth + 1));
            }
            _ => {
                out.nodes[node].first = start as u32;
                out.nodes[node].count = count as u32;
            }
        }
    }
    out.prims = idx.iter().map(|&r| owner[r as usize]).collect();
    out
}

/// The build references: one box per triangle, or per piece of a large triangle cut by
/// early split clipping. Returns `(box, centroid)` per reference and its triangle id.
fn references(mesh: &Mesh, params: &BvhParams) -> (Vec<(Bounds, DVec3)>, Vec<u32>) {
    let verts: Vec<[DVec3; 3]> =
        mesh.triangles.iter().map(|t| t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)))).collect();
    let boxes: Vec<Bounds> =
        verts.iter().map(|v| Bounds { lo: v[0].min(v[1]).min(v[2]), hi: v[0].max(v[1]).max(v[2]) }).collect();
    let (lo, hi) = mesh.bounds();
    let extent = (DVec3::from(hi.map(f64::from)) - DVec3::from(lo.map(f64::from))).max_element();
    let limit = params.presplit_extent * extent;
    let budget = (params.max_refs_per_triangle * mesh.triangles.len() as f64) as usize;
    let mut refs = Vec::with_capacity(mesh.triangles.len());
    let mut owner = Vec::with_capacity(mesh.triangles.len());
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
            Some(ps) => {
                for b in ps {
                    refs.push((b, (b.lo + b.hi) * 0.5));
                    owner.push(t as u32);
                }
            }
            None => {
                refs.push((boxes[t], (boxes[t].lo + boxes[t].hi) * 0.5));
                owner.push(t as u32);
            }
        }
    }
    (refs, owner)
}

/// Halves `b` along its longest axis while it is longer than `limit`, keeping the box of
/// the triangle's part in each half (at most `max` pieces).
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
    for half in [left, right] {
        if let Some(c) = clipped_bounds(v, &half) {
            clip_split(v, c, limit, max, out);
        }
    }
}

/// Bounds of the part of triangle `v` inside box `b` (Sutherland–Hodgman clipping).
fn clipped_bounds(v: &[DVec3; 3], b: &Bounds) -> Option<Bounds> {
    let mut poly: Vec<DVec3> = v.to_vec();
    for axis in 0..3 {
        for (plane, keep_above) in [(b.lo[axis], true), (b.hi[axis], false)] {
            let inside = |p: &DVec3| if keep_above { p[axis] >= plane } else { p[axis] <= plane };
            let mut next = Vec::with_capacity(poly.len() + 2);
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                let (ip, iq) = (inside(&p), inside(&q));
                if ip {
                    next.push(p);
                }
                if ip != iq {
                    let t = (plane - p[axis]) / (q[axis] - p[axis]);
                    let mut x = p + (q - p) * t;
                    x[axis] = plane;
                    next.push(x);
                }
            }
            poly = next;
            if poly.is_empty() {
                return None;
            }
        }
    }
    let mut out = Bounds::EMPTY;
    for p in &poly {
        out.grow(&Bounds { lo: *p, hi: *p });
    }
    // Clipping may round a hair inside the triangle: keep the piece inside the half box
    // but never smaller than what the arithmetic produced.
    out.lo = out.lo.max(b.lo);
    out.hi = out.hi.min(b.hi);
    Some(out)
}

/// The best binned-SAH plane `(axis, position)` if splitting beats a leaf (or the node is
/// too big for one).
fn find_split(
    tris: &[(Bounds, DVec3)],
    idx: &[u32],
    bounds: &Bounds,
    cbounds: &Bounds,
    p: &BvhParams,
) -> Option<(usize, f64)> {
    let n = idx.len();
    let blocks = |n: usize| n.div_ceil(p.leaf_block.max(1)) as f64;
    let leaf_cost = p.intersection_cost * blocks(n);
    let parent_area = bounds.area().max(f64::MIN_POSITIVE);
    let mut best: Option<(f64, usize, f64)> = None;
    for axis in 0..3 {
        let (lo, hi) = (cbounds.lo[axis], cbounds.hi[axis]);
        if hi <= lo || hi.is_nan() || lo.is_nan() {
            continue;
        }
        let scale = p.bins as f64 / (hi - lo);
        let mut bin_bounds = vec![Bounds::EMPTY; p.bins];
        let mut bin_count = vec![0usize; p.bins];
        for &i in idx {
            let (b, c) = &tris[i as usize];
            let k = (((c[axis] - lo) * scale) as usize).min(p.bins - 1);
            bin_bounds[k].grow(b);
            bin_count[k] += 1;
        }
        // Sweep from the right, then from the left.
        let mut right_area = vec![0.0; p.bins];
        let mut acc = Bounds::EMPTY;
        for k in (1..p.bins).rev() {
            acc.grow(&bin_bounds[k]);
            right_area[k] = acc.area();
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
            let cost = p.traversal_cost
                + p.intersection_cost * (left.area() * blocks(nl) + right_area[k] * blocks(nr)) / parent_area;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, lo + k as f64 / scale));
            }
        }
    }
    match best {
        Some((cost, axis, pos)) if cost < leaf_cost || n > p.max_leaf => Some((axis, pos)),
        _ => None,
    }
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

/// Collapses a binary BVH into a wide one: each wide node takes the (up to `WIDTH`)
/// descendants reached by repeatedly opening the largest inner child (Wald et al. 2008).
pub fn collapse_wide<N: WideNode>(bvh: &BuiltBvh) -> BuiltWideBvh<N> {
    let area = |n: &BvhNode| {
        let e = [n.max[0] - n.min[0], n.max[1] - n.min[1], n.max[2] - n.min[2]];
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    };
    let mut out = BuiltWideBvh { nodes: vec![*N::empty()], prims: bvh.prims.clone(), depth: 1 };
    // (binary node whose children fill wide node `target`, depth)
    let mut todo = vec![(0usize, 0usize, 1u32)];
    while let Some((src, target, depth)) = todo.pop() {
        out.depth = out.depth.max(depth);
        let root = &bvh.nodes[src];
        let mut slots: Vec<usize> = if root.count > 0 {
            vec![src] // a leaf root becomes a single leaf slot
        } else {
            vec![root.first as usize, root.first as usize + 1]
        };
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

    #[test]
    fn aligned_leaves_start_on_blocks_and_keep_their_triangles() {
        let mesh = strip(300);
        let params = BvhParams { leaf_block: 4, ..BvhParams::default() };
        let mut bvh = collapse_wide::<Bvh8Node>(&build_bvh(&mesh, &params));
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
}
