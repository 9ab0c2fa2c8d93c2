//! Eight rays into a packet's lanes in AVX: one 8×8 transpose of their records
//! (`RayPacket::fill`'s fast form).

use super::Avx;
use crate::ray::Ray;

/// A packet's eight lane arrays, in a ray record's order: origin x, y, z, direction x,
/// y, z, `t_min`, `t_max`.
pub(crate) type LaneArrays<'a, const N: usize> = [&'a mut [f32; N]; 8];

/// Stores the eight rays of `octet` in lanes `i .. i + 8` of the arrays `p` and returns the bits of
/// the valid ones (`Ray::is_valid`, lane for lane); nothing, and 0, where `octet` is not
/// eight rays or the lanes do not fit.
#[inline(always)]
pub(crate) fn fill8<const N: usize>(avx: Avx, p: LaneArrays<'_, N>, i: usize, octet: &[Ray]) -> u64 {
    let Avx(()) = avx;
    // SAFETY: an `Avx` token exists only where the CPU has AVX (see `Avx`).
    #[allow(unsafe_code)]
    unsafe {
        fill8_avx(p, i, octet)
    }
}

/// Rays `octet` (eight of them) into lanes `i .. i + 8` by one 8×8 transpose in AVX
/// registers (each ray is one 32-byte row, see [`Ray`]), returning the bits of the
/// valid ones (`Ray::is_valid`, lane for lane). Instructions per ray of the bunny's
/// 8×8 packets: 169.6 → 163.4 against the two 4×4 transposes.
///
/// # Safety
///
/// The CPU must support AVX.
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
unsafe fn fill8_avx<const N: usize>(p: LaneArrays<'_, N>, i: usize, octet: &[Ray]) -> u64 {
    use core::arch::x86_64::*;
    if octet.len() < 8 || i + 8 > N {
        return 0;
    }
    // SAFETY: `Ray` is `repr(C)`, eight f32 (asserted in `ray.rs`); `loadu` needs no
    // alignment.
    let row = |k: usize| unsafe { _mm256_loadu_ps((&octet[k] as *const Ray).cast::<f32>()) };
    let (r0, r1, r2, r3, r4, r5, r6, r7) = (row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7));
    let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
    let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
    let (t4, t5) = (_mm256_unpacklo_ps(r4, r5), _mm256_unpackhi_ps(r4, r5));
    let (t6, t7) = (_mm256_unpacklo_ps(r6, r7), _mm256_unpackhi_ps(r6, r7));
    let (u0, u1) = (_mm256_shuffle_ps::<0x44>(t0, t2), _mm256_shuffle_ps::<0xEE>(t0, t2));
    let (u2, u3) = (_mm256_shuffle_ps::<0x44>(t1, t3), _mm256_shuffle_ps::<0xEE>(t1, t3));
    let (u4, u5) = (_mm256_shuffle_ps::<0x44>(t4, t6), _mm256_shuffle_ps::<0xEE>(t4, t6));
    let (u6, u7) = (_mm256_shuffle_ps::<0x44>(t5, t7), _mm256_shuffle_ps::<0xEE>(t5, t7));
    let ox = _mm256_permute2f128_ps::<0x20>(u0, u4);
    let oy = _mm256_permute2f128_ps::<0x20>(u1, u5);
    let oz = _mm256_permute2f128_ps::<0x20>(u2, u6);
    let dx = _mm256_permute2f128_ps::<0x20>(u3, u7);
    let dy = _mm256_permute2f128_ps::<0x31>(u0, u4);
    let dz = _mm256_permute2f128_ps::<0x31>(u1, u5);
    let t_min = _mm256_permute2f128_ps::<0x31>(u2, u6);
    let t_max = _mm256_permute2f128_ps::<0x31>(u3, u7);
    let [pox, poy, poz, pdx, pdy, pdz, pt0, pt1] = p;
    let lanes = [(ox, pox), (oy, poy), (oz, poz), (dx, pdx), (dy, pdy), (dz, pdz), (t_min, pt0), (t_max, pt1)];
    for (v, a) in lanes {
        // SAFETY: `i + 8 <= N` (checked above); `storeu` needs no alignment.
        unsafe { _mm256_storeu_ps(a[i..i + 8].as_mut_ptr(), v) };
    }
    // `Ray::is_valid`, lane for lane, as in the four-lane form of `fill`.
    let zero = _mm256_setzero_ps();
    let finite_axis = |o: __m256, d: __m256| {
        _mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_add_ps(_mm256_sub_ps(o, o), _mm256_sub_ps(d, d)), zero)
    };
    let finite = _mm256_and_ps(_mm256_and_ps(finite_axis(ox, dx), finite_axis(oy, dy)), finite_axis(oz, dz));
    let moving = _mm256_or_ps(
        _mm256_or_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(dx, zero), _mm256_cmp_ps::<_CMP_NEQ_UQ>(dy, zero)),
        _mm256_cmp_ps::<_CMP_NEQ_UQ>(dz, zero),
    );
    let ordered = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_min, t_max), _mm256_cmp_ps::<_CMP_GE_OQ>(t_min, zero));
    _mm256_movemask_ps(_mm256_and_ps(_mm256_and_ps(finite, moving), ordered)) as u32 as u64
}
