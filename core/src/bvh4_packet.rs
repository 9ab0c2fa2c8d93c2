//! Packet traversal of the 4-wide BVH: the packet visits a node if any of its rays may
//! hit one of the node's boxes, nearest child first; a leaf intersects its triangles with
//! exactly the rays that enter its box.

use crate::bvh4::{nearest_first, slab4};
use glam::{Vec3A, Vec4};

use crate::aabb::SLAB_GROWTH;
use crate::hit::Hit;
use crate::image::{Bvh4Node, Bvh4View, SceneView, MAX_TREE_DEPTH, NULL_INDEX};
use crate::packet::{Lanes, PacketCounters, PacketHits, RayPacket, MAX_PACKET};
use crate::probe::MemoryProbe;
use crate::ray_box::{recip, RayBox};
use crate::triangle::{test_triangle, Intersector};

const STACK: usize = 3 * MAX_TREE_DEPTH as usize + 4;

/// The packet as one conservative "frustum": the box of its origins and of its
/// reciprocal directions. Interval arithmetic on these bounds gives, for a box, an entry
/// distance no larger and an exit no smaller than any single ray's (rounding is monotone,
/// so the bounds are attained at the corners), hence a box rejected for the packet is
/// rejected by every ray (Reshetov et al. 2005; Wald et al. 2007).
#[derive(Clone, Copy, Debug)]
struct Frustum {
    olo: [f32; 3],
    ohi: [f32; 3],
    ilo: [f32; 3],
    ihi: [f32; 3],
    t_min: f32,
}

impl Frustum {
    fn new<const N: usize>(p: &RayPacket<N>, mask: u64) -> Option<Frustum> {
        let mut f = Frustum {
            olo: [f32::INFINITY; 3],
            ohi: [f32::NEG_INFINITY; 3],
            ilo: [f32::INFINITY; 3],
            ihi: [f32::NEG_INFINITY; 3],
            t_min: f32::INFINITY,
        };
        for i in Lanes(mask) {
            let o = [p.ox[i], p.oy[i], p.oz[i]];
            let d = [p.dx[i], p.dy[i], p.dz[i]];
            for a in 0..3 {
                // A zero direction component needs the exact per-ray rule of `RayBox`.
                if d[a] == 0.0 {
                    return None;
                }
                let inv = recip(d[a]);
                f.olo[a] = f.olo[a].min(o[a]);
                f.ohi[a] = f.ohi[a].max(o[a]);
                f.ilo[a] = f.ilo[a].min(inv);
                f.ihi[a] = f.ihi[a].max(inv);
            }
            f.t_min = f.t_min.min(p.t_min[i]);
        }
        Some(f)
    }

    /// Lower bound of the entry distance into each child box, and which boxes some ray
    /// may hit before `t_end` (the largest best-hit distance of the packet).
    #[inline(always)]
    fn slab4(&self, n: &Bvh4Node, t_end: f32) -> (Vec4, u32) {
        let mut near = Vec4::splat(self.t_min);
        let mut far = Vec4::splat(f32::INFINITY);
        let planes = [(n.min_x, n.max_x), (n.min_y, n.max_y), (n.min_z, n.max_z)];
        for (a, (lo, hi)) in planes.into_iter().enumerate() {
            let (il, ih) = (Vec4::splat(self.ilo[a]), Vec4::splat(self.ihi[a]));
            let (ol, oh) = (Vec4::splat(self.olo[a]), Vec4::splat(self.ohi[a]));
            let (lo, hi) = (Vec4::from_array(lo), Vec4::from_array(hi));
            let p = [(lo - oh) * il, (lo - oh) * ih, (lo - ol) * il, (lo - ol) * ih];
            let q = [(hi - oh) * il, (hi - oh) * ih, (hi - ol) * il, (hi - ol) * ih];
            let mut mn = p[0];
            let mut mx = p[0];
            for v in p.iter().chain(q.iter()) {
                mn = mn.min(*v);
                mx = mx.max(*v);
            }
            near = near.max(mn);
            far = far.min(mx * SLAB_GROWTH);
        }
        far = far.min(Vec4::splat(t_end));
        let valid = (0..4).fold(0u32, |m, k| m | (((n.child[k] != NULL_INDEX) as u32) << k));
        (near, near.cmple(far).bitmask() & valid)
    }
}

/// Lanes `4g .. 4g + 4` of a per-ray array as one SIMD register (a single load).
#[inline(always)]
fn load4<const N: usize>(a: &[f32; N], g: usize) -> Vec4 {
    match a.get(4 * g..4 * g + 4).and_then(|s| <[f32; 4]>::try_from(s).ok()) {
        Some(v) => Vec4::from_array(v),
        None => Vec4::ZERO,
    }
}

/// Traces all active rays of `packet`; `hits[i]` receives ray `i`'s closest hit.
///
/// Inner nodes are tested once for the whole packet with the interval-arithmetic
/// [`Frustum`]; at a leaf each ray tests the leaf's box (up to its own best hit) and only
/// the rays that enter it test the triangles. Since the frustum test is conservative,
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
    let rays: [_; N] = core::array::from_fn(|i| packet.ray(i));
    *hits = [None; N];
    let mask = packet.active;
    if mask == 0 {
        return;
    }
    // The watertight constants are computed the first time a ray enters a leaf: most
    // rays of a frame never do.
    let mut preps: [I::Prepared; N] = [I::Prepared::default(); N];
    let mut prepared = 0u64;
    let frustum = Frustum::new(packet, mask);
    // Reciprocal directions for the 4-rays-at-once leaf box test (the packet is already
    // a structure of arrays).
    let org = [&packet.ox, &packet.oy, &packet.oz];
    let inv: [[f32; N]; 3] = [
        core::array::from_fn(|i| recip(packet.dx[i])),
        core::array::from_fn(|i| recip(packet.dy[i])),
        core::array::from_fn(|i| recip(packet.dz[i])),
    ];
    let t_min = &packet.t_min;
    let mut ends: [f32; N] = packet.t_max;
    // Per group of four lanes, the largest of their ends (for whole-group culling), and
    // the largest of all: how far any ray of the packet still looks.
    let groups = N.div_ceil(4);
    let group_end_of = |ends: &[f32; N], g: usize| {
        (4 * g..(4 * g + 4).min(N)).filter(|&j| mask & (1 << j) != 0).fold(f32::NEG_INFINITY, |m, j| m.max(ends[j]))
    };
    let mut group_end = [f32::NEG_INFINITY; MAX_PACKET / 4];
    for (g, e) in group_end.iter_mut().enumerate().take(groups) {
        *e = group_end_of(&ends, g);
    }
    let mut t_end = group_end.iter().take(groups).fold(f32::NEG_INFINITY, |m, &e| m.max(e));
    // (child or first entry, leaf count or 0, entry bound, leaf box as min xyz, max xyz)
    let mut stack: heapless::Vec<(u32, u32, f32, [f32; 6]), STACK> = heapless::Vec::new();
    let mut current = (0u32, 0u32, [0f32; 6], 0f32);
    let mut c = PacketCounters::default();
    loop {
        let (index, count, leaf_box, leaf_t) = current;
        c.visits += 1;
        if count == 0 {
            let node = bvh.node(index, probe);
            let (tn, needed) = match &frustum {
                Some(f) => {
                    c.active_lanes += mask.count_ones() as u64;
                    f.slab4(node, t_end)
                }
                None => {
                    let mut needed = 0u32;
                    let mut t = Vec4::INFINITY;
                    for i in Lanes(mask) {
                        let end = hits[i].map_or(rays[i].t_max, |h: Hit| h.t);
                        let (tn, m) = slab4(&RayBox::new(&rays[i]), node, rays[i].t_min, end);
                        if m != 0 {
                            c.active_lanes += 1;
                            needed |= m;
                            let hit = glam::BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
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
                    [node.min_x[k], node.min_y[k], node.min_z[k], node.max_x[k], node.max_y[k], node.max_z[k]]
                };
                for &k in order[1..n].iter().rev() {
                    let _ = stack.push((node.child[k], node.count[k], child_t[k], slot_box(k)));
                }
                let k = order[0];
                current = (node.child[k], node.count[k], slot_box(k), child_t[k]);
                continue;
            }
        } else {
            let mut enter = 0u64;
            if frustum.is_some() && N.is_multiple_of(4) {
                // Four rays against the leaf box at once (no zero direction components,
                // so the plain slab test is exact here).
                for (g, &group_end) in group_end.iter().enumerate().take(N / 4) {
                    let m4 = (mask >> (4 * g)) & 0xF;
                    // `leaf_t` bounds every ray's entry from below: a group whose rays all
                    // have nearer hits skips the exact test.
                    if m4 == 0 || leaf_t > group_end {
                        continue;
                    }
                    let mut tn = load4(t_min, g);
                    let mut tf = load4(&ends, g);
                    for a in 0..3 {
                        let o = load4(org[a], g);
                        let iv = load4(&inv[a], g);
                        let p = (Vec4::splat(leaf_box[a]) - o) * iv;
                        let q = (Vec4::splat(leaf_box[a + 3]) - o) * iv;
                        tn = tn.max(p.min(q));
                        tf = tf.min(p.max(q) * SLAB_GROWTH);
                    }
                    enter |= ((tn.cmple(tf).bitmask() as u64) & m4) << (4 * g);
                }
            } else {
                let lo = Vec3A::new(leaf_box[0], leaf_box[1], leaf_box[2]);
                let hi = Vec3A::new(leaf_box[3], leaf_box[4], leaf_box[5]);
                for i in Lanes(mask) {
                    if RayBox::new(&rays[i]).entry(lo, hi, rays[i].t_min, ends[i]).is_some() {
                        enter |= 1 << i;
                    }
                }
            }
            c.active_lanes += enter.count_ones() as u64;
            if enter != 0 {
                for i in Lanes(enter & !prepared) {
                    preps[i] = I::prepare(&rays[i]);
                }
                prepared |= enter;
                for e in index..index.wrapping_add(count) {
                    let prim = bvh.prim(e, probe);
                    let verts = I::fetch(scene, prim, probe);
                    for i in Lanes(enter) {
                        test_triangle::<I>(&preps[i], &rays[i], &verts, prim, &mut hits[i]);
                    }
                }
                c.tri_tests += count as u64 * enter.count_ones() as u64;
                let mut touched = 0u64;
                for i in Lanes(enter) {
                    ends[i] = hits[i].map_or(rays[i].t_max, |h: Hit| h.t);
                    touched |= 1 << (i / 4);
                }
                for g in Lanes(touched) {
                    if let Some(e) = group_end.get_mut(g) {
                        *e = group_end_of(&ends, g);
                    }
                }
                t_end = group_end.iter().take(groups).fold(f32::NEG_INFINITY, |m, &e| m.max(e));
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
