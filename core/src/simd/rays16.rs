//! Sixteen rays of many origins in SIMD registers: a 4-wide node's boxes and one
//! triangle tested for all sixteen at once, as Embree's `rtcOccluded16` does — in one
//! AVX-512 register per quantity, or in two AVX registers (lanes 0–7, then 8–15) where
//! the CPU has no AVX-512. Lane by lane the four-lane forms' operations in the same order
//! (`packet::bvh4::many_origins`, `intersect::watertight`), hence the same bits, with
//! four (AVX: two) times the lanes per instruction.

use super::{Avx, Avx512, Wide16};
use crate::image::Bvh4Node;
use crate::intersect::triangle::LaneHits;
use glam::Vec4;

/// Sixteen rays as the box test reads them: per axis their origins and reciprocal
/// directions (near and far planes, see `RayBox`), and their intervals; lanes `4g ..
/// 4g + 4` in entry `g` of each array (the first four entries are read).
#[derive(Clone, Copy)]
pub(crate) struct BoxLanes<'a> {
    pub(crate) org: &'a [[Vec4; 16]; 3],
    pub(crate) inv: &'a [[Vec4; 16]; 3],
    pub(crate) inv_far: &'a [[Vec4; 16]; 3],
    pub(crate) t0: &'a [Vec4; 16],
    pub(crate) t1: &'a [Vec4; 16],
    /// Per axis, all directions negative (`Some`), when the rays share one octant.
    pub(crate) octant: Option<[bool; 3]>,
}

/// The rays that enter each of `node`'s four boxes: box `k`'s in bits `16k .. 16k + 16`
/// (one register returned: an array written lane by lane and read whole stalled the
/// caller on the store). Lanes outside `live` may be left out: the AVX form skips a half
/// of eight lanes without a live ray.
#[inline(always)]
pub(crate) fn boxes16(wide: Wide16, rays: &BoxLanes<'_>, node: &Bvh4Node, live: u32) -> u64 {
    match wide {
        Wide16::Avx512(Avx512(())) => {
            // SAFETY: an `Avx512` token exists only where the CPU has AVX-512 F.
            #[allow(unsafe_code)]
            unsafe {
                boxes16_avx512(rays, node)
            }
        }
        Wide16::Avx(Avx(())) => {
            // SAFETY: an `Avx` token exists only where the CPU has AVX.
            #[allow(unsafe_code)]
            unsafe {
                boxes16_avx(rays, node, live)
            }
        }
    }
}

/// The box test of [`boxes16`] in the lanes one register holds, written once for both
/// instruction sets: `$load` reads a row of the lanes, `$set1`, `$sub`, `$mul`, `$min`,
/// `$max` and `$zero` are the register width's intrinsics, `$mask` turns `tn ≤ tf` into
/// the lanes' bits and `$at` is the first lane's bit in box 0's sixteen.
macro_rules! boxes_in_register {
    ($rays:expr, $node:expr, $load:expr, $set1:ident, $sub:ident, $mul:ident, $min:ident, $max:ident,
     $zero:ident, $mask:expr, $at:expr) => {{
        let (rays, node): (&BoxLanes<'_>, &Bvh4Node) = ($rays, $node);
        let load = $load;
        let o = [load(&rays.org[0]), load(&rays.org[1]), load(&rays.org[2])];
        let inv = [load(&rays.inv[0]), load(&rays.inv[1]), load(&rays.inv[2])];
        let inv_far = [load(&rays.inv_far[0]), load(&rays.inv_far[1]), load(&rays.inv_far[2])];
        let (t0, t1) = (load(rays.t0), load(rays.t1));
        let lo = [&node.min_x, &node.min_y, &node.min_z];
        let hi = [&node.max_x, &node.max_y, &node.max_z];
        let mut out = 0u64;
        for k in 0..4 {
            // Empty slots hold inverted boxes: never entered.
            if node.min_x[k] > node.max_x[k] {
                continue;
            }
            let mut near = [$zero(); 3];
            let mut far = [$zero(); 3];
            for a in 0..3 {
                let plane = |p: &[f32; 4]| $sub($set1(p[k]), o[a]);
                match rays.octant {
                    Some(neg) => {
                        let (n, f) = if neg[a] { (hi[a], lo[a]) } else { (lo[a], hi[a]) };
                        near[a] = $mul(plane(n), inv[a]);
                        far[a] = $mul(plane(f), inv_far[a]);
                    }
                    None => {
                        let (l, h) = (plane(lo[a]), plane(hi[a]));
                        near[a] = $min($mul(l, inv[a]), $mul(h, inv[a]));
                        far[a] = $max($mul(l, inv_far[a]), $mul(h, inv_far[a]));
                    }
                }
            }
            let tn = $max($max(near[0], near[1]), $max(near[2], t0));
            let tf = $min($min(far[0], far[1]), $min(far[2], t1));
            out |= u64::from($mask(tn, tf)) << (16 * k + $at);
        }
        out
    }};
}

/// [`boxes16`] with AVX-512 F enabled.
///
/// # Safety
///
/// The CPU must support AVX-512 F.
#[allow(unsafe_code)]
#[target_feature(enable = "avx512f")]
unsafe fn boxes16_avx512(rays: &BoxLanes<'_>, node: &Bvh4Node) -> u64 {
    use core::arch::x86_64::*;
    // SAFETY: each array holds sixteen `Vec4`s in a row; the first four are 16 floats.
    let load = |v: &[Vec4; 16]| unsafe { _mm512_loadu_ps(v.as_ptr() as *const f32) };
    let mask = |tn, tf| _mm512_cmp_ps_mask::<_CMP_LE_OQ>(tn, tf);
    boxes_in_register!(
        rays,
        node,
        load,
        _mm512_set1_ps,
        _mm512_sub_ps,
        _mm512_mul_ps,
        _mm512_min_ps,
        _mm512_max_ps,
        _mm512_setzero_ps,
        mask,
        0
    )
}

/// [`boxes16`] with AVX, in one call: each half of eight lanes that holds a ray of
/// `live`. (A packet's rays part ways as it descends: skipping a half without one took
/// the bunny's shadow packets of 16 from 222 to 208 million instructions.)
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
unsafe fn boxes16_avx(rays: &BoxLanes<'_>, node: &Bvh4Node, live: u32) -> u64 {
    let mut out = 0;
    for h in 0..2 {
        if (live >> (8 * h)) & 0xFF != 0 {
            // SAFETY: the caller's CPU supports AVX, as this function's contract requires.
            out |= unsafe { boxes8_avx(rays, node, h) };
        }
    }
    out
}

/// [`boxes16`]'s lanes `8h .. 8h + 8` with AVX (`h`: 0 or 1), in the same bits of the
/// result as the sixteen-lane form's.
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[inline]
#[target_feature(enable = "avx")]
unsafe fn boxes8_avx(rays: &BoxLanes<'_>, node: &Bvh4Node, h: usize) -> u64 {
    use core::arch::x86_64::*;
    let h = h & 1;
    // SAFETY: each array holds sixteen `Vec4`s in a row; its first 16 floats are the
    // lanes, of which this reads eight from lane 8h.
    let load = |v: &[Vec4; 16]| unsafe { _mm256_loadu_ps((v.as_ptr() as *const f32).add(8 * h)) };
    let mask = |tn, tf| _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32 & 0xFF;
    boxes_in_register!(
        rays,
        node,
        load,
        _mm256_set1_ps,
        _mm256_sub_ps,
        _mm256_mul_ps,
        _mm256_min_ps,
        _mm256_max_ps,
        _mm256_setzero_ps,
        mask,
        8 * h
    )
}

/// The watertight test of sixteen rays of one frame (per axis of the frame their origins
/// `org` and the shear `s`: `sx`, `sy`, `sz`) against the triangle whose vertices `v` are
/// given in the frame's axis order: lane by lane the four-lane test's verdicts and bits
/// (lanes with an edge function of exactly zero are left in `redo`), into `out`: its
/// `hit` and `redo` always, its distances and barycentrics only where a lane hits (most
/// tests hit nothing: a whole record written per test was a fifth of a shadow packet's
/// time).
#[inline(always)]
pub(crate) fn watertight16(
    wide: Wide16,
    org: &[[f32; 16]; 3],
    s: &[[f32; 16]; 3],
    v: &[[f32; 3]; 3],
    out: &mut LaneHits<16>,
) {
    match wide {
        Wide16::Avx512(Avx512(())) => {
            // SAFETY: an `Avx512` token exists only where the CPU has AVX-512 F.
            #[allow(unsafe_code)]
            unsafe {
                watertight16_avx512(org, s, v, out)
            }
        }
        Wide16::Avx(Avx(())) => {
            // SAFETY: an `Avx` token exists only where the CPU has AVX.
            #[allow(unsafe_code)]
            unsafe {
                watertight16_avx(org, s, v, out)
            }
        }
    }
}

/// [`watertight16`] with AVX-512 F enabled.
///
/// # Safety
///
/// The CPU must support AVX-512 F.
#[allow(unsafe_code)]
#[target_feature(enable = "avx512f")]
unsafe fn watertight16_avx512(org: &[[f32; 16]; 3], s: &[[f32; 16]; 3], v: &[[f32; 3]; 3], out: &mut LaneHits<16>) {
    use core::arch::x86_64::*;
    // SAFETY: each row holds sixteen floats; `loadu` needs no alignment.
    let load = |a: &[f32; 16]| unsafe { _mm512_loadu_ps(a.as_ptr()) };
    let o = [load(&org[0]), load(&org[1]), load(&org[2])];
    let (sx, sy, sz) = (load(&s[0]), load(&s[1]), load(&s[2]));
    // Vertices relative to each ray's origin (`intersect_rays4`'s `rel`).
    let rel = |p: &[f32; 3]| {
        [
            _mm512_sub_ps(_mm512_set1_ps(p[0]), o[0]),
            _mm512_sub_ps(_mm512_set1_ps(p[1]), o[1]),
            _mm512_sub_ps(_mm512_set1_ps(p[2]), o[2]),
        ]
    };
    let (a, b, c) = (rel(&v[0]), rel(&v[1]), rel(&v[2]));
    let [eu, ev, ew] = watertight_edges!(_mm512_sub_ps, _mm512_mul_ps, a, b, c, sx, sy);
    // `lanes`: glam's cmpeq, cmplt, cmpgt and cmpne give the results of EQ_OQ, LT_OQ,
    // GT_OQ and NEQ_UQ (the signalling forms differ in exceptions only).
    let zero = _mm512_setzero_ps();
    macro_rules! any {
        ($p:ident) => {
            _mm512_cmp_ps_mask::<$p>(eu, zero) | _mm512_cmp_ps_mask::<$p>(ev, zero) | _mm512_cmp_ps_mask::<$p>(ew, zero)
        };
    }
    let redo = u32::from(any!(_CMP_EQ_OQ));
    let (neg, pos) = (any!(_CMP_LT_OQ), any!(_CMP_GT_OQ));
    let det = _mm512_add_ps(_mm512_add_ps(eu, ev), ew);
    let nonzero = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(det, zero);
    let hit = u32::from(!(neg & pos) & nonzero) & !redo;
    (out.hit, out.redo) = (hit, redo);
    if hit == 0 {
        return;
    }
    // `scaled_distance`, then the division.
    let t_scaled = watertight_scaled_distance!(_mm512_add_ps, _mm512_mul_ps, [eu, ev, ew], [a[2], b[2], c[2]], sz);
    let inv = _mm512_div_ps(_mm512_set1_ps(1.0), det);
    // SAFETY: each array holds sixteen floats; `storeu` needs no alignment.
    unsafe {
        _mm512_storeu_ps(out.t.as_mut_ptr(), _mm512_mul_ps(t_scaled, inv));
        _mm512_storeu_ps(out.u.as_mut_ptr(), _mm512_mul_ps(ev, inv));
        _mm512_storeu_ps(out.v.as_mut_ptr(), _mm512_mul_ps(ew, inv));
    }
}

/// [`watertight16`] with AVX: both halves in one call.
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
unsafe fn watertight16_avx(org: &[[f32; 16]; 3], s: &[[f32; 16]; 3], v: &[[f32; 3]; 3], out: &mut LaneHits<16>) {
    (out.hit, out.redo) = (0, 0);
    // SAFETY: the caller's CPU supports AVX, as this function's contract requires.
    unsafe {
        watertight8_avx(org, s, v, out, 0);
        watertight8_avx(org, s, v, out, 1);
    }
}

/// [`watertight16`]'s lanes `8h .. 8h + 8` with AVX (`h`: 0 or 1): their bits of `hit`
/// and `redo` added to `out`'s, their distances and barycentrics written where one hits.
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[inline]
#[target_feature(enable = "avx")]
unsafe fn watertight8_avx(
    org: &[[f32; 16]; 3],
    s: &[[f32; 16]; 3],
    v: &[[f32; 3]; 3],
    out: &mut LaneHits<16>,
    h: usize,
) {
    use core::arch::x86_64::*;
    let at = 8 * (h & 1);
    // SAFETY: each row holds sixteen floats, of which this reads eight from lane `at`
    // (at most 8); `loadu` needs no alignment.
    let load = |a: &[f32; 16]| unsafe { _mm256_loadu_ps(a.as_ptr().add(at)) };
    let o = [load(&org[0]), load(&org[1]), load(&org[2])];
    let (sx, sy, sz) = (load(&s[0]), load(&s[1]), load(&s[2]));
    // Vertices relative to each ray's origin (`intersect_rays4`'s `rel`).
    let rel = |p: &[f32; 3]| {
        [
            _mm256_sub_ps(_mm256_set1_ps(p[0]), o[0]),
            _mm256_sub_ps(_mm256_set1_ps(p[1]), o[1]),
            _mm256_sub_ps(_mm256_set1_ps(p[2]), o[2]),
        ]
    };
    let (a, b, c) = (rel(&v[0]), rel(&v[1]), rel(&v[2]));
    let [eu, ev, ew] = watertight_edges!(_mm256_sub_ps, _mm256_mul_ps, a, b, c, sx, sy);
    // `lanes`, with the predicates of the sixteen-lane form.
    let zero = _mm256_setzero_ps();
    macro_rules! any {
        ($p:ident) => {
            _mm256_movemask_ps(_mm256_or_ps(
                _mm256_or_ps(_mm256_cmp_ps::<$p>(eu, zero), _mm256_cmp_ps::<$p>(ev, zero)),
                _mm256_cmp_ps::<$p>(ew, zero),
            )) as u32
        };
    }
    let redo = any!(_CMP_EQ_OQ);
    let (neg, pos) = (any!(_CMP_LT_OQ), any!(_CMP_GT_OQ));
    let det = _mm256_add_ps(_mm256_add_ps(eu, ev), ew);
    let nonzero = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero)) as u32;
    let hit = !(neg & pos) & nonzero & !redo & 0xFF;
    out.hit |= hit << at;
    out.redo |= (redo & 0xFF) << at;
    if hit == 0 {
        return;
    }
    // `scaled_distance`, then the division.
    let t_scaled = watertight_scaled_distance!(_mm256_add_ps, _mm256_mul_ps, [eu, ev, ew], [a[2], b[2], c[2]], sz);
    let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    // SAFETY: each array holds sixteen floats, of which this writes eight from lane
    // `at`; `storeu` needs no alignment.
    unsafe {
        _mm256_storeu_ps(out.t.as_mut_ptr().add(at), _mm256_mul_ps(t_scaled, inv));
        _mm256_storeu_ps(out.u.as_mut_ptr().add(at), _mm256_mul_ps(ev, inv));
        _mm256_storeu_ps(out.v.as_mut_ptr().add(at), _mm256_mul_ps(ew, inv));
    }
}

#[cfg(test)]
mod tests {
    use crate::intersect::triangle::Intersector;
    use crate::intersect::watertight::Watertight;
    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// In each form this CPU has (AVX-512, AVX): sixteen rays of many origins made ready
    /// at once take, lane by lane, the frame and constants of [`Watertight::prepare`],
    /// cover exactly the lanes of the first lane's frame, and against a triangle give the
    /// one-ray test's verdicts and bits (lanes left undecided where an edge function is
    /// zero).
    #[test]
    fn sixteen_rays_of_many_origins_match_the_one_ray_test() {
        if super::Avx::detected().is_none() {
            return;
        }
        // SAFETY: the CPU has AVX (detected above); AVX-512 is reported only where the
        // operating system says this CPU has it.
        #[allow(unsafe_code)]
        unsafe {
            super::super::assume_avx();
            super::super::assume_avx16(true);
            super::super::assume_avx512(super::Avx512::detected().is_some());
        };
        for form in super::Wide16::detected_forms().into_iter().flatten() {
            match_the_one_ray_test_in(form);
        }
    }

    fn match_the_one_ray_test_in(form: super::Wide16) {
        let mut g = Lcg(29);
        let (mut checked, mut hit, mut redo, mut left_out) = (0, 0, 0, 0);
        for case in 0..4000 {
            // Shadow rays: many origins towards one point, or any directions.
            let light = Vec3::new(g.lattice(), 4.0, g.lattice()) * 2.0;
            let rays: [Ray; 16] = core::array::from_fn(|_| {
                let o = Vec3::new(g.lattice(), g.lattice(), g.lattice()) * 2.0;
                let d = if case % 3 == 0 {
                    Vec3::new(g.lattice(), g.lattice(), g.lattice()) + Vec3::splat(0.01)
                } else {
                    light - o
                };
                Ray::new(o, d)
            });
            let org = core::array::from_fn(|a| core::array::from_fn(|i| rays[i].origin[a]));
            let dir = core::array::from_fn(|a| core::array::from_fn(|i| rays[i].dir[a]));
            let lanes = [0xFFFF, 0x0F0F, 0x8001, 0x0040][case % 4];
            let Some((prep, covered)) = Watertight::prepare_rays16(&org, &dir, lanes) else {
                panic!("case {case}: no sixteen-lane form on a CPU with AVX");
            };
            let prep = prep.in_form(form);
            let own = rays.map(|r| Watertight::prepare(&r));
            let lead = &own[lanes.trailing_zeros() as usize];
            assert_ne!(covered & (1 << lanes.trailing_zeros()), 0, "case {case}: the first lane left out");
            assert_eq!(covered & !lanes, 0, "case {case}: a lane not asked for covered");
            for (i, o) in own.iter().enumerate() {
                if lanes & (1 << i) != 0 {
                    let same = o.kx_ky_kz() == lead.kx_ky_kz();
                    assert_eq!(covered & (1 << i) != 0, same, "case {case} lane {i}: covered by frame");
                    left_out += u32::from(!same);
                }
            }
            let v: [Vec3; 3] = core::array::from_fn(|_| Vec3::new(g.lattice(), g.lattice(), g.lattice()));
            let mut r = crate::intersect::triangle::LaneHits::default();
            Watertight::intersect_rays16(&prep, &v, &mut r);
            for i in (0..16).filter(|i| covered & (1 << i) != 0) {
                let one = Watertight::intersect(&own[i], &v);
                if r.redo & (1 << i) != 0 {
                    redo += 1;
                    continue;
                }
                match one {
                    Some((t, u, w)) => {
                        assert_ne!(r.hit & (1 << i), 0, "case {case} lane {i}: a hit missed");
                        let got = [r.t[i], r.u[i], r.v[i]].map(f32::to_bits);
                        assert_eq!(got, [t, u, w].map(f32::to_bits), "case {case} lane {i}");
                        hit += 1;
                    }
                    None => assert_eq!(r.hit & (1 << i), 0, "case {case} lane {i}: a miss hit"),
                }
                checked += 1;
            }
        }
        assert!(
            checked > 20_000 && hit > 300 && redo > 100 && left_out > 500,
            "{checked} lanes, {hit} hits, {redo} undecided, {left_out} lanes of another frame"
        );
    }
}
