//! 8-wide BVH node test: one node holds the boxes of eight children, tested together by
//! an 8-lane slab test written over plain arrays, which the compiler turns into two SSE
//! registers per plane, or one AVX register where the caller is compiled for AVX (the
//! host's AVX2 build of its loops). A ray visits fewer, wider nodes than in the 4-wide
//! BVH (Embree's BVH8). The walk itself is the wide BVH's ([`crate::traverse::wide_bvh`]).

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{Bvh8Node, Bvh8View, SceneView};
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::wide_bvh::last_occluder::LastOccluder;
use crate::traverse::wide_bvh::{
    occluded_wide_bvh, occluded_wide_bvh_cached, occluded_wide_bvh_cached4, stack_capacity, trace_wide_bvh, NodeRay,
    WideBvhTraversal, WideSlab,
};

/// `max` as the SIMD instruction computes it (the second operand when either is NaN),
/// written so that the compiler emits exactly that instruction.
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `min`, likewise.
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// Entry distances of the ray into the eight child boxes of `n`, within `[t0, t1]`, and
/// the bit mask of those it hits (empty slots, whose boxes are inverted, never). The
/// same arithmetic as [`crate::traverse::wide_bvh::node4::slab4`], eight lanes wide.
#[inline(always)]
pub fn slab8(r: &NodeRay, n: &Bvh8Node, t0: f32, t1: f32) -> ([f32; 8], u32) {
    let mut tn = [0.0f32; 8];
    let mask = slab8_into(r, n, t0, t1, &mut tn);
    (tn, mask)
}

/// [`slab8`] writing the entry distances to `tn`: each form of the test stores them
/// there once (returned by value, they went through a stack slot, then were copied).
#[inline(always)]
pub fn slab8_into(r: &NodeRay, n: &Bvh8Node, t0: f32, t1: f32, tn: &mut [f32; 8]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if let Some(fma) = r.fma8 {
        return crate::simd::slab8::slab8_fused(fma, r, n, t0, t1, tn);
    }
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = r.avx8 {
        return crate::simd::slab8::slab8(avx, r, n, t0, t1, tn);
    }
    if r.rb.zero_axes != 0 {
        let (t, mask) = slab8_exact(&r.rb, n, t0, t1);
        *tn = t;
        return mask;
    }
    // The node's planes as rows: min x, y, z, then max x, y, z (then children, counts).
    let rows: &[[f32; 8]; 8] = bytemuck::cast_ref(n);
    let (o, inv, inv_far) = (r.rb.origin.to_array(), r.rb.inv.to_array(), r.rb.inv_far.to_array());
    let (nx, ny, nz) =
        (&rows[r.rows.near[0] as usize & 7], &rows[r.rows.near[1] as usize & 7], &rows[r.rows.near[2] as usize & 7]);
    let (fx, fy, fz) =
        (&rows[r.rows.far[0] as usize & 7], &rows[r.rows.far[1] as usize & 7], &rows[r.rows.far[2] as usize & 7]);
    let mut hit = [0u8; 8];
    for k in 0..8 {
        // Monotone in the plane: these are the min and max of the two planes' distances
        // for a valid box; an inverted (empty) slot gets near > far and fails.
        let near = max(max((nx[k] - o[0]) * inv[0], (ny[k] - o[1]) * inv[1]), max((nz[k] - o[2]) * inv[2], t0));
        let far =
            min(min((fx[k] - o[0]) * inv_far[0], (fy[k] - o[1]) * inv_far[1]), min((fz[k] - o[2]) * inv_far[2], t1));
        tn[k] = near;
        hit[k] = (near <= far) as u8;
    }
    mask8(hit)
}

/// The bits of eight lanes' outcomes (bit `k` for lane `k`, from bytes of 0 or 1).
/// One multiplication gathers byte `k`'s low bit into bit `56 + k` with no carries
/// (the compiler does not find a move-mask for a loop over the lanes).
#[inline(always)]
fn mask8(hit: [u8; 8]) -> u32 {
    (u64::from_le_bytes(hit).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
}

/// [`slab8`] for any ray, including one with a zero direction component (whose axis is
/// tested as "origin inside the slab", see [`crate::traverse::boxes::slab::RayBox`]).
#[inline(never)]
pub fn slab8_exact(r: &RayBox, n: &Bvh8Node, t0: f32, t1: f32) -> ([f32; 8], u32) {
    let (o, inv, inv_far, zero) = (r.origin.to_array(), r.inv.to_array(), r.inv_far.to_array(), r.zero_axes);
    let lo = [&n.min_x, &n.min_y, &n.min_z];
    let hi = [&n.max_x, &n.max_y, &n.max_z];
    let mut tn = [0.0f32; 8];
    let mut hit = [0u8; 8];
    for k in 0..8 {
        let (mut near, mut far, mut inside) = (t0, f32::INFINITY, true);
        for a in 0..3 {
            if zero & (1 << a) != 0 {
                inside &= o[a] >= lo[a][k] && o[a] <= hi[a][k];
            } else {
                let (dl, dh) = (lo[a][k] - o[a], hi[a][k] - o[a]);
                near = max(min(dl * inv[a], dh * inv[a]), near);
                far = min(max(dl * inv_far[a], dh * inv_far[a]), far);
            }
        }
        let far = min(far, t1);
        tn[k] = near;
        // Inverted (empty) slots: min > max on x.
        hit[k] = (near <= far && inside && lo[0][k] <= hi[0][k]) as u8;
    }
    (tn, mask8(hit))
}

impl WideSlab for Bvh8Node {
    type Dist = [f32; 8];

    #[inline(always)]
    fn slab(&self, r: &NodeRay, t0: f32, t1: f32, tn: &mut [f32; 8]) -> u32 {
        // The AVX test reads the ray's splatted lanes (`NodeRay::lanes8`); hoisted out of
        // a walk's loop by the compiler, such registers were spilled to the stack and
        // reloaded at every node, and each ray's start stalled on the spill (rays that
        // miss the bunny cost twice the 4-wide walk's; without `black_box` in the
        // per-octant walks, bunny 0.93x). Behind `black_box` the ray is opaque at each
        // node, so they are read from its record instead. (The 4-wide test took 11% more
        // instructions that way, so it keeps the hoisted splats.)
        slab8_into(core::hint::black_box(r), self, t0, t1, tn)
    }

    const OCTANT_FORMS: bool = cfg!(target_arch = "x86_64");

    #[inline(always)]
    fn slab_in<const O: usize>(&self, r: &NodeRay, t0: f32, t1: f32, tn: &mut [f32; 8]) -> u32 {
        // The walks per octant run for rays with the fused form only (`walk_octant`): a
        // second form inlined beside it in each walk cost the fused form's gain and more.
        #[cfg(target_arch = "x86_64")]
        if let Some(fma) = r.fma8 {
            return crate::simd::slab8::slab8_fused_in::<O>(fma, core::hint::black_box(r), self, t0, t1, tn);
        }
        slab8_into(core::hint::black_box(r), self, t0, t1, tn)
    }
}

/// One ray's walk through the 8-wide BVH, with the box test `R`.
pub type Bvh8Traversal<R = NodeRay> = WideBvhTraversal<Bvh8Node, { stack_capacity(8) }, R>;

/// The closest hit of `ray` through the 8-wide BVH (see [`trace_wide_bvh`]).
#[inline(always)]
pub fn trace_bvh8<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh8View<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    trace_wide_bvh::<Bvh8Node, { stack_capacity(8) }, I, P>(scene, bvh, ray, probe, counters)
}

/// Whether `ray` is blocked within its interval in the 8-wide BVH (see
/// [`occluded_wide_bvh`]).
#[inline(always)]
pub fn occluded_bvh8<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh8View<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    occluded_wide_bvh::<Bvh8Node, { stack_capacity(8) }, I, P>(scene, bvh, ray, probe, counters)
}

/// [`occluded_bvh8`] with the shadow cache `cache` (see [`occluded_wide_bvh_cached`]):
/// the same answer, for every ray and every cache.
#[inline(always)]
pub fn occluded_bvh8_cached<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh8View<'_>,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> bool {
    occluded_wide_bvh_cached::<Bvh8Node, { stack_capacity(8) }, I, P>(scene, bvh, ray, cache, probe, counters)
}

/// [`occluded_bvh8_cached`] for up to four rays at once (see
/// [`occluded_wide_bvh_cached4`]): bit `k` of the result says ray `k` is blocked.
#[inline(always)]
pub fn occluded_bvh8_cached4<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    bvh: &Bvh8View<'_>,
    rays: [Option<&Ray>; 4],
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> u32 {
    occluded_wide_bvh_cached4::<Bvh8Node, { stack_capacity(8) }, I, P>(scene, bvh, rays, cache, probe, counters)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{Bvh4Node, WideNode};
    use crate::test_lcg::Lcg;
    use crate::traverse::wide_bvh::node4::slab4;
    use glam::Vec3;

    /// The 8-lane test, in its portable and its AVX form, gives slot for slot the 4-lane
    /// test's verdict and entry distance (bit for bit), for rays of every octant, rays
    /// with zero direction components, and nodes with empty slots.
    #[test]
    fn eight_lanes_agree_with_two_four_lane_nodes() {
        let mut g = Lcg(7);
        for case in 0..4000 {
            let mut wide = Bvh8Node::EMPTY;
            let mut halves = [Bvh4Node::EMPTY; 2];
            let used = 1 + case % 8;
            // Every eleventh case starts the ray inside slot 0, flat on one axis: its entry
            // and exit are both exactly 0 (the `<=` of the test decides).
            let inside_flat = case % 11 == 3;
            let mut center = [0.0f32; 3];
            for k in 0..used {
                let c: [f32; 3] = core::array::from_fn(|_| g.range(-4.0, 4.0));
                let mut e: [f32; 3] = core::array::from_fn(|_| if g.unit() < 0.1 { 0.0 } else { g.range(0.0, 2.0) });
                if k == 0 && inside_flat {
                    (e[case % 3], center) = (0.0, c);
                }
                let lo = [c[0] - e[0], c[1] - e[1], c[2] - e[2]];
                let hi = [c[0] + e[0], c[1] + e[1], c[2] + e[2]];
                wide.set_slot(k, lo, hi, k as u32 + 1, 0);
                halves[k / 4].set_slot(k % 4, lo, hi, k as u32 + 1, 0);
            }
            let mut d: [f32; 3] = core::array::from_fn(|_| g.range(-1.0, 1.0));
            if case % 5 == 0 {
                d[case % 3] = 0.0;
            }
            if d == [0.0; 3] {
                d[0] = 1.0;
            }
            let mut o: [f32; 3] = core::array::from_fn(|_| g.range(-6.0, 6.0));
            if case % 5 == 0 && case % 2 == 0 {
                // On a face of a box, along an axis the ray does not move on.
                let (a, k) = (case % 3, (case / 7) % used);
                let (lo, hi, _, _) = wide.slot(k);
                o[a] = if case % 4 == 0 { lo[a] } else { hi[a] };
            }
            if inside_flat {
                (o, d[case % 3]) = (center, 0.5);
            }
            let ray = Ray::new(Vec3::from(o), Vec3::from(d));
            // The unfused forms (the fused one is conservative, not the same bits: see
            // `fused_form_never_rejects_a_box_the_ray_touches`).
            let r = NodeRay::with_fma(&ray, None);
            let (t0, t1) = (0.0, if case % 3 == 0 { g.range(0.5, 8.0) } else { f32::INFINITY });
            let four = halves.map(|node| {
                let (t4, m4) = slab4(&r, &node, t0, t1);
                (t4.to_array(), m4)
            });
            // The portable form, and the AVX form where this CPU has AVX.
            for avx in [None, crate::simd::Avx::detected()] {
                let (t8, m8) = match avx {
                    // (`slab8` sends rays with a zero direction component to the exact test.)
                    #[cfg(target_arch = "x86_64")]
                    Some(avx) if r.rb.zero_axes == 0 => {
                        let mut t8 = [0.0; 8];
                        let m8 = crate::simd::slab8::slab8(avx, &r, &wide, t0, t1, &mut t8);
                        // The fused form's walks per octant, with their offsets as constants:
                        // the fused form's bits.
                        if let Some(fma) = crate::simd::AvxFma::detected() {
                            let f = NodeRay::with_fma(&ray, Some(fma));
                            let (mut t_in, mut t_f) = ([0.0; 8], [0.0; 8]);
                            use crate::simd::slab8::{slab8_fused, slab8_fused_in};
                            let m_f = slab8_fused(fma, &f, &wide, t0, t1, &mut t_f);
                            let m_in = match f.octant() {
                                0 => slab8_fused_in::<0>(fma, &f, &wide, t0, t1, &mut t_in),
                                1 => slab8_fused_in::<1>(fma, &f, &wide, t0, t1, &mut t_in),
                                2 => slab8_fused_in::<2>(fma, &f, &wide, t0, t1, &mut t_in),
                                3 => slab8_fused_in::<3>(fma, &f, &wide, t0, t1, &mut t_in),
                                4 => slab8_fused_in::<4>(fma, &f, &wide, t0, t1, &mut t_in),
                                5 => slab8_fused_in::<5>(fma, &f, &wide, t0, t1, &mut t_in),
                                6 => slab8_fused_in::<6>(fma, &f, &wide, t0, t1, &mut t_in),
                                _ => slab8_fused_in::<7>(fma, &f, &wide, t0, t1, &mut t_in),
                            };
                            assert_eq!(m_in, m_f, "case {case}: octant form's mask");
                            assert_eq!(
                                t_in.map(f32::to_bits),
                                t_f.map(f32::to_bits),
                                "case {case}: octant form's distances"
                            );
                        }
                        (t8, m8)
                    }
                    _ => slab8(&r, &wide, t0, t1),
                };
                let avx = avx.is_some();
                for (h, (t4, m4)) in four.iter().enumerate() {
                    assert_eq!((m8 >> (4 * h)) & 0xF, *m4, "case {case} avx {avx}: masks differ");
                    for k in 0..4 {
                        if m4 & (1 << k) != 0 {
                            assert_eq!(t8[4 * h + k].to_bits(), t4[k].to_bits(), "case {case} avx {avx} slot {k}");
                        }
                    }
                }
                assert_eq!(m8 >> used, 0, "case {case} avx {avx}: an empty slot was hit");
            }
        }
    }

    /// The box test of `(o, d)` against `[lo, hi]` within `[t0, t1]` in `f64`, whose
    /// quotients of `f32` values are within 2⁻⁵³ of exact: `Some(near)` where it hits.
    fn exact_entry(o: [f32; 3], d: [f32; 3], lo: [f32; 3], hi: [f32; 3], t0: f32, t1: f32) -> Option<f64> {
        let (mut near, mut far) = (f64::from(t0), f64::from(t1));
        for a in 0..3 {
            let (l, h) = ((f64::from(lo[a]) - f64::from(o[a])), (f64::from(hi[a]) - f64::from(o[a])));
            let (tl, th) = (l / f64::from(d[a]), h / f64::from(d[a]));
            near = near.max(tl.min(th));
            far = far.min(tl.max(th));
        }
        (near <= far).then_some(near)
    }

    /// The fused form (one multiply-subtract per plane, `FusedOffsets`) never rejects a
    /// box the ray touches — rays far from the origin and boxes near them or far away,
    /// rays grazing a face — and its entry distances stay within a few ulps of the
    /// unfused test's (relative to the distance or to the origin's `o·inv`).
    #[test]
    fn fused_form_never_rejects_a_box_the_ray_touches() {
        #[cfg(target_arch = "x86_64")]
        let (Some(fma), Some(avx)) = (crate::simd::AvxFma::detected(), crate::simd::Avx::detected()) else {
            return;
        };
        #[cfg(not(target_arch = "x86_64"))]
        return;
        #[cfg(target_arch = "x86_64")]
        {
            let mut g = Lcg(11);
            let (mut touched, mut checked) = (0, 0);
            for case in 0..20000 {
                // Origins up to 1e4 from the world's origin, boxes near the ray's path.
                let scale = [1.0, 100.0, 1e4][case % 3];
                let o: [f32; 3] = core::array::from_fn(|_| g.range(-scale, scale));
                let d: [f32; 3] = core::array::from_fn(|_| {
                    let v = g.range(-1.0, 1.0);
                    if v.abs() < 1e-6 {
                        1e-3
                    } else {
                        v
                    }
                });
                let mut wide = Bvh8Node::EMPTY;
                let mut slots = [([0.0f32; 3], [0.0f32; 3]); 8];
                for (k, slot) in slots.iter_mut().enumerate() {
                    // A point along the ray, and a box around it (some flat, some with a
                    // face through that point: the ray grazes it).
                    let t = g.range(0.0, 4.0 * scale);
                    let p: [f32; 3] = core::array::from_fn(|a| o[a] + t * d[a]);
                    let e: [f32; 3] =
                        core::array::from_fn(|_| if g.unit() < 0.2 { 0.0 } else { g.range(0.0, 0.01 * scale) });
                    let shift: [f32; 3] = core::array::from_fn(|a| if g.unit() < 0.3 { e[a] } else { 0.0 });
                    let lo: [f32; 3] = core::array::from_fn(|a| p[a] - e[a] + shift[a]);
                    let hi: [f32; 3] = core::array::from_fn(|a| p[a] + e[a] + shift[a]);
                    wide.set_slot(k, lo, hi, k as u32 + 1, 0);
                    *slot = (lo, hi);
                }
                let ray = Ray::new(Vec3::from(o), Vec3::from(d));
                let fused = NodeRay::with_fma(&ray, Some(fma));
                let plain = NodeRay::with_fma(&ray, None);
                if fused.fma8.is_none() {
                    continue;
                }
                let (t0, t1) = (0.0, if case % 4 == 0 { g.range(0.0, 4.0 * scale) } else { f32::INFINITY });
                let (mut tf, mut tp) = ([0.0; 8], [0.0; 8]);
                let mf = crate::simd::slab8::slab8_fused(fma, &fused, &wide, t0, t1, &mut tf);
                let mp = crate::simd::slab8::slab8(avx, &plain, &wide, t0, t1, &mut tp);
                for (k, (lo, hi)) in slots.iter().enumerate() {
                    checked += 1;
                    if exact_entry(o, d, *lo, *hi, t0, t1).is_some() {
                        touched += 1;
                        assert!(
                            mf & (1 << k) != 0,
                            "case {case} slot {k}: the fused test rejects a box the ray touches"
                        );
                    }
                    if mf & mp & (1 << k) != 0 {
                        let inv = fused.rb.inv.to_array();
                        let bound = (0..3).map(|a| (o[a] * inv[a]).abs()).fold(tp[k].abs(), f32::max) * 1e-5;
                        assert!((tf[k] - tp[k]).abs() <= bound, "case {case} slot {k}: {} against {}", tf[k], tp[k]);
                    }
                }
            }
            assert!(touched > checked / 4, "the cases touch boxes: {touched} of {checked}");
        }
    }

    #[test]
    fn lane_mask_gathers_each_byte_into_its_bit() {
        for m in 0u32..256 {
            let bytes: [u8; 8] = core::array::from_fn(|k| ((m >> k) & 1) as u8);
            assert_eq!(mask8(bytes), m);
        }
    }
}
