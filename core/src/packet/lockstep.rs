//! The lock-step packet driver shared by the structures whose rays cannot share one walk
//! (the grid, whose rays leave a voxel at different distances, and the kd-tree, whose
//! rays cross a plane at different distances): each ray keeps its own traversal
//! registers, and each round every active ray takes one step, intersecting a leaf it
//! reaches in the same round — the streaming organisation of Purcell 2002 §3.2 applied
//! to a packet. Rays of a coherent packet walk the same nodes in the same rounds, so node
//! reads are shared in a cache (Wald & Slusallek 2001 §4); the active fraction per round
//! is the SIMD efficiency.

use crate::hit::Hit;
use crate::image::SceneView;
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::packet::{LanesOf, PacketCounters, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// One ray's walk through a structure, one node per [`RayWalk::advance`].
pub trait RayWalk {
    /// Takes one step. At a leaf, calls `test(prim, probe)` for each of its triangles
    /// (which updates the walk's best hit through [`RayWalk::best_mut`]). Returns false
    /// once the walk is over.
    fn advance<P: MemoryProbe>(
        &mut self,
        ray: &Ray,
        probe: &mut P,
        test: &mut impl FnMut(&mut Self, u32, &mut P),
    ) -> bool;

    /// The closest hit so far.
    fn best_mut(&mut self) -> &mut Option<Hit>;
}

/// Traces all active rays of `packet` in lock-step; `start` begins a ray's walk (`None`
/// when it cannot enter the structure at all) and `hits[i]` receives ray `i`'s closest hit.
pub fn trace_lock_step<W: RayWalk, I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
    start: impl Fn(&Ray) -> Option<W>,
) {
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    let preps: [I::Prepared; N] = core::array::from_fn(|i| I::prepare(&rays[i]));
    let mut walks: [Option<W>; N] = core::array::from_fn(|i| start(&rays[i]));
    let mut active = 0u64;
    for i in LanesOf::<N>(packet.live()) {
        if walks[i].is_some() {
            active |= 1 << i;
        }
    }
    let mut c = PacketCounters::default();
    while active != 0 {
        c.visits += 1;
        c.active_lanes += active.count_ones() as u64;
        for i in LanesOf::<N>(active) {
            let Some(walk) = walks[i].as_mut() else { continue };
            let (prep, ray) = (&preps[i], &rays[i]);
            let mut test = |w: &mut W, prim: u32, probe: &mut P| {
                let tri = I::fetch(scene, prim, probe);
                test_triangle::<I>(prep, ray, &tri, prim, w.best_mut());
                c.tri_tests += 1;
            };
            if !walk.advance(ray, probe, &mut test) {
                active &= !(1 << i);
            }
        }
    }
    for (i, hit) in hits.iter_mut().enumerate() {
        *hit = match walks[i].as_mut() {
            Some(w) if packet.live() & (1 << i) != 0 => *w.best_mut(),
            _ => None,
        };
    }
    counters.add(&c);
}
