//! Packet traversal of the 4-wide BVH: the packet visits a node if any of its rays may
//! hit one of the node's boxes, nearest child first; a leaf intersects its triangles with
//! exactly the rays that enter its box, in groups of four lanes (SIMD registers) for the
//! box test and, where the intersector has a four-ray form, for the triangles too. Rays
//! of one origin (a camera's) meet each triangle made ready once for it, eight lanes at a
//! time where the CPU has AVX (`simd::watertight8`).

use crate::traverse::wide_bvh::node4::slab4_exact;
use glam::{BVec4A, Vec3, Vec3A, Vec4};

use crate::counters::RayCounters;
use crate::hit::keep_closest;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView, MAX_WIDE_DEPTH, NULL_INDEX};
use crate::intersect::triangle::{in_range, test_triangle, Intersector, LaneHits, RayPair, SharedTris};
use crate::packet::{ray_by_ray, Lanes, PacketCounters, PacketHits, RayPacket, MAX_PACKET};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::clip::SLAB_GROWTH;
use crate::traverse::boxes::datapath::NodeTests;
use crate::traverse::boxes::slab::{recip, recip4, RayBox};
use crate::traverse::wide_bvh::node4::trace_bvh4;

const STACK: usize = 3 * MAX_WIDE_DEPTH as usize + 4;

/// The packet as one conservative "frustum": the box of its origins and of its
/// reciprocal directions. Interval arithmetic on these bounds gives, for a box, an entry
/// distance no larger and an exit no smaller than any single ray's (rounding is monotone,
/// so the bounds are attained at the corners), hence a box rejected for the packet is
/// rejected by every ray (Reshetov et al. 2005; Wald et al. 2007).
#[derive(Clone, Copy, Debug)]
struct Frustum {
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
    fn new(q: &Groups, groups: usize, mask: u64) -> Option<Frustum> {
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
    fn from_full_packet<const N: usize>(p: &RayPacket<N>) -> Option<(Frustum, f32)> {
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

    /// The packet's one origin, if all its rays start at one point.
    #[inline(always)]
    fn origin(&self) -> Option<[f32; 3]> {
        self.one_origin.then(|| [self.olo[0].x, self.olo[1].x, self.olo[2].x])
    }

    /// Lower bound of the entry distance into each child box, and which boxes some ray
    /// may hit before `t_end` (the largest best-hit distance of the packet).
    #[inline(always)]
    fn slab4(&self, n: &Bvh4Node, t_end: f32) -> (Vec4, u32) {
        let mut near = Vec4::splat(self.t_min);
        let mut far = Vec4::splat(f32::INFINITY);
        let planes = [(n.min_x, n.max_x), (n.min_y, n.max_y), (n.min_z, n.max_z)];
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
        let valid = (0..4).fold(0u32, |m, k| m | (((n.child[k] != NULL_INDEX) as u32) << k));
        (near, near.cmple(far).bitmask() & valid)
    }
}

/// The smallest and largest of `N` lanes, four at a time.
#[inline(always)]
fn extremes<const N: usize>(a: &[f32; N]) -> (f32, f32) {
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

/// How the packet culls boxes: by its frustum, or ray by ray with each ray's exact box
/// test when some ray has a zero direction component (see [`RayBox`]).
// No heap in core to box the per-ray tests: they live on the stack for one packet, and
// are borrowed here, so that the frustum's packets (nearly all) do not move them (a
// copy of the whole record per packet was 2% of the bunny's packet time).
enum Cull<'b, const N: usize> {
    Frustum(Frustum),
    Exact(&'b [RayBox; N]),
}

/// Lanes of a group of four as a SIMD mask, by the group's 4 bits of the active mask.
const GROUP_LANES: [BVec4A; 16] = {
    let mut t = [BVec4A::new(false, false, false, false); 16];
    let mut m = 0;
    while m < 16 {
        t[m] = BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
        m += 1;
    }
    t
};

/// Groups of four lanes in the largest packet.
pub(crate) const GROUPS: usize = MAX_PACKET / 4;

/// The packet regrouped as SIMD registers of four lanes each, with reciprocal
/// directions: loaded once, so that a leaf's box test per group is six aligned loads.
pub(crate) struct Groups {
    pub(crate) org: [[Vec4; GROUPS]; 3],
    pub(crate) inv: [[Vec4; GROUPS]; 3],
    pub(crate) t_min: [Vec4; GROUPS],
    /// Each lane's best-hit distance so far (or its ray's end).
    pub(crate) ends: [Vec4; GROUPS],
    /// Per group, the largest end of its active lanes (−∞ without any).
    group_end: [f32; GROUPS],
    /// Some active lane has a zero direction component.
    zero_dir: bool,
}

impl Groups {
    /// No lanes yet: every group's end −∞.
    const EMPTY: Groups = Groups {
        org: [[Vec4::ZERO; GROUPS]; 3],
        inv: [[Vec4::ZERO; GROUPS]; 3],
        t_min: [Vec4::ZERO; GROUPS],
        ends: [Vec4::ZERO; GROUPS],
        group_end: [f32::NEG_INFINITY; GROUPS],
        zero_dir: false,
    };

    /// The packet's lanes, by value (for tests).
    #[cfg(test)]
    fn new<const N: usize>(p: &RayPacket<N>, groups: usize, mask: u64) -> Groups {
        let mut slot = None;
        Groups::fill(&mut slot, p, groups, mask);
        slot.unwrap_or(Groups::EMPTY)
    }

    /// The packet's lanes written into `slot` in place (built elsewhere and moved in,
    /// the two kilobytes were copied once more per packet: 1% of the bunny's packet time).
    #[inline(always)]
    fn fill<'s, const N: usize>(
        slot: &'s mut Option<Groups>,
        p: &RayPacket<N>,
        groups: usize,
        mask: u64,
    ) -> &'s mut Groups {
        let lanes = |a: &[f32; N], g: usize| match a.get(4 * g..4 * g + 4) {
            // One load; only a packet of fewer than four rays takes the other arm.
            Some(l) => Vec4::from_slice(l),
            None => Vec4::from_array(core::array::from_fn(|k| a.get(4 * g + k).copied().unwrap_or(0.0))),
        };
        let q = slot.insert(Groups::EMPTY);
        for g in 0..groups.min(GROUPS) {
            let act = GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
            for (a, (o, d)) in [(&p.ox, &p.dx), (&p.oy, &p.dy), (&p.oz, &p.dz)].into_iter().enumerate() {
                let d = lanes(d, g);
                q.org[a][g] = lanes(o, g);
                q.inv[a][g] = recip4(d);
                q.zero_dir |= (d.cmpeq(Vec4::ZERO) & act).any();
            }
            q.t_min[g] = lanes(&p.t_min, g);
            q.ends[g] = lanes(&p.t_max, g);
            q.update_end(g, mask);
        }
        q
    }

    // `largest_end` reads the ends as four registers.
    const _FOUR_QUADS: () = assert!(GROUPS == 16);

    /// The largest end of the groups' active lanes: how far any ray of the packet still
    /// looks. (Groups past the packet's have no active lane: their end stays −∞.)
    #[inline(always)]
    fn largest_end(&self) -> f32 {
        let e = &self.group_end;
        let quad = |k: usize| Vec4::new(e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]);
        quad(0).max(quad(1)).max(quad(2).max(quad(3))).max_element()
    }

    /// Recomputes group `g`'s largest end.
    #[inline(always)]
    fn update_end(&mut self, g: usize, mask: u64) {
        let act = GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
        self.group_end[g] = Vec4::select(act, self.ends[g], Vec4::NEG_INFINITY).max_element();
    }
}

/// The slots set in `mask`, ordered by entry distance `t` (insertion sort: at most four),
/// and how many there are.
#[inline(always)]
fn nearest_first(mask: u32, t: &[f32; 4]) -> ([usize; 4], usize) {
    let mut order = [0usize; 4];
    let mut m = 0;
    for k in 0..4 {
        if mask & (1 << k) != 0 {
            let mut j = m;
            // Indices masked below 4: the compiler sees them in range (no panic path).
            while j > 0 && t[order[(j - 1) & 3] & 3] > t[k] {
                order[j & 3] = order[(j - 1) & 3];
                j -= 1;
            }
            order[j & 3] = k;
            m += 1;
        }
    }
    (order, m)
}

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
///
/// Inner nodes are tested once for the whole packet with the interval-arithmetic
/// `Frustum`; at a leaf each ray tests the leaf's box (up to its own best hit) and only
/// the rays that enter it test the triangles (four rays against one triangle at once where
/// two or more of a group of four lanes enter). Since the frustum test is conservative,
/// every ray still tests every triangle its single-ray walk would. A packet whose rays
/// have a zero direction component falls back to one exact 4-box test per ray and node.
pub fn trace_bvh4_packet<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    hits: &mut PacketHits<N>,
    probe: &mut P,
    counters: &mut PacketCounters,
) {
    if !<I::Nodes as NodeTests>::FLOAT {
        let walk = |r: &Ray, c: &mut RayCounters| trace_bvh4::<I, P>(scene, bvh, r, probe, c);
        return ray_by_ray(packet, hits, counters, walk);
    }
    *hits = [None; N];
    let mask = packet.live();
    if mask == 0 {
        return;
    }
    let groups = N.div_ceil(4);
    let full = N <= 64 && mask == u64::MAX >> (64 - N.clamp(1, 64));
    // The lanes in SIMD registers with their reciprocals: computed when the first leaf
    // needs them, if the frustum can do without (see `Frustum::from_full_packet`).
    let mut lanes: Option<Groups> = None;
    // Each ray's exact box test, where the frustum cannot serve.
    let mut boxes: Option<[RayBox; N]> = None;
    // `t_end`: how far any ray of the packet still looks.
    let (cull, mut t_end): (Cull<N>, f32) = match full.then(|| Frustum::from_full_packet(packet)).flatten() {
        Some((f, t_end)) => (Cull::Frustum(f), t_end),
        None => {
            let q = Groups::fill(&mut lanes, packet, groups, mask);
            let t_end = q.largest_end();
            match Frustum::new(q, groups, mask) {
                Some(f) => (Cull::Frustum(f), t_end),
                None => (Cull::Exact(boxes.insert(core::array::from_fn(|i| RayBox::new(&packet.ray(i))))), t_end),
            }
        }
    };
    // The watertight constants are computed the first time a ray enters a leaf: most
    // rays of a frame never do.
    let mut preps = Preps::<I, N>::new();
    // (child or first entry, leaf count or 0, entry bound, leaf box as min xyz, max xyz)
    let mut stack: heapless::Vec<(u32, u32, f32, [f32; 6]), STACK> = heapless::Vec::new();
    let mut current = (0u32, 0u32, [0f32; 6], 0f32);
    let mut c = PacketCounters::default();
    loop {
        let (index, count, leaf_box, leaf_t) = current;
        c.visits += 1;
        if count == 0 {
            let node = bvh.node(index, probe);
            let (tn, needed) = match &cull {
                Cull::Frustum(f) => {
                    c.active_lanes += mask.count_ones() as u64;
                    f.slab4(node, t_end)
                }
                Cull::Exact(boxes) => {
                    let mut needed = 0u32;
                    let mut t = Vec4::INFINITY;
                    for i in Lanes(mask) {
                        let end = hits[i].map_or(packet.t_max[i], |h: Hit| h.t);
                        let (tn, m) = slab4_exact(&boxes[i], node, packet.t_min[i], end);
                        if m != 0 {
                            c.active_lanes += 1;
                            needed |= m;
                            let hit = BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
                            t = t.min(Vec4::select(hit, tn, Vec4::INFINITY));
                        }
                    }
                    (t, needed)
                }
            };
            let child_t = tn.to_array();
            // Needed children, nearest first.
            let (order, n) = nearest_first(needed, &child_t);
            if n > 0 {
                let slot_box = |k: usize| {
                    let k = k & 3;
                    [node.min_x[k], node.min_y[k], node.min_z[k], node.max_x[k], node.max_y[k], node.max_z[k]]
                };
                for &k in order.get(1..n).unwrap_or_default().iter().rev() {
                    let k = k & 3;
                    let _ = stack.push((node.child[k], node.count[k], child_t[k], slot_box(k)));
                }
                let k = order[0] & 3;
                current = (node.child[k], node.count[k], slot_box(k), child_t[k]);
                continue;
            }
        } else {
            let q = match lanes {
                Some(ref mut q) => q,
                None => Groups::fill(&mut lanes, packet, groups, mask),
            };
            let enter = match &cull {
                Cull::Exact(boxes) => {
                    let lo = Vec3A::new(leaf_box[0], leaf_box[1], leaf_box[2]);
                    let hi = Vec3A::new(leaf_box[3], leaf_box[4], leaf_box[5]);
                    let mut enter = 0u64;
                    for i in Lanes(mask) {
                        let end = hits[i].map_or(packet.t_max[i], |h: Hit| h.t);
                        if boxes[i].entry(lo, hi, packet.t_min[i], end).is_some() {
                            enter |= 1 << i;
                        }
                    }
                    enter
                }
                Cull::Frustum(f) => leaf_entries(q, groups, mask, &leaf_box, leaf_t, f.origin()),
            };
            c.active_lanes += enter.count_ones() as u64;
            if enter != 0 {
                preps.fours.prepare(packet, q, mask, enter);
                let shared = match &cull {
                    Cull::Frustum(f) => f.origin().map(Vec3::from).is_some_and(|o| {
                        test_leaf_shared::<I, P, N>(scene, bvh, packet, &mut preps, enter, index, count, o, hits, probe)
                    }),
                    Cull::Exact(_) => false,
                };
                if !shared {
                    test_leaf::<I, P, N>(scene, bvh, packet, &mut preps, enter, index, count, hits, probe);
                }
                c.tri_tests += count as u64 * enter.count_ones() as u64;
                // The ends of the groups that entered, all four lanes from their hits (the
                // other lanes' hits are unchanged, and inactive lanes have none: their
                // ends stay their rays' ends).
                for g in Lanes(groups_of(enter)) {
                    let end = |k: usize| {
                        let i = (4 * g + k).min(N - 1);
                        hits[i].map_or(packet.t_max[i], |h: Hit| h.t)
                    };
                    if let Some(e) = q.ends.get_mut(g) {
                        *e = Vec4::new(end(0), end(1), end(2), end(3));
                        q.update_end(g, mask);
                    }
                }
                t_end = q.largest_end();
            }
        }
        // Pop the next entry whose entry bound is not beyond every ray's best hit.
        loop {
            let Some((child, count, t, b)) = stack.pop() else {
                counters.add(&c);
                return;
            };
            if t > t_end {
                continue;
            }
            current = (child, count, b, t);
            break;
        }
    }
}

/// The active lanes of `mask` that enter the leaf box `[lo, hi]` (`leaf_box`) before
/// their best hit: four rays against the box at once (no zero direction components, so
/// the plain slab test is exact here). `origin`: the rays' one origin, if they share one
/// (every active lane of `q.org` holds it), so that `lo − o` and `hi − o` are computed
/// once per leaf rather than once per group: the same values, hence the same lanes.
#[inline(always)]
fn leaf_entries(
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
fn leaf_entries_portable(
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

/// The rays' intersection constants, computed for a group of four lanes the first time
/// one of its rays enters a leaf (most rays of a frame never do), as four SIMD lanes for
/// the intersector's four-ray form; one ray's own constants only when it is tested alone.
struct Preps<I: Intersector, const N: usize> {
    // Per group of four lanes.
    fours: Fours<I>,
    // Per lane: only lanes tested one by one (redone lanes, lone rays, groups without a
    // four-ray form) need them.
    ones: Ones<I, N>,
}

impl<I: Intersector, const N: usize> Preps<I, N> {
    #[inline(always)]
    fn new() -> Self {
        Preps {
            fours: Fours { four: heapless::Vec::new(), four_slot: [0; GROUPS], ready: 0 },
            ones: Ones { one: heapless::Vec::new(), one_slot: [0; N], one_ready: 0 },
        }
    }
}

/// The four-ray constants of the groups that have needed them. (Computed constants are
/// kept in the order they were asked for, and per group the index of its entry: nothing
/// is written for groups that never need constants; the arrays of every lane's record,
/// initialised per packet, cost packets that miss the scene a tenth of their time.)
struct Fours<I: Intersector> {
    four: heapless::Vec<Option<I::Prepared4>, GROUPS>,
    four_slot: [u8; GROUPS],
    // Groups whose constants are computed.
    ready: u32,
}

impl<I: Intersector> Fours<I> {
    /// Group `g`'s four-ray constants, if ready and the intersector has them.
    #[inline(always)]
    fn get(&self, g: usize) -> Option<&I::Prepared4> {
        if self.ready & (1 << (g % GROUPS)) == 0 {
            return None;
        }
        self.four.get(self.four_slot[g % GROUPS] as usize).and_then(|p| p.as_ref())
    }

    /// Makes the constants of every group with a lane in `enter` ready.
    #[inline(always)]
    fn prepare<const N: usize>(&mut self, packet: &RayPacket<N>, q: &Groups, mask: u64, enter: u64) {
        for g in Lanes(groups_of(enter) & !(self.ready as u64)) {
            let m4 = (mask >> (4 * g)) & 0xF;
            self.ready |= 1 << g;
            // Inactive lanes borrow an active lane's ray (their results are unused).
            let any = 4 * g + m4.trailing_zeros() as usize;
            let act = GROUP_LANES[m4 as usize];
            // A group with all four lanes active (most of them) takes its registers as
            // they are, with one load each.
            let pick = |v: Vec4, a: &[f32; N]| {
                if m4 == 0xF {
                    v
                } else {
                    Vec4::select(act, v, Vec4::splat(a.get(any).copied().unwrap_or(0.0)))
                }
            };
            let lanes = |a: &[f32; N]| match a.get(4 * g..4 * g + 4) {
                Some(l) => Vec4::from_slice(l),
                None => Vec4::from_array(core::array::from_fn(|k| a.get(4 * g + k).copied().unwrap_or(0.0))),
            };
            let org = [pick(q.org[0][g], &packet.ox), pick(q.org[1][g], &packet.oy), pick(q.org[2][g], &packet.oz)];
            let dir = [&packet.dx, &packet.dy, &packet.dz].map(|d| pick(lanes(d), d));
            if let Some(slot) = self.four_slot.get_mut(g) {
                *slot = self.four.len() as u8;
                // Cannot be full: one entry per group.
                let _ = self.four.push(I::prepare_rays4(org, dir));
            }
        }
    }
}

/// The one-ray constants of the lanes that have needed them (as [`Fours`] keeps them).
struct Ones<I: Intersector, const N: usize> {
    one: heapless::Vec<I::Prepared, N>,
    one_slot: [u8; N],
    // Lanes whose constants are computed.
    one_ready: u64,
}

impl<I: Intersector, const N: usize> Ones<I, N> {
    /// Ray `i`'s one-ray constants, computed the first time they are asked for.
    #[inline(always)]
    fn get(&mut self, packet: &RayPacket<N>, i: usize) -> I::Prepared {
        let i = i.min(N - 1);
        if self.one_ready & (1 << i) == 0 {
            self.one_slot[i] = self.one.len() as u8;
            // Cannot be full: one entry per lane.
            let _ = self.one.push(I::prepare(&packet.ray(i)));
            self.one_ready |= 1 << i;
        }
        // Always present (pushed above); the fallback keeps the kernel free of panics.
        match self.one.get(self.one_slot[i] as usize) {
            Some(p) => *p,
            None => I::prepare(&packet.ray(i)),
        }
    }
}

/// Bit `g` set when some lane of group `g` (lanes `4g .. 4g + 4`) is in `lanes`.
#[inline(always)]
fn groups_of(lanes: u64) -> u64 {
    // Each group's four bits folded into its lowest (bit 4g), then those gathered to bit
    // g in halving steps: a dozen operations instead of a loop of sixteen tests.
    let x = lanes | (lanes >> 1);
    let x = (x | (x >> 2)) & 0x1111_1111_1111_1111;
    let x = (x | (x >> 3)) & 0x0303_0303_0303_0303;
    let x = (x | (x >> 6)) & 0x000F_000F_000F_000F;
    let x = (x | (x >> 12)) & 0x0000_00FF_0000_00FF;
    (x | (x >> 24)) & 0xFFFF
}

/// Tests the leaf's triangles (list entries `first .. first + count`) with the rays of
/// `enter`, each triangle read once: four rays at a time where two or more of a group
/// enter and the intersector has a four-ray form, one by one otherwise.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn test_leaf<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    preps: &mut Preps<I, N>,
    enter: u64,
    first: u32,
    count: u32,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) {
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
                        keep_lane(packet, &mut preps.ones, hits, &r, k, (4 * g + k).min(N - 1), prim, || verts);
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

/// Keeps lane `k` of a multi-lane test's outcome `r` on triangle `prim` for packet ray
/// `i`: its hit if in the ray's range, or, where the lane was left undecided, the one-ray
/// test's verdict on the triangle `tri()`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn keep_lane<I: Intersector, const N: usize, const L: usize>(
    packet: &RayPacket<N>,
    ones: &mut Ones<I, N>,
    hits: &mut PacketHits<N>,
    r: &LaneHits<L>,
    k: usize,
    i: usize,
    prim: u32,
    tri: impl FnOnce() -> I::Triangle,
) {
    let ray = packet.ray(i);
    if r.redo & (1 << k) != 0 {
        test_triangle::<I>(&ones.get(packet, i), &ray, &tri(), prim, &mut hits[i]);
    } else if let Some(hit) = in_range(&ray, Some((r.t[k], r.u[k], r.v[k])), prim) {
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
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn test_leaf_shared<I: Intersector, P: MemoryProbe, const N: usize>(
    scene: &SceneView<'_>,
    bvh: &Bvh4View<'_>,
    packet: &RayPacket<N>,
    preps: &mut Preps<I, N>,
    enter: u64,
    first: u32,
    count: u32,
    origin: Vec3,
    hits: &mut PacketHits<N>,
    probe: &mut P,
) -> bool {
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
                keep_lane(packet, &mut preps.ones, hits, o, lane, i, prim, tri);
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

    use crate::image::WideNode;
    use crate::ray::Ray;
    use crate::test_lcg::Lcg;
    use glam::Vec3;

    /// The bit trick gives the definition's groups: bit `g` where some lane of `4g .. 4g
    /// + 4` is set.
    #[test]
    fn groups_of_marks_the_groups_with_a_lane() {
        let mut g = Lcg(3);
        for case in 0..20_000u64 {
            // Sparse masks too, so that groups with one lane (each of the four) occur.
            let lanes = match case % 3 {
                0 => g.next(),
                1 => g.next() & g.next() & g.next(),
                _ => 1 << (case % 64),
            };
            let want = (0..GROUPS).fold(0u64, |m, k| m | ((((lanes >> (4 * k)) & 0xF) != 0) as u64) << k);
            assert_eq!(groups_of(lanes), want, "lanes {lanes:#x}");
        }
    }

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
