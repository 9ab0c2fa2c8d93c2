//! 4-wide BVH node test: one node holds the boxes of four children, tested together by a
//! 4-lane slab test (SSE on x86-64 through glam's `Vec4`; Wald, Benthin & Boulos 2008;
//! Embree's BVH4). The walk itself — nearest child first, the others on a fixed-capacity
//! stack — is the wide BVH's ([`crate::traverse::wide_bvh`]); the packet kernel is
//! [`crate::packet::bvh4`].

use glam::{BVec4A, Vec4};

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView};
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::wide_bvh::last_occluder::LastOccluder;
pub use crate::traverse::wide_bvh::NodeRay;
use crate::traverse::wide_bvh::{
    occluded_wide_bvh, occluded_wide_bvh_cached, occluded_wide_bvh_cached4, stack_capacity, trace_wide_bvh,
    WideBvhTraversal, WideSlab,
};

/// Entry distances of the ray into the four child boxes of `n`, within `[t0, t1]`, and
/// the bit mask of those it hits (empty slots, whose boxes are inverted, never).
#[inline(always)]
pub fn slab4(r: &NodeRay, n: &Bvh4Node, t0: f32, t1: f32) -> (Vec4, u32) {
    if r.rb.zero_axes != 0 {
        return slab4_exact(&r.rb, n, t0, t1);
    }
    // The node's planes as rows: min x, y, z, then max x, y, z (then children, counts).
    let rows: &[[f32; 4]; 8] = bytemuck::cast_ref(n);
    // Origin and reciprocal direction splatted per axis (loop-invariant in a walk).
    let (o, inv) = (r.rb.origin.to_array().map(Vec4::splat), r.rb.inv.to_array().map(Vec4::splat));
    let inv_far = r.rb.inv_far.to_array().map(Vec4::splat);
    let near = |a: usize| (Vec4::from_array(rows[r.rows.near[a] as usize & 7]) - o[a]) * inv[a];
    let far = |a: usize| (Vec4::from_array(rows[r.rows.far[a] as usize & 7]) - o[a]) * inv_far[a];
    // The product is monotone in the plane, so these are the min and max of the two
    // planes' distances for a valid box; an inverted (empty) slot gets near > far on
    // every axis and fails the comparison.
    let tn = near(0).max(near(1)).max(near(2).max(Vec4::splat(t0)));
    let tf = far(0).min(far(1)).min(far(2).min(Vec4::splat(t1)));
    (tn, tn.cmple(tf).bitmask())
}

/// [`slab4`] for any ray, including one with a zero direction component (whose axis is
/// tested as "origin inside the slab", see [`RayBox`]).
#[inline(always)]
pub fn slab4_exact(rb: &RayBox, n: &Bvh4Node, t0: f32, t1: f32) -> (Vec4, u32) {
    let (o, inv, inv_far) = (rb.origin, rb.inv, rb.inv_far);
    // Per axis, the two planes' distances with the plain and with the far reciprocal.
    let planes = |lo: [f32; 4], hi: [f32; 4], o: f32, inv: f32, inv_far: f32| {
        let (dl, dh) = (Vec4::from_array(lo) - o, Vec4::from_array(hi) - o);
        ((dl * inv).min(dh * inv), (dl * inv_far).max(dh * inv_far))
    };
    // For a valid box the near plane's distance is the smaller; an empty slot's inverted
    // box becomes an interval too, so empty slots are masked by the sign test below.
    let (mut nx, mut fx) = planes(n.min_x, n.max_x, o.x, inv.x, inv_far.x);
    let (mut ny, mut fy) = planes(n.min_y, n.max_y, o.y, inv.y, inv_far.y);
    let (mut nz, mut fz) = planes(n.min_z, n.max_z, o.z, inv.z, inv_far.z);
    let mut inside = BVec4A::splat(true);
    if rb.zero_axes != 0 {
        // A direction component of zero: inside the slab or never (see `RayBox`).
        let axes = [
            (0, &mut nx, &mut fx, n.min_x, n.max_x, o.x),
            (1, &mut ny, &mut fy, n.min_y, n.max_y, o.y),
            (2, &mut nz, &mut fz, n.min_z, n.max_z, o.z),
        ];
        for (k, near, far, lo, hi, ok) in axes {
            if rb.zero_axes & (1 << k) != 0 {
                let o4 = Vec4::splat(ok);
                inside &= o4.cmpge(Vec4::from_array(lo)) & o4.cmple(Vec4::from_array(hi));
                *near = Vec4::NEG_INFINITY;
                *far = Vec4::INFINITY;
            }
        }
    }
    let tn = nx.max(ny).max(nz.max(Vec4::splat(t0)));
    let tf = fx.min(fy).min(fz.min(Vec4::splat(t1)));
    // Inverted (empty) slots: min > max on x.
    let real = Vec4::from_array(n.min_x).cmple(Vec4::from_array(n.max_x));
    (tn, (tn.cmple(tf) & inside & real).bitmask())
}

impl WideSlab for Bvh4Node {
    type Dist = [f32; 4];

    #[inline(always)]
    fn slab(&self, r: &NodeRay, t0: f32, t1: f32, tn: &mut [f32; 4]) -> u32 {
        let (t, mask) = slab4(r, self, t0, t1);
        *tn = t.to_array();
        mask
    }
}

/// One ray's walk through the 4-wide BVH, with the box test `R`.
pub type Bvh4Traversal<R = NodeRay> = WideBvhTraversal<Bvh4Node, { stack_capacity(4) }, R>;

/// The closest hit of `ray` through the 4-wide BVH (see [`trace_wide_bvh`]).
#[inline(always)]
pub fn trace_bvh4<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    trace_wide_bvh::<Bvh4Node, { stack_capacity(4) }, I, P>(scene, bvh, ray, probe, counters)
}

/// Whether `ray` is blocked within its interval in the 4-wide BVH (see
/// [`occluded_wide_bvh`]).
#[inline(always)]
pub fn occluded_bvh4<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    occluded_wide_bvh::<Bvh4Node, { stack_capacity(4) }, I, P>(scene, bvh, ray, probe, counters)
}

/// [`occluded_bvh4`] with the shadow cache `cache` (see [`occluded_wide_bvh_cached`]):
/// the same answer, for every ray and every cache.
#[inline(always)]
pub fn occluded_bvh4_cached<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    occluded_wide_bvh_cached::<Bvh4Node, { stack_capacity(4) }, I, P>(scene, bvh, ray, cache, probe, counters)
}

/// [`occluded_bvh4_cached`] for up to four rays at once (see
/// [`occluded_wide_bvh_cached4`]): bit `k` of the result says ray `k` is blocked.
#[inline(always)]
pub fn occluded_bvh4_cached4<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    rays: [Option<&Ray>; 4],
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> u32 {
    occluded_wide_bvh_cached4::<Bvh4Node, { stack_capacity(4) }, I, P>(scene, bvh, rays, cache, probe, counters)
}
