//! Packets through the uniform grid in lock-step: every active ray keeps its own DDA
//! registers (rays of a packet leave a voxel at different distances, so they cannot share
//! one walk), and each round every active ray takes one traversal step, then the rays
//! whose voxel holds triangles run the intersection kernel — the streaming organisation
//! of Purcell 2002 §3.2 applied to a packet. The active fraction per round is the SIMD
//! efficiency.

use crate::grid::{GridEvent, GridTraversal};
use crate::image::{GridView, SceneView, NULL_INDEX};
use crate::packet::{Lanes, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::triangle::{test_triangle, Intersector};

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
pub fn trace_grid_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    grid: &GridView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
    let mut trav: [GridTraversal; N] = core::array::from_fn(|i| GridTraversal::new(grid, &rays[i]));
    let mut active = 0u64;
    for i in Lanes(packet.active) {
        if !trav[i].missed_bounds() {
            active |= 1 << i;
        }
    }
    let mut c = PacketCounters::default();
    while active != 0 {
        c.visits += 1;
        c.active_lanes += active.count_ones() as u64;
        for i in Lanes(active) {
            match trav[i].step(grid, probe) {
                GridEvent::Done => active &= !(1 << i),
                GridEvent::Empty(voxel) => trav[i].finish_voxel(&voxel),
                GridEvent::Cell { voxel, list } => {
                    let mut pos = list;
                    loop {
                        let prim = grid.list_entry(pos, probe);
                        if prim == NULL_INDEX {
                            break;
                        }
                        c.tri_tests += 1;
                        let verts = I::fetch(scene, prim, probe);
                        test_triangle::<I>(&preps[i], &rays[i], &verts, prim, &mut trav[i].best);
                        pos = pos.wrapping_add(1);
                    }
                    trav[i].finish_voxel(&voxel);
                }
            }
        }
    }
    for i in 0..N {
        hits[i] = if packet.active & (1 << i) != 0 { trav[i].best } else { None };
    }
    counters.add(&c);
}
