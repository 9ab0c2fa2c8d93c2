//! Shadow rays that end at one point (a point light, seen from a block of pixels' hits)
//! bounded by one pyramid with its apex at that point, as MLRTA treats shadow rays: from
//! the light, they are a frustum of one origin (Reshetov, Soupikov & Hurley 2005, §2.3).
//!
//! The rays' origins lie far apart, so the frustum of their origins and directions culls
//! almost nothing (see `many_origins`), but seen from the light the segments fill a narrow
//! pyramid: four planes through the apex around the segments' starts, and a far plane
//! beyond them. A node's four boxes are tested against five planes for the whole packet,
//! where the many-origin walk tests every ray.
//!
//! The test only culls: it is conservative, with a slack far above the rounding of its
//! own arithmetic and of the exact per-ray box test (whose boxes grow by
//! [`crate::traverse::boxes::clip::SLAB_GROWTH`]), so every box that a ray's exact walk
//! enters passes it. At a leaf every ray still takes its own exact box test and its own
//! triangle tests, so each ray's answer is its single-ray any-hit answer.

use crate::image::{Bvh4Node, NULL_INDEX};
use crate::packet::{Lanes, RayPacket, MAX_PACKET};

use super::groups::{groups_of, GROUP_LANES};
use glam::{BVec4A, Vec3, Vec4};

/// Four planes around the apex and the far plane.
const PLANES: usize = 5;

/// Slack of every plane, relative to the largest coordinate involved: 2⁻¹², some 2¹⁰
/// times the relative rounding of the plane arithmetic and of the exact box test.
const SLACK: f32 = 1.0 / 4096.0;

/// The ends' box is used only while it is this many times smaller than the shortest
/// segment: a wider apex makes a pyramid no tighter than the rays' own tests.
const NARROW: f32 = 16.0;

/// The widest pyramid used, as the largest difference of its rays' slopes seen from the
/// apex: a block of pixels whose hits lie metres apart (an edge in front of a far wall)
/// makes a pyramid far wider than its rays, and the many-origin walk, ray by ray, then
/// visits fewer nodes. (Sponza's shadow rays in packets of 64 at 0.1: 1.0× the
/// many-origin walk; all pyramids: 0.5×. Lost Empire at 0.1: 0.8×, at 0.04: 0.9×.)
pub(super) const WIDE: f32 = 0.04;

/// The pyramid: per plane, a normal and a limit; a box whose least `normal · x` exceeds
/// the limit holds no point of the segments it bounds. It keeps each ray's place seen
/// from the apex, so that as rays leave the walk (blocked) it shrinks to the rest.
#[derive(Clone, Copy, Debug)]
pub(super) struct Apex {
    /// Per plane, the normal's components splatted over four lanes (one per child box).
    normal: [[Vec4; 3]; PLANES],
    /// Per plane and axis, all lanes set where the normal's component is negative: the
    /// box's upper bound then gives the least `normal · x`.
    upper: [[BVec4A; 3]; PLANES],
    limit: [Vec4; PLANES],
    /// Per axis, the scene's bounds splatted: boxes are clipped to them.
    clip: [(Vec4, Vec4); 3],
    /// The rays the planes bound.
    bounds: u64,
    /// The planes have been shrunk since the pyramid was made.
    shrunk: bool,
    /// The apex `c`, the axis `w` from it towards the starts, `a` and `b` across it, and
    /// the ends' half box grown by the slack, `h`.
    c: Vec3,
    w: Vec3,
    a: Vec3,
    b: Vec3,
    h: Vec3,
    /// Per ray, its start's slopes across the axis seen from the apex, and its distance
    /// along the axis.
    x: [Vec4; MAX_PACKET / 4],
    y: [Vec4; MAX_PACKET / 4],
    s: [Vec4; MAX_PACKET / 4],
}

impl Apex {
    /// The pyramid of the rays of `mask`, or `None` when they do not end near one point
    /// (an end at infinity, ends spread wide beside the segments, segments around the
    /// apex on all sides, a pyramid wider than [`WIDE`]) or a direction has a zero
    /// component. `bounds`: the scene's bounds, which hold every triangle; the tested
    /// boxes are clipped to them, so that the plane arithmetic's rounding stays within
    /// the slack whatever boxes an image holds. Four lanes at a time: made for every
    /// packet of shadow rays, it must cost little.
    pub(super) fn new<const N: usize>(packet: &RayPacket<N>, mask: u64, bounds: (Vec3, Vec3)) -> Option<Apex> {
        let scale = bounds.0.abs().max(bounds.1.abs()).max_element();
        if !N.is_multiple_of(4) {
            return None;
        }
        let groups = (N / 4).min(MAX_PACKET / 4);
        let lanes = |a: &[f32; N], g: usize| a.get(4 * g..4 * g + 4).map_or(Vec4::ZERO, Vec4::from_slice);
        let act = |g: usize| GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
        let start = |g: usize| {
            let t0 = lanes(&packet.t_min, g);
            [(&packet.ox, &packet.dx), (&packet.oy, &packet.dy), (&packet.oz, &packet.dz)]
                .map(|(o, d)| lanes(o, g) + lanes(d, g) * t0)
        };
        let (inf, ninf) = (Vec4::INFINITY, Vec4::NEG_INFINITY);
        let (mut lo, mut hi, mut m) = ([inf; 3], [ninf; 3], Vec4::splat(scale));
        let mut bad = false;
        for g in 0..groups {
            let on = act(g);
            let (s, t1) = (start(g), lanes(&packet.t_max, g));
            for (a, (o, d)) in
                [(&packet.ox, &packet.dx), (&packet.oy, &packet.dy), (&packet.oz, &packet.dz)].into_iter().enumerate()
            {
                let (o, d) = (lanes(o, g), lanes(d, g));
                let e = o + d * t1;
                // A zero component, or an end or start not finite (its size is not below ∞).
                let finite = e.abs().cmplt(inf) & s[a].abs().cmplt(inf);
                bad |= ((d.cmpeq(Vec4::ZERO) | !finite) & on).any();
                lo[a] = lo[a].min(Vec4::select(on, e, inf));
                hi[a] = hi[a].max(Vec4::select(on, e, ninf));
                m = m.max(Vec4::select(on, e.abs().max(s[a].abs()), Vec4::ZERO));
            }
        }
        let m = m.max_element();
        let (lo, hi) = (Vec3::from(lo.map(|v| v.min_element())), Vec3::from(hi.map(|v| v.max_element())));
        if bad || !m.is_finite() || lo.cmpgt(hi).any() {
            return None;
        }
        let c = (lo + hi) * 0.5;
        // The ends' half box, grown by the slack: it bounds every rounding error below.
        let h = (hi - lo) * 0.5 + Vec3::splat(m * SLACK);
        let (mut axis, mut shortest) = ([Vec4::ZERO; 3], inf);
        for g in 0..groups {
            let (on, s) = (act(g), start(g));
            let p = [0, 1, 2].map(|a| Vec4::select(on, s[a] - Vec4::splat(c[a]), Vec4::ZERO));
            for a in 0..3 {
                axis[a] += p[a];
            }
            shortest = shortest.min(Vec4::select(on, p[0] * p[0] + p[1] * p[1] + p[2] * p[2], inf));
        }
        let narrow = h.max_element() * NARROW;
        // (Every coordinate is finite here, so neither side is NaN.)
        if shortest.min_element() <= narrow * narrow {
            return None;
        }
        let w = Vec3::new(axis[0].element_sum(), axis[1].element_sum(), axis[2].element_sum()).normalize_or_zero();
        let (a, b) = w.any_orthonormal_pair();
        let mut apex = Apex {
            normal: [[Vec4::ZERO; 3]; PLANES],
            upper: [[BVec4A::new(false, false, false, false); 3]; PLANES],
            limit: [Vec4::ZERO; PLANES],
            clip: [0, 1, 2].map(|k| (Vec4::splat(bounds.0[k]), Vec4::splat(bounds.1[k]))),
            bounds: 0,
            shrunk: false,
            c,
            w,
            a,
            b,
            h,
            x: [Vec4::ZERO; MAX_PACKET / 4],
            y: [Vec4::ZERO; MAX_PACKET / 4],
            s: [Vec4::ZERO; MAX_PACKET / 4],
        };
        let dot = |p: &[Vec4; 3], v: Vec3| p[0] * v.x + p[1] * v.y + p[2] * v.z;
        for g in 0..groups {
            let (on, st) = (act(g), start(g));
            let p = [0, 1, 2].map(|k| st[k] - Vec4::splat(c[k]));
            let s = dot(&p, w);
            // A start beside or behind the apex (the pyramid would open too wide).
            let len2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
            if ((s.cmple(Vec4::ZERO) | (s * s * 4.0).cmple(len2)) & on).any() {
                return None;
            }
            if let (Some(x), Some(y), Some(sl)) = (apex.x.get_mut(g), apex.y.get_mut(g), apex.s.get_mut(g)) {
                (*x, *y, *sl) = (dot(&p, a) / s, dot(&p, b) / s, s);
            }
        }
        apex.bound(mask).is_some_and(|spread| spread <= WIDE).then_some(apex)
    }

    /// Shrinks the pyramid to the rays of `mask` (a subset of those it bounds) once they
    /// are three quarters of them or fewer; `false` if it is empty.
    #[inline(always)]
    pub(super) fn shrink(&mut self, mask: u64) -> bool {
        let (now, was) = (mask.count_ones(), self.bounds.count_ones());
        if mask == 0 {
            return false;
        }
        if 4 * now <= 3 * was && self.bound(mask).is_some() {
            self.shrunk = true;
        }
        true
    }

    /// The planes have been shrunk since the pyramid was made: children pushed before
    /// may lie outside them now (before, every pushed child passed these very planes).
    #[inline(always)]
    pub(super) fn shrunk(&self) -> bool {
        self.shrunk
    }

    /// The planes around the rays of `mask`, and the pyramid's width (the largest
    /// difference of their slopes); `None`, and the planes kept, if a limit is not finite
    /// (the old planes bound a superset of the rays: still conservative).
    fn bound(&mut self, mask: u64) -> Option<f32> {
        let (inf, ninf) = (Vec4::INFINITY, Vec4::NEG_INFINITY);
        let (mut x0, mut x1, mut y0, mut y1, mut far) = (inf, ninf, inf, ninf, ninf);
        for g in Lanes(groups_of(mask)) {
            let on = GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
            let (x, y, s) = (self.x[g % 16], self.y[g % 16], self.s[g % 16]);
            (x0, x1) = (x0.min(Vec4::select(on, x, inf)), x1.max(Vec4::select(on, x, ninf)));
            (y0, y1) = (y0.min(Vec4::select(on, y, inf)), y1.max(Vec4::select(on, y, ninf)));
            far = far.max(Vec4::select(on, s, ninf));
        }
        let (x0, x1, y0, y1) = (x0.min_element(), x1.max_element(), y0.min_element(), y1.max_element());
        let far = far.max_element();
        let (w, a, b) = (self.w, self.a, self.b);
        // Each start lies on the near side of the four planes through the apex, up to
        // the rounding of its slopes (within the slack); each end within `|n| · h` of it.
        let planes = [(a - w * x1, 0.0), (w * x0 - a, 0.0), (b - w * y1, 0.0), (w * y0 - b, 0.0), (w, far)];
        let limits = planes.map(|(n, reach)| reach + n.abs().dot(self.h) + n.dot(self.c));
        if !limits.iter().all(|l| l.is_finite()) {
            return None;
        }
        for (k, ((n, _), limit)) in planes.into_iter().zip(limits).enumerate() {
            self.normal[k] = [Vec4::splat(n.x), Vec4::splat(n.y), Vec4::splat(n.z)];
            self.upper[k] = [n.x, n.y, n.z].map(|v| BVec4A::splat(v < 0.0));
            self.limit[k] = Vec4::splat(limit);
        }
        self.bounds = mask;
        Some((x1 - x0).max(y1 - y0))
    }

    /// Whether the box `b` (min xyz, max xyz) may hold a point of some segment: one
    /// box of [`Apex::cull4`]'s test, for a child waiting on the stack while the pyramid
    /// shrank.
    #[inline(always)]
    pub(super) fn holds(&self, b: &[f32; 6]) -> bool {
        (0..PLANES).all(|k| {
            let (nk, up) = (&self.normal[k], &self.upper[k]);
            let least = |a: usize| {
                let (lo, hi) = (b[a].max(self.clip[a].0.x), b[3 + a].min(self.clip[a].1.x));
                nk[a].x * if up[a].test(0) { hi } else { lo }
            };
            least(0) + least(1) + least(2) <= self.limit[k].x
        })
    }

    /// Which of `n`'s four boxes may hold a point of some segment.
    #[inline(always)]
    pub(super) fn cull4(&self, n: &Bvh4Node) -> u32 {
        let (c, mins, maxs) = (&self.clip, [n.min_x, n.min_y, n.min_z], [n.max_x, n.max_y, n.max_z]);
        let lo: [Vec4; 3] = core::array::from_fn(|a| Vec4::from_array(mins[a]).max(c[a].0));
        let hi: [Vec4; 3] = core::array::from_fn(|a| Vec4::from_array(maxs[a]).min(c[a].1));
        let mut out = BVec4A::new(false, false, false, false);
        for k in 0..PLANES {
            let (nk, up) = (&self.normal[k], &self.upper[k]);
            let least = |a: usize| nk[a] * Vec4::select(up[a], hi[a], lo[a]);
            out |= (least(0) + least(1) + least(2)).cmpgt(self.limit[k]);
        }
        let valid = (0..4).fold(0u32, |m, k| m | (((n.child[k] != NULL_INDEX) as u32) << k));
        !out.bitmask() & valid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::image::Bvh4Node;
    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use crate::traverse::boxes::slab::RayBox;

    /// A node of four boxes, one per slot, all children present.
    fn node(boxes: [([f32; 3], [f32; 3]); 4]) -> Bvh4Node {
        let mut n: Bvh4Node = bytemuck::Zeroable::zeroed();
        for (k, (lo, hi)) in boxes.into_iter().enumerate() {
            (n.min_x[k], n.min_y[k], n.min_z[k]) = (lo[0], lo[1], lo[2]);
            (n.max_x[k], n.max_y[k], n.max_z[k]) = (hi[0], hi[1], hi[2]);
            n.child[k] = k as u32;
        }
        n
    }

    /// Boxes that some segment enters by its exact box test are never culled, and boxes
    /// far off the pyramid are: shadow segments from scattered points to one light, tiny
    /// and huge coordinates.
    #[test]
    fn the_pyramid_keeps_every_box_a_segment_enters() {
        let mut g = Lcg(11);
        let (mut kept, mut culled, mut built) = (0u32, 0u32, 0u32);
        for case in 0..3000 {
            let scale = [1e-3f32, 1.0, 1e3][case % 3];
            let light = Vec3::new(g.range(-1.0, 1.0), g.range(2.0, 4.0), g.range(-1.0, 1.0)) * scale;
            let centre = Vec3::new(g.range(-2.0, 2.0), g.range(-1.0, 0.0), g.range(-2.0, 2.0)) * scale;
            let spread = [0.005f32, 0.03, 0.1][(case / 3) % 3] * scale;
            let rays: [Ray; 16] = core::array::from_fn(|_| {
                let p =
                    centre + Vec3::new(g.range(-spread, spread), g.range(-spread, spread), g.range(-spread, spread));
                Ray { origin: p, dir: light - p, t_min: 0.0, t_max: 1.0 - 1e-4 }
            });
            let mut packet = RayPacket::<16>::new();
            packet.fill(&rays);
            let Some(whole) = Apex::new(&packet, packet.live(), (Vec3::splat(-4.0 * scale), Vec3::splat(4.0 * scale)))
            else {
                continue;
            };
            built += 1;
            // Every other case, the pyramid shrunk to the rays some lanes of a mask leave.
            let mut apex = whole;
            let left = if case % 2 == 0 { 0x0F0F & (g.next() | 1) } else { 0xFFFF };
            assert!(apex.shrink(left));
            for _ in 0..20 {
                // Boxes about a segment's point (entered) or anywhere (mostly not).
                let boxes: [([f32; 3], [f32; 3]); 4] = core::array::from_fn(|k| {
                    let r = &rays[(g.next() % 16) as usize];
                    let at = if k % 2 == 0 {
                        r.origin + r.dir * g.range(0.0, 1.0)
                    } else {
                        Vec3::new(g.range(-4.0, 4.0), g.range(-4.0, 4.0), g.range(-4.0, 4.0)) * scale
                    };
                    let half = Vec3::splat(g.range(0.0, 0.05) * scale);
                    ((at - half).to_array(), (at + half).to_array())
                });
                let n = node(boxes);
                let pass = apex.cull4(&n);
                for (k, (lo, hi)) in boxes.iter().enumerate() {
                    let flat = [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]];
                    assert_eq!(apex.holds(&flat), pass & (1 << k) != 0, "case {case}: one box's test differs");
                    let enters = rays.iter().enumerate().filter(|(i, _)| left & (1 << i) != 0).any(|(_, r)| {
                        RayBox::new(r).entry(Vec3::from(*lo).into(), Vec3::from(*hi).into(), r.t_min, r.t_max).is_some()
                    });
                    if enters {
                        assert!(
                            pass & (1 << k) != 0,
                            "case {case}: culled box {k} {lo:?}..{hi:?} that a segment enters"
                        );
                        kept += 1;
                    } else if pass & (1 << k) == 0 {
                        culled += 1;
                    }
                }
            }
        }
        assert!(built > 1500 && kept > 10_000 && culled > 10_000, "built {built}, kept {kept}, culled {culled}");
    }

    /// No pyramid for rays without a common end, or with one at infinity.
    #[test]
    fn rays_without_one_end_have_no_pyramid() {
        let light = Vec3::new(0.25, 5.0, 0.5);
        let seg = |p: Vec3, t_max: f32| Ray { origin: p, dir: light - p, t_min: 0.0, t_max };
        let far = [seg(Vec3::new(-1.0, 0.0, 0.0), f32::INFINITY), seg(Vec3::new(1.0, 0.0, 0.0), 1.0)];
        let spread = [seg(Vec3::new(-1.0, 0.0, 0.0), 0.5), seg(Vec3::new(1.0, 0.0, 0.0), 0.99)];
        let around = [seg(Vec3::new(0.0, 0.0, 0.0), 1.0), seg(Vec3::new(0.0, 10.0, 0.0), 1.0)];
        let zero = [seg(Vec3::new(0.25, 0.0, 0.0), 1.0), seg(Vec3::new(1.0, 0.0, 0.0), 1.0)];
        for rays in [far, spread, around, zero] {
            let mut packet = RayPacket::<4>::new();
            packet.fill(&rays);
            assert!(Apex::new(&packet, packet.live(), (Vec3::splat(-10.0), Vec3::splat(10.0))).is_none(), "{rays:?}");
        }
        let wide = [seg(Vec3::new(-1.0, 0.0, 0.0), 1.0), seg(Vec3::new(1.0, 0.0, 0.25), 1.0)];
        let mut packet = RayPacket::<4>::new();
        packet.fill(&wide);
        assert!(
            Apex::new(&packet, packet.live(), (Vec3::splat(-10.0), Vec3::splat(10.0))).is_none(),
            "wider than WIDE"
        );
        let ok = [seg(Vec3::new(-0.05, 0.0, 0.0), 1.0), seg(Vec3::new(0.05, 0.0, 0.025), 1.0)];
        let mut packet = RayPacket::<4>::new();
        packet.fill(&ok);
        assert!(Apex::new(&packet, packet.live(), (Vec3::splat(-10.0), Vec3::splat(10.0))).is_some());
    }
}
