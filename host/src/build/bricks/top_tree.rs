//! The top-level BVH of a bricked scene: the partition's tree, one brick per leaf, each
//! node's box the union of its bricks' boxes (each brick's triangles' boxes clipped to
//! its region and grown by the scene's margin: [`super::region`]), laid out as the binary BVH's 32-byte nodes with children side by
//! side after their parent.

use raypipe_core::image::BvhNode;

use super::partition::Part;

/// Nodes of the tree over `part`, whose leaf `k` (left to right) is brick `k` with box
/// `boxes[k]`. List entry `k` is brick `k`.
pub fn top_nodes(part: &Part, boxes: &[([f32; 3], [f32; 3])]) -> Vec<BvhNode> {
    let mut nodes = vec![BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 }];
    let mut next_leaf = 0u32;
    fill(part, 0, &mut nodes, boxes, &mut next_leaf);
    nodes
}

/// Writes node `at` for `part` and its subtree; returns its box.
fn fill(
    part: &Part,
    at: usize,
    nodes: &mut Vec<BvhNode>,
    boxes: &[([f32; 3], [f32; 3])],
    next_leaf: &mut u32,
) -> ([f32; 3], [f32; 3]) {
    match part {
        Part::Leaf => {
            let k = *next_leaf;
            *next_leaf += 1;
            let (lo, hi) = boxes[k as usize];
            nodes[at] = BvhNode { min: lo, first: k, max: hi, count: 1 };
            (lo, hi)
        }
        Part::Inner(a, b) => {
            let c = nodes.len();
            nodes.push(nodes[at]);
            nodes.push(nodes[at]);
            let (alo, ahi) = fill(a, c, nodes, boxes, next_leaf);
            let (blo, bhi) = fill(b, c + 1, nodes, boxes, next_leaf);
            let lo = std::array::from_fn(|i| alo[i].min(blo[i]));
            let hi = std::array::from_fn(|i| ahi[i].max(bhi[i]));
            nodes[at] = BvhNode { min: lo, first: c as u32, max: hi, count: 0 };
            (lo, hi)
        }
    }
}
