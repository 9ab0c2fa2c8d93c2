//! Builds a BVH by the binned surface area heuristic (Wald 2007, "On fast construction of
//! SAH-based bounding volume hierarchies"), writing 32-byte nodes whose children sit side
//! by side (`BvhNode`). Each node's box is grown outwards by a small margin, so that a
//! triangle lying on a box face is never culled by the rounding of the entry distance.

use glam::DVec3;
use raypipe_core::image::{BvhNode, MAX_TREE_DEPTH};

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
}

impl Default for BvhParams {
    fn default() -> Self {
        BvhParams { bins: 16, traversal_cost: 1.0, intersection_cost: 1.0, max_leaf: 8 }
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
    let tris: Vec<(Bounds, DVec3)> = mesh
        .triangles
        .iter()
        .map(|t| {
            let v = t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)));
            let b = Bounds { lo: v[0].min(v[1]).min(v[2]), hi: v[0].max(v[1]).max(v[2]) };
            (b, (b.lo + b.hi) * 0.5)
        })
        .collect();
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
    out.prims = idx;
    out
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
    let leaf_cost = p.intersection_cost * n as f64;
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
                + p.intersection_cost * (left.area() * nl as f64 + right_area[k] * nr as f64) / parent_area;
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
