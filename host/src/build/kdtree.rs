//! Builds a kd-tree by the surface area heuristic over binned candidate planes (Wald &
//! Havran 2006 give the exact O(n log n) sweep; binning is the common fast variant), with
//! pbrt's cost constants, and writes Wald's 8-byte nodes (`KdNode`).
//!
//! A triangle goes to every child whose half-space its bounding box (clipped to the node
//! and grown by a margin) reaches, so the tree is conservative: the traversal's rounding
//! near a plane can never lose a triangle.

use glam::DVec3;
use raypipe_core::image::{KdNode, MAX_TREE_DEPTH};

use crate::build::bvh::box_margin;
use crate::build::tree_part::{PartNode, TreePart};
use crate::input::mesh::Mesh;

/// SAH cost constants and limits (defaults from pbrt-v3's `KdTreeAccel`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdParams {
    /// Cost of a traversal step.
    pub traversal_cost: f64,
    /// Cost of a triangle test.
    pub intersection_cost: f64,
    /// Fraction of the cost saved when one side of a split is empty.
    pub empty_bonus: f64,
    /// Leaves at or below this many triangles are not split.
    pub max_leaf: usize,
    /// Candidate planes per axis.
    pub bins: usize,
    /// Depth limit; `None`: `8 + 1.3·log2(n)`, capped by the traversal stack.
    pub max_depth: Option<u32>,
}

impl Default for KdParams {
    fn default() -> Self {
        KdParams {
            traversal_cost: 1.0,
            intersection_cost: 80.0,
            empty_bonus: 0.5,
            max_leaf: 1,
            bins: 32,
            max_depth: None,
        }
    }
}

/// A built kd-tree.
#[derive(Clone, Debug, Default)]
pub struct BuiltKd {
    /// Nodes; 0 is the root.
    pub nodes: Vec<KdNode>,
    /// Triangle ids referenced by the leaves.
    pub prims: Vec<u32>,
    /// Depth of the deepest leaf (root = 1).
    pub depth: u32,
}

struct Ctx<'a> {
    tri_lo: Vec<DVec3>,
    tri_hi: Vec<DVec3>,
    params: &'a KdParams,
    margin: f64,
    max_depth: u32,
}

/// Nodes with at least this many triangles build their two subtrees as parallel tasks
/// (rayon's `join`, on the current thread pool); whether a node forks depends on its
/// size alone, so the tree is the same on any number of threads.
const FORK_TRIS: usize = 4096;

impl PartNode for KdNode {
    fn moved(self, nodes: u32, prims: u32) -> Self {
        match self.axis() {
            KdNode::LEAF => KdNode::leaf(self.index() + prims, self.value),
            axis => KdNode::inner(axis, self.split(), self.index() + nodes),
        }
    }

    fn with_children(self, child: u32) -> Self {
        KdNode::inner(self.axis(), self.split(), child)
    }
}

/// Builds the kd-tree over the scene bounds.
pub fn build_kdtree(mesh: &Mesh, params: &KdParams) -> BuiltKd {
    let (ctx, root) = Ctx::new(mesh, params);
    let all: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    let part = ctx.build(all, root, 1);
    BuiltKd { nodes: part.nodes, prims: part.prims, depth: part.depth }
}

fn area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

impl<'a> Ctx<'a> {
    /// The build's triangle boxes, depth limit and margin, and the root cell (the scene's
    /// bounds).
    fn new(mesh: &Mesh, params: &'a KdParams) -> (Ctx<'a>, (DVec3, DVec3)) {
        let mut tri_lo = Vec::with_capacity(mesh.triangles.len());
        let mut tri_hi = Vec::with_capacity(mesh.triangles.len());
        for t in &mesh.triangles {
            let v = t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
            tri_lo.push(v[0].min(v[1]).min(v[2]));
            tri_hi.push(v[0].max(v[1]).max(v[2]));
        }
        let n = mesh.triangles.len().max(1) as f64;
        let auto_depth = (8.0 + 1.3 * n.log2()).round() as u32;
        let max_depth = params.max_depth.unwrap_or(auto_depth).min(MAX_TREE_DEPTH - 4);
        let (lo, hi) = mesh.bounds();
        let root = (DVec3::from(lo.map(f64::from)), DVec3::from(hi.map(f64::from)));
        (Ctx { tri_lo, tri_hi, params, margin: box_margin(mesh), max_depth }, root)
    }

    /// The subtree of `tris` in the cell `lo..hi` at `depth`. A node of [`FORK_TRIS`]
    /// triangles or more builds its children as two parallel tasks; smaller subtrees are
    /// built on this thread, depth first.
    fn build(&self, tris: Vec<u32>, cell: (DVec3, DVec3), depth: u32) -> TreePart<KdNode> {
        if tris.len() < FORK_TRIS {
            let mut part = TreePart { nodes: vec![KdNode::leaf(0, 0)], prims: Vec::new(), depth, spare: 0 };
            self.sequential(&mut part, 0, tris, cell, depth);
            return part;
        }
        match self.split(tris, cell, depth) {
            Err(tris) => TreePart { nodes: vec![KdNode::leaf(0, tris.len() as u32)], prims: tris, depth, spare: 0 },
            Ok((node, (below, cell_below), (above, cell_above))) => {
                let (l, r) = rayon::join(
                    || self.build(below, cell_below, depth + 1),
                    || self.build(above, cell_above, depth + 1),
                );
                TreePart::join(node, l, r)
            }
        }
    }

    /// Builds the subtree of `tris` into `out` at node `index` (allocated), its
    /// children's nodes appended side by side, the left subtree first.
    fn sequential(&self, out: &mut TreePart<KdNode>, index: usize, tris: Vec<u32>, cell: (DVec3, DVec3), depth: u32) {
        out.depth = out.depth.max(depth);
        match self.split(tris, cell, depth) {
            Err(tris) => {
                out.nodes[index] = KdNode::leaf(out.prims.len() as u32, tris.len() as u32);
                out.prims.extend_from_slice(&tris);
            }
            Ok((node, (below, cell_below), (above, cell_above))) => {
                let child = out.nodes.len();
                out.nodes.extend([KdNode::leaf(0, 0); 2]);
                out.nodes[index] = node.with_children(child as u32);
                self.sequential(out, child, below, cell_below, depth + 1);
                self.sequential(out, child + 1, above, cell_above, depth + 1);
            }
        }
    }

    /// The plane of the node at `depth` (children not yet placed) and the triangles and
    /// cells of its two sides; the triangles back where the node is a leaf (small enough,
    /// deep enough, or cheaper so).
    #[allow(clippy::type_complexity)]
    fn split(
        &self,
        tris: Vec<u32>,
        (lo, hi): (DVec3, DVec3),
        depth: u32,
    ) -> Result<(KdNode, (Vec<u32>, (DVec3, DVec3)), (Vec<u32>, (DVec3, DVec3))), Vec<u32>> {
        if tris.len() <= self.params.max_leaf || depth >= self.max_depth {
            return Err(tris);
        }
        let Some((axis, pos)) = self.find_split(&tris, lo, hi) else {
            return Err(tris);
        };
        let m = self.margin;
        let below: Vec<u32> = tris.iter().copied().filter(|&t| self.tri_lo[t as usize][axis] <= pos + m).collect();
        let above: Vec<u32> = tris.iter().copied().filter(|&t| self.tri_hi[t as usize][axis] >= pos - m).collect();
        // The plane as stored (f32) bounds the children, so builder and kernel agree.
        let p = pos as f32 as f64;
        let mut hi_below = hi;
        hi_below[axis] = p;
        let mut lo_above = lo;
        lo_above[axis] = p;
        Ok((KdNode::inner(axis as u32, pos as f32, 0), (below, (lo, hi_below)), (above, (lo_above, hi))))
    }

    /// The cheapest plane by the SAH, if it beats a leaf and actually separates.
    fn find_split(&self, tris: &[u32], lo: DVec3, hi: DVec3) -> Option<(usize, f64)> {
        let p = self.params;
        let n = tris.len();
        let total_area = area(lo, hi);
        if total_area.is_nan() || total_area <= 0.0 {
            return None;
        }
        let leaf_cost = p.intersection_cost * n as f64;
        let mut best: Option<(f64, usize, f64)> = None;
        for axis in 0..3 {
            let extent = hi[axis] - lo[axis];
            if extent.is_nan() || extent <= 0.0 {
                continue;
            }
            let scale = p.bins as f64 / extent;
            let mut starts = vec![0usize; p.bins + 1];
            let mut ends = vec![0usize; p.bins + 1];
            for &t in tris {
                let a = ((self.tri_lo[t as usize][axis] - lo[axis]) * scale).clamp(0.0, p.bins as f64) as usize;
                let b = ((self.tri_hi[t as usize][axis] - lo[axis]) * scale).clamp(0.0, p.bins as f64) as usize;
                starts[a] += 1;
                ends[b] += 1;
            }
            // Plane k lies between bins k-1 and k: triangles starting before it are
            // below, triangles ending after it are above.
            let (mut below, mut above) = (0usize, n);
            for k in 1..p.bins {
                below += starts[k - 1];
                above -= ends[k - 1];
                let pos = lo[axis] + k as f64 / scale;
                let (mut hb, mut la) = (hi, lo);
                hb[axis] = pos;
                la[axis] = pos;
                let pb = area(lo, hb) / total_area;
                let pa = area(la, hi) / total_area;
                let bonus = if below == 0 || above == 0 { p.empty_bonus } else { 0.0 };
                let cost =
                    p.traversal_cost + p.intersection_cost * (1.0 - bonus) * (pb * below as f64 + pa * above as f64);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, pos));
                }
            }
        }
        let (cost, axis, pos) = best?;
        if cost >= leaf_cost {
            return None;
        }
        // Refuse a plane that leaves every triangle on both sides: it would only recurse.
        let m = self.margin;
        let below = tris.iter().filter(|&&t| self.tri_lo[t as usize][axis] <= pos + m).count();
        let above = tris.iter().filter(|&&t| self.tri_hi[t as usize][axis] >= pos - m).count();
        if below == n && above == n {
            return None;
        }
        Some((axis, pos))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::test_meshes::scatter;

    /// The kd-tree built with parallel tasks is node for node the one built depth first
    /// on one thread (the kd-tree has no budget to share), on any number of threads.
    #[test]
    fn parallel_kd_builds_equal_the_depth_first_build() {
        let mesh = scatter(3 * FORK_TRIS as u32, 9);
        let params = KdParams::default();
        let built: Vec<BuiltKd> = [1, 2, 3]
            .iter()
            .map(|&t| crate::render::in_pool(Some(t), || build_kdtree(&mesh, &params)).unwrap())
            .collect();
        // The same build with every subtree on this thread, depth first.
        let (ctx, cell) = Ctx::new(&mesh, &params);
        let mut one = TreePart { nodes: vec![KdNode::leaf(0, 0)], prims: Vec::new(), depth: 1, spare: 0 };
        ctx.sequential(&mut one, 0, (0..mesh.triangles.len() as u32).collect(), cell, 1);
        assert!(one.nodes.len() > 1000, "{} nodes", one.nodes.len());
        for b in &built {
            assert_eq!((&b.nodes, &b.prims, b.depth), (&one.nodes, &one.prims, one.depth));
        }
    }
}
