//! Picks the structure kernel the scene image holds (grid, BVH, kd-tree, or brute force
//! without one) and the intersection kernel the user asked for.

use std::borrow::Borrow;

use crate::platform::isa::with_avx2;

use raypipe_core::packet::bvh::trace_bvh_packet;
use raypipe_core::packet::bvh4::{occluded_bvh4_packet_cached, trace_bvh4_packet};
use raypipe_core::packet::bvh8::trace_bvh8_packet;
use raypipe_core::packet::grid::trace_grid_packet;
use raypipe_core::packet::kdtree::trace_kdtree_packet;
use raypipe_core::packet::{PacketCounters, PacketHits, RayPacket};
use raypipe_core::traverse::bvh::trace_bvh;
use raypipe_core::traverse::grid::trace_grid;
use raypipe_core::traverse::kdtree::trace_kdtree;
use raypipe_core::traverse::occlusion::occluded as occluded_by_walk;
use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;
use raypipe_core::traverse::wide_bvh::node4::{occluded_bvh4_cached4, trace_bvh4};
use raypipe_core::traverse::wide_bvh::node8::{occluded_bvh8_cached4, trace_bvh8};
use raypipe_core::{
    traverse::brute_force::trace_brute_force, Hit, Intersector, MemoryProbe, Ray, RayCounters, SceneView,
};

/// Which ray–triangle test to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum IntersectorKind {
    /// Woop, Benthin & Wald 2013 (default).
    #[default]
    Watertight,
    /// Möller & Trumbore 1997, for comparison.
    MollerTrumbore,
    /// Wald's projection test on 48-byte precomputed triangles (Wald 2004).
    Wald,
}

impl IntersectorKind {
    /// The test the user asked for, or by default the one the image's triangle layout
    /// is for (Wald's if it stores Wald triangles, watertight otherwise).
    pub fn resolve(choice: Option<IntersectorKind>, scene: &SceneView<'_>) -> IntersectorKind {
        choice.unwrap_or(if scene.has_wald_triangles() { IntersectorKind::Wald } else { IntersectorKind::Watertight })
    }

    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            IntersectorKind::Watertight => "watertight",
            IntersectorKind::MollerTrumbore => "moller-trumbore",
            IntersectorKind::Wald => "wald",
        }
    }
}

/// Traces one ray with the scene's structure.
#[inline(always)]
pub fn trace<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    if scene.level(0).is_some() {
        // A hierarchical grid (an animated mesh under Reinhard's update): its levels'
        // walk, one step kernel for all of them.
        raypipe_core::traverse::walk::trace_walk::<I, P>(scene, ray, probe)
    } else if let Some(grid) = scene.grid() {
        trace_grid::<I, P>(scene, grid, ray, probe, counters)
    } else if let Some(bvh) = scene.bvh4() {
        trace_bvh4::<I, P>(scene, bvh, ray, probe, counters)
    } else if let Some(bvh) = scene.bvh8() {
        trace_bvh8::<I, P>(scene, bvh, ray, probe, counters)
    } else if let Some(bvh) = scene.bvh() {
        trace_bvh::<I, P>(scene, bvh, ray, probe, counters)
    } else if let Some(kd) = scene.kdtree() {
        trace_kdtree::<I, P>(scene, kd, ray, probe, counters)
    } else {
        trace_brute_force::<I, P>(scene, ray, probe, counters)
    }
}

/// `for $i in 0..$n { $body }` in one function compiled for AVX2 where the CPU has it
/// ([`with_avx2`]), with the body inlined there.
macro_rules! avx2_loop {
    ($n:expr, $i:ident => $body:expr) => {
        with_avx2(
            #[inline(always)]
            || {
                for $i in 0..$n {
                    $body
                }
            },
        )
    };
}

/// Traces the rays `ray(i)` for `i` in `0..n` (`None`: no ray, hence no hit) and hands
/// each ray and its closest hit to `hit(i, …)`, choosing the structure's kernel once for
/// the whole run rather than per ray, with the CPU's widest SIMD instructions
/// ([`with_avx2`]). Besides the dispatch saved, each wide BVH gets its
/// own loop, in which the kernel's result goes straight to `hit`: behind the per-ray
/// dispatch, the hit record was put together in a stack slot by stores of mixed widths
/// and read back by a wider load, which the CPU could not forward (11% of the time of
/// the bunny's single rays, most of it rays that miss).
#[inline(always)]
pub fn trace_each<I: Intersector, P: MemoryProbe, R: Borrow<Ray>>(
    scene: &SceneView<'_>,
    n: usize,
    mut ray: impl FnMut(usize) -> Option<R>,
    probe: &mut P,
    counters: &mut RayCounters,
    mut hit: impl FnMut(usize, Option<R>, Option<Hit>),
) {
    // `R` is `&Ray` where the rays are in memory already: a copy of the 32-byte record,
    // stored as overlapping 16-byte halves and read back, stalled the next ray's start.
    // Each structure's loop is compiled on its own (its own `with_avx2` function), so
    // that a change to one walk does not reshuffle the registers of another.
    macro_rules! each_ray {
        ($kernel:expr) => {
            avx2_loop!(n, i => match ray(i) {
                Some(r) => {
                    let h = $kernel(r.borrow());
                    hit(i, Some(r), h)
                }
                None => hit(i, None, None),
            })
        };
    }
    if let Some(bvh) = scene.bvh8() {
        each_ray!(|r: &Ray| trace_bvh8::<I, P>(scene, bvh, r, probe, counters))
    } else if let Some(bvh) = scene.bvh4() {
        each_ray!(|r: &Ray| trace_bvh4::<I, P>(scene, bvh, r, probe, counters))
    } else {
        each_ray!(|r: &Ray| trace::<I, P>(scene, r, probe, counters))
    }
}

/// The any-hit query of rays `0 .. n` (`ray(i)`, `None` for a row that is no ray), each
/// answer to `blocked(i, answer)`: core's [`occluded_by_walk`], with the wide BVHs'
/// walks chosen once for the run, in one loop compiled for AVX2 where the CPU has it.
#[inline(always)]
pub fn occluded_each<'r, I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    n: usize,
    mut ray: impl FnMut(usize) -> Option<&'r Ray>,
    probe: &mut P,
    counters: &mut RayCounters,
    mut blocked: impl FnMut(usize, bool),
) {
    // As in `trace_each`: each wide BVH's walk in its own loop, inlined into the AVX2
    // function (core's `occluded` is a call away, compiled without AVX2: 1.08-1.11x
    // slower on the conference room's and Sponza's shadow rays, paired runs).
    macro_rules! each_ray {
        ($kernel:expr) => {
            avx2_loop!(n, i => {
                let b = ray(i).is_some_and(|r| $kernel(r));
                blocked(i, b)
            })
        };
    }
    // One shadow cache for the run of rays: consecutive rays are neighbours (a block of
    // pixels' shadow rays), mostly blocked in one leaf.
    let mut cache = LastOccluder::default();
    // The wide BVHs take the rays four at a time: the cached leaf is tested by the four
    // at once.
    macro_rules! each_four {
        ($kernel:expr) => {
            avx2_loop!(n.div_ceil(4), g => {
                let rays: [Option<&Ray>; 4] = core::array::from_fn(|k| {
                    let i = 4 * g + k;
                    if i < n { ray(i) } else { None }
                });
                let b = $kernel(rays);
                for k in 0..4usize.min(n - 4 * g) {
                    blocked(4 * g + k, b & (1 << k) != 0);
                }
            })
        };
    }
    if let Some(bvh) = scene.bvh8() {
        each_four!(|r| occluded_bvh8_cached4::<I, P>(scene, bvh, r, &mut cache, probe, counters))
    } else if let Some(bvh) = scene.bvh4() {
        each_four!(|r| occluded_bvh4_cached4::<I, P>(scene, bvh, r, &mut cache, probe, counters))
    } else {
        each_ray!(|r: &Ray| occluded_by_walk::<I, P>(scene, r, probe, counters))
    }
}

/// Calls `$body` with `$I` bound to the intersector type chosen by `$kind`.
#[macro_export]
macro_rules! with_intersector {
    ($kind:expr, $I:ident => $body:expr) => {
        match $kind {
            $crate::render::tracer::IntersectorKind::Watertight => {
                type $I = raypipe_core::Watertight;
                $body
            }
            $crate::render::tracer::IntersectorKind::MollerTrumbore => {
                type $I = raypipe_core::MollerTrumbore;
                $body
            }
            $crate::render::tracer::IntersectorKind::Wald => {
                type $I = raypipe_core::WaldProjection;
                $body
            }
        }
    };
}

/// Calls `$body` with `$I` bound to the fixed-point triangle test of `$datapath`
/// (a `raypipe_hw::Datapath`), or evaluates `$f32` for the `f32` datapath.
#[macro_export]
macro_rules! with_datapath {
    ($datapath:expr, $I:ident => $body:expr, f32 => $f32:expr) => {
        match $datapath {
            raypipe_hw::Datapath::F32 => $f32,
            raypipe_hw::Datapath::Q16_16 => {
                type $I = raypipe_core::FixedWatertight<32, 16>;
                $body
            }
            raypipe_hw::Datapath::Q20_12 => {
                type $I = raypipe_core::FixedWatertight<32, 12>;
                $body
            }
            raypipe_hw::Datapath::Q12_20 => {
                type $I = raypipe_core::FixedWatertight<32, 20>;
                $body
            }
            raypipe_hw::Datapath::Q24_8 => {
                type $I = raypipe_core::FixedWatertight<32, 8>;
                $body
            }
            raypipe_hw::Datapath::Q12_12 => {
                type $I = raypipe_core::FixedWatertight<24, 12>;
                $body
            }
            raypipe_hw::Datapath::Q8_16 => {
                type $I = raypipe_core::FixedWatertight<24, 16>;
                $body
            }
            raypipe_hw::Datapath::Q16_8 => {
                type $I = raypipe_core::FixedWatertight<24, 8>;
                $body
            }
        }
    };
}

/// Why the fixed-point datapath cannot run on this scene: it needs a BVH (binary, 4- or
/// 8-wide) or none, whose box tests it has; the grid's and kd-tree's steps are `f32`
/// and would drop hits the fixed-point test finds half a unit across a cell boundary.
pub fn fixed_point_unsupported(scene: &SceneView<'_>) -> Option<&'static str> {
    if scene.grid().is_some() {
        Some("the scene has a grid")
    } else if scene.kdtree().is_some() {
        Some("the scene has a kd-tree")
    } else {
        None
    }
}

/// Whether the scene's structure has a packet kernel; packets of the others (no
/// structure) are traced ray by ray.
pub fn has_packet_kernel(scene: &SceneView<'_>) -> bool {
    scene.grid().is_some()
        || scene.bvh4().is_some()
        || scene.bvh8().is_some()
        || scene.bvh().is_some()
        || scene.kdtree().is_some()
}

/// The any-hit query for a packet (bit `i` set: ray `i` is blocked): the 4-wide BVH's
/// packet walk, which drops each ray at its first hit, after the leaf of the shadow
/// cache `cache` (keep one across a run of neighbouring packets); the other structures
/// ask ray by ray (their packet walks order leaves for the closest hit, which a shadow
/// ray does not need).
#[inline]
pub fn occluded_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    packet: &RayPacket<N>,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut PacketCounters,
) -> u64 {
    if let Some(bvh) = scene.bvh4() {
        return occluded_bvh4_packet_cached::<I, P, N>(scene, bvh, packet, cache, probe, counters);
    }
    let any = |r: &Ray, c: &mut RayCounters| occluded_by_walk::<I, P>(scene, r, probe, c);
    raypipe_core::packet::occluded_ray_by_ray(packet, counters, any)
}

/// Traces a packet with the scene's structure, in lock-step.
#[inline]
pub fn trace_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    if let Some(grid) = scene.grid() {
        trace_grid_packet::<I, P, N>(scene, grid, packet, hits, probe, counters)
    } else if let Some(bvh) = scene.bvh4() {
        trace_bvh4_packet::<I, P, N>(scene, bvh, packet, hits, probe, counters)
    } else if let Some(bvh) = scene.bvh8() {
        trace_bvh8_packet::<I, P, N>(scene, bvh, packet, hits, probe, counters)
    } else if let Some(bvh) = scene.bvh() {
        trace_bvh_packet::<I, P, N>(scene, bvh, packet, hits, probe, counters)
    } else if let Some(kd) = scene.kdtree() {
        trace_kdtree_packet::<I, P, N>(scene, kd, packet, hits, probe, counters)
    } else {
        // No packet kernel (no structure, or a hierarchical grid): each ray by itself.
        raypipe_core::packet::ray_by_ray(packet, hits, counters, |r, c| trace::<I, P>(scene, r, probe, c));
    }
}
