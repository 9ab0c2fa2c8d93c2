//! Ray packets (Wald & Slusallek 2001 §4): up to 64 rays as a structure of arrays with an
//! active mask, traversed and intersected in lock-step. A packet descends into a node if
//! any of its active rays needs it, and carries on with exactly those rays (the node's
//! mask), so each ray still meets every triangle the single-ray kernel would test — the
//! hits are the same bit for bit — while node fetches and stack work are shared.

pub mod bvh;
pub mod bvh4;
pub mod bvh8;
pub mod grid;
pub mod instanced;
pub mod kdtree;
mod lanes;
pub mod lockstep;
pub mod step;

pub use lanes::{Lanes, LanesOf};

use glam::{Mat4, Vec3, Vec4};

use crate::hit::Hit;
use crate::ray::Ray;

/// Largest packet (the active mask is a `u64`).
pub const MAX_PACKET: usize = 64;

/// `N` rays as a structure of arrays.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<const N: usize> {
    /// Origin x of each ray.
    pub ox: [f32; N],
    /// Origin y.
    pub oy: [f32; N],
    /// Origin z.
    pub oz: [f32; N],
    /// Direction x.
    pub dx: [f32; N],
    /// Direction y.
    pub dy: [f32; N],
    /// Direction z.
    pub dz: [f32; N],
    /// Interval start.
    pub t_min: [f32; N],
    /// Interval end.
    pub t_max: [f32; N],
    /// Bit `i` set: ray `i` takes part.
    pub active: u64,
}

impl<const N: usize> Default for RayPacket<N> {
    fn default() -> Self {
        // 1 to 64 lanes, checked at compile time (the active mask is a `u64`).
        let () = Self::CHECK;
        RayPacket {
            ox: [0.0; N],
            oy: [0.0; N],
            oz: [0.0; N],
            dx: [0.0; N],
            dy: [0.0; N],
            dz: [0.0; N],
            t_min: [0.0; N],
            t_max: [0.0; N],
            active: 0,
        }
    }
}

impl<const N: usize> RayPacket<N> {
    const CHECK: () = assert!(N >= 1 && N <= MAX_PACKET, "packets hold 1 to 64 rays");

    /// An empty packet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The active lanes that exist: [`RayPacket::active`] is public, and the kernels read
    /// only its first `N` bits, so stray higher bits cannot index past the lanes.
    #[inline(always)]
    pub fn live(&self) -> u64 {
        self.active & step::lane_mask(N)
    }

    /// The live lanes whose rays are valid ([`Ray::is_valid`], lane by lane over the
    /// packet's arrays: building each lane's `Ray` to ask it stalled on the stores).
    #[inline(always)]
    pub fn valid_lanes(&self) -> u64 {
        let mut valid = 0u64;
        for i in 0..N.min(64) {
            let o = [self.ox[i], self.oy[i], self.oz[i]];
            let d = [self.dx[i], self.dy[i], self.dz[i]];
            // `x − x` is 0 for a finite `x`, NaN otherwise (as `Ray::is_valid` tests); `&`
            // and `|`, not `&&` and `||`: no branch, so that the loop runs in SIMD lanes.
            #[allow(clippy::eq_op)]
            let fin = |a: usize| (o[a] - o[a]) + (d[a] - d[a]) == 0.0;
            let finite = fin(0) & fin(1) & fin(2);
            let moving = (d[0] != 0.0) | (d[1] != 0.0) | (d[2] != 0.0);
            let interval = (self.t_min[i] >= 0.0) & (self.t_min[i] <= self.t_max[i]);
            valid |= u64::from(finite & moving & interval) << i;
        }
        valid & self.live()
    }

    /// Stores ray `i` and marks it active; invalid rays stay inactive (they miss).
    #[inline]
    pub fn set(&mut self, i: usize, r: &Ray) {
        if i >= N {
            return;
        }
        self.store(i, r);
        if r.is_valid() {
            self.active |= 1 << i;
        } else {
            self.active &= !(1 << i);
        }
    }

    /// Stores four rays of one origin (directions `dir`: lane `k` of each register is ray
    /// `k`'s; all with the interval `[t_min, t_max]`) in lanes `i .. i + 4`, and makes
    /// exactly the valid ones of `keep` (bit `k` for lane `i + k`) active: as
    /// [`RayPacket::set`] on the rays of `keep`, four lanes per store (set lane by lane,
    /// an image tile's packets spent a sixth of their time storing rays).
    #[inline]
    pub fn set4(&mut self, i: usize, origin: Vec3, dir: [Vec4; 3], t_min: f32, t_max: f32, keep: u32) {
        if N < 4 || i > N - 4 {
            return;
        }
        let o = [origin.x, origin.y, origin.z].map(Vec4::splat);
        for (v, a) in [(o[0], &mut self.ox), (o[1], &mut self.oy), (o[2], &mut self.oz)] {
            v.write_to_slice(&mut a[i..i + 4]);
        }
        for (v, a) in [(dir[0], &mut self.dx), (dir[1], &mut self.dy), (dir[2], &mut self.dz)] {
            v.write_to_slice(&mut a[i..i + 4]);
        }
        Vec4::splat(t_min).write_to_slice(&mut self.t_min[i..i + 4]);
        Vec4::splat(t_max).write_to_slice(&mut self.t_max[i..i + 4]);
        // `Ray::is_valid`, lane for lane, as in `fill`.
        #[allow(clippy::eq_op)]
        let finite = ((o[0] - o[0]) + (dir[0] - dir[0])).cmpeq(Vec4::ZERO)
            & ((o[1] - o[1]) + (dir[1] - dir[1])).cmpeq(Vec4::ZERO)
            & ((o[2] - o[2]) + (dir[2] - dir[2])).cmpeq(Vec4::ZERO);
        let moving = dir[0].cmpne(Vec4::ZERO) | dir[1].cmpne(Vec4::ZERO) | dir[2].cmpne(Vec4::ZERO);
        // `0 <= t_min <= t_max`, as `Ray::is_valid`.
        let ordered = Vec4::splat(t_min).cmple(Vec4::splat(t_max)) & Vec4::splat(t_min).cmpge(Vec4::ZERO);
        let valid = (finite & moving & ordered).bitmask() & keep & 0xF;
        self.active = (self.active & !(0xF << i)) | (valid as u64) << i;
    }

    /// The eight lane arrays, in a ray record's order (what the AVX transpose stores).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn lane_arrays(&mut self) -> [&mut [f32; N]; 8] {
        [
            &mut self.ox,
            &mut self.oy,
            &mut self.oz,
            &mut self.dx,
            &mut self.dy,
            &mut self.dz,
            &mut self.t_min,
            &mut self.t_max,
        ]
    }

    /// Stores `rays` in lanes `0 ..` (at most `N`) and makes exactly their valid ones
    /// active, as [`RayPacket::set`] one by one would after clearing the mask.
    #[inline]
    pub fn fill(&mut self, rays: &[Ray]) {
        let all = &rays[..rays.len().min(N)];
        let mut active = 0u64;
        let mut i = 0;
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = crate::simd::Avx::reported() {
            for octet in all.chunks_exact(8) {
                let valid = crate::simd::transpose::fill8(avx, self.lane_arrays(), i, octet);
                active |= valid << i;
                i += 8;
            }
        }
        let rays = &all[i..];
        let mut quads = rays.chunks_exact(4);
        // Four rays at a time: two 4×4 transposes turn four records into four lanes of
        // each array (the scalar form, a store per field and ray, cost a third of the
        // time of packets that miss the scene).
        for q in &mut quads {
            let head = Mat4::from_cols_array_2d(&[q[0].head(), q[1].head(), q[2].head(), q[3].head()]).transpose();
            let tail = Mat4::from_cols_array_2d(&[q[0].tail(), q[1].tail(), q[2].tail(), q[3].tail()]).transpose();
            let [ox, oy, oz, dx] = [head.x_axis, head.y_axis, head.z_axis, head.w_axis];
            let [dy, dz, t_min, t_max] = [tail.x_axis, tail.y_axis, tail.z_axis, tail.w_axis];
            for (v, a) in [(ox, &mut self.ox), (oy, &mut self.oy), (oz, &mut self.oz), (dx, &mut self.dx)] {
                v.write_to_slice(&mut a[i..i + 4]);
            }
            for (v, a) in [(dy, &mut self.dy), (dz, &mut self.dz), (t_min, &mut self.t_min), (t_max, &mut self.t_max)] {
                v.write_to_slice(&mut a[i..i + 4]);
            }
            // `Ray::is_valid`, lane for lane.
            #[allow(clippy::eq_op)]
            let finite = ((ox - ox) + (dx - dx)).cmpeq(Vec4::ZERO)
                & ((oy - oy) + (dy - dy)).cmpeq(Vec4::ZERO)
                & ((oz - oz) + (dz - dz)).cmpeq(Vec4::ZERO);
            let moving = dx.cmpne(Vec4::ZERO) | dy.cmpne(Vec4::ZERO) | dz.cmpne(Vec4::ZERO);
            let ordered = t_min.cmple(t_max) & t_min.cmpge(Vec4::ZERO);
            active |= ((finite & moving & ordered).bitmask() as u64) << i;
            i += 4;
        }
        for r in quads.remainder() {
            self.store(i, r);
            active |= (r.is_valid() as u64) << i;
            i += 1;
        }
        self.active = active;
    }

    /// Writes ray `r` into lane `i < N`.
    #[inline(always)]
    fn store(&mut self, i: usize, r: &Ray) {
        self.ox[i] = r.origin.x;
        self.oy[i] = r.origin.y;
        self.oz[i] = r.origin.z;
        self.dx[i] = r.dir.x;
        self.dy[i] = r.dir.y;
        self.dz[i] = r.dir.z;
        self.t_min[i] = r.t_min;
        self.t_max[i] = r.t_max;
    }

    /// True when every active ray starts at one point, bit for bit (a pinhole camera's
    /// rays, a light's, a hemisphere of rays from one hit); true for no active ray.
    #[inline]
    pub fn one_origin(&self) -> bool {
        self.one_origin_in(self.live())
    }

    /// [`RayPacket::one_origin`] for the live lanes of `mask` only.
    #[inline]
    pub fn one_origin_in(&self, mask: u64) -> bool {
        let o = |i: usize| [self.ox[i].to_bits(), self.oy[i].to_bits(), self.oz[i].to_bits()];
        self.lanes_agree(mask & self.live(), o)
    }

    /// True when, on each axis, every active ray's direction has one sign (a negative
    /// zero counts as negative); true for no active ray.
    #[inline]
    pub fn one_octant(&self) -> bool {
        let signs = |i: usize| [self.dx[i].to_bits() >> 31, self.dy[i].to_bits() >> 31, self.dz[i].to_bits() >> 31];
        self.lanes_agree(self.live(), signs)
    }

    /// True when `key` is the same for every lane of `live` (true for none).
    #[inline(always)]
    fn lanes_agree(&self, live: u64, key: impl Fn(usize) -> [u32; 3]) -> bool {
        let first = live.trailing_zeros() as usize;
        if first >= N {
            return true;
        }
        let want = key(first);
        if live == u64::MAX >> (64 - N.clamp(1, 64)) {
            // Every lane (most packets): one pass, differing bits gathered by `|` in SIMD
            // registers (a fold of array compares: ~800 instructions per 64 lanes).
            let diff = (0..N).fold([0u32; 3], |d, i| {
                let k = key(i);
                [d[0] | (k[0] ^ want[0]), d[1] | (k[1] ^ want[1]), d[2] | (k[2] ^ want[2])]
            });
            return diff == [0; 3];
        }
        LanesOf::<N>(live).all(|i| key(i) == want)
    }

    /// Ray `i`; past the last lane, the last lane's ray.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        let i = i.min(N.saturating_sub(1));
        let get = |a: &[f32; N]| a.get(i).copied().unwrap_or(0.0);
        Ray {
            origin: Vec3::new(get(&self.ox), get(&self.oy), get(&self.oz)),
            dir: Vec3::new(get(&self.dx), get(&self.dy), get(&self.dz)),
            t_min: get(&self.t_min),
            t_max: get(&self.t_max),
        }
    }
}

/// Per-packet work counters; the SIMD efficiency is `active_lanes / (visits · N)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PacketCounters {
    /// Node (and leaf) visits by the packet.
    pub visits: u64,
    /// Sum over visits of the rays that needed the node.
    pub active_lanes: u64,
    /// Ray–triangle tests.
    pub tri_tests: u64,
}

impl PacketCounters {
    /// Adds another packet's counters.
    pub fn add(&mut self, o: &PacketCounters) {
        self.visits += o.visits;
        self.active_lanes += o.active_lanes;
        self.tri_tests += o.tri_tests;
    }

    /// Adds the work of rays traced one by one: each node or leaf visit counts one lane.
    pub fn add_rays(&mut self, c: &crate::counters::RayCounters) {
        let visits = u64::from(c.nodes) + u64::from(c.leaves);
        self.visits += visits;
        self.active_lanes += visits;
        self.tri_tests += u64::from(c.tri_tests);
    }
}

/// A packet traced ray by ray with the single-ray kernel `trace`: what the packet kernels
/// do for a triangle test whose box tests are not the `f32` ones their lanes share (the
/// fixed-point datapath, [`crate::traverse::boxes::datapath`]). Each visit counts one lane.
#[inline]
pub fn ray_by_ray<const N: usize>(
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    counters: &mut PacketCounters,
    mut trace: impl FnMut(&Ray, &mut crate::counters::RayCounters) -> Option<Hit>,
) {
    let mut c = crate::counters::RayCounters::default();
    for (i, hit) in hits.iter_mut().enumerate() {
        *hit = if packet.live() & (1 << i) != 0 { trace(&packet.ray(i), &mut c) } else { None };
    }
    counters.add_rays(&c);
}

/// The any-hit query of a packet asked ray by ray with the single-ray query `blocked`
/// (bit `i` set: ray `i` is blocked), counted as [`ray_by_ray`] counts.
#[inline]
pub fn occluded_ray_by_ray<const N: usize>(
    packet: &RayPacket<N>,
    counters: &mut PacketCounters,
    blocked: impl FnMut(&Ray, &mut crate::counters::RayCounters) -> bool,
) -> u64 {
    occluded_lanes_ray_by_ray(packet, packet.live(), counters, blocked)
}

/// [`occluded_ray_by_ray`] for the live lanes of `lanes` only.
#[inline]
pub fn occluded_lanes_ray_by_ray<const N: usize>(
    packet: &RayPacket<N>,
    lanes: u64,
    counters: &mut PacketCounters,
    mut blocked: impl FnMut(&Ray, &mut crate::counters::RayCounters) -> bool,
) -> u64 {
    let mut c = crate::counters::RayCounters::default();
    let mut mask = 0u64;
    for i in LanesOf::<N>(lanes & packet.live()) {
        mask |= (blocked(&packet.ray(i), &mut c) as u64) << i;
    }
    counters.add_rays(&c);
    mask
}

/// The best hit of each ray of a packet.
pub type PacketHits<const N: usize> = [Option<Hit>; N];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;

    /// A component drawn to hit every case of `Ray::is_valid`: ordinary, zero, ±0,
    /// infinite and NaN values.
    fn component(g: &mut Lcg) -> f32 {
        match g.next() >> 60 {
            0 => 0.0,
            1 => -0.0,
            2 => f32::INFINITY,
            3 => f32::NEG_INFINITY,
            4 => f32::NAN,
            _ => g.range(-3.0, 3.0),
        }
    }

    /// The transposing `fill` stores every lane and activates exactly the valid rays, as
    /// `set` one ray at a time does, for every length up to the packet's size (whole
    /// groups of four and the scalar remainder).
    fn fill_matches_set<const N: usize>(g: &mut Lcg) {
        for len in 0..=N + 2 {
            let rays: [Ray; 70] = core::array::from_fn(|_| {
                let rare = g.next() >> 61 == 0;
                let c = |g: &mut Lcg| if rare { component(g) } else { g.range(-3.0, 3.0) };
                let (t_min, t_max) = if g.next() >> 62 == 0 { (c(g), c(g)) } else { (0.0, f32::INFINITY) };
                Ray { origin: Vec3::new(c(g), c(g), c(g)), dir: Vec3::new(c(g), c(g), c(g)), t_min, t_max }
            });
            let rays = &rays[..len];
            let mut filled = RayPacket::<N>::new();
            filled.active = u64::MAX;
            filled.fill(rays);
            let mut set = RayPacket::<N>::new();
            for (i, r) in rays.iter().enumerate().take(N) {
                set.set(i, r);
            }
            assert_eq!(filled.active, set.active, "N = {N}, {len} rays");
            // The AVX transpose, where this CPU has AVX, octet by octet.
            #[cfg(target_arch = "x86_64")]
            if let Some(avx8) = crate::simd::Avx::detected() {
                let mut avx = RayPacket::<N>::new();
                let mut active = 0u64;
                let whole = len.min(N) / 8 * 8;
                for k in (0..whole).step_by(8) {
                    let valid = crate::simd::transpose::fill8(avx8, avx.lane_arrays(), k, &rays[k..k + 8]);
                    active |= valid << k;
                }
                for (i, r) in rays.iter().enumerate().take(N).skip(whole) {
                    avx.set(i, r);
                    active |= (r.is_valid() as u64) << i;
                }
                assert_eq!(active, set.active, "AVX, N = {N}, {len} rays");
                for i in 0..len.min(N) {
                    let bits = |r: Ray| {
                        [r.origin.to_array(), r.dir.to_array(), [r.t_min, r.t_max, 0.0]].map(|v| v.map(f32::to_bits))
                    };
                    assert_eq!(bits(avx.ray(i)), bits(set.ray(i)), "AVX, N = {N}, lane {i}");
                }
            }
            for i in 0..len.min(N) {
                let (a, b) = (filled.ray(i), set.ray(i));
                let bits = |r: Ray| {
                    [r.origin.to_array(), r.dir.to_array(), [r.t_min, r.t_max, 0.0]].map(|v| v.map(f32::to_bits))
                };
                assert_eq!(bits(a), bits(b), "N = {N}, lane {i}");
            }
        }
    }

    /// `valid_lanes` over the packet's arrays gives each live lane's `Ray::is_valid`, on
    /// rays with zero, infinite and NaN components and every kind of interval.
    #[test]
    fn valid_lanes_are_the_lanes_whose_rays_are_valid() {
        let mut g = Lcg(23);
        let (mut valid, mut invalid) = (0, 0);
        for _ in 0..3000 {
            let mut p = RayPacket::<16>::new();
            let rays: [Ray; 16] = core::array::from_fn(|_| {
                let rare = g.next() >> 62 == 0;
                let c = |g: &mut Lcg| if rare { component(g) } else { g.range(-3.0, 3.0) };
                let (t_min, t_max) = if g.next() >> 62 == 0 { (c(&mut g), c(&mut g)) } else { (0.0, 2.0) };
                Ray {
                    origin: Vec3::new(c(&mut g), c(&mut g), c(&mut g)),
                    dir: Vec3::new(c(&mut g), c(&mut g), c(&mut g)),
                    t_min,
                    t_max,
                }
            });
            for (i, r) in rays.iter().enumerate() {
                p.store(i, r);
            }
            p.active = g.next() | (1 << 40);
            let want = (0..16).fold(0u64, |m, i| m | (u64::from(rays[i].is_valid() && p.active & (1 << i) != 0) << i));
            assert_eq!(p.valid_lanes(), want);
            valid += want.count_ones();
            invalid += (p.live() & !want).count_ones();
        }
        assert!(valid > 10_000 && invalid > 2_000, "{valid} valid, {invalid} invalid lanes");
    }

    #[test]
    fn one_origin_looks_at_active_lanes_only() {
        let ray = |x: f32| Ray::new(Vec3::new(x, 0.0, 0.0), Vec3::X);
        let mut p = RayPacket::<4>::new();
        assert!(p.one_origin(), "no active ray");
        p.set(0, &ray(1.0));
        p.set(2, &ray(1.0));
        assert!(p.one_origin());
        p.set(3, &ray(2.0));
        assert!(!p.one_origin());
        p.active &= !(1 << 3);
        assert!(p.one_origin(), "an inactive lane's origin does not count");
        // Bit for bit: -0 is another origin than +0.
        p.set(1, &ray(-0.0));
        p.set(0, &ray(0.0));
        p.active = 0b11;
        assert!(!p.one_origin());
    }

    #[test]
    fn one_octant_looks_at_active_lanes_and_signs_only() {
        let ray = |d: [f32; 3]| Ray::new(Vec3::ZERO, Vec3::from(d));
        let mut p = RayPacket::<4>::new();
        assert!(p.one_octant(), "no active ray");
        p.set(0, &ray([1.0, -2.0, 3.0]));
        p.set(1, &ray([0.5, -0.1, 9.0]));
        assert!(p.one_octant(), "other directions, the same signs");
        p.set(3, &ray([1.0, 2.0, 3.0]));
        assert!(!p.one_octant(), "y changes sign");
        p.active &= !(1 << 3);
        assert!(p.one_octant(), "an inactive lane's direction does not count");
        // A negative zero is negative, as its reciprocal is.
        p.set(2, &ray([1.0, -0.0, 1.0]));
        assert!(p.one_octant());
        p.set(2, &ray([1.0, -1.0, -0.0]));
        assert!(!p.one_octant());
    }

    /// Full packets take the one-pass form: every lane counts, the last one included.
    #[test]
    fn full_packets_agree_only_when_every_lane_does() {
        for n in [4usize, 16, 64] {
            let rays: [Ray; 64] = core::array::from_fn(|i| Ray::new(Vec3::ONE, Vec3::new(1.0, -1.0 - i as f32, 0.5)));
            let mut p = RayPacket::<64>::new();
            p.fill(&rays[..n]);
            assert_eq!(p.live().count_ones() as usize, n);
            assert!(p.one_origin() && p.one_octant(), "{n} lanes");
            for odd in [0, n / 2, n - 1] {
                let mut q = rays;
                q[odd] =
                    Ray::new(Vec3::new(1.0, 1.0, f32::from_bits(1.0f32.to_bits() + 1)), Vec3::new(1.0, -1.0, -0.5));
                p.fill(&q[..n]);
                assert!(!p.one_origin() && !p.one_octant(), "{n} lanes, lane {odd} differs");
            }
        }
        let mut p = RayPacket::<4>::new();
        p.fill(&[Ray::new(Vec3::ZERO, Vec3::X); 4]);
        p.set(3, &Ray::new(Vec3::Y, -Vec3::X));
        assert!(!p.one_origin() && !p.one_octant(), "a packet of exactly N lanes");
    }

    #[test]
    fn transposing_fill_matches_setting_ray_by_ray() {
        let mut g = Lcg(11);
        for _ in 0..50 {
            fill_matches_set::<1>(&mut g);
            fill_matches_set::<4>(&mut g);
            fill_matches_set::<7>(&mut g);
            fill_matches_set::<16>(&mut g);
            fill_matches_set::<64>(&mut g);
        }
    }

    /// Four rays of one origin stored at once: the lanes `set` would store for the kept
    /// rays, and the same active mask (invalid and left-out rays inactive).
    #[test]
    fn four_rays_of_one_origin_set_as_one_by_one() {
        let mut g = Lcg(13);
        for case in 0..2000 {
            let rare = |g: &mut Lcg| if g.next() >> 61 == 0 { component(g) } else { g.range(-3.0, 3.0) };
            let origin = Vec3::new(rare(&mut g), rare(&mut g), rare(&mut g));
            let dirs: [Vec3; 4] = core::array::from_fn(|_| Vec3::new(rare(&mut g), rare(&mut g), rare(&mut g)));
            let (t_min, t_max) = if case % 5 == 0 { (rare(&mut g), rare(&mut g)) } else { (0.0, f32::INFINITY) };
            let keep = (g.next() >> 60) as u32;
            let i = 4 * (case % 4);
            let mut four = RayPacket::<16>::new();
            four.active = u64::MAX;
            let lanes = |a: usize| Vec4::from_array(dirs.map(|d| d[a]));
            four.set4(i, origin, [lanes(0), lanes(1), lanes(2)], t_min, t_max, keep);
            let mut one = RayPacket::<16>::new();
            one.active = u64::MAX;
            for (k, d) in dirs.iter().enumerate() {
                if keep & (1 << k) != 0 {
                    one.set(i + k, &Ray { origin, dir: *d, t_min, t_max });
                } else {
                    one.active &= !(1 << (i + k));
                }
            }
            assert_eq!(four.active, one.active, "case {case}");
            for k in (0..4).filter(|k| keep & (1 << k) != 0) {
                let bits = |r: Ray| {
                    [r.origin.to_array(), r.dir.to_array(), [r.t_min, r.t_max, 0.0]].map(|v| v.map(f32::to_bits))
                };
                assert_eq!(bits(four.ray(i + k)), bits(one.ray(i + k)), "case {case} lane {k}");
            }
        }
    }
}
