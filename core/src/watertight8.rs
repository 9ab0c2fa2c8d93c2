//! The watertight test (see [`crate::watertight`]) on eight rays at once in AVX: two
//! groups of four rays of one packet, with one origin and one axis order, against the
//! triangles of a leaf made ready once for that origin ([`crate::triangle::SharedTri`]).
//! Lane by lane the operations of the four-lane test in the same order, hence the same
//! bits, with twice the lanes per instruction, and the rays' constants loaded once for
//! all the triangles of a leaf rather than once per triangle.

use crate::triangle::{Hits8, SharedTri};
use glam::Vec4;

/// Per triangle of `tris`, the watertight test's outcome for eight rays, whose shear
/// constants are `s` (sx, sy, sz, each as two groups' four lanes: lanes 0–3, then 4–7),
/// handed to `found` with the triangle's index where some lane of `lanes` hits or is
/// undecided.
///
/// # Safety
///
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
pub(crate) unsafe fn shared8_avx(tris: &[SharedTri], s: [Vec4; 6], lanes: u32, mut found: impl FnMut(usize, &Hits8)) {
    use core::arch::x86_64::*;
    let sx = _mm256_set_m128(s[1].into(), s[0].into());
    let sy = _mm256_set_m128(s[3].into(), s[2].into());
    let sz = _mm256_set_m128(s[5].into(), s[4].into());
    let zero = _mm256_setzero_ps();
    for (index, tri) in tris.iter().enumerate() {
        // Written out: a closure here (`map`) is compiled without AVX and called, not
        // inlined.
        let r = &tri.rel;
        let a = [_mm256_set1_ps(r[0][0]), _mm256_set1_ps(r[0][1]), _mm256_set1_ps(r[0][2])];
        let b = [_mm256_set1_ps(r[1][0]), _mm256_set1_ps(r[1][1]), _mm256_set1_ps(r[1][2])];
        let c = [_mm256_set1_ps(r[2][0]), _mm256_set1_ps(r[2][1]), _mm256_set1_ps(r[2][2])];
        // `shear_edges` with the frame's axes 0, 1, 2.
        let ax = _mm256_sub_ps(a[0], _mm256_mul_ps(sx, a[2]));
        let ay = _mm256_sub_ps(a[1], _mm256_mul_ps(sy, a[2]));
        let bx = _mm256_sub_ps(b[0], _mm256_mul_ps(sx, b[2]));
        let by = _mm256_sub_ps(b[1], _mm256_mul_ps(sy, b[2]));
        let cx = _mm256_sub_ps(c[0], _mm256_mul_ps(sx, c[2]));
        let cy = _mm256_sub_ps(c[1], _mm256_mul_ps(sy, c[2]));
        // `edges`.
        let eu = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
        let ev = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
        let ew = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
        // `lanes`: glam's cmpeq, cmplt, cmpgt and cmpne are the predicates EQ_OQ, LT_OS,
        // GT_OS and NEQ_UQ.
        macro_rules! any {
            ($p:ident) => {
                _mm256_or_ps(
                    _mm256_or_ps(_mm256_cmp_ps::<$p>(eu, zero), _mm256_cmp_ps::<$p>(ev, zero)),
                    _mm256_cmp_ps::<$p>(ew, zero),
                )
            };
        }
        let redo = _mm256_movemask_ps(any!(_CMP_EQ_OQ)) as u32;
        let (neg, pos) = (any!(_CMP_LT_OS), any!(_CMP_GT_OS));
        let det = _mm256_add_ps(_mm256_add_ps(eu, ev), ew);
        let nonzero = _mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero);
        let hit = _mm256_movemask_ps(_mm256_andnot_ps(_mm256_and_ps(neg, pos), nonzero)) as u32 & !redo;
        if (hit | redo) & lanes == 0 {
            continue;
        }
        let mut o = Hits8 { hit, redo, ..Hits8::default() };
        if hit != 0 {
            // `scaled_distance`, then the division.
            let t_scaled = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(eu, _mm256_mul_ps(sz, a[2])), _mm256_mul_ps(ev, _mm256_mul_ps(sz, b[2]))),
                _mm256_mul_ps(ew, _mm256_mul_ps(sz, c[2])),
            );
            let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
            // SAFETY: each array holds eight floats; `storeu` needs no alignment.
            unsafe {
                _mm256_storeu_ps(o.t.as_mut_ptr(), _mm256_mul_ps(t_scaled, inv));
                _mm256_storeu_ps(o.u.as_mut_ptr(), _mm256_mul_ps(ev, inv));
                _mm256_storeu_ps(o.v.as_mut_ptr(), _mm256_mul_ps(ew, inv));
            }
        }
        found(index, &o);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;
    use crate::triangle::Intersector;
    use crate::watertight::Watertight;
    use glam::Vec3;

    /// Small lattice values, so that edge functions are often exactly zero (lanes the
    /// test leaves to the scalar form) and triangles are often hit.
    fn lattice(g: &mut Lcg) -> f32 {
        ((g.next() >> 33) % 9) as f32 * 0.25 - 1.0
    }

    /// Where this CPU has AVX: the eight-ray form on triangles made ready for the rays'
    /// one origin gives, lane by lane, the four-ray form's verdicts (hit and undecided
    /// lanes) and its distances and barycentrics bit for bit, for rays of every frame.
    /// (And a triangle made ready from a leaf block is the one made ready from its
    /// vertices.)
    #[test]
    fn eight_rays_on_shared_triangles_match_the_four_ray_test() {
        if !crate::cpu::detected_avx() {
            return;
        }
        let mut g = Lcg(17);
        let (mut checked, mut hit, mut redo, mut quiet) = (0, 0, 0, 0);
        for case in 0..4000 {
            let origin = Vec3::new(lattice(&mut g), lattice(&mut g), lattice(&mut g)) * 3.0;
            // A coherent bundle around one direction (as a camera's 8×8 block), or any.
            let base = Vec3::new(lattice(&mut g), lattice(&mut g), lattice(&mut g)) + Vec3::splat(0.01);
            let dirs: [Vec3; 8] = core::array::from_fn(|_| {
                let jitter = Vec3::new(lattice(&mut g), lattice(&mut g), lattice(&mut g));
                if case % 2 == 0 {
                    base + jitter * 0.05
                } else {
                    base + jitter * 0.5
                }
            });
            let group = |h: usize| {
                let d: [Vec4; 3] =
                    core::array::from_fn(|a| Vec4::from_array(core::array::from_fn(|k| dirs[4 * h + k][a])));
                Watertight::prepare_rays4([Vec4::splat(origin.x), Vec4::splat(origin.y), Vec4::splat(origin.z)], d)
            };
            let (Some(lo), Some(hi)) = (group(0), group(1)) else { continue };
            if Watertight::frame4(&lo) != Watertight::frame4(&hi) {
                continue;
            }
            let verts: [[Vec3; 3]; 5] = core::array::from_fn(|_| {
                core::array::from_fn(|_| {
                    origin + base * 2.0 + Vec3::new(lattice(&mut g), lattice(&mut g), lattice(&mut g))
                })
            });
            let tris = verts.map(|v| Watertight::share(&lo, origin, &v));
            // The same triangles from a leaf block (copies of their vertices in lanes).
            let block = crate::image::TriBlock4 {
                v: core::array::from_fn(|i| core::array::from_fn(|a| core::array::from_fn(|lane| verts[lane][i][a]))),
            };
            for (lane, tri) in tris.iter().enumerate().take(4) {
                let b = Watertight::share_block(&lo, origin, &block, lane);
                assert_eq!(b.rel.map(|p| p.map(f32::to_bits)), tri.rel.map(|p| p.map(f32::to_bits)), "case {case}");
            }
            let mut out = [None; 5];
            let all = if case % 3 == 0 { 0x0F } else { 0xFF };
            let s = [lo.sx, hi.sx, lo.sy, hi.sy, lo.sz, hi.sz];
            // SAFETY: this CPU has AVX (checked above).
            #[allow(unsafe_code)]
            unsafe {
                shared8_avx(&tris, s, all, |k, o| out[k] = Some(*o))
            };
            for (v, o) in verts.iter().zip(&out) {
                let four = [Watertight::intersect_rays4(&lo, v), Watertight::intersect_rays4(&hi, v)];
                let live = |r: &crate::triangle::Rays4Result| r.hit | r.redo;
                let Some(o) = o else {
                    // Handed over exactly where some lane of the mask hits or is undecided.
                    assert_eq!((live(&four[0]) | live(&four[1]) << 4) & all, 0, "case {case}");
                    quiet += 1;
                    continue;
                };
                for lane in 0..8 {
                    let (r, k) = (&four[lane / 4], lane % 4);
                    assert_eq!(o.hit >> lane & 1, r.hit >> k & 1, "case {case} lane {lane}: hit");
                    assert_eq!(o.redo >> lane & 1, r.redo >> k & 1, "case {case} lane {lane}: undecided");
                    if r.hit >> k & 1 != 0 {
                        let got = [o.t[lane], o.u[lane], o.v[lane]].map(f32::to_bits);
                        assert_eq!(got, [r.t[k], r.u[k], r.v[k]].map(f32::to_bits), "case {case} lane {lane}");
                        hit += 1;
                    }
                    redo += r.redo >> k & 1;
                    checked += 1;
                }
            }
        }
        assert!(
            checked > 10_000 && hit > 2_000 && redo > 100 && quiet > 1_000,
            "{checked} lanes, {hit} hits, {redo} undecided, {quiet} triangles with neither"
        );
    }
}
