//! What a packet step is, whatever the tree: the events one step reports, the trait each
//! structure's packet walk implements, and the lane masks they share.

use crate::hit::Hit;
use crate::image::SceneView;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::walk::Leaf;

/// What one packet step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketEvent {
    /// One inner node was read, once for the packet, and its box or plane tested by the
    /// rays of `lanes` (the datapath's work: one ray–node test per lane).
    Node {
        /// The rays tested against the node.
        lanes: u64,
    },
    /// The packet stands at a leaf: the rays of `lanes` test its triangles (PRIM_LISTS
    /// entries `first .. first + count`), then [`PacketStep::finish_leaf`].
    Leaf {
        /// The leaf's triangles.
        leaf: Leaf,
        /// The rays that test them.
        lanes: u64,
    },
    /// The walk is over; [`PacketStep::best`] holds each ray's hit.
    Done,
}

/// A packet's shared walk through a tree, one node per step.
pub trait PacketStep {
    /// Reads one node for the whole packet and moves on, or reports the leaf it stands on.
    fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, rays: &[Ray], probe: &mut P) -> PacketEvent;
    /// After the leaf's triangles were tested into [`PacketStep::best_mut`].
    fn finish_leaf(&mut self);
    /// Ray `i`'s closest hit so far (`None` past the packet's size).
    fn best(&self, i: usize) -> Option<Hit>;
    /// Ray `i`'s closest hit so far, for the intersection kernel to update (`None` past
    /// the packet's size).
    fn best_mut(&mut self, i: usize) -> Option<&mut Option<Hit>>;
}

/// The mask of lanes `0 .. n` (all 64 for `n >= 64`).
#[inline]
pub const fn lane_mask(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

/// Lane `i`'s end along its ray in a BVH packet walk: its best hit's distance, or its
/// interval's end (0 past the lanes).
#[inline]
pub(crate) fn lane_end<const N: usize>(best: &[Option<Hit>; N], t_max: &[f32; N], i: usize) -> f32 {
    let t_max = t_max.get(i).copied().unwrap_or(0.0);
    best.get(i).copied().flatten().map_or(t_max, |h| h.t)
}

/// A packet's lanes limited to those that exist: the rays of `rays` and the packet's `N`.
#[inline]
pub(crate) fn existing(active: u64, rays: usize, n: usize) -> u64 {
    active & lane_mask(rays.min(n))
}
