//! The kd-tree walked by a whole packet (Wald & Slusallek 2001 §4–5; SaarCOR's traversal
//! unit, Schmittler et al. 2002): one node per step for the packet, one shared stack
//! whose entries hold the node, the mask of rays that need it and each such ray's
//! interval. At an inner node every active ray decides as its single-ray walk would
//! ([`crate::traverse::kdtree`]: the same split distance, the same comparisons): near
//! child, far child or both; the packet goes to the child most of the rays that need both
//! visit first and pushes the other. A ray whose order the packet reverses meets its
//! leaves out of order; its hit stays the same because a popped entry keeps only the
//! rays whose hit so far is not nearer than the entry's interval (the single-ray walk's
//! own termination test, applied per ray when it pops).

use crate::hit::Hit;
use crate::image::{KdNode, KdTreeView, SceneView, MAX_TREE_DEPTH};
use crate::packet::LanesOf;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::clip::clip_ray;
use crate::traverse::walk::Leaf;

use super::interface::{existing, PacketEvent, PacketStep};

/// A shared-stack entry: a node, the rays that need it, and their intervals in it.
#[derive(Clone, Copy, Debug)]
struct Entry<const N: usize> {
    node: u32,
    mask: u64,
    t_min: [f32; N],
    t_max: [f32; N],
}

/// The registers of a packet in the kd-tree.
#[derive(Clone, Debug)]
pub struct KdPacketTraversal<const N: usize> {
    index: u32,
    mask: u64,
    t_min: [f32; N],
    t_max: [f32; N],
    stack: heapless::Vec<Entry<N>, { MAX_TREE_DEPTH as usize }>,
    done: bool,
    best: [Option<Hit>; N],
}

impl<const N: usize> KdPacketTraversal<N> {
    /// Starts the valid rays of `active` at the root, each clipped to the tree's box.
    pub fn new(kd: &KdTreeView<'_>, rays: &[Ray], active: u64) -> KdPacketTraversal<N> {
        let mut t = KdPacketTraversal {
            index: 0,
            mask: 0,
            t_min: [0.0; N],
            t_max: [0.0; N],
            stack: heapless::Vec::new(),
            done: false,
            best: [None; N],
        };
        for i in LanesOf::<N>(existing(active, rays.len(), N)) {
            let Some(ray) = rays.get(i) else { continue };
            if let Some((t0, t1)) = if ray.is_valid() { clip_ray(ray, kd.min, kd.max) } else { None } {
                t.mask |= 1 << i;
                (t.t_min[i], t.t_max[i]) = (t0, t1);
            }
        }
        t.done = t.mask == 0;
        t
    }

    /// Reads one node for the packet: an inner node sends each ray to its children (the
    /// packet to one of them, the other pushed), a leaf is reported.
    pub fn step<P: MemoryProbe>(&mut self, kd: &KdTreeView<'_>, rays: &[Ray], probe: &mut P) -> PacketEvent {
        if self.done {
            return PacketEvent::Done;
        }
        let node = kd.node(self.index, probe);
        let axis = node.axis();
        if axis == KdNode::LEAF {
            let leaf = Leaf::Range { first: node.index(), count: node.value };
            return PacketEvent::Leaf { leaf, lanes: self.mask };
        }
        let a = axis as usize;
        let (split, c) = (node.split(), node.index());
        // Per child (0: below the plane, node c; 1: above, c + 1): the rays that need it
        // and their intervals in it.
        let mut need = [0u64; 2];
        let mut t0 = [[0.0f32; N]; 2];
        let mut t1 = [[0.0f32; N]; 2];
        // Rays that need both children, by which one they visit first.
        let mut first_votes = [0u32; 2];
        let tested = self.mask;
        for i in LanesOf::<N>(self.mask) {
            let Some(ray) = rays.get(i) else { continue };
            let (o, d) = (ray.origin[a], ray.dir[a]);
            let (lo, hi) = (self.t_min[i], self.t_max[i]);
            // The single-ray kernel's decisions (`KdTraversal::step`), bit for bit.
            let below_first = o < split || (o == split && d <= 0.0);
            let (first, second) = if below_first { (0, 1) } else { (1, 0) };
            let mut go = |k: usize, a: f32, b: f32| {
                need[k] |= 1 << i;
                (t0[k][i], t1[k][i]) = (a, b);
            };
            if d == 0.0 {
                go(first, lo, hi);
                continue;
            }
            let t_split = (split - o) / d;
            if t_split > hi || t_split <= 0.0 {
                go(first, lo, hi);
            } else if t_split < lo {
                go(second, lo, hi);
            } else {
                go(first, lo, t_split);
                go(second, t_split, hi);
                first_votes[first] += 1;
            }
        }
        let go_to = match (need[0] != 0, need[1] != 0) {
            (true, true) => usize::from(first_votes[1] > first_votes[0]),
            (false, true) => 1,
            _ => 0,
        };
        let other = 1 - go_to;
        if need[other] != 0 {
            // Cannot be full: `parse` bounds the depth, and one entry waits per level.
            let _ = self.stack.push(Entry {
                node: c.wrapping_add(other as u32),
                mask: need[other],
                t_min: t0[other],
                t_max: t1[other],
            });
        }
        self.index = c.wrapping_add(go_to as u32);
        self.mask = need[go_to];
        for i in LanesOf::<N>(self.mask) {
            (self.t_min[i], self.t_max[i]) = (t0[go_to][i], t1[go_to][i]);
        }
        PacketEvent::Node { lanes: tested }
    }

    /// After a leaf: on to the next pushed node with the rays that may still find a
    /// nearer hit there (a hit nearer than a ray's interval in it is final for that ray).
    pub fn finish_leaf(&mut self) {
        while let Some(e) = self.stack.pop() {
            let mut still = 0u64;
            for i in LanesOf::<N>(e.mask) {
                if !self.best.get(i).copied().flatten().is_some_and(|h| h.t < e.t_min[i]) {
                    still |= 1 << i;
                }
            }
            if still != 0 {
                self.index = e.node;
                self.mask = still;
                for i in LanesOf::<N>(still) {
                    (self.t_min[i], self.t_max[i]) = (e.t_min[i], e.t_max[i]);
                }
                return;
            }
        }
        self.done = true;
    }
}

impl<const N: usize> PacketStep for KdPacketTraversal<N> {
    #[inline]
    fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, rays: &[Ray], probe: &mut P) -> PacketEvent {
        match scene.kdtree() {
            Some(kd) => KdPacketTraversal::step(self, kd, rays, probe),
            None => PacketEvent::Done,
        }
    }

    fn finish_leaf(&mut self) {
        KdPacketTraversal::finish_leaf(self)
    }

    fn best(&self, i: usize) -> Option<Hit> {
        self.best.get(i).copied().flatten()
    }

    fn best_mut(&mut self, i: usize) -> Option<&mut Option<Hit>> {
        self.best.get_mut(i)
    }
}
