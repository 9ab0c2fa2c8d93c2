//! Packet traversal of the binary BVH (Wald, Boulos & Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies"): the packet enters a
//! child with the mask of its rays that hit the child's box, nearer child first.

use glam::Vec3A;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{BvhView, SceneView, MAX_TREE_DEPTH};
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::packet::{ray_by_ray, LanesOf, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::bvh::trace_bvh;

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_bvh_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &BvhView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    if !<I::Nodes as NodeTests>::FLOAT {
        let walk = |r: &Ray, c: &mut RayCounters| trace_bvh::<I, P>(scene, bvh, r, probe, c);
        return ray_by_ray(packet, hits, counters, walk);
    }
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    let boxes: [RayBox; N] = core::array::from_fn(|i| RayBox::new(&rays[i]));
    let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
    *hits = [None; N];
    let best_t = |hits: &PacketHits<N>, i: usize| hits[i].map_or(rays[i].t_max, |h: Hit| h.t);
    let mut stack: heapless::Vec<(u32, f32, u64), { MAX_TREE_DEPTH as usize }> = heapless::Vec::new();
    let mut c = PacketCounters::default();
    // The root box first.
    let root = bvh.node(0, probe);
    let mut mask = 0u64;
    for i in LanesOf::<N>(packet.live()) {
        let hit =
            boxes[i].entry(Vec3A::from_array(root.min), Vec3A::from_array(root.max), rays[i].t_min, rays[i].t_max);
        if hit.is_some() {
            mask |= 1 << i;
        }
    }
    let mut node = root;
    if mask != 0 {
        loop {
            c.visits += 1;
            c.active_lanes += mask.count_ones() as u64;
            let mut descended = false;
            if node.count > 0 {
                for e in node.first..node.first.wrapping_add(node.count) {
                    let prim = bvh.prim(e, probe);
                    let verts = I::fetch(scene, prim, probe);
                    for i in LanesOf::<N>(mask) {
                        test_triangle::<I>(&preps[i], &rays[i], &verts, prim, &mut hits[i]);
                    }
                }
                c.tri_tests += node.count as u64 * mask.count_ones() as u64;
            } else {
                let (ia, ib) = (node.first, node.first.wrapping_add(1));
                let a = bvh.node(ia, probe);
                let b = bvh.node(ib, probe);
                let (alo, ahi) = (Vec3A::from_array(a.min), Vec3A::from_array(a.max));
                let (blo, bhi) = (Vec3A::from_array(b.min), Vec3A::from_array(b.max));
                let (mut ma, mut mb) = (0u64, 0u64);
                let (mut ta, mut tb) = (f32::INFINITY, f32::INFINITY);
                for i in LanesOf::<N>(mask) {
                    let end = best_t(hits, i);
                    if let Some(t) = boxes[i].entry(alo, ahi, rays[i].t_min, end) {
                        ma |= 1 << i;
                        ta = ta.min(t);
                    }
                    if let Some(t) = boxes[i].entry(blo, bhi, rays[i].t_min, end) {
                        mb |= 1 << i;
                        tb = tb.min(t);
                    }
                }
                match (ma != 0, mb != 0) {
                    (true, true) => {
                        let (near, nm, far, ft, fm) = if ta <= tb { (a, ma, ib, tb, mb) } else { (b, mb, ia, ta, ma) };
                        let _ = stack.push((far, ft, fm));
                        node = near;
                        mask = nm;
                        descended = true;
                    }
                    (true, false) => {
                        node = a;
                        mask = ma;
                        descended = true;
                    }
                    (false, true) => {
                        node = b;
                        mask = mb;
                        descended = true;
                    }
                    (false, false) => {}
                }
            }
            if descended {
                continue;
            }
            let mut next = None;
            while let Some((index, t, m)) = stack.pop() {
                let mut still = 0u64;
                for i in LanesOf::<N>(m) {
                    if t <= best_t(hits, i) {
                        still |= 1 << i;
                    }
                }
                if still != 0 {
                    next = Some((index, still));
                    break;
                }
            }
            let Some((index, m)) = next else { break };
            node = bvh.node(index, probe);
            mask = m;
        }
    }
    counters.add(&c);
}
