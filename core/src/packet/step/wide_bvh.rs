//! A 4- or 8-wide BVH walked by a whole packet: one step reads one node for the packet
//! (all its children's boxes) and runs the node test for every active ray, each against
//! its own interval up to its best hit so far ([`WideSlab::slab`], the single-ray walk's
//! test, bit for bit). Each child gets the mask of the rays that hit it and their nearest
//! entry; the packet enters the nearest child and pushes the others farthest first, as
//! the single-ray walk ([`crate::traverse::wide_bvh`]) does for one ray. A popped entry
//! keeps the rays whose best hit is not nearer than that entry.

use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh8Node, SceneView, WideBvhView};
use crate::packet::LanesOf;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::walk::Leaf;
use crate::traverse::wide_bvh::{stack_capacity, NodeRay, WideSlab};

use super::interface::{existing, lane_end, PacketEvent, PacketStep};

/// A shared-stack entry: child (or first list entry), leaf count or 0, the nearest
/// entry distance of the rays that need it, and their mask.
type Entry = (u32, u32, f32, u64);

/// The registers of a packet in a wide BVH of nodes `W`, with a stack of `C` entries.
#[derive(Clone, Debug)]
pub struct WidePacketTraversal<W: WideSlab, const N: usize, const C: usize> {
    rays: [Option<NodeRay>; N],
    t_min: [f32; N],
    t_max: [f32; N],
    current: (u32, u32),
    mask: u64,
    stack: heapless::Vec<Entry, C>,
    done: bool,
    best: [Option<Hit>; N],
    node: core::marker::PhantomData<fn() -> W>,
}

/// A packet in the 4-wide BVH.
pub type Bvh4PacketTraversal<const N: usize> = WidePacketTraversal<Bvh4Node, N, { stack_capacity(4) }>;
/// A packet in the 8-wide BVH.
pub type Bvh8PacketTraversal<const N: usize> = WidePacketTraversal<Bvh8Node, N, { stack_capacity(8) }>;

impl<W: WideSlab, const N: usize, const C: usize> WidePacketTraversal<W, N, C> {
    /// Starts the valid rays of `active` at the root.
    pub fn new(rays: &[Ray], active: u64) -> WidePacketTraversal<W, N, C> {
        let mut t = WidePacketTraversal {
            rays: [None; N],
            t_min: [0.0; N],
            t_max: [0.0; N],
            current: (0, 0),
            mask: 0,
            stack: heapless::Vec::new(),
            done: false,
            best: [None; N],
            node: core::marker::PhantomData,
        };
        for i in LanesOf::<N>(existing(active, rays.len(), N)) {
            let Some(ray) = rays.get(i) else { continue };
            if ray.is_valid() {
                t.mask |= 1 << i;
                t.rays[i] = Some(NodeRay::new(ray));
                (t.t_min[i], t.t_max[i]) = (ray.t_min, ray.t_max);
            }
        }
        t.done = t.mask == 0;
        t
    }

    /// Ray `i`'s end: its best hit's distance or its interval's end.
    fn t_end(&self, i: usize) -> f32 {
        lane_end(&self.best, &self.t_max, i)
    }

    /// Reads one inner node for the packet and moves to its nearest child needed by any
    /// ray (pushing the others), or reports the leaf the packet stands on.
    pub fn step<P: MemoryProbe>(&mut self, bvh: &WideBvhView<'_, W>, probe: &mut P) -> PacketEvent {
        if self.done {
            return PacketEvent::Done;
        }
        let (index, count) = self.current;
        if count > 0 {
            return PacketEvent::Leaf { leaf: Leaf::Range { first: index, count }, lanes: self.mask };
        }
        let node = bvh.node(index, probe);
        let mut need = [0u64; 8];
        let mut near = [f32::INFINITY; 8];
        let tested = self.mask;
        for i in LanesOf::<N>(self.mask) {
            let Some(r) = &self.rays[i] else { continue };
            let mut tn = W::Dist::default();
            let mut hit = node.slab(r, self.t_min[i], self.t_end(i), &mut tn);
            while hit != 0 {
                let k = hit.trailing_zeros() as usize & (W::WIDTH - 1) & 7;
                hit &= hit - 1;
                need[k] |= 1 << i;
                near[k] = near[k].min(tn[k]);
            }
        }
        // Slots in order of their nearest entry, farthest pushed first, ties in slot
        // order (as the single-ray walk sorts them).
        // Pushed one by one: `collect` into a fixed-capacity Vec keeps a panic path for an
        // iterator longer than the capacity, which the compiler cannot always rule out.
        let mut order: heapless::Vec<usize, 8> = heapless::Vec::new();
        for k in (0..W::WIDTH.min(8)).filter(|&k| need[k & 7] != 0) {
            let _ = order.push(k);
        }
        if order.is_empty() {
            self.pop();
            return PacketEvent::Node { lanes: tested };
        }
        for i in 1..order.len() {
            let mut j = i;
            // Read through `get` and slots masked below 8: no bounds checks, no panic path.
            while j > 0 {
                let Some(pair) = order.get_mut(j - 1..=j) else { break };
                if near[pair[0] & 7] > near[pair[1] & 7] {
                    break;
                }
                pair.swap(0, 1);
                j -= 1;
            }
        }
        let Some(nearest) = order.pop() else { return PacketEvent::Node { lanes: tested } };
        for &k in order.iter() {
            let (c, n) = node.link(k);
            // Cannot be full: `parse` bounds the depth (see `stack_capacity`).
            let _ = self.stack.push((c, n, near[k & 7], need[k & 7]));
        }
        self.current = node.link(nearest);
        self.mask = need[nearest & 7];
        PacketEvent::Node { lanes: tested }
    }

    /// After a leaf: on to the next entry some ray may still find a closer hit in.
    pub fn finish_leaf(&mut self) {
        self.pop();
    }

    fn pop(&mut self) {
        while let Some((c, n, t, m)) = self.stack.pop() {
            let mut still = 0u64;
            for i in LanesOf::<N>(m) {
                if t <= self.t_end(i) {
                    still |= 1 << i;
                }
            }
            if still != 0 {
                (self.current, self.mask) = ((c, n), still);
                return;
            }
        }
        self.done = true;
    }
}

/// The view of a scene's wide BVH of nodes `W`.
pub trait WideOf: WideSlab + Sized {
    /// The scene's BVH of these nodes, if it holds one.
    fn view<'s, 'a>(scene: &'s SceneView<'a>) -> Option<&'s WideBvhView<'a, Self>>;
}

impl WideOf for Bvh4Node {
    fn view<'s, 'a>(scene: &'s SceneView<'a>) -> Option<&'s WideBvhView<'a, Self>> {
        scene.bvh4()
    }
}

impl WideOf for Bvh8Node {
    fn view<'s, 'a>(scene: &'s SceneView<'a>) -> Option<&'s WideBvhView<'a, Self>> {
        scene.bvh8()
    }
}

impl<W: WideOf, const N: usize, const C: usize> PacketStep for WidePacketTraversal<W, N, C> {
    #[inline]
    fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, _rays: &[Ray], probe: &mut P) -> PacketEvent {
        match W::view(scene) {
            Some(bvh) => WidePacketTraversal::step(self, bvh, probe),
            None => PacketEvent::Done,
        }
    }

    fn finish_leaf(&mut self) {
        WidePacketTraversal::finish_leaf(self)
    }

    fn best(&self, i: usize) -> Option<Hit> {
        self.best.get(i).copied().flatten()
    }

    fn best_mut(&mut self, i: usize) -> Option<&mut Option<Hit>> {
        self.best.get_mut(i)
    }
}
