//! Packet traversal of the 4-wide BVH: the packet visits a node if any of its rays hits
//! one of the node's boxes; each child is entered with the mask of the rays that hit it
//! (nearest child first by the smallest entry distance of those rays), and a leaf
//! intersects its triangles with exactly the rays in its mask.

use crate::bvh4::slab4;
use crate::hit::Hit;
use crate::image::{Bvh4View, SceneView, MAX_TREE_DEPTH};
use crate::packet::{Lanes, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray_box::RayBox;
use crate::triangle::{test_triangle, Intersector};

const STACK: usize = 3 * MAX_TREE_DEPTH as usize + 4;

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_bvh4_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    let boxes: [RayBox; N] = core::array::from_fn(|i| RayBox::new(&rays[i]));
    let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
    *hits = [None; N];
    let best_t = |hits: &PacketHits<N>, i: usize| hits[i].map_or(rays[i].t_max, |h: Hit| h.t);
    // (child or first entry, leaf count or 0, smallest entry distance, ray mask)
    let mut stack = [(0u32, 0u32, 0f32, 0u64); STACK];
    let mut sp = 0usize;
    let mut current = (0u32, 0u32, packet.active);
    let mut c = PacketCounters::default();
    loop {
        let (index, count, mask) = current;
        c.visits += 1;
        c.active_lanes += mask.count_ones() as u64;
        if count == 0 {
            let node = bvh.node(index, probe);
            let mut child_mask = [0u64; 4];
            let mut child_t = [f32::INFINITY; 4];
            for i in Lanes(mask) {
                let (tn, hit) = slab4(&boxes[i], node, rays[i].t_min, best_t(hits, i));
                let m = hit.bitmask();
                if m == 0 {
                    continue;
                }
                let t = tn.to_array();
                for k in 0..4 {
                    if m & (1 << k) != 0 {
                        child_mask[k] |= 1 << i;
                        child_t[k] = child_t[k].min(t[k]);
                    }
                }
            }
            // Order the children that any ray needs, nearest first.
            let mut order = [0usize; 4];
            let mut n = 0;
            for k in 0..4 {
                if child_mask[k] != 0 {
                    let mut j = n;
                    while j > 0 && child_t[order[j - 1]] > child_t[k] {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = k;
                    n += 1;
                }
            }
            if n > 0 {
                for &k in order[1..n].iter().rev() {
                    if let Some(slot) = stack.get_mut(sp) {
                        *slot = (node.child[k], node.count[k], child_t[k], child_mask[k]);
                        sp += 1;
                    }
                }
                let k = order[0];
                current = (node.child[k], node.count[k], child_mask[k]);
                continue;
            }
        } else {
            for e in index..index.wrapping_add(count) {
                let prim = bvh.prim(e, probe);
                let verts = scene.triangle(prim, probe);
                for i in Lanes(mask) {
                    test_triangle::<I>(&preps[i], &rays[i], &verts, prim, &mut hits[i]);
                }
            }
            c.tri_tests += count as u64 * mask.count_ones() as u64;
        }
        // Pop the next entry, dropping the rays whose hit is already nearer than it.
        loop {
            if sp == 0 {
                counters.add(&c);
                return;
            }
            sp -= 1;
            let (child, count, t, mask) = stack[sp];
            let mut still = 0u64;
            for i in Lanes(mask) {
                if t <= best_t(hits, i) {
                    still |= 1 << i;
                }
            }
            if still != 0 {
                current = (child, count, still);
                break;
            }
        }
    }
}
