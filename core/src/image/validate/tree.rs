//! The shape every tree section must have, whatever its nodes: a tree rooted at node 0,
//! children after their parents, bounded depth and bounded leaf entries.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::limits::{MAX_TREE_DEPTH, MAX_WIDE_DEPTH};

/// The inner children of one tree node (at most eight: the 8-wide BVH).
pub(in crate::image) type Children = heapless::Vec<u32, 8>;

/// Checks, with a fixed-capacity stack and no allocation, that `children(i)` describes a
/// tree rooted at node 0: every child comes after its parent and inside the section, no
/// path is `max_depth` nodes deep ([`MAX_TREE_DEPTH`] for binary trees, whose traversal
/// kernels' stacks hold one entry per level; [`MAX_WIDE_DEPTH`] for wide BVHs, seven
/// entries per level for the 8-wide one), and the walk visits exactly `n` nodes. `children(i)`
/// is `Err` for a malformed node, else the node's inner children (none for a leaf) and
/// the list entries its leaves hold; summed over every visit of the walk they may not
/// exceed `list_entries`.
///
/// That bounds the work of any ray on an accepted tree ([scene-format.md](https://github.com/raypipe/raypipe/blob/main/docs/scene-format.md), "Work
/// bounds"): the walk visits each node at most once per path from the root, the paths
/// are exactly the visits counted here (at most `n`), so a ray takes at most `n` node
/// steps and tests at most `list_entries` list entries.
pub(in crate::image) fn validate_tree(
    n: usize,
    section: SectionKind,
    max_depth: u32,
    list_entries: u64,
    mut children: impl FnMut(usize) -> Result<(Children, u64), ()>,
) -> Result<(), SceneError> {
    let bad = |node: usize| SceneError::BadTree { section, node: node as u32 };
    if n == 0 {
        return Err(bad(0));
    }
    // (node, depth); a depth-first walk pushes at most one more entry per level of a
    // binary tree, seven of an 8-wide one.
    const CAPACITY: usize = {
        let (binary, wide) = (MAX_TREE_DEPTH as usize + 1, 7 * MAX_WIDE_DEPTH as usize + 1);
        if binary > wide {
            binary
        } else {
            wide
        }
    };
    let mut stack: heapless::Vec<(u32, u32), CAPACITY> = heapless::Vec::new();
    let _ = stack.push((0, 0));
    let mut visited = 0usize;
    let mut leaf_entries = 0u64;
    while let Some((i, depth)) = stack.pop() {
        let i = i as usize;
        visited += 1;
        if visited > n || depth >= max_depth {
            return Err(bad(i));
        }
        let (inner, entries) = children(i).map_err(|_| bad(i))?;
        leaf_entries += entries;
        if leaf_entries > list_entries {
            return Err(bad(i));
        }
        for c in inner {
            if c as usize <= i || c as usize >= n || stack.push((c, depth + 1)).is_err() {
                return Err(bad(i));
            }
        }
    }
    if visited != n {
        return Err(bad(n - 1));
    }
    Ok(())
}

/// The two adjacent children `c` and `c + 1` of a binary inner node.
pub(in crate::image) fn pair(c: u32) -> Children {
    Children::from_iter([c, c.wrapping_add(1)])
}
