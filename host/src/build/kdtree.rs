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
    out: BuiltKd,
}

/// Builds the kd-tree over the scene bounds.
pub fn build_kdtree(mesh: &Mesh, params: &KdParams) -> BuiltKd {
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
    let mut ctx = Ctx { tri_lo, tri_hi, params, margin: box_margin(mesh), max_depth, out: BuiltKd::default() };
    ctx.out.nodes.push(KdNode::leaf(0, 0));
    let all: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    ctx.build(0, all, root, 1);
    ctx.out
}

fn area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

impl Ctx<'_> {
    fn build(&mut self, node: usize, tris: Vec<u32>, (lo, hi): (DVec3, DVec3), depth: u32) {
        self.out.depth = self.out.depth.max(depth);
        let split = if tris.len() <= self.params.max_leaf || depth >= self.max_depth {
            None
        } else {
            self.find_split(&tris, lo, hi)
        };
        let Some((axis, pos)) = split else {
            self.out.nodes[node] = KdNode::leaf(self.out.prims.len() as u32, tris.len() as u32);
            self.out.prims.extend_from_slice(&tris);
            return;
        };
        let m = self.margin;
        let below: Vec<u32> = tris.iter().copied().filter(|&t| self.tri_lo[t as usize][axis] <= pos + m).collect();
        let above: Vec<u32> = tris.iter().copied().filter(|&t| self.tri_hi[t as usize][axis] >= pos - m).collect();
        let child = self.out.nodes.len();
        self.out.nodes.push(KdNode::leaf(0, 0));
        self.out.nodes.push(KdNode::leaf(0, 0));
        self.out.nodes[node] = KdNode::inner(axis as u32, pos as f32, child as u32);
        drop(tris);
        // The plane as stored (f32) bounds the children, so builder and kernel agree.
        let p = pos as f32 as f64;
        let mut hi_below = hi;
        hi_below[axis] = p;
        let mut lo_above = lo;
        lo_above[axis] = p;
        self.build(child, below, (lo, hi_below), depth + 1);
        self.build(child + 1, above, (lo_above, hi), depth + 1);
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
