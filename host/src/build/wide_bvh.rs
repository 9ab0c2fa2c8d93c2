//! The wide BVHs (4 or 8 children per node, Embree's BVH4 and BVH8; Wald, Benthin &
//! Boulos 2008): the binary BVH collapsed by the SAH into wide nodes, rebuilt shallower
//! where it would be deeper than the walks' stacks allow, and leaves aligned to the
//! triangle blocks.

use raypipe_core::image::{BvhNode, WideNode, MAX_WIDE_DEPTH};

use crate::build::bvh::{build_bvh, BuiltBvh};
use crate::build::sah::{leaf_cost, Bounds, BvhParams};
use crate::input::mesh::Mesh;

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
    use crate::build::test_meshes::{scatter, strip};
    use raypipe_core::image::Bvh8Node;

    /// The leaves of a wide BVH, as `(first, count)` list ranges.
    fn leaves<N: WideNode>(bvh: &BuiltWideBvh<N>) -> Vec<(u32, u32)> {
        let slots = bvh.nodes.iter().flat_map(|n| (0..N::WIDTH).map(|k| n.link(k)));
        slots.filter(|&(_, count)| count > 0).collect()
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
