//! A packet of up to sixteen rays in one AVX-512 register per quantity (or two AVX
//! ones): their watertight constants made at once, and a leaf's triangles each read once
//! and tested against all of them (as Embree's `rtcOccluded16` does), lane by lane the
//! one-ray test's bits.

use crate::image::{Bvh4View, SceneView};
use crate::intersect::leaf_blocks::entry_triangle;
use crate::intersect::triangle::{Intersector, LaneHits};
use crate::packet::{Lanes, RayPacket};
use crate::probe::MemoryProbe;
use crate::simd::Wide16;

/// The sixteen-lane constants of the rays of `lanes` that share the first one's frame,
/// and the lanes they cover; `None` for packets of more than 16 rays, and where the test
/// or this CPU has no sixteen-lane form (nothing is gathered then).
#[inline(always)]
pub(super) fn shear16<I: Intersector, const N: usize>(
    packet: &RayPacket<N>,
    lanes: u32,
) -> Option<(I::Prepared16, u32)> {
    if N > 16 {
        return None;
    }
    shear16_at::<I, N>(packet, 0, lanes)
}

/// [`shear16`] for the sixteen rays of `packet` from ray `16 · chunk` (bit `k` of
/// `lanes`: ray `16 · chunk + k`), of a packet of any size; `None` past its end.
#[inline(always)]
pub(super) fn shear16_at<I: Intersector, const N: usize>(
    packet: &RayPacket<N>,
    chunk: usize,
    lanes: u32,
) -> Option<(I::Prepared16, u32)> {
    let base = chunk.checked_mul(16).filter(|&b| b < N)?;
    Wide16::reported()?;
    let row = |a: &[f32; N]| -> [f32; 16] { core::array::from_fn(|i| a.get(base + i).copied().unwrap_or(0.0)) };
    let org = [row(&packet.ox), row(&packet.oy), row(&packet.oz)];
    let dir = [row(&packet.dx), row(&packet.dy), row(&packet.dz)];
    I::prepare_rays16(&org, &dir, lanes & 0xFFFF)
}

/// The rays of `lanes` (bits 0–15, all covered by `shear`; bit `k`: ray `base + k` of
/// `packet`) that `leaf` blocks: each of its triangles read once and tested against the
/// sixteen lanes
/// ([`Intersector::intersect_rays16`]; a lane it leaves undecided gets the one-ray test
/// with the ray's constants from `preps`, if given), until every such ray is blocked.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn leaf_blocks16<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    shear: &I::Prepared16,
    (lanes, base): (u32, usize),
    (first, count): (u32, u32),
    preps: Option<&[Option<I::Prepared>; N]>,
    probe: &mut P,
) -> u32 {
    let mut blocked = 0u32;
    let blocks = I::BLOCKS && scene.has_tri_blocks();
    let mut block = None;
    let mut r = LaneHits::<16>::default();
    for e in first..first.saturating_add(count) {
        let tri = entry_triangle::<I, P, _>(scene, bvh, (e, first), blocks, &mut block, probe);
        I::intersect_rays16(shear, &tri, &mut r);
        let decide = lanes & !blocked & (r.hit | r.redo);
        if decide == 0 {
            continue;
        }
        let prim = bvh.prim(e, probe);
        for k in Lanes(u64::from(decide)) {
            // The lane's interval is all a decided lane needs: its whole `Ray` only for
            // the one-ray constants of an undecided lane without any.
            let i = (base + k).min(N - 1);
            let prep = || preps.and_then(|p| p.get(i).copied().flatten()).unwrap_or_else(|| I::prepare(&packet.ray(i)));
            let hit = r.lane_hit_in::<I>(k, (packet.t_min[i], packet.t_max[i]), prim, prep, || tri);
            blocked |= u32::from(hit.is_some()) << k;
        }
        if blocked == lanes {
            break;
        }
    }
    blocked
}
