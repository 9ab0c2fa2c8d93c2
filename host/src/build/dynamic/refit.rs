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

/// Recomputes every box of `nodes` (leaves index `prims`, triangle ids into
/// `triangles`) from `positions`, leaf boxes grown by `margin`.
pub fn refit(nodes: &mut [BvhNode], prims: &[u32], triangles: &[[u32; 3]], positions: &[Position], margin: f32) {
    for i in (0..nodes.len()).rev() {
        let n = nodes[i];
        let (lo, hi) = if n.count > 0 {
            let mut lo = Vec3A::splat(f32::INFINITY);
            let mut hi = Vec3A::splat(f32::NEG_INFINITY);
            for &p in &prims[n.first as usize..(n.first + n.count) as usize] {
                for v in triangles[p as usize] {
                    let q = Vec3A::from_array(positions[v as usize].0);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            grow(lo, hi, margin)
        } else {
            let (a, b) = (nodes[n.first as usize], nodes[n.first as usize + 1]);
            let lo = Vec3A::from_array(a.min).min(Vec3A::from_array(b.min));
            let hi = Vec3A::from_array(a.max).max(Vec3A::from_array(b.max));
            (lo.to_array(), hi.to_array())
        };
        nodes[i].min = lo;
        nodes[i].max = hi;
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
}
