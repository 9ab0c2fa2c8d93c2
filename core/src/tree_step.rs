//! The event a tree traversal step reports — what a hardware traversal unit emits each
//! cycle: an inner node was read (step again), a leaf was reached (hand its primitive
//! list to the intersection unit, then call the walk's `finish_leaf`), or the walk is
//! over. kd-tree, BVH and 4-wide BVH steps all speak it.

/// What one tree traversal step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeEvent {
    /// An inner node was read; step again.
    Inner,
    /// A leaf: test PRIM_LISTS entries `first .. first + count`, then finish the leaf.
    Leaf {
        /// First list entry.
        first: u32,
        /// Number of triangles.
        count: u32,
    },
    /// The walk is over.
    Done,
}
