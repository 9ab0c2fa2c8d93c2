//! A leaf reached by the packet: which rays enter its box (four at a time), and its
//! triangles tested by those rays — four rays against one triangle where a group has
//! two or more, one origin's triangle set-up shared where the rays have one.

use crate::hit::keep_closest;
use crate::image::{SceneView, WideBvhView, WideNode};
use crate::intersect::triangle::{test_triangle, Intersector, LaneHits, RayPair, SharedTris};
use crate::packet::{Lanes, PacketHits, RayPacket};
use crate::probe::MemoryProbe;
use crate::traverse::boxes::clip::SLAB_GROWTH;
use glam::{Vec3, Vec4};

use super::groups::{groups_of, Groups, GROUPS};
use super::prepared::{Ones, Preps};

/// The active lanes of `mask` that enter the leaf box `[lo, hi]` (`leaf_box`) before
/// their best hit: four rays against the box at once (no zero direction components, so
/// the plain slab test is exact here). `origin`: the rays' one origin, if they share one
/// (every active lane of `q.org` holds it), so that `lo − o` and `hi − o` are computed
/// once per leaf rather than once per group: the same values, hence the same lanes.
#[inline(always)]
pub(in crate::packet) fn leaf_entries(
    q: &Groups,
    groups: usize,
    mask: u64,
    leaf_box: &[f32; 6],
    leaf_t: f32,
    origin: Option<[f32; 3]>,
) -> u64 {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = crate::simd::Avx::reported() {
        return crate::simd::leaf_entries::leaf_entries(avx, q, groups, mask, leaf_box, origin);
    }
    leaf_entries_portable(q, groups, mask, leaf_box, leaf_t, origin)
}

/// [`leaf_entries`] over glam's four-lane registers, group by group.
#[inline(always)]
pub(in crate::packet) fn leaf_entries_portable(
    q: &Groups,
    groups: usize,
    mask: u64,
    leaf_box: &[f32; 6],
    leaf_t: f32,
    origin: Option<[f32; 3]>,
) -> u64 {
    let lo = [Vec4::splat(leaf_box[0]), Vec4::splat(leaf_box[1]), Vec4::splat(leaf_box[2])];
    let hi = [Vec4::splat(leaf_box[3]), Vec4::splat(leaf_box[4]), Vec4::splat(leaf_box[5])];
    let offsets: Option<[(Vec4, Vec4); 3]> = origin
        .map(|o| core::array::from_fn(|a| (Vec4::splat(leaf_box[a] - o[a]), Vec4::splat(leaf_box[3 + a] - o[a]))));
    let mut enter = 0u64;
    for g in 0..groups.min(GROUPS) {
        let m4 = (mask >> (4 * g)) & 0xF;
        // `leaf_t` bounds every ray's entry from below: a group whose rays all have
        // nearer hits skips the exact test.
        if m4 == 0 || leaf_t > q.group_end[g] {
            continue;
        }
        let mut tn = q.t_min[g];
        let mut tf = q.ends[g];
        for a in 0..3 {
            let (dl, dh) = match offsets {
                Some(d) => d[a],
                None => (lo[a] - q.org[a][g], hi[a] - q.org[a][g]),
            };
            let (p, r) = (dl * q.inv[a][g], dh * q.inv[a][g]);
            tn = tn.max(p.min(r));
            tf = tf.min(p.max(r) * SLAB_GROWTH);
        }
        enter |= ((tn.cmple(tf).bitmask() as u64) & m4) << (4 * g);
    }
    enter
}

/// A leaf the packet reached: the scene and tree it is in, the packet, and its list
/// entries `first .. first + count`.
#[derive(Clone, Copy)]
pub(in crate::packet) struct LeafVisit<'v, 's, W: WideNode, const N: usize> {
    pub(in crate::packet) scene: &'v SceneView<'s>,
    pub(in crate::packet) bvh: &'v WideBvhView<'s, W>,
    pub(in crate::packet) packet: &'v RayPacket<N>,
    pub(in crate::packet) first: u32,
    pub(in crate::packet) count: u32,
}

/// Tests the leaf's triangles (list entries `first .. first + count`) with the rays of
/// `enter`, each triangle read once: four rays at a time where two or more of a group
/// enter and the intersector has a four-ray form, one by one otherwise.
#[inline(always)]
pub(in crate::packet) fn test_leaf<I: Intersector, P: MemoryProbe, W: WideNode, const N: usize>(
    leaf: &LeafVisit<'_, '_, W, N>,
    enter: u64,
    preps: &mut Preps<I, N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) {
    let LeafVisit { scene, bvh, packet, first, count } = *leaf;
    let groups = groups_of(enter);
    for e in first..first.wrapping_add(count) {
        let prim = bvh.prim(e, probe);
        let verts = I::fetch(scene, prim, probe);
        for g in Lanes(groups) {
            let m4 = (enter >> (4 * g)) & 0xF;
            let four = preps.fours.get(g);
            match four {
                Some(rays) if m4.count_ones() >= 2 => {
                    let r = I::intersect_rays4(rays, &verts);
                    for k in Lanes(m4 & (r.hit | r.redo) as u64) {
                        let lane = LaneOutcome { hits: &r, lane: k, ray: (4 * g + k).min(N - 1) };
                        keep_lane(packet, &mut preps.ones, hits, lane, prim, || verts);
                    }
                }
                _ => {
                    for i in Lanes(m4 << (4 * g)) {
                        let i = i.min(N - 1);
                        test_triangle::<I>(&preps.ones.get(packet, i), &packet.ray(i), &verts, prim, &mut hits[i]);
                    }
                }
            }
        }
    }
}

/// The triangles of `leaf` against the rays of `enter`, which entered its box: their
/// constants made first (from the lanes `q` of the packet's active lanes `mask`), then
/// the one-origin test where the rays share `origin` and the test has that form, else
/// groups of four ([`test_leaf`]).
#[inline(always)]
pub(in crate::packet) fn test_entered<I: Intersector, P: MemoryProbe, W: WideNode, const N: usize>(
    leaf: &LeafVisit<'_, '_, W, N>,
    enter: u64,
    (q, mask): (&Groups, u64),
    origin: Option<[f32; 3]>,
    preps: &mut Preps<I, N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) {
    preps.fours.prepare(leaf.packet, q, mask, enter);
    let shared =
        origin.map(Vec3::from).is_some_and(|o| test_leaf_shared::<I, P, W, N>(leaf, enter, o, preps, hits, probe));
    if !shared {
        test_leaf::<I, P, W, N>(leaf, enter, preps, hits, probe);
    }
}

/// One lane of a multi-lane test's outcome, and the packet ray it belongs to.
#[derive(Clone, Copy)]
pub(in crate::packet) struct LaneOutcome<'r, const L: usize> {
    /// The test's outcome for all its lanes.
    pub(in crate::packet) hits: &'r LaneHits<L>,
    /// The lane.
    pub(in crate::packet) lane: usize,
    /// The packet ray the lane tested.
    pub(in crate::packet) ray: usize,
}

/// Keeps lane `k` of a multi-lane test's outcome `r` on triangle `prim` for packet ray
/// `i` (`outcome`): its hit if in the ray's range, or, where the lane was left undecided,
/// the one-ray test's verdict on the triangle `tri()`.
#[inline(always)]
pub(in crate::packet) fn keep_lane<I: Intersector, const N: usize, const L: usize>(
    packet: &RayPacket<N>,
    ones: &mut Ones<I, N>,
    hits: &mut PacketHits<N>,
    outcome: LaneOutcome<'_, L>,
    prim: u32,
    tri: impl FnOnce() -> I::Triangle,
) {
    let LaneOutcome { hits: r, lane: k, ray: i } = outcome;
    let i = i.min(N - 1);
    let range = (packet.t_min[i], packet.t_max[i]);
    if let Some(hit) = r.lane_hit_in::<I>(k, range, prim, || ones.get(packet, i), tri) {
        keep_closest(&mut hits[i], hit);
    }
}

/// [`test_leaf`] for rays of one origin `origin` (a pinhole camera's): each triangle made
/// ready once for the origin ([`Intersector::share`]), then tested against the entering
/// groups two at a time, eight lanes per instruction ([`Intersector::intersect_shared8`]),
/// lone rays included. The same hits as [`test_leaf`]: the eight-ray form gives the four-
/// and one-ray forms' bits, and a lane's closest hit does not depend on the order its
/// triangles are tested in. Returns false, having tested nothing, where it does not apply
/// (the test has no such form, this CPU lacks it, or the groups do not share one frame).
#[inline(always)]
pub(in crate::packet) fn test_leaf_shared<I: Intersector, P: MemoryProbe, W: WideNode, const N: usize>(
    leaf: &LeafVisit<'_, '_, W, N>,
    enter: u64,
    origin: Vec3,
    preps: &mut Preps<I, N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) -> bool {
    let LeafVisit { scene, bvh, packet, first, count } = *leaf;
    if !I::SHARED8 {
        return false;
    }
    let groups = groups_of(enter);
    let Some(&frame_rays) = preps.fours.get(groups.trailing_zeros() as usize) else {
        return false;
    };
    let frame = I::frame4(&frame_rays);
    for g in Lanes(groups) {
        match preps.fours.get(g) {
            Some(r) if I::frame4(r) == frame => {}
            _ => return false,
        }
    }
    // The entering groups two by two (the last one, if alone, with itself); both ready
    // (checked above).
    let fours = &preps.fours;
    let mut pairs = heapless::Vec::<RayPair<'_, I::Prepared4>, { GROUPS / 2 }>::new();
    let mut pair_groups = [(0usize, 0usize); GROUPS / 2];
    let lanes_of = |g: usize| ((enter >> (4 * g)) & 0xF) as u32;
    let mut rest = groups;
    while rest != 0 {
        let ga = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let gb = if rest != 0 { rest.trailing_zeros() as usize } else { ga };
        rest &= rest.wrapping_sub(1);
        let lanes = lanes_of(ga) | if gb != ga { lanes_of(gb) << 4 } else { 0 };
        let (Some(lo), Some(hi)) = (fours.get(ga), fours.get(gb)) else { continue };
        if let Some(slot) = pair_groups.get_mut(pairs.len()) {
            *slot = (ga, gb);
        }
        // Cannot be full: at most `GROUPS / 2` pairs.
        let _ = pairs.push(RayPair { lo, hi, lanes });
    }
    let blocks = I::BLOCKS && scene.has_tri_blocks();
    let mut tris = SharedTris::default();
    let mut verts: [Option<I::Triangle>; SharedTris::SLOTS] = [None; SharedTris::SLOTS];
    let mut prims = [0u32; SharedTris::SLOTS];
    let mut done = 0u32;
    while done < count {
        let n = (count - done).min(SharedTris::SLOTS as u32) as usize;
        let start = first.wrapping_add(done);
        for (k, prim) in prims.iter_mut().take(n).enumerate() {
            *prim = bvh.prim(start.wrapping_add(k as u32), probe);
        }
        // From the leaf's blocks where the image has them and the leaf starts on one (the
        // builder aligns leaves so): in a row, with no vertex indices to follow (their
        // misses were a fifth of the bunny's packet time), four at a time.
        let from_blocks = blocks && start.is_multiple_of(4);
        for half in 0..n.div_ceil(4) {
            let block = from_blocks.then(|| scene.tri_block(start / 4 + half as u32, probe)).flatten();
            if let Some(block) = block {
                I::share_block(&frame_rays, origin, block, &mut tris, half);
                verts[4 * half..(4 * half + 4).min(SharedTris::SLOTS)].fill(None);
                continue;
            }
            for k in 4 * half..n.min(4 * half + 4) {
                let v = I::fetch(scene, prims[k], probe);
                I::share(&frame_rays, origin, &v, &mut tris, k);
                verts[k] = Some(v);
            }
        }
        done += n as u32;
        let tested = I::intersect_shared8(&pairs, &tris, n, |k, p, o| {
            let prim = prims.get(k).copied().unwrap_or(0);
            let (ga, gb) = pair_groups.get(p).copied().unwrap_or((0, 0));
            let lanes = pairs.get(p).map_or(0, |p| p.lanes);
            for lane in Lanes(((o.hit | o.redo) & lanes) as u64) {
                let i = if lane < 4 { 4 * ga + lane } else { 4 * gb + lane - 4 }.min(N - 1);
                // An undecided lane (rare) reads the triangle here if it came from a block.
                let tri = || match verts.get(k) {
                    Some(Some(v)) => *v,
                    _ => I::fetch(scene, prim, probe),
                };
                keep_lane(packet, &mut preps.ones, hits, LaneOutcome { hits: o, lane, ray: i }, prim, tri);
            }
        });
        if !tested {
            // Only the first call can fail (the CPU does not change): nothing tested.
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::image::{Bvh4Node, WideNode};
    use crate::packet::bvh4::frustum::Frustum;
    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// The AVX form of the leaf entry test (where this CPU has AVX) and the one-origin
    /// forms let exactly the portable form's rays in, for leaves the packet's frustum
    /// reaches (as in the walk): packets of every size and active mask, rays that end
    /// early, flat boxes.
    #[test]
    fn avx_leaf_entries_match_the_portable_test() {
        let mut g = Lcg(11);
        let (mut checked, mut entered) = (0, 0);
        for case in 0..3000 {
            let eye = Vec3::new(g.range(-3.0, 3.0), g.range(-3.0, 3.0), -6.0);
            // Every third case, each ray from its own point near the eye.
            let shared = case % 3 != 2;
            let rays: [Ray; 64] = core::array::from_fn(|_| {
                let target = Vec3::new(g.range(-2.0, 2.0), g.range(-2.0, 2.0), g.range(-1.0, 1.0));
                let start = if shared { eye } else { eye + Vec3::new(g.range(-0.1, 0.1), g.range(-0.1, 0.1), 0.0) };
                let mut ray = Ray::new(start, target - start);
                if g.unit() < 0.3 {
                    ray.t_max = g.range(1.0, 8.0);
                }
                ray
            });
            let n: usize = [4, 16, 64][case % 3];
            let mut packet = RayPacket::<64>::new();
            packet.fill(&rays[..n]);
            let mask = packet.active & if case % 4 == 0 { g.0 } else { u64::MAX };
            let groups = n.div_ceil(4);
            let q = Groups::new(&packet, groups, mask);
            let mut c: [f32; 3] = core::array::from_fn(|_| g.range(-2.0, 2.0));
            let mut e: [f32; 3] = core::array::from_fn(|_| if g.unit() < 0.15 { 0.0 } else { g.range(0.0, 1.5) });
            if case % 7 == 1 {
                // The rays start on a flat box: entry and exit both exactly 0.
                (c, e[2]) = (eye.to_array(), 0.0);
            }
            let leaf_box = [c[0] - e[0], c[1] - e[1], c[2] - e[2], c[0] + e[0], c[1] + e[1], c[2] + e[2]];
            // The kernel's `leaf_t`: the packet frustum's entry bound for this box.
            let Some(frustum) = Frustum::new(&q, groups, mask) else { continue };
            let mut node = Bvh4Node::EMPTY;
            node.set_slot(0, [leaf_box[0], leaf_box[1], leaf_box[2]], [leaf_box[3], leaf_box[4], leaf_box[5]], 1, 1);
            let (tn, reached) = frustum.slab4(&node, f32::INFINITY);
            if reached & 1 == 0 {
                continue;
            }
            let leaf_t = tn.x;
            let portable = leaf_entries_portable(&q, groups, mask, &leaf_box, leaf_t, None);
            // The one-origin forms, where the rays share one (the lanes' own origins
            // otherwise), let exactly the same rays in.
            let origin = frustum.origin();
            assert_eq!(origin.is_some(), shared && mask != 0, "case {case}");
            let one = leaf_entries_portable(&q, groups, mask, &leaf_box, leaf_t, origin);
            assert_eq!(one, portable, "case {case}");
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = crate::simd::Avx::detected() {
                let avx = [None, origin]
                    .map(|o| crate::simd::leaf_entries::leaf_entries(avx, &q, groups, mask, &leaf_box, o));
                assert_eq!(avx, [portable; 2], "case {case}");
            }
            assert_eq!(portable & !mask, 0, "case {case}: an inactive lane entered");
            checked += 1;
            entered += (portable != 0) as u32;
        }
        assert!(checked > 1500 && entered > 500, "{checked} leaves checked, {entered} entered");
    }
}
