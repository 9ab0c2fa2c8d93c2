//! A subtree built by one task of a parallel build, and how two of them are joined
//! under their parent: in the order the sequential build writes nodes (each node's two
//! children side by side, the left child's subtree before the right's), so a tree built
//! in parallel is laid out as if built on one thread.

/// A node of a binary tree whose children sit side by side: it can be moved into a
/// larger tree, its child index (inner node) or first list entry (leaf) shifted.
pub(crate) trait PartNode: Copy {
    /// The node with its child index moved by `nodes` (inner) or its first list entry
    /// by `prims` (leaf).
    fn moved(self, nodes: u32, prims: u32) -> Self;
    /// The inner node whose children are at `child` and `child + 1`.
    fn with_children(self, child: u32) -> Self;
}

/// A subtree built on its own: its nodes (its root first; child indices and list
/// entries within the part), its leaves' list, its depth, and the reference budget it
/// left unspent (for builders that have one).
pub(crate) struct TreePart<N> {
    pub(crate) nodes: Vec<N>,
    pub(crate) prims: Vec<u32>,
    pub(crate) depth: u32,
    pub(crate) spare: usize,
}

impl<N: PartNode> TreePart<N> {
    /// The part of inner node `node` over its children's parts `l` and `r`: `node`, the
    /// two children's roots side by side, then the rest of the left part and of the
    /// right, moved to their new places.
    pub(crate) fn join(node: N, l: TreePart<N>, r: TreePart<N>) -> TreePart<N> {
        let (ln, lp) = (l.nodes.len() as u32, l.prims.len() as u32);
        let mut nodes = Vec::with_capacity(1 + l.nodes.len() + r.nodes.len());
        nodes.push(node.with_children(1));
        // Left index i ≥ 1 lands at i + 2, right index i ≥ 1 at i + 1 + ln (children
        // never point at their part's root, which moves to 1 or 2). Every part holds at
        // least its root.
        nodes.push(l.nodes[0].moved(2, 0));
        nodes.push(r.nodes[0].moved(1 + ln, lp));
        nodes.extend(l.nodes[1..].iter().map(|n| n.moved(2, 0)));
        nodes.extend(r.nodes[1..].iter().map(|n| n.moved(1 + ln, lp)));
        let mut prims = l.prims;
        prims.extend_from_slice(&r.prims);
        TreePart { nodes, prims, depth: l.depth.max(r.depth), spare: l.spare + r.spare }
    }
}
