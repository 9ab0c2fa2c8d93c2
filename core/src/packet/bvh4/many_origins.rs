//! The any-hit query for a packet of rays of many origins (shadow rays from a block of
//! pixels' hits to a light) through the 4-wide BVH: each node's boxes are tested against
//! the packet's rays four at a time, SIMD across rays (as Embree's packet kernels do,
//! Wald et al. 2001 §4), with no frustum: the rays' origins lie far apart along the
//! light's direction, and a frustum bounding them culled almost nothing.
//!
//! A box's test in lane `i` is [`slab4_exact`]'s for ray `i` with the plane operations in
//! the same order, so a child's ray mask holds exactly the rays whose single-ray walk
//! enters it; each ray then meets a leaf's triangles through the single-ray leaf test.
//! The packet descends into a child with the rays that enter it and drops a ray at its
//! first hit: the answer of each ray is its single-ray any-hit answer.

use glam::Vec4;

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView};
use crate::intersect::triangle::Intersector;
use crate::packet::{occluded_lanes_ray_by_ray, Lanes, LanesOf, PacketCounters, RayPacket};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::wide_bvh::node4::occluded_bvh4;
use crate::traverse::wide_bvh::test_wide_leaf;

use super::groups::{groups_of, GROUP_LANES};
use super::rays16::{leaf_blocks16, shear16};
use super::walk::STACK;
#[cfg(target_arch = "x86_64")]
use crate::simd::rays16::{boxes16, BoxLanes};
use crate::simd::Wide16;
use crate::traverse::boxes::clip::SLAB_GROWTH;
use crate::traverse::boxes::slab::recip4;

/// Rays of one frame entering a leaf from which the sixteen-lane test pays: it costs
/// about what one ray's test of a leaf costs (four triangles per instruction).
const WIDE_LEAF_RAYS: u32 = 4;

/// Groups of four lanes in the largest packet.
const MAX_GROUPS: usize = 16;

/// The packet's rays as groups of four SIMD lanes: origins, reciprocal directions (near
/// and far, see [`RayBox`]) and intervals. Lanes not walked here hold an empty interval.
///
/// [`RayBox`]: crate::traverse::boxes::slab::RayBox
struct RayGroups {
    // Per axis, per group: the lanes of one axis lie in a row (sixteen rays in one
    // AVX-512 register, `simd::rays16`).
    org: [[Vec4; MAX_GROUPS]; 3],
    inv: [[Vec4; MAX_GROUPS]; 3],
    inv_far: [[Vec4; MAX_GROUPS]; 3],
    t0: [Vec4; MAX_GROUPS],
    t1: [Vec4; MAX_GROUPS],
    /// Per axis, the rays' direction signs agree (bit set: all negative), or `None`.
    octant: Option<[bool; 3]>,
}

impl RayGroups {
    /// The groups of the rays of `mask`, and the rays of `mask` left out: those with a
    /// zero direction component, whose axis needs `RayBox`'s exact rule.
    /// Every group empty: no lane enters a box.
    const EMPTY: RayGroups = RayGroups {
        org: [[Vec4::ZERO; MAX_GROUPS]; 3],
        inv: [[Vec4::ZERO; MAX_GROUPS]; 3],
        inv_far: [[Vec4::ZERO; MAX_GROUPS]; 3],
        t0: [Vec4::INFINITY; MAX_GROUPS],
        t1: [Vec4::NEG_INFINITY; MAX_GROUPS],
        octant: None,
    };

    /// The groups, written into `slot` in place: built elsewhere and returned, the three
    /// kilobytes were copied once more per packet (4% of Sibenik's shadow packet time).
    #[inline(always)]
    fn fill<'s, const N: usize>(
        slot: &'s mut Option<RayGroups>,
        packet: &RayPacket<N>,
        mask: u64,
    ) -> (&'s RayGroups, u64) {
        let q = slot.insert(RayGroups::EMPTY);
        // Group by group from the packet's arrays, as `RayBox::new` makes each ray's
        // (lane by lane the same reciprocals): building each lane's `Ray` stalled on
        // its stores.
        let lanes = |a: &[f32; N], g: usize| match a.get(4 * g..4 * g + 4) {
            Some(l) => Vec4::from_slice(l),
            None => Vec4::from_array(core::array::from_fn(|k| a.get(4 * g + k).copied().unwrap_or(0.0))),
        };
        let mut exact = 0u64;
        // Per axis: every walked ray's direction negative, every one positive.
        let (mut all_neg, mut all_pos) = ([true; 3], [true; 3]);
        for g in 0..N.div_ceil(4).min(MAX_GROUPS) {
            let m4 = ((mask >> (4 * g)) & 0xF) as usize;
            if m4 == 0 {
                continue;
            }
            let d = [lanes(&packet.dx, g), lanes(&packet.dy, g), lanes(&packet.dz, g)];
            let zero = (d[0].cmpeq(Vec4::ZERO) | d[1].cmpeq(Vec4::ZERO) | d[2].cmpeq(Vec4::ZERO)).bitmask() as usize;
            exact |= ((zero & m4) as u64) << (4 * g);
            let walked = m4 & !zero;
            let act = GROUP_LANES[walked];
            let o = [lanes(&packet.ox, g), lanes(&packet.oy, g), lanes(&packet.oz, g)];
            for a in 0..3 {
                let inv = recip4(d[a]);
                q.org[a][g] = Vec4::select(act, o[a], Vec4::ZERO);
                q.inv[a][g] = Vec4::select(act, inv, Vec4::ZERO);
                q.inv_far[a][g] = Vec4::select(act, inv * SLAB_GROWTH, Vec4::ZERO);
                let neg = inv.cmplt(Vec4::ZERO).bitmask() as usize & walked;
                all_neg[a] &= neg == walked;
                all_pos[a] &= neg == 0;
            }
            q.t0[g] = Vec4::select(act, lanes(&packet.t_min, g), Vec4::INFINITY);
            q.t1[g] = Vec4::select(act, lanes(&packet.t_max, g), Vec4::NEG_INFINITY);
        }
        // No ray walked here: any octant (no lane enters a box).
        let agree = (0..3).fold(true, |ok, a| ok & (all_neg[a] | all_pos[a]));
        q.octant = agree.then(|| core::array::from_fn(|a| all_neg[a] & !all_pos[a]));
        (q, exact)
    }

    /// The rays of group `g` (bits 0–3) that enter each of `node`'s four boxes.
    #[inline(always)]
    fn enter(&self, node: &Bvh4Node, g: usize) -> [u32; 4] {
        let g = g % MAX_GROUPS;
        let lanes = |v: &[[Vec4; MAX_GROUPS]; 3]| [v[0][g], v[1][g], v[2][g]];
        let (o, inv, inv_far) = (lanes(&self.org), lanes(&self.inv), lanes(&self.inv_far));
        let lo = [&node.min_x, &node.min_y, &node.min_z];
        let hi = [&node.max_x, &node.max_y, &node.max_z];
        let mut out = [0u32; 4];
        for (k, out) in out.iter_mut().enumerate() {
            // Empty slots hold inverted boxes: never entered.
            if node.min_x[k] > node.max_x[k] {
                continue;
            }
            let plane = |p: &[f32; 4], a: usize| Vec4::splat(p[k]) - o[a];
            let (near, far): ([Vec4; 3], [Vec4; 3]) = match self.octant {
                // One octant: the near plane's product is the smaller for every lane
                // (the products are monotone in the plane), as `slab4_exact`'s min and
                // max pick for a valid box.
                Some(neg) => {
                    let pick = |a: usize| if neg[a] { (hi[a], lo[a]) } else { (lo[a], hi[a]) };
                    let near = core::array::from_fn(|a| plane(pick(a).0, a) * inv[a]);
                    let far = core::array::from_fn(|a| plane(pick(a).1, a) * inv_far[a]);
                    (near, far)
                }
                None => {
                    let near = core::array::from_fn(|a| (plane(lo[a], a) * inv[a]).min(plane(hi[a], a) * inv[a]));
                    let far =
                        core::array::from_fn(|a| (plane(lo[a], a) * inv_far[a]).max(plane(hi[a], a) * inv_far[a]));
                    (near, far)
                }
            };
            let tn = near[0].max(near[1]).max(near[2].max(self.t0[g]));
            let tf = far[0].min(far[1]).min(far[2].min(self.t1[g]));
            *out = tn.cmple(tf).bitmask();
        }
        out
    }

    /// The rays of `rays` that enter each of `node`'s four boxes: sixteen lanes at once
    /// where `wide` holds a sixteen-lane token (packets of up to 16), else group by group.
    #[inline(always)]
    fn node_entries(&self, node: &Bvh4Node, rays: u64, wide: Option<Wide16>) -> [u64; 4] {
        let mut enter = [0u64; 4];
        #[cfg(target_arch = "x86_64")]
        if let Some(wide) = wide {
            let lanes = BoxLanes {
                org: &self.org,
                inv: &self.inv,
                inv_far: &self.inv_far,
                t0: &self.t0,
                t1: &self.t1,
                octant: self.octant,
            };
            let m = boxes16(wide, &lanes, node, rays as u32);
            for (k, enter) in enter.iter_mut().enumerate() {
                *enter = (m >> (16 * k)) & 0xFFFF & rays;
            }
            return enter;
        }
        let _ = wide;
        for g in Lanes(groups_of(rays)) {
            let m = self.enter(node, g);
            let mine = (rays >> (4 * g)) & 0xF;
            for k in 0..4 {
                enter[k] |= (u64::from(m[k]) & mine) << (4 * g);
            }
        }
        enter
    }
}

/// Bit `i` set when ray `i` of `live` (live lanes of `packet`) is blocked within its interval: exactly
/// [`occluded_bvh4`] for each ray, for rays of any origins (see the module's text).
pub(super) fn occluded_many_origins<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    live: u64,
    found: &mut Option<(u32, u32)>,
    probe: &mut P,
    counters: &mut PacketCounters,
) -> u64 {
    let mut slot = None;
    let (q, exact) = RayGroups::fill(&mut slot, packet, live);
    let mut c = PacketCounters::default();
    // Rays with a zero direction component: the single-ray walk, which has the exact rule.
    let any = |r: &Ray, rc: &mut RayCounters| occluded_bvh4::<I, P>(scene, bvh, r, probe, rc);
    let mut blocked = occluded_lanes_ray_by_ray(packet, exact, &mut c, any);
    let blocks = scene.has_tri_blocks();
    let mut todo = live & !exact;
    // Each ray's intersection constants, made at its first leaf (most rays reach few).
    let mut preps = [None::<I::Prepared>; N];
    // Packets of up to 16 where the CPU has AVX: nodes and leaves sixteen lanes at
    // a time; the sixteen-lane constants made at the first leaf that needs them.
    let wide = Wide16::reported().filter(|_| N <= 16);
    let mut wide16: Option<Option<(I::Prepared16, u32)>> = None;
    // (child or first entry, leaf count or 0, the rays that enter it)
    let mut stack: heapless::Vec<(u32, u32, u64), STACK> = heapless::Vec::new();
    let mut current = (0u32, 0u32, todo);
    loop {
        let (index, count, rays) = current;
        let rays = rays & todo;
        if rays != 0 {
            c.visits += 1;
            c.active_lanes += rays.count_ones() as u64;
            if count == 0 {
                let node = bvh.node(index, probe);
                let enter = q.node_entries(node, rays, wide);
                // Children in slot order: an any-hit walk needs no order, and sorting by
                // the nearest entry of any ray measured 6% slower on Sponza's shadow rays.
                // The first entered is next, the others wait on the stack.
                let mut next = None;
                for k in (0..4).rev().filter(|&k| enter[k] != 0) {
                    if let Some(n) = next.replace((node.child[k], node.count[k], enter[k])) {
                        // Cannot be full: `parse` bounds the depth (see `STACK`).
                        let _ = stack.push(n);
                    }
                }
                if let Some(n) = next {
                    current = n;
                    continue;
                }
            } else {
                // Four rays or more of one frame: the sixteen-lane test, each triangle
                // read once for them.
                let mut rays = rays;
                if wide.is_some() && rays.count_ones() >= WIDE_LEAF_RAYS {
                    let shear = wide16.get_or_insert_with(|| shear16::<I, N>(packet, todo as u32));
                    if let Some((shear, covered)) = shear {
                        let lanes = rays as u32 & *covered;
                        if lanes.count_ones() >= WIDE_LEAF_RAYS {
                            let leaf = (index, count);
                            let b = leaf_blocks16::<I, P, N>(
                                scene,
                                bvh,
                                packet,
                                shear,
                                (lanes, 0),
                                leaf,
                                Some(&preps),
                                probe,
                            );
                            c.tri_tests += u64::from(count) * u64::from(lanes.count_ones());
                            if b != 0 {
                                blocked |= u64::from(b);
                                todo &= !u64::from(b);
                                *found = Some(leaf);
                            }
                            rays &= !u64::from(lanes);
                        }
                    }
                }
                for i in LanesOf::<N>(rays) {
                    let ray = packet.ray(i);
                    let Some(slot) = preps.get_mut(i) else { continue };
                    let prep = *slot.get_or_insert_with(|| I::prepare(&ray));
                    let mut best: Option<Hit> = None;
                    test_wide_leaf::<I, P, _, true>(scene, bvh, &prep, &ray, (index, count), &mut best, blocks, probe);
                    c.tri_tests += u64::from(count);
                    if best.is_some() {
                        blocked |= 1 << i;
                        todo &= !(1 << i);
                        *found = Some((index, count));
                    }
                }
                if todo == 0 {
                    break;
                }
            }
        }
        match stack.pop() {
            Some(n) => current = n,
            None => break,
        }
    }
    counters.add(&c);
    blocked & live
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::traverse::boxes::slab::RayBox;

    use crate::image::WideNode;
    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// The groups made from the packet's arrays hold, lane by lane, each walked ray's
    /// `RayBox` bit for bit and its interval; rays with a zero direction component are
    /// left out, and the octant is the walked rays' common one.
    #[test]
    fn ray_groups_hold_each_rays_box() {
        let mut g = Lcg(43);
        let (mut walked, mut left_out, mut octants) = (0, 0, 0);
        for case in 0..3000 {
            let light = Vec3::new(g.range(-9.0, 9.0), 9.0, g.range(-9.0, 9.0));
            let rays: [Ray; 64] = core::array::from_fn(|i| {
                let o = Vec3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(-1.0, 1.0));
                let mut d =
                    if case % 2 == 0 { light - o } else { Vec3::new(g.range(-1.0, 1.0), 1.0, g.range(-1.0, 1.0)) };
                if (i + case) % 13 == 0 {
                    d.x = 0.0;
                }
                Ray { origin: o, dir: d, t_min: g.range(0.0, 0.1), t_max: g.range(1.0, 9.0) }
            });
            let n: usize = [16, 64, 4][case % 3];
            let mut packet = RayPacket::<64>::new();
            packet.fill(&rays[..n]);
            let mask = packet.live() & if case % 4 == 0 { g.next() } else { u64::MAX };
            let mut slot = None;
            let (q, exact) = RayGroups::fill(&mut slot, &packet, mask);
            let mut signs = None;
            let mut agree = true;
            for i in 0..64 {
                let (gr, l) = (i / 4, i % 4);
                let rb = RayBox::new(&rays[i.min(n - 1)]);
                let walk = mask & (1 << i) != 0 && rb.zero_axes == 0;
                assert_eq!(exact & (1 << i) != 0, mask & (1 << i) != 0 && rb.zero_axes != 0, "case {case} lane {i}");
                if !walk {
                    assert_eq!((q.t0[gr][l], q.t1[gr][l]), (f32::INFINITY, f32::NEG_INFINITY), "case {case} lane {i}");
                    left_out += 1;
                    continue;
                }
                for a in 0..3 {
                    let bits = |v: f32| v.to_bits();
                    assert_eq!(bits(q.org[a][gr][l]), bits(rb.origin[a]), "case {case} lane {i}");
                    assert_eq!(bits(q.inv[a][gr][l]), bits(rb.inv[a]), "case {case} lane {i}");
                    assert_eq!(bits(q.inv_far[a][gr][l]), bits(rb.inv_far[a]), "case {case} lane {i}");
                }
                assert_eq!((q.t0[gr][l], q.t1[gr][l]), (rays[i].t_min, rays[i].t_max), "case {case} lane {i}");
                let neg = [rb.inv.x < 0.0, rb.inv.y < 0.0, rb.inv.z < 0.0];
                agree &= *signs.get_or_insert(neg) == neg;
                walked += 1;
            }
            let want = agree.then(|| signs.unwrap_or_default());
            assert_eq!(q.octant, want, "case {case}");
            octants += u32::from(want.is_some());
        }
        assert!(
            walked > 50_000 && left_out > 5_000 && octants > 500,
            "{walked} walked, {left_out} left out, {octants}"
        );
    }

    /// In each of its forms this CPU has (AVX-512, AVX), the sixteen-lane node test lets
    /// exactly the rays of the four-lane groups' test into each box, for packets of one
    /// octant and of many, rays with intervals, boxes flat or empty, and any subset of the
    /// rays (some in one half of the lanes only).
    #[test]
    fn sixteen_lane_boxes_match_the_groups_test() {
        for form in crate::simd::Wide16::detected_forms().into_iter().flatten() {
            sixteen_lane_boxes_match_in(form);
        }
    }

    fn sixteen_lane_boxes_match_in(form: Wide16) {
        let mut g = Lcg(41);
        let (mut checked, mut entered, mut one_octant) = (0, 0, 0);
        for case in 0..3000 {
            let light = Vec3::new(g.range(-9.0, 9.0), 9.0, g.range(-9.0, 9.0));
            // A block of pixels' hits (near each other), or points anywhere.
            let (centre, spread) = (Vec3::new(g.range(-2.0, 2.0), g.range(-2.0, 0.0), g.range(-2.0, 2.0)), 1.0);
            let spread = if case % 4 < 2 { spread * 0.2 } else { spread * 3.0 };
            let rays: [Ray; 16] = core::array::from_fn(|_| {
                let o =
                    centre + Vec3::new(g.range(-spread, spread), g.range(-spread, spread), g.range(-spread, spread));
                let d = if case % 2 == 0 {
                    light - o
                } else {
                    Vec3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(-1.0, 1.0))
                };
                let mut ray = Ray::new(o, d);
                if g.unit() < 0.3 {
                    (ray.t_min, ray.t_max) = (g.range(0.0, 0.5), g.range(0.5, 3.0));
                }
                ray
            });
            let mut packet = RayPacket::<16>::new();
            packet.fill(&rays);
            if case % 7 == 1 {
                packet.t_min[0] = 0.0;
            }
            // Any subset, all rays, or rays of one half of the lanes (the AVX form skips
            // the other half).
            let half = [0x00FF_u64, 0xFF00][case % 2];
            let pick = match case % 3 {
                0 => g.next(),
                1 => u64::MAX,
                _ => half & (g.next() | 1 << (8 * (case % 2))),
            };
            let mask = packet.live() & pick;
            let mut slot = None;
            let (q, exact) = RayGroups::fill(&mut slot, &packet, mask);
            one_octant += u32::from(q.octant.is_some());
            let mut node = Bvh4Node::EMPTY;
            for k in 0..4 {
                if case % 5 == k {
                    continue;
                }
                let c: [f32; 3] = core::array::from_fn(|_| g.range(-3.0, 3.0));
                let e: [f32; 3] = core::array::from_fn(|_| if g.unit() < 0.1 { 0.0 } else { g.range(0.0, 2.0) });
                node.set_slot(k, core::array::from_fn(|a| c[a] - e[a]), core::array::from_fn(|a| c[a] + e[a]), 1, 1);
            }
            if case % 7 == 1 {
                // A flat box through the first ray's origin: entry and exit both 0.
                let o = rays[0].origin;
                node.set_slot(0, [o.x - 1.0, o.y - 1.0, o.z], [o.x + 1.0, o.y + 1.0, o.z], 1, 1);
            }
            let rays_in = mask & !exact;
            let groups = q.node_entries(&node, rays_in, None);
            let wide = q.node_entries(&node, rays_in, Some(form));
            assert_eq!(wide, groups, "case {case} ({form:?})");
            checked += 1;
            entered += groups.iter().map(|m| m.count_ones()).sum::<u32>();
        }
        assert!(checked == 3000 && entered > 5_000 && one_octant > 500, "{entered} entries, {one_octant} one-octant");
    }
}
