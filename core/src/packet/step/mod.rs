//! SaarCOR's packet traversal as step kernels (Schmittler, Wald & Slusallek 2002; Wald &
//! Slusallek 2001 §5.3, §7.3): a packet of rays shares one walk — one node per step,
//! fetched once for the whole packet, and one fixed-capacity stack — and carries a mask
//! of the rays that need the node it stands on. A packet descends into a child if any of
//! its active rays needs it, with exactly those rays, so each ray still meets every leaf
//! its single-ray walk meets (in another order, at worst) and its closest hit is the
//! same, bit for bit.
//!
//! This is the interface a hardware traversal unit drives, one [`PacketStep::step`] per
//! node: the kd-tree ([`kdtree`]), the binary BVH ([`bvh`]) and
//! the 4- and 8-wide BVHs ([`wide_bvh`]). The uniform grid has no shared
//! walk: its rays leave a voxel at different distances, so its packets keep per-ray
//! lock-step (Purcell 2002 §3.2, [`crate::packet::lockstep`]).

pub mod bvh;
mod interface;
pub mod kdtree;
pub mod wide_bvh;

use crate::hit::Hit;
use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::packet::LanesOf;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::walk::trace_walk;

pub use interface::{lane_mask, PacketEvent, PacketStep};

use bvh::BvhPacketTraversal;
use kdtree::KdPacketTraversal;
use wide_bvh::{Bvh4PacketTraversal, Bvh8PacketTraversal};

/// The shared packet walk of whichever tree the scene image holds; `None` for the grid
/// and for an image without a structure (their packets step ray by ray).
// The variants hold fixed-capacity stacks of different widths; core has no heap to box
// them in, and a walk is a fixed-size register file anyway.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum PacketWalk<const N: usize> {
    /// kd-tree.
    Kd(KdPacketTraversal<N>),
    /// Binary BVH.
    Bvh(BvhPacketTraversal<N>),
    /// 4-wide BVH.
    Bvh4(Bvh4PacketTraversal<N>),
    /// 8-wide BVH.
    Bvh8(Bvh8PacketTraversal<N>),
}

impl<const N: usize> PacketWalk<N> {
    /// Starts the rays of `active` (bits of `rays`' indices; invalid rays stay out) in
    /// the scene's tree, or `None` if the scene has no tree.
    pub fn start(scene: &SceneView<'_>, rays: &[Ray], active: u64) -> Option<PacketWalk<N>> {
        // Only lanes that exist: stray bits past the rays (or past N) take no part.
        let active = active & lane_mask(rays.len().min(N));
        if scene.grid().is_some() {
            None
        } else if scene.bvh4().is_some() {
            Some(PacketWalk::Bvh4(Bvh4PacketTraversal::new(rays, active)))
        } else if scene.bvh8().is_some() {
            Some(PacketWalk::Bvh8(Bvh8PacketTraversal::new(rays, active)))
        } else if scene.bvh().is_some() {
            Some(PacketWalk::Bvh(BvhPacketTraversal::new(rays, active)))
        } else {
            scene.kdtree().map(|kd| PacketWalk::Kd(KdPacketTraversal::new(kd, rays, active)))
        }
    }
}

impl<const N: usize> PacketStep for PacketWalk<N> {
    #[inline]
    fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, rays: &[Ray], probe: &mut P) -> PacketEvent {
        match self {
            PacketWalk::Kd(w) => PacketStep::step(w, scene, rays, probe),
            PacketWalk::Bvh(w) => PacketStep::step(w, scene, rays, probe),
            PacketWalk::Bvh4(w) => PacketStep::step(w, scene, rays, probe),
            PacketWalk::Bvh8(w) => PacketStep::step(w, scene, rays, probe),
        }
    }

    #[inline]
    fn finish_leaf(&mut self) {
        match self {
            PacketWalk::Kd(w) => PacketStep::finish_leaf(w),
            PacketWalk::Bvh(w) => PacketStep::finish_leaf(w),
            PacketWalk::Bvh4(w) => PacketStep::finish_leaf(w),
            PacketWalk::Bvh8(w) => PacketStep::finish_leaf(w),
        }
    }

    #[inline]
    fn best(&self, i: usize) -> Option<Hit> {
        match self {
            PacketWalk::Kd(w) => w.best(i),
            PacketWalk::Bvh(w) => w.best(i),
            PacketWalk::Bvh4(w) => w.best(i),
            PacketWalk::Bvh8(w) => w.best(i),
        }
    }

    #[inline]
    fn best_mut(&mut self, i: usize) -> Option<&mut Option<Hit>> {
        match self {
            PacketWalk::Kd(w) => w.best_mut(i),
            PacketWalk::Bvh(w) => w.best_mut(i),
            PacketWalk::Bvh4(w) => w.best_mut(i),
            PacketWalk::Bvh8(w) => w.best_mut(i),
        }
    }
}

/// The rays of `active` traced by driving the scene's shared packet walk to the end —
/// what the hardware model's traversal and intersection units do, in one loop (the
/// equivalence suite compares it with single rays); `hits[i]` receives ray `i`'s closest
/// hit. Scenes without a tree trace ray by ray ([`trace_walk`]). Returns the node steps
/// taken (one node fetch each).
pub fn trace_packet_steps<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    rays: &[Ray; N],
    active: u64,
    hits: &mut [Option<Hit>; N],
    probe: &mut P,
) -> u64 {
    *hits = [None; N];
    let active = active & lane_mask(N);
    let Some(mut walk) = PacketWalk::<N>::start(scene, rays, active) else {
        for i in LanesOf::<N>(active) {
            hits[i] = trace_walk::<I, P>(scene, &rays[i], probe);
        }
        return 0;
    };
    let preps: [Option<I::Prepared>; N] =
        core::array::from_fn(|i| (active & (1 << i) != 0).then(|| I::prepare(&rays[i])));
    let mut steps = 0;
    loop {
        match walk.step(scene, rays, probe) {
            PacketEvent::Node { .. } => steps += 1,
            PacketEvent::Leaf { leaf, lanes } => {
                for i in LanesOf::<N>(lanes & active) {
                    if let (Some(prep), Some(best)) = (&preps[i], walk.best_mut(i)) {
                        leaf.test::<I, P>(scene, prep, &rays[i], false, best, probe);
                    }
                }
                walk.finish_leaf();
            }
            PacketEvent::Done => break,
        }
    }
    for (i, h) in hits.iter_mut().enumerate() {
        *h = if active & (1 << i) != 0 { walk.best(i) } else { None };
    }
    steps
}
