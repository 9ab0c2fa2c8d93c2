//! Packets through the uniform grid in lock-step ([`crate::packet::lockstep`]): every ray keeps
//! its own DDA registers, and a packet round is one voxel step of each active ray.

use crate::hit::Hit;
use crate::image::{GridView, SceneView, NULL_INDEX};
use crate::intersect::triangle::Intersector;
use crate::packet::lockstep::{trace_lock_step, RayWalk};
use crate::packet::{PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::grid::{GridEvent, GridTraversal};

/// A ray's walk through the grid.
struct GridWalk<'g> {
    grid: &'g GridView<'g>,
    trav: GridTraversal,
}

impl RayWalk for GridWalk<'_> {
    #[inline]
    fn advance<P: MemoryProbe>(
        &mut self,
        _ray: &Ray,
        probe: &mut P,
        test: &mut impl FnMut(&mut Self, u32, &mut P),
    ) -> bool {
        match self.trav.step(self.grid, probe) {
            GridEvent::Done => false,
            GridEvent::Empty(voxel) => {
                self.trav.finish_voxel(&voxel);
                true
            }
            GridEvent::Cell { voxel, list } => {
                let mut pos = list;
                loop {
                    let prim = self.grid.list_entry(pos, probe);
                    if prim == NULL_INDEX {
                        break;
                    }
                    test(self, prim, probe);
                    pos = pos.wrapping_add(1);
                }
                self.trav.finish_voxel(&voxel);
                true
            }
        }
    }

    fn best_mut(&mut self) -> &mut Option<Hit> {
        &mut self.trav.best
    }
}

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit. Rays
/// that miss the grid's box take no part.
pub fn trace_grid_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    grid: &GridView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    trace_lock_step::<GridWalk<'_>, I, P, N>(scene, packet, hits, probe, counters, |ray| {
        let trav = GridTraversal::new(grid, ray);
        (!trav.missed_bounds()).then_some(GridWalk { grid, trav })
    });
}
