//! The binary BVH walked by a whole packet (Wald, Boulos & Shirley 2007): one step reads
//! the node the packet stands on (its two children's adjacent records, once for the
//! packet) and tests both boxes for every active ray, each against its own interval up
//! to its best hit so far; the packet enters the child nearest to any of its rays with
//! the rays that hit it and pushes the other with its rays and their nearest entry. A
//! popped entry keeps the rays whose best hit is not nearer than that entry (the packet's
//! nearest entry is no farther than each ray's own, so no ray loses a box it needs).

use glam::Vec3A;

use crate::hit::Hit;
use crate::image::{BvhNode, BvhView, SceneView, MAX_TREE_DEPTH};
use crate::packet::LanesOf;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::walk::Leaf;

use super::interface::{existing, lane_end, PacketEvent, PacketStep};

/// The registers of a packet in the binary BVH.
#[derive(Clone, Debug)]
pub struct BvhPacketTraversal<const N: usize> {
    boxes: [Option<RayBox>; N],
    t_min: [f32; N],
    t_max: [f32; N],
    /// The node the packet stands on (its record is held, not re-read).
    node: Option<BvhNode>,
    /// A node to read at the next step: the root at the start, then popped nodes.
    pending: Option<u32>,
    mask: u64,
    stack: heapless::Vec<(u32, f32, u64), { MAX_TREE_DEPTH as usize }>,
    started: bool,
    done: bool,
    best: [Option<Hit>; N],
}

impl<const N: usize> BvhPacketTraversal<N> {
    /// Starts the valid rays of `active` at the root.
    pub fn new(rays: &[Ray], active: u64) -> BvhPacketTraversal<N> {
        let mut t = BvhPacketTraversal {
            boxes: [None; N],
            t_min: [0.0; N],
            t_max: [0.0; N],
            node: None,
            pending: Some(0),
            mask: 0,
            stack: heapless::Vec::new(),
            started: false,
            done: false,
            best: [None; N],
        };
        for i in LanesOf::<N>(existing(active, rays.len(), N)) {
            let Some(ray) = rays.get(i) else { continue };
            if ray.is_valid() {
                t.mask |= 1 << i;
                t.boxes[i] = Some(RayBox::new(ray));
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

    /// One node for the packet: a popped node or the root is read first; an inner node's
    /// children are read and tested, a leaf reported.
    pub fn step<P: MemoryProbe>(&mut self, bvh: &BvhView<'_>, probe: &mut P) -> PacketEvent {
        if self.done {
            return PacketEvent::Done;
        }
        let mut tested = 0;
        if let Some(index) = self.pending.take() {
            let node = bvh.node(index, probe);
            self.node = Some(node);
            if !self.started {
                // The root's own box is tested once; children are tested by their parent.
                self.started = true;
                let (lo, hi) = (Vec3A::from_array(node.min), Vec3A::from_array(node.max));
                tested = self.mask;
                let mut entered = 0;
                for i in LanesOf::<N>(self.mask) {
                    if self.boxes[i].is_some_and(|b| b.entry(lo, hi, self.t_min[i], self.t_max[i]).is_some()) {
                        entered |= 1 << i;
                    }
                }
                self.mask = entered;
                if entered == 0 {
                    self.done = true;
                    return PacketEvent::Node { lanes: tested };
                }
            }
        }
        let Some(node) = self.node else {
            self.done = true;
            return PacketEvent::Done;
        };
        if node.count > 0 {
            let leaf = Leaf::Range { first: node.first, count: node.count };
            return PacketEvent::Leaf { leaf, lanes: self.mask };
        }
        let (ia, ib) = (node.first, node.first.wrapping_add(1));
        // The children's address comes from the node record.
        probe.dependent();
        let a = bvh.node(ia, probe);
        let b = bvh.node(ib, probe);
        let (alo, ahi) = (Vec3A::from_array(a.min), Vec3A::from_array(a.max));
        let (blo, bhi) = (Vec3A::from_array(b.min), Vec3A::from_array(b.max));
        let (mut ma, mut mb) = (0u64, 0u64);
        let (mut ta, mut tb) = (f32::INFINITY, f32::INFINITY);
        tested |= self.mask;
        for i in LanesOf::<N>(self.mask) {
            let Some(rb) = self.boxes[i] else { continue };
            // Boxes entered beyond the best hit cannot hold a closer one; equal is kept.
            let end = self.t_end(i);
            if let Some(t) = rb.entry(alo, ahi, self.t_min[i], end) {
                ma |= 1 << i;
                ta = ta.min(t);
            }
            if let Some(t) = rb.entry(blo, bhi, self.t_min[i], end) {
                mb |= 1 << i;
                tb = tb.min(t);
            }
        }
        match (ma != 0, mb != 0) {
            (true, true) => {
                let (near, nm, far, ft, fm) = if ta <= tb { (a, ma, ib, tb, mb) } else { (b, mb, ia, ta, ma) };
                // Cannot be full: `parse` bounds the depth.
                let _ = self.stack.push((far, ft, fm));
                (self.node, self.mask) = (Some(near), nm);
            }
            (true, false) => (self.node, self.mask) = (Some(a), ma),
            (false, true) => (self.node, self.mask) = (Some(b), mb),
            (false, false) => self.pop(),
        }
        PacketEvent::Node { lanes: tested }
    }

    /// After a leaf: on to the next entry some ray may still find a closer hit in.
    pub fn finish_leaf(&mut self) {
        self.pop();
    }

    fn pop(&mut self) {
        while let Some((index, t, m)) = self.stack.pop() {
            let mut still = 0u64;
            for i in LanesOf::<N>(m) {
                if t <= self.t_end(i) {
                    still |= 1 << i;
                }
            }
            if still != 0 {
                (self.pending, self.mask) = (Some(index), still);
                return;
            }
        }
        self.done = true;
    }
}

impl<const N: usize> PacketStep for BvhPacketTraversal<N> {
    #[inline]
    fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, _rays: &[Ray], probe: &mut P) -> PacketEvent {
        match scene.bvh() {
            Some(bvh) => BvhPacketTraversal::step(self, bvh, probe),
            None => PacketEvent::Done,
        }
    }

    fn finish_leaf(&mut self) {
        BvhPacketTraversal::finish_leaf(self)
    }

    fn best(&self, i: usize) -> Option<Hit> {
        self.best.get(i).copied().flatten()
    }

    fn best_mut(&mut self, i: usize) -> Option<&mut Option<Hit>> {
        self.best.get_mut(i)
    }
}
