//! The watertight test (see [`crate::intersect::watertight`]) on eight rays at once in AVX: two
//! groups of four rays of one packet, with one origin and one axis order, against the
//! triangles of a leaf made ready once for that origin ([`crate::intersect::triangle::SharedTris`]).
//! Lane by lane the operations of the four-lane test in the same order, hence the same
//! bits, with twice the lanes per instruction; each triangle's vertices are broadcast
//! once for all the pairs of groups that entered its leaf.

use super::Avx;
use crate::intersect::triangle::{Hits8, SharedTris};

/// Two groups of four rays' shear constants as eight lanes (sx, sy, sz: lanes 0–3 the
/// first group's, 4–7 the second's), and the lanes that take part.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SharedShear {
    pub(crate) s: [[f32; 8]; 3],
    pub(crate) lanes: u32,
}

/// Per triangle of the first `n` of `tris`, and per pair of ray groups of `pairs`, the
/// watertight test's outcome for the pair's eight rays, handed to `found` with the
/// triangle's slot and the pair's index where some lane of the pair's `lanes` hits or
/// is undecided. Triangle by triangle: its vertices are broadcast once for all pairs.
#[inline(always)]
pub(crate) fn shared8(
    avx: Avx,
    tris: &SharedTris,
    n: usize,
    pairs: &[SharedShear],
    found: impl FnMut(usize, usize, &Hits8),
) {
    let Avx(()) = avx;
    // SAFETY: an `Avx` token exists only where the CPU has AVX (see `Avx`).
    #[allow(unsafe_code)]
    unsafe {
        shared8_avx(tris, n, pairs, found)
    }
}

/// [`shared8`] with AVX enabled.
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
unsafe fn shared8_avx(tris: &SharedTris, n: usize, pairs: &[SharedShear], mut found: impl FnMut(usize, usize, &Hits8)) {
    use core::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    for index in 0..n.min(SharedTris::SLOTS) {
        // Written out: a closure here (`map`) is compiled without AVX and called, not
        // inlined.
        let r = &tris.rel;
        let a = [_mm256_set1_ps(r[0][0][index]), _mm256_set1_ps(r[0][1][index]), _mm256_set1_ps(r[0][2][index])];
        let b = [_mm256_set1_ps(r[1][0][index]), _mm256_set1_ps(r[1][1][index]), _mm256_set1_ps(r[1][2][index])];
        let c = [_mm256_set1_ps(r[2][0][index]), _mm256_set1_ps(r[2][1][index]), _mm256_set1_ps(r[2][2][index])];
        for (pair, p) in pairs.iter().enumerate() {
            // SAFETY: each row holds eight floats; `loadu` needs no alignment.
            let (sx, sy, sz) = unsafe {
                (_mm256_loadu_ps(p.s[0].as_ptr()), _mm256_loadu_ps(p.s[1].as_ptr()), _mm256_loadu_ps(p.s[2].as_ptr()))
            };
            let [eu, ev, ew] = watertight_edges!(_mm256_sub_ps, _mm256_mul_ps, a, b, c, sx, sy);
            // `lanes`: glam's cmpeq, cmplt, cmpgt and cmpne are the predicates EQ_OQ,
            // LT_OS, GT_OS and NEQ_UQ.
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
            if (hit | redo) & p.lanes == 0 {
                continue;
            }
            let mut o = Hits8 { hit, redo, ..Hits8::default() };
            if hit != 0 {
                // `scaled_distance`, then the division.
                let t_scaled =
                    watertight_scaled_distance!(_mm256_add_ps, _mm256_mul_ps, [eu, ev, ew], [a[2], b[2], c[2]], sz);
                let inv = _mm256_div_ps(_mm256_set1_ps(1.0), det);
                // SAFETY: each array holds eight floats; `storeu` needs no alignment.
                unsafe {
                    _mm256_storeu_ps(o.t.as_mut_ptr(), _mm256_mul_ps(t_scaled, inv));
                    _mm256_storeu_ps(o.u.as_mut_ptr(), _mm256_mul_ps(ev, inv));
                    _mm256_storeu_ps(o.v.as_mut_ptr(), _mm256_mul_ps(ew, inv));
                }
            }
            found(index, pair, &o);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intersect::triangle::Intersector;
    use crate::intersect::watertight::Watertight;
    use crate::test_lcg::Lcg;
    use glam::{Vec3, Vec4};

    /// Where this CPU has AVX: the eight-ray form on triangles made ready for the rays'
    /// one origin gives, lane by lane, the four-ray form's verdicts (hit and undecided
    /// lanes) and its distances and barycentrics bit for bit, for rays of every frame,
    /// for each of several pairs of groups. (And triangles made ready from two leaf
    /// blocks are the ones made ready from their vertices.)
    #[test]
    fn eight_rays_on_shared_triangles_match_the_four_ray_test() {
        let Some(avx) = Avx::detected() else { return };
        let mut g = Lcg(17);
        let (mut checked, mut hit, mut redo, mut quiet) = (0, 0, 0, 0);
        for case in 0..3000 {
            let origin = Vec3::new(g.lattice(), g.lattice(), g.lattice()) * 3.0;
            // A coherent bundle around one direction (as a camera's 8×8 block), or any.
            let base = Vec3::new(g.lattice(), g.lattice(), g.lattice()) + Vec3::splat(0.01);
            let dirs: [Vec3; 16] = core::array::from_fn(|_| {
                let jitter = Vec3::new(g.lattice(), g.lattice(), g.lattice());
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
            let Some(groups) = (0..4).map(group).collect::<Option<heapless::Vec<_, 4>>>() else { continue };
            if groups.iter().any(|r| Watertight::frame4(r) != Watertight::frame4(&groups[0])) {
                continue;
            }
            let verts: [[Vec3; 3]; SharedTris::SLOTS] = core::array::from_fn(|_| {
                core::array::from_fn(|_| origin + base * 2.0 + Vec3::new(g.lattice(), g.lattice(), g.lattice()))
            });
            let mut tris = SharedTris::default();
            for (slot, v) in verts.iter().enumerate() {
                Watertight::share(&groups[0], origin, v, &mut tris, slot);
            }
            // The same triangles from two leaf blocks (copies of their vertices in lanes).
            let mut from_blocks = SharedTris::default();
            for half in 0..2 {
                let block = crate::image::TriBlock4 {
                    v: core::array::from_fn(|i| {
                        core::array::from_fn(|a| core::array::from_fn(|lane| verts[4 * half + lane][i][a]))
                    }),
                };
                Watertight::share_block(&groups[0], origin, &block, &mut from_blocks, half);
            }
            let bits = |t: &SharedTris| t.rel.map(|v| v.map(|a| a.map(f32::to_bits)));
            assert_eq!(bits(&from_blocks), bits(&tris), "case {case}");
            // Some triangles, each pair with some of its lanes.
            let n = 1 + case % SharedTris::SLOTS;
            let lanes = [[0xFF, 0x0F], [0xF0, 0x5A], [0x01, 0xFF]][case % 3];
            let pairs = [0, 1].map(|p| SharedShear::pair(&groups[2 * p], &groups[2 * p + 1], lanes[p]));
            let mut out = [[None; 2]; SharedTris::SLOTS];
            shared8(avx, &tris, n, &pairs, |k, p, o| out[k][p] = Some(*o));
            for (k, (v, o)) in verts.iter().zip(&out).enumerate() {
                for (p, o) in o.iter().enumerate() {
                    let four = [
                        Watertight::intersect_rays4(&groups[2 * p], v),
                        Watertight::intersect_rays4(&groups[2 * p + 1], v),
                    ];
                    let live = |r: &crate::intersect::triangle::Rays4Result| r.hit | r.redo;
                    let Some(o) = o else {
                        // Handed over exactly where some lane of the pair's mask hits or is
                        // undecided, and only for the first `n` triangles.
                        if k < n {
                            assert_eq!((live(&four[0]) | live(&four[1]) << 4) & lanes[p], 0, "case {case}");
                            quiet += 1;
                        }
                        continue;
                    };
                    assert!(k < n, "case {case}: triangle {k} of {n} tested");
                    for lane in 0..8 {
                        let (r, j) = (&four[lane / 4], lane % 4);
                        assert_eq!(o.hit >> lane & 1, r.hit >> j & 1, "case {case} lane {lane}: hit");
                        assert_eq!(o.redo >> lane & 1, r.redo >> j & 1, "case {case} lane {lane}: undecided");
                        if r.hit >> j & 1 != 0 {
                            let got = [o.t[lane], o.u[lane], o.v[lane]].map(f32::to_bits);
                            assert_eq!(got, [r.t[j], r.u[j], r.v[j]].map(f32::to_bits), "case {case} lane {lane}");
                            hit += 1;
                        }
                        redo += r.redo >> j & 1;
                        checked += 1;
                    }
                }
            }
        }
        assert!(
            checked > 10_000 && hit > 2_000 && redo > 100 && quiet > 1_000,
            "{checked} lanes, {hit} hits, {redo} undecided, {quiet} triangles with neither"
        );
    }
}
