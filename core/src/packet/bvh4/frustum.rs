//! The packet as one conservative frustum: interval arithmetic on the box of its
//! origins and reciprocal directions culls a node's four boxes for all rays at once
//! (Reshetov et al. 2005; Wald et al. 2007).

use crate::image::{Bvh4Node, Bvh8Node};
use crate::packet::RayPacket;
use crate::traverse::boxes::clip::SLAB_GROWTH;
use crate::traverse::boxes::slab::recip;
use glam::Vec4;

use super::groups::{Groups, GROUPS, GROUP_LANES};

/// The packet as one conservative "frustum": the box of its origins and of its
/// reciprocal directions. Interval arithmetic on these bounds gives, for a box, an entry
/// distance no larger and an exit no smaller than any single ray's (rounding is monotone,
/// so the bounds are attained at the corners), hence a box rejected for the packet is
/// rejected by every ray (Reshetov et al. 2005; Wald et al. 2007).
#[derive(Clone, Copy, Debug)]
pub(in crate::packet) struct Frustum {
    // Per axis, splatted over four lanes (one per child box).
    olo: [Vec4; 3],
    ohi: [Vec4; 3],
    ilo: [Vec4; 3],
    ihi: [Vec4; 3],
    t_min: f32,
    // All origins are one point (a pinhole camera's primary rays): half of the interval
    // products coincide, and the node test skips them.
    one_origin: bool,
}

impl Frustum {
    /// The frustum of the packet's active lanes; `None` if a direction has a zero
    /// component (the exact per-ray rule of `RayBox` is needed then).
    pub(in crate::packet) fn new(q: &Groups, groups: usize, mask: u64) -> Option<Frustum> {
        if q.zero_dir {
            return None;
        }
        let (inf, ninf) = (Vec4::INFINITY, Vec4::NEG_INFINITY);
        let (mut olo, mut ohi, mut ilo, mut ihi, mut t_min) = ([inf; 3], [ninf; 3], [inf; 3], [ninf; 3], inf);
        for g in 0..groups.min(GROUPS) {
            let m4 = ((mask >> (4 * g)) & 0xF) as usize;
            if m4 == 0xF {
                // All four lanes active (most groups): no lane to mask out.
                for a in 0..3 {
                    olo[a] = olo[a].min(q.org[a][g]);
                    ohi[a] = ohi[a].max(q.org[a][g]);
                    ilo[a] = ilo[a].min(q.inv[a][g]);
                    ihi[a] = ihi[a].max(q.inv[a][g]);
                }
                t_min = t_min.min(q.t_min[g]);
                continue;
            }
            let act = GROUP_LANES[m4];
            for a in 0..3 {
                olo[a] = olo[a].min(Vec4::select(act, q.org[a][g], inf));
                ohi[a] = ohi[a].max(Vec4::select(act, q.org[a][g], ninf));
                ilo[a] = ilo[a].min(Vec4::select(act, q.inv[a][g], inf));
                ihi[a] = ihi[a].max(Vec4::select(act, q.inv[a][g], ninf));
            }
            t_min = t_min.min(Vec4::select(act, q.t_min[g], inf));
        }
        let (olo, ohi) = (olo.map(|v| Vec4::splat(v.min_element())), ohi.map(|v| Vec4::splat(v.max_element())));
        let one_origin = (0..3).all(|a| olo[a].x.to_bits() == ohi[a].x.to_bits());
        Some(Frustum {
            olo,
            ohi,
            one_origin,
            ilo: ilo.map(|v| Vec4::splat(v.min_element())),
            ihi: ihi.map(|v| Vec4::splat(v.max_element())),
            t_min: t_min.min_element(),
        })
    }

    /// The frustum of a packet whose `N` lanes are all active, straight from its arrays
    /// (no per-lane reciprocals): `None` unless each axis's directions all have one sign.
    /// Then `1/d` falls as `d` grows and rounding keeps that order, so the reciprocals'
    /// extremes are the reciprocals of the directions' extremes: the same bounds, bit for
    /// bit, as [`Frustum::new`] takes from every lane's reciprocal. With the largest end
    /// of the packet's rays. Packets whose rays all miss the scene then never compute the
    /// per-lane reciprocals (most of them, for an object in the middle of the view).
    pub(in crate::packet) fn from_full_packet<const N: usize>(p: &RayPacket<N>) -> Option<(Frustum, f32)> {
        let o = [extremes(&p.ox), extremes(&p.oy), extremes(&p.oz)];
        let (t_min, _) = extremes(&p.t_min);
        let (_, t_end) = extremes(&p.t_max);
        let mut ilo = [Vec4::ZERO; 3];
        let mut ihi = [Vec4::ZERO; 3];
        for (a, d) in [&p.dx, &p.dy, &p.dz].into_iter().enumerate() {
            let (lo, hi) = extremes(d);
            // Also rules out zero components (and NaN, which no valid ray has).
            if !(lo > 0.0 || hi < 0.0) {
                return None;
            }
            ilo[a] = Vec4::splat(recip(hi));
            ihi[a] = Vec4::splat(recip(lo));
        }
        let (olo, ohi) = (o.map(|(lo, _)| Vec4::splat(lo)), o.map(|(_, hi)| Vec4::splat(hi)));
        let one_origin = o.iter().all(|&(lo, hi)| lo.to_bits() == hi.to_bits());
        Some((Frustum { olo, ohi, ilo, ihi, t_min, one_origin }, t_end))
    }

    /// The frustum of the rays of `mask` (live lanes of `p`), and the largest end of
    /// those rays: straight from the arrays where every lane is active
    /// ([`Frustum::from_full_packet`]), else from the lanes in registers, made in `lanes`;
    /// no frustum where a direction has a zero component.
    #[inline(always)]
    pub(in crate::packet) fn of_packet<const N: usize>(
        p: &RayPacket<N>,
        mask: u64,
        lanes: &mut Option<Groups>,
    ) -> (Option<Frustum>, f32) {
        let full = N <= 64 && mask == u64::MAX >> (64 - N.clamp(1, 64));
        if let Some((f, t_end)) = full.then(|| Frustum::from_full_packet(p)).flatten() {
            return (Some(f), t_end);
        }
        let q = Groups::fill(lanes, p, N.div_ceil(4), mask);
        (Frustum::new(q, N.div_ceil(4), mask), q.largest_end())
    }

    /// The packet's one origin, if all its rays start at one point.
    #[inline(always)]
    pub(in crate::packet) fn origin(&self) -> Option<[f32; 3]> {
        self.one_origin.then(|| [self.olo[0].x, self.olo[1].x, self.olo[2].x])
    }

    /// Lower bound of the entry distance into each child box, and which boxes some ray
    /// may hit before `t_end` (the largest best-hit distance of the packet).
    #[inline(always)]
    pub(in crate::packet) fn slab4(&self, n: &Bvh4Node, t_end: f32) -> (Vec4, u32) {
        self.slab_quad([(n.min_x, n.max_x), (n.min_y, n.max_y), (n.min_z, n.max_z)], t_end)
    }

    /// [`Frustum::slab4`] for the eight child boxes of an 8-wide node, as two quads of
    /// lanes: the same interval arithmetic per box.
    #[inline(always)]
    pub(in crate::packet) fn slab8(&self, n: &Bvh8Node, t_end: f32) -> ([f32; 8], u32) {
        let mut near = [0f32; 8];
        let mut hit = 0u32;
        for h in 0..2 {
            let half = |a: &[f32; 8]| -> [f32; 4] { [a[4 * h], a[4 * h + 1], a[4 * h + 2], a[4 * h + 3]] };
            let planes =
                [(half(&n.min_x), half(&n.max_x)), (half(&n.min_y), half(&n.max_y)), (half(&n.min_z), half(&n.max_z))];
            let (t, m) = self.slab_quad(planes, t_end);
            near[4 * h..4 * h + 4].copy_from_slice(&t.to_array());
            hit |= m << (4 * h);
        }
        (near, hit)
    }

    /// The interval test of four boxes given by their planes per axis `(lower, upper)`:
    /// entry bounds, and the boxes whose bounds leave an interval before `t_end`. Empty
    /// slots are not among them: interval arithmetic would take their inverted boxes
    /// (the only boxes with a lower plane above the upper: see `validate::wide_bvh`) for
    /// all of space.
    #[inline(always)]
    fn slab_quad(&self, planes: [([f32; 4], [f32; 4]); 3], t_end: f32) -> (Vec4, u32) {
        // (Read from the boxes, not the child indices: one compare of four lanes, where
        // the indices' eight compares were 7 instructions per ray in the conference
        // room's eye-ray packets.)
        let real = Vec4::from_array(planes[0].0).cmple(Vec4::from_array(planes[0].1)).bitmask();
        let mut near = Vec4::splat(self.t_min);
        let mut far = Vec4::splat(f32::INFINITY);
        for (a, (lo, hi)) in planes.into_iter().enumerate() {
            let (il, ih, ol, oh) = (self.ilo[a], self.ihi[a], self.olo[a], self.ohi[a]);
            let (lo, hi) = (Vec4::from_array(lo), Vec4::from_array(hi));
            let (mn, mx) = if self.one_origin {
                // `ol == oh`: the products below with `ol` equal those with `oh`, so the
                // extremes of these four are the extremes of all eight.
                let p = [(lo - oh) * il, (lo - oh) * ih, (hi - oh) * il, (hi - oh) * ih];
                (p[0].min(p[1]).min(p[2].min(p[3])), p[0].max(p[1]).max(p[2].max(p[3])))
            } else {
                let p = [(lo - oh) * il, (lo - oh) * ih, (lo - ol) * il, (lo - ol) * ih];
                let q = [(hi - oh) * il, (hi - oh) * ih, (hi - ol) * il, (hi - ol) * ih];
                let mut mn = p[0];
                let mut mx = p[0];
                for v in p.iter().chain(q.iter()) {
                    mn = mn.min(*v);
                    mx = mx.max(*v);
                }
                (mn, mx)
            };
            near = near.max(mn);
            far = far.min(mx * SLAB_GROWTH);
        }
        far = far.min(Vec4::splat(t_end));
        (near, near.cmple(far).bitmask() & real)
    }
}

/// The smallest and largest of `N` lanes, four at a time.
#[inline(always)]
pub(in crate::packet) fn extremes<const N: usize>(a: &[f32; N]) -> (f32, f32) {
    let mut quads = a.chunks_exact(4);
    let (mut lo, mut hi) = (Vec4::INFINITY, Vec4::NEG_INFINITY);
    for q in &mut quads {
        let v = Vec4::from_slice(q);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let (mut lo, mut hi) = (lo.min_element(), hi.max_element());
    for &x in quads.remainder() {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// A full packet's frustum taken from its arrays has exactly the bounds of the one
    /// taken from every lane's reciprocal (so it culls the same boxes), and there is none
    /// when an axis's directions change sign or one is zero.
    #[test]
    fn a_full_packets_frustum_from_its_arrays_equals_the_frustum_of_its_lanes() {
        let mut g = Lcg(5);
        let (mut direct, mut declined) = (0, 0);
        for case in 0..2000 {
            let eye = Vec3::new(g.range(-3.0, 3.0), g.range(-3.0, 3.0), g.range(-6.0, 6.0));
            let shared = case % 2 == 0;
            // A small patch of directions (a tile of primary rays), sometimes straddling
            // an axis, sometimes with a zero component.
            let centre = Vec3::new(g.range(-1.0, 1.0), g.range(-1.0, 1.0), g.range(-1.0, 1.0));
            let spread = [0.01, 0.2, 2.0][case % 3];
            let rays: [Ray; 64] = core::array::from_fn(|i| {
                let mut d = centre + Vec3::new(g.range(-spread, spread), g.range(-spread, spread), 0.1);
                if case % 11 == 3 && i == 7 {
                    d.x = 0.0;
                }
                let start = if shared { eye } else { eye + Vec3::new(g.range(-0.1, 0.1), 0.0, g.range(-0.1, 0.1)) };
                let mut ray = Ray::new(start, d);
                ray.t_min = g.range(0.0, 0.01);
                ray.t_max = if g.unit() < 0.3 { g.range(1.0, 8.0) } else { f32::INFINITY };
                ray
            });
            let n: usize = [4, 16, 64][case % 3];
            let mut packet = RayPacket::<64>::new();
            packet.fill(&rays[..n]);
            let mask = u64::MAX >> (64 - n);
            assert_eq!(packet.active & mask, mask);
            let q = Groups::new(&packet, n.div_ceil(4), mask);
            // The arrays' lanes beyond `n` hold no rays: a packet of `n` lanes.
            let fit = |a: &[f32; 64]| -> [f32; 64] { core::array::from_fn(|i| a[i.min(n - 1)]) };
            let mut p = packet;
            for a in [&mut p.ox, &mut p.oy, &mut p.oz, &mut p.dx, &mut p.dy, &mut p.dz, &mut p.t_min, &mut p.t_max] {
                *a = fit(a);
            }
            let sign_change = [&p.dx, &p.dy, &p.dz].iter().any(|d| {
                let (lo, hi) = extremes(d);
                !(lo > 0.0 || hi < 0.0)
            });
            match (Frustum::from_full_packet(&p), Frustum::new(&q, n.div_ceil(4), mask)) {
                (Some((f, t_end)), Some(lanes)) => {
                    let bits = |v: &[Vec4; 3]| v.map(|x| x.to_array().map(f32::to_bits));
                    assert_eq!(bits(&f.olo), bits(&lanes.olo), "case {case}");
                    assert_eq!(bits(&f.ohi), bits(&lanes.ohi), "case {case}");
                    assert_eq!(bits(&f.ilo), bits(&lanes.ilo), "case {case}");
                    assert_eq!(bits(&f.ihi), bits(&lanes.ihi), "case {case}");
                    assert_eq!(f.t_min.to_bits(), lanes.t_min.to_bits(), "case {case}");
                    assert_eq!(f.one_origin, lanes.one_origin, "case {case}");
                    assert_eq!(f.one_origin, shared, "case {case}");
                    assert_eq!(t_end, q.largest_end(), "case {case}");
                    assert!(!sign_change, "case {case}");
                    direct += 1;
                }
                (None, _) => {
                    assert!(sign_change, "case {case}: declined a packet whose directions keep their signs");
                    declined += 1;
                }
                (Some(_), None) => panic!("case {case}: a frustum where the lanes' test needs exact boxes"),
            }
        }
        assert!(direct > 500 && declined > 200, "{direct} direct, {declined} declined");
    }
}
