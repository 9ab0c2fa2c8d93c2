//! Builds a BVH by the binned surface area heuristic (Wald 2007, "On fast construction of
//! SAH-based bounding volume hierarchies"), writing 32-byte nodes whose children sit side
//! by side (`BvhNode`). Each node's box is grown outwards by a small margin, so that a
//! triangle lying on a box face is never culled by the rounding of the entry distance.

use glam::DVec3;
use raypipe_core::image::{BvhNode, MAX_TREE_DEPTH};

use crate::build::sah::{leaf_cost, split_cost, Bounds, BvhParams, Ref, Split};
use crate::build::spatial_split::{find_spatial_split, split_references};
use crate::build::tree_part::{PartNode, TreePart};
use crate::input::mesh::Mesh;

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

/// Margin that node boxes are grown by: relative to the scene's size and magnitude.
pub fn box_margin(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.margin_reference();
    let (lo, hi) = (DVec3::from(lo.map(f64::from)), DVec3::from(hi.map(f64::from)));
    1e-5 * (hi - lo).max_element() + 8.0 * f64::from(f32::EPSILON) * lo.abs().max(hi.abs()).max_element()
}

/// The box `lo..hi` grown by `margin` on every side and rounded outwards to `f32`.
pub fn grow_by_margin((lo, hi): ([f32; 3], [f32; 3]), margin: f64) -> ([f32; 3], [f32; 3]) {
    (lo.map(|c| ((f64::from(c) - margin) as f32).next_down()), hi.map(|c| ((f64::from(c) + margin) as f32).next_up()))
}

/// Nodes with at least this many references build their two subtrees as parallel tasks
/// (rayon's `join`, on the current thread pool). Whether a node forks depends on its size
/// alone, never on the thread count, so the tree is the same on any number of threads.
const FORK_REFS: usize = 4096;

/// Builds the BVH, its large subtrees in parallel.
pub fn build_bvh(mesh: &Mesh, params: &BvhParams) -> BuiltBvh {
    let verts: Vec<[DVec3; 3]> =
        mesh.triangles.iter().map(|t| t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)))).collect();
    let budget = (params.max_refs_per_triangle * verts.len() as f64) as usize;
    let refs = presplit_references(mesh, &verts, params, budget);
    let spare = budget.saturating_sub(refs.len());
    let mut root = Bounds::EMPTY;
    for r in &refs {
        root.grow(&r.b);
    }
    let build = Build {
        verts: &verts,
        params,
        // Spatial splits are tried only where the object split's children overlap by
        // more than this area (Stich et al. 2009, section 4.4: alpha of the root's area).
        min_overlap: params.spatial_alpha * root.area(),
        margin: box_margin(mesh),
        max_depth: params.max_depth.clamp(1, MAX_TREE_DEPTH - 4),
    };
    let part = build.task(refs, 1, spare);
    BuiltBvh { nodes: part.nodes, prims: part.prims, depth: part.depth }
}

/// What every task of one build reads.
struct Build<'a> {
    verts: &'a [[DVec3; 3]],
    params: &'a BvhParams,
    min_overlap: f64,
    margin: f64,
    max_depth: u32,
}

type Part = TreePart<BvhNode>;

impl PartNode for BvhNode {
    fn moved(mut self, nodes: u32, prims: u32) -> Self {
        self.first += if self.count == 0 { nodes } else { prims };
        self
    }

    fn with_children(mut self, child: u32) -> Self {
        (self.first, self.count) = (child, 0);
        self
    }
}

impl Build<'_> {
    /// The subtree of `refs` at `depth`, with `spare` references for splitting. A root
    /// of [`FORK_REFS`] or more builds its children as two tasks in parallel, the budget
    /// shared by their references; smaller ones build sequentially, depth first, the left
    /// child spending the budget first.
    fn task(&self, refs: Vec<Ref>, depth: u32, mut spare: usize) -> Part {
        if refs.len() < FORK_REFS {
            return self.sequential(refs, depth, spare);
        }
        let (node, left, right) = self.node(refs, depth, &mut spare);
        if right.is_empty() {
            return self.leaf(node, left, depth, spare);
        }
        let (nl, nr) = (left.len() as u128, right.len() as u128);
        let spare_left = (spare as u128 * nl / (nl + nr)) as usize;
        let (l, r) =
            rayon::join(|| self.task(left, depth + 1, spare_left), || self.task(right, depth + 1, spare - spare_left));
        Part::join(node, l, r)
    }

    /// One node: its box, and its references split in two (the right side empty for a
    /// leaf).
    fn node(&self, refs: Vec<Ref>, depth: u32, spare: &mut usize) -> (BvhNode, Vec<Ref>, Vec<Ref>) {
        let params = self.params;
        let mut bounds = Bounds::EMPTY;
        let mut cbounds = Bounds::EMPTY;
        for r in &refs {
            bounds.grow(&r.b);
            let c = r.centroid();
            cbounds.grow(&Bounds { lo: c, hi: c });
        }
        let m = DVec3::splat(self.margin);
        let node = BvhNode { min: round_down(bounds.lo - m), first: 0, max: round_up(bounds.hi + m), count: 0 };
        let count = refs.len();
        let split = if count <= 1 || depth >= self.max_depth {
            None
        } else {
            let object = find_split(&refs, &bounds, &cbounds, params);
            let spatial = match object {
                Some(o) if *spare > 0 && self.min_overlap > 0.0 && o.overlap > self.min_overlap => {
                    find_spatial_split(self.verts, &refs, &bounds, params)
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
                split_references(self.verts, refs, axis, pos, &sides, params, spare)
            }
            Some(s) => refs.into_iter().partition(|r| r.centroid()[s.axis] < s.pos),
            // Too many triangles for a leaf and no useful plane (e.g. equal centroids):
            // split the list in half.
            None if count > params.max_leaf && depth < self.max_depth => {
                let mut left = refs;
                let right = left.split_off(count / 2);
                (left, right)
            }
            None => (refs, Vec::new()),
        };
        // A split that leaves one side empty makes a leaf of all of them.
        if left.is_empty() {
            return (node, right, Vec::new());
        }
        if right.is_empty() {
            return (node, left, Vec::new());
        }
        (node, left, right)
    }

    /// A part of one leaf: each triangle once, however many of its pieces arrived here.
    fn leaf(&self, mut node: BvhNode, refs: Vec<Ref>, depth: u32, spare: usize) -> Part {
        let tris = leaf_triangles(&refs);
        node.count = tris.len() as u32;
        Part { nodes: vec![node], prims: tris, depth, spare }
    }

    /// The subtree of `refs` on this thread: nodes in the order they are split (each
    /// node's two children side by side, the left subtree's before the right's).
    fn sequential(&self, refs: Vec<Ref>, depth: u32, mut spare: usize) -> Part {
        let mut out = Part {
            nodes: vec![BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 }],
            prims: Vec::new(),
            depth,
            spare: 0,
        };
        // (node, its references, depth)
        let mut todo = vec![(0usize, refs, depth)];
        while let Some((index, refs, depth)) = todo.pop() {
            out.depth = out.depth.max(depth);
            let (mut node, left, right) = self.node(refs, depth, &mut spare);
            if right.is_empty() {
                let tris = leaf_triangles(&left);
                node.first = out.prims.len() as u32;
                node.count = tris.len() as u32;
                out.prims.extend_from_slice(&tris);
            } else {
                let child = out.nodes.len();
                out.nodes.extend([node, node]);
                node.first = child as u32;
                todo.push((child + 1, right, depth + 1));
                todo.push((child, left, depth + 1));
            }
            out.nodes[index] = node;
        }
        out.spare = spare;
        out
    }
}

/// A leaf's triangles: each once, in id order, however many of its pieces arrived.
fn leaf_triangles(refs: &[Ref]) -> Vec<u32> {
    let mut tris: Vec<u32> = refs.iter().map(|r| r.tri).collect();
    tris.sort_unstable();
    tris.dedup();
    tris
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::test_meshes::slivers;

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

    /// Large meshes build their big subtrees as parallel tasks: the tree is the same on
    /// any number of threads (also with a reference budget too small for every split, so
    /// that how the tasks share it matters), and it is whole — every node reached once
    /// from the root, children inside their parent's box, and every corner and centroid
    /// of every triangle inside a leaf that lists it.
    #[test]
    fn parallel_builds_are_whole_and_the_same_on_any_number_of_threads() {
        use crate::build::test_meshes::scatter;
        let mut mesh = scatter(3 * FORK_REFS as u32, 5);
        // Long slivers across the cube: presplits and spatial splits spend the budget.
        let base = mesh.positions.len() as u32;
        for i in 0..200u32 {
            let y = i as f32 / 200.0;
            mesh.positions.extend([[0.0, y, 0.1], [1.0, y + 0.3, 0.9], [1.0, y + 0.3, 0.95]]);
            mesh.triangles.push([base + 3 * i, base + 3 * i + 1, base + 3 * i + 2]);
        }
        for refs in [1.05, 3.0] {
            let params = BvhParams { max_refs_per_triangle: refs, ..BvhParams::default() };
            let builds: Vec<BuiltBvh> = [1, 2, 3]
                .iter()
                .map(|&t| crate::render::in_pool(Some(t), || build_bvh(&mesh, &params)).unwrap())
                .collect();
            for b in &builds[1..] {
                assert_eq!((&b.nodes, &b.prims, b.depth), (&builds[0].nodes, &builds[0].prims, builds[0].depth));
            }
            let bvh = &builds[0];
            let used = bvh.prims.len() as f64 / mesh.triangles.len() as f64;
            assert!(used > 1.0 && used <= refs + 1e-9, "{used} references per triangle");
            // Walk from the root: every node once, children within their parent.
            let mut seen = vec![false; bvh.nodes.len()];
            let mut listed_in: Vec<Vec<usize>> = vec![Vec::new(); mesh.triangles.len()];
            let mut todo = vec![0usize];
            while let Some(i) = todo.pop() {
                assert!(!std::mem::replace(&mut seen[i], true), "node {i} reached twice");
                let n = bvh.nodes[i];
                if n.count > 0 {
                    for &t in &bvh.prims[n.first as usize..(n.first + n.count) as usize] {
                        listed_in[t as usize].push(i);
                    }
                    continue;
                }
                for c in [n.first as usize, n.first as usize + 1] {
                    let k = bvh.nodes[c];
                    assert!((0..3).all(|a| n.min[a] <= k.min[a] && k.max[a] <= n.max[a]), "node {c} outside {i}");
                    todo.push(c);
                }
            }
            assert!(seen.iter().all(|&s| s), "unreachable nodes");
            for (t, tri) in mesh.triangles.iter().enumerate() {
                let v = tri.map(|i| glam::Vec3::from(mesh.positions[i as usize]));
                for p in [v[0], v[1], v[2], (v[0] + v[1] + v[2]) / 3.0] {
                    let held = listed_in[t].iter().any(|&i| {
                        let n = bvh.nodes[i];
                        (0..3).all(|a| n.min[a] <= p[a] && p[a] <= n.max[a])
                    });
                    assert!(held, "triangle {t}: {p} in no leaf listing it");
                }
            }
        }
    }
}
