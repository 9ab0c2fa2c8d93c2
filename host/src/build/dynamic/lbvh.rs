//! The fast rebuild: a linear BVH (Lauterbach et al. 2009, "Fast BVH construction on
//! GPUs"; Karras 2012's split rule). Each triangle's centroid gets a 30-bit Morton code
//! in the centroids' box, the codes are radix-sorted, and a node's range splits where
//! its codes' highest differing bit turns on — no surface area is evaluated, so the
//! tree costs a sort and a pass. Boxes are left to [`super::refit::refit`].

use glam::Vec3A;
use raypipe_core::image::{BvhNode, Position, MAX_TREE_DEPTH};

/// Spreads the low 10 bits of `v` to every third bit.
fn spread(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x030000ff;
    x = (x | (x << 8)) & 0x0300f00f;
    x = (x | (x << 4)) & 0x030c30c3;
    (x | (x << 2)) & 0x09249249
}

/// Sorts `(code, id)` pairs by code, least significant 11 bits first (three passes
/// cover the 30 bits; equal codes keep their order, so the result is deterministic).
fn radix_sort(keys: &mut Vec<(u32, u32)>) {
    let mut tmp = vec![(0u32, 0u32); keys.len()];
    for shift in [0u32, 11, 22] {
        let mut count = [0usize; 2048];
        for &(k, _) in keys.iter() {
            count[((k >> shift) & 2047) as usize] += 1;
        }
        let mut sum = 0;
        for c in count.iter_mut() {
            let n = *c;
            *c = sum;
            sum += n;
        }
        for &e in keys.iter() {
            let b = ((e.0 >> shift) & 2047) as usize;
            tmp[count[b]] = e;
            count[b] += 1;
        }
        std::mem::swap(keys, &mut tmp);
    }
}

/// Builds the tree's topology over `triangles` (at most `max_leaf` per leaf, unless
/// their codes are equal deep down): nodes with zero boxes, children adjacent, and the
/// leaf list.
pub fn build_lbvh(triangles: &[[u32; 3]], positions: &[Position], max_leaf: usize) -> (Vec<BvhNode>, Vec<u32>) {
    let centroid = |t: &[u32; 3]| {
        let p = |k: usize| Vec3A::from_array(positions[t[k] as usize].0);
        (p(0) + p(1) + p(2)) * (1.0 / 3.0)
    };
    let mut lo = Vec3A::splat(f32::INFINITY);
    let mut hi = Vec3A::splat(f32::NEG_INFINITY);
    let centroids: Vec<Vec3A> = triangles.iter().map(centroid).collect();
    for &c in &centroids {
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let scale = Vec3A::splat(1023.0) / (hi - lo).max(Vec3A::splat(f32::MIN_POSITIVE));
    let mut keys: Vec<(u32, u32)> = centroids
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            let q = ((c - lo) * scale).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
            ((spread(q.x as u32) << 2) | (spread(q.y as u32) << 1) | spread(q.z as u32), i as u32)
        })
        .collect();
    radix_sort(&mut keys);
    let zero = BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 };
    let mut nodes = Vec::with_capacity(2 * triangles.len() / max_leaf.max(1) + 1);
    nodes.push(zero);
    let max_leaf = max_leaf.max(1);
    // (node, range start, range end, depth)
    let mut todo = vec![(0usize, 0usize, keys.len(), 1u32)];
    while let Some((at, s, e, depth)) = todo.pop() {
        if e - s <= max_leaf || depth + 8 >= MAX_TREE_DEPTH {
            nodes[at] = BvhNode { first: s as u32, count: (e - s) as u32, ..zero };
            continue;
        }
        let (first, last) = (keys[s].0, keys[e - 1].0);
        let mid = if first == last {
            (s + e) / 2
        } else {
            let bit = 31 - (first ^ last).leading_zeros();
            s + keys[s..e].partition_point(|k| (k.0 >> bit) & 1 == 0)
        };
        let child = nodes.len();
        nodes.push(zero);
        nodes.push(zero);
        nodes[at] = BvhNode { first: child as u32, count: 0, ..zero };
        todo.push((child + 1, mid, e, depth + 1));
        todo.push((child, s, mid, depth + 1));
    }
    (nodes, keys.into_iter().map(|(_, i)| i).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_codes_interleave_and_the_sort_orders_them() {
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(1023), 0x09249249);
        let mut keys: Vec<(u32, u32)> = (0..5000u32).map(|i| (i.wrapping_mul(2654435761) >> 2, i)).collect();
        let mut want = keys.clone();
        want.sort_by_key(|k| k.0);
        radix_sort(&mut keys);
        assert_eq!(keys, want);
    }

    #[test]
    fn every_triangle_is_in_one_leaf() {
        let positions: Vec<Position> =
            (0..3000).map(|i| Position([(i % 17) as f32, (i % 29) as f32 * 0.5, (i / 100) as f32])).collect();
        // Many triangles with equal centroids too.
        let triangles: Vec<[u32; 3]> =
            (0..1000).map(|t| [3 * (t % 700), 3 * (t % 700) + 1, 3 * (t % 700) + 2]).collect();
        let (nodes, prims) = build_lbvh(&triangles, &positions, 4);
        let mut seen = vec![0; triangles.len()];
        for n in nodes.iter().filter(|n| n.count > 0) {
            for &p in &prims[n.first as usize..(n.first + n.count) as usize] {
                seen[p as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        for (i, n) in nodes.iter().enumerate().filter(|(_, n)| n.count == 0) {
            assert!(n.first as usize > i && (n.first as usize + 1) < nodes.len());
        }
    }
}
