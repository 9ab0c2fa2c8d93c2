//! Refitting a binary BVH to moved vertices (Wald, Boulos & Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies"): the topology stays,
//! every box is recomputed bottom-up. Children always follow their parents in the node
//! array, so one pass from the last node to the first sees every child before its
//! parent. Leaf boxes are grown by the margin the static builder uses (relative to the
//! mesh's extent and magnitude), so a refitted tree stays conservative.

use glam::Vec3A;
use raypipe_core::image::{BvhNode, Position};

/// The margin leaf boxes are grown by for a mesh of bounds `(lo, hi)`, as the static
/// builder's `box_margin`: relative to the extent and to the coordinates' magnitude.
pub fn margin_for(lo: Vec3A, hi: Vec3A) -> f32 {
    let m = 1e-5 * f64::from((hi - lo).max_element())
        + 8.0 * f64::from(f32::EPSILON) * f64::from(lo.abs().max(hi.abs()).max_element());
    (m as f32).next_up()
}

/// The box of `positions`.
pub fn bounds_of(positions: &[Position]) -> (Vec3A, Vec3A) {
    let mut b = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    for p in positions {
        let v = Vec3A::from_array(p.0);
        b = (b.0.min(v), b.1.max(v));
    }
    b
}

fn grow(lo: Vec3A, hi: Vec3A, margin: f32) -> ([f32; 3], [f32; 3]) {
    (
        (lo - Vec3A::splat(margin)).to_array().map(f32::next_down),
        (hi + Vec3A::splat(margin)).to_array().map(f32::next_up),
    )
}

/// What refitting reads besides the nodes.
#[derive(Clone, Copy)]
struct Geometry<'a> {
    prims: &'a [u32],
    triangles: &'a [[u32; 3]],
    positions: &'a [Position],
    margin: f32,
}

impl Geometry<'_> {
    /// Node `n`'s box: its triangles' grown by the margin (a leaf), or its children's
    /// union (read through `child`).
    #[inline]
    fn node_box(&self, n: &BvhNode, child: impl Fn(u32) -> Option<BvhNode>) -> Option<([f32; 3], [f32; 3])> {
        if n.count > 0 {
            let mut lo = Vec3A::splat(f32::INFINITY);
            let mut hi = Vec3A::splat(f32::NEG_INFINITY);
            for &p in self.prims.get(n.first as usize..(n.first + n.count) as usize)? {
                for v in *self.triangles.get(p as usize)? {
                    let q = Vec3A::from_array(self.positions.get(v as usize)?.0);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            Some(grow(lo, hi, self.margin))
        } else {
            let (a, b) = (child(n.first)?, child(n.first + 1)?);
            let lo = Vec3A::from_array(a.min).min(Vec3A::from_array(b.min));
            let hi = Vec3A::from_array(a.max).max(Vec3A::from_array(b.max));
            Some((lo.to_array(), hi.to_array()))
        }
    }
}

/// Refits the nodes with indices `base .. base + part.len()`, last first; `false` if a
/// child lies outside them.
fn refit_part(part: &mut [BvhNode], base: usize, g: &Geometry<'_>) -> bool {
    for i in (0..part.len()).rev() {
        let n = part[i];
        let child = |c: u32| (c as usize).checked_sub(base).and_then(|k| part.get(k)).copied();
        let Some((lo, hi)) = g.node_box(&n, child) else { return false };
        part[i].min = lo;
        part[i].max = hi;
    }
    true
}

/// Refits the descendants of a node, which sit at `base .. base + part.len()`: its two
/// children first, then the first child's descendants, then the second's — the order
/// raypipe's builders lay trees out in (each node's subtree is finished before its
/// sibling's is begun). The two subtrees are refitted in parallel down to `depth`
/// levels; `false` if the tree is not laid out so.
fn refit_descendants(part: &mut [BvhNode], base: usize, g: &Geometry<'_>, depth: u32) -> bool {
    if part.len() < 2 || depth == 0 || part.len() < 4096 {
        return refit_part(part, base, g);
    }
    let right = part[1];
    // The second child's descendants start at its first child (none for a leaf).
    let split = if right.count == 0 { right.first as usize } else { base + part.len() };
    let Some(k) = split.checked_sub(base).filter(|&k| (2..=part.len()).contains(&k)) else { return false };
    let (children, rest) = part.split_at_mut(2);
    let (left, right) = rest.split_at_mut(k - 2);
    let (a, b) = rayon::join(
        || refit_descendants(left, base + 2, g, depth - 1),
        || refit_descendants(right, base + k, g, depth - 1),
    );
    // The two children themselves, from their children (now refitted).
    let child = |c: u32| {
        let c = c as usize;
        if c >= base + k { right.get(c - base - k) } else { left.get(c.checked_sub(base + 2)?) }.copied()
    };
    for i in [1usize, 0] {
        let Some((lo, hi)) = g.node_box(&children[i], child) else { return false };
        children[i].min = lo;
        children[i].max = hi;
    }
    a && b
}

/// Recomputes every box of `nodes` (leaves index `prims`, triangle ids into
/// `triangles`) from `positions`, leaf boxes grown by `margin`: the top of the tree's
/// subtrees on the worker pool, as raypipe's builders lay them out, and any other tree
/// node by node.
pub fn refit(nodes: &mut [BvhNode], prims: &[u32], triangles: &[[u32; 3]], positions: &[Position], margin: f32) {
    let g = Geometry { prims, triangles, positions, margin };
    let parallel = nodes.len() > 1 && {
        let (root, rest) = nodes.split_at_mut(1);
        let done = refit_descendants(rest, 1, &g, 3);
        let child = |c: u32| (c as usize).checked_sub(1).and_then(|k| rest.get(k)).copied();
        done && g.node_box(&root[0], child).map(|(lo, hi)| (root[0].min, root[0].max) = (lo, hi)).is_some()
    };
    if !parallel {
        refit_part(nodes, 0, &g);
    }
}

/// The tree's SAH cost relative to its root's surface area: the expected node visits
/// plus triangle tests of a random ray through the root box (Goldsmith & Salmon 1987;
/// MacDonald & Booth 1990). A refitted tree's cost grows as its boxes stretch; the
/// automatic update rebuilds when it has grown past a threshold.
pub fn sah_cost(nodes: &[BvhNode]) -> f64 {
    let area = |n: &BvhNode| {
        let d = Vec3A::from_array(n.max) - Vec3A::from_array(n.min);
        f64::from(d.x * d.y + d.y * d.z + d.z * d.x)
    };
    let Some(root) = nodes.first() else { return 0.0 };
    let root_area = area(root).max(f64::MIN_POSITIVE);
    nodes.iter().map(|n| area(n) / root_area * if n.count > 0 { n.count as f64 } else { 1.0 }).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::dynamic::lbvh::build_lbvh;

    /// After the vertices move, every refitted leaf holds its triangles and every node
    /// its children; the topology is untouched.
    #[test]
    fn a_refitted_tree_holds_the_moved_triangles() {
        let mut g = 7u64;
        let mut r = || {
            g = g.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (g >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut positions: Vec<Position> = (0..300).map(|_| Position([r() * 4.0, r() * 4.0, r() * 4.0])).collect();
        let triangles: Vec<[u32; 3]> = (0..100).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let (mut nodes, prims) = build_lbvh(&triangles, &positions, 4);
        let (lo, hi) = bounds_of(&positions);
        refit(&mut nodes, &prims, &triangles, &positions, margin_for(lo, hi));
        let topology: Vec<(u32, u32)> = nodes.iter().map(|n| (n.first, n.count)).collect();
        for p in &mut positions {
            p.0 = [p.0[0] * 1.5 + r(), p.0[1] - 2.0, p.0[2] + r() * 3.0];
        }
        let (lo, hi) = bounds_of(&positions);
        refit(&mut nodes, &prims, &triangles, &positions, margin_for(lo, hi));
        assert_eq!(topology, nodes.iter().map(|n| (n.first, n.count)).collect::<Vec<_>>());
        let inside = |n: &BvhNode, p: [f32; 3]| (0..3).all(|a| n.min[a] <= p[a] && p[a] <= n.max[a]);
        for n in &nodes {
            if n.count > 0 {
                for &t in &prims[n.first as usize..(n.first + n.count) as usize] {
                    for v in triangles[t as usize] {
                        assert!(inside(n, positions[v as usize].0));
                    }
                }
            } else {
                for c in [nodes[n.first as usize], nodes[n.first as usize + 1]] {
                    assert!(inside(n, c.min) && inside(n, c.max));
                }
            }
        }
        assert!(sah_cost(&nodes) > 1.0);
    }

    /// The parallel refit of a large tree gives exactly the node-by-node refit's boxes,
    /// for the layouts of both builders, and for a tree laid out otherwise.
    #[test]
    fn the_parallel_refit_equals_the_sequential_one() {
        let mut g = 11u64;
        let mut r = || {
            g = g.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (g >> 40) as f32 / (1u64 << 24) as f32
        };
        let positions: Vec<Position> = (0..60_000).map(|_| Position([r() * 9.0, r() * 3.0, r() * 5.0])).collect();
        let triangles: Vec<[u32; 3]> = (0..20_000).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let boxes: Vec<([f32; 3], [f32; 3])> = triangles
            .iter()
            .map(|t| {
                let p = |k: usize| Vec3A::from_array(positions[t[k] as usize].0);
                (p(0).min(p(1)).min(p(2)).to_array(), p(0).max(p(1)).max(p(2)).to_array())
            })
            .collect();
        let sah = crate::build::box_bvh::build_box_bvh(&boxes, 4);
        for (nodes, prims) in [build_lbvh(&triangles, &positions, 4), (sah.nodes, sah.list)] {
            let g = Geometry { prims: &prims, triangles: &triangles, positions: &positions, margin: 0.01 };
            let mut one = nodes.clone();
            assert!(refit_part(&mut one, 0, &g));
            let mut par = nodes.clone();
            refit(&mut par, &prims, &triangles, &positions, 0.01);
            assert_eq!(one, par);
            // Swapping two sibling subtrees' places breaks the layout: still right.
            let mut odd = nodes.clone();
            let (a, b) = (odd[1], odd[2]);
            (odd[1], odd[2]) = (b, a);
            let mut seq = odd.clone();
            assert!(refit_part(&mut seq, 0, &g));
            refit(&mut odd, &prims, &triangles, &positions, 0.01);
            assert_eq!(seq, odd);
        }
    }
}
