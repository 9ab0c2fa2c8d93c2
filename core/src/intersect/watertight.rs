//! Watertight ray–triangle intersection: Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013. The ray is sheared so that it runs along +z through
//! the origin; the 2D edge functions U, V, W then decide the hit with no epsilon, and a
//! ray through a shared edge or vertex hits at least one of the triangles sharing it.
//! When an edge function is exactly zero it is recomputed in double precision (§3.4).

use core::ops::{Add, Mul, Sub};

use glam::{Vec3, Vec4};

use crate::image::{SceneView, TriBlock4};
use crate::intersect::triangle::{Hits8, Intersector, LaneHits, RayPair, Rays4Result, SharedTris};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
#[cfg(target_arch = "x86_64")]
use crate::simd::watertight8::SharedShear;

/// The watertight test (default).
#[derive(Clone, Copy, Debug, Default)]
pub struct Watertight;

/// Per-ray shear constants (paper, Fig. 1 lines 1–14).
#[derive(Clone, Copy, Debug, Default)]
pub struct ShearedRay {
    org: Vec3,
    // Axis indices as bytes: the record stays small (packets keep one per ray).
    kx: u8,
    ky: u8,
    kz: u8,
    sx: f32,
    sy: f32,
    sz: f32,
}

impl Intersector for Watertight {
    type Prepared = ShearedRay;
    type Triangle = [Vec3; 3];
    const NAME: &'static str = "watertight";
    type Nodes = crate::traverse::boxes::datapath::FloatNodes;
    type Prepared4 = ShearedRays4;
    type Prepared16 = ShearedRays16;

    /// The lanes whose axis order is the first lane's: every lane's constants computed
    /// in that order, row by row (the other lanes' are not read). The axis order by
    /// [`Watertight::prepare`]'s rule; the divisions sixteen lanes at once (exact, so the
    /// same bits as one by one).
    #[inline(always)]
    fn prepare_rays16(org: &[[f32; 16]; 3], dir: &[[f32; 16]; 3], lanes: u32) -> Option<(ShearedRays16, u32)> {
        let wide = crate::simd::Wide16::reported()?;
        let lead = lanes.trailing_zeros() as usize % 16;
        let k = axis_order(Vec3::new(dir[0][lead], dir[1][lead], dir[2][lead]));
        let [kx, ky, kz] = k.map(|a| a.min(2));
        // The lanes whose largest component is on `kz` (ties to the lower axis, as
        // `axis_order`) with the lead's sign there: lane by lane over the rows, with no
        // branch (so that the loop runs in SIMD lanes).
        let (x, y, z, dk) = (&dir[0], &dir[1], &dir[2], &dir[kz]);
        let lead_negative = dk[lead] < 0.0;
        let mut covered = 0u32;
        for i in 0..16 {
            let (ax, ay, az) = (x[i].abs(), y[i].abs(), z[i].abs());
            let x_major = (ax >= ay) & (ax >= az);
            let y_major = !x_major & (ay >= az);
            let major = match kz {
                0 => x_major,
                1 => y_major,
                _ => !x_major & !y_major,
            };
            covered |= u32::from(major & ((dk[i] < 0.0) == lead_negative)) << i;
        }
        let (dx, dy, dz) = (&dir[kx], &dir[ky], &dir[kz]);
        let out = ShearedRays16 {
            org: [org[kx], org[ky], org[kz]],
            s: [
                core::array::from_fn(|i| dx[i] / dz[i]),
                core::array::from_fn(|i| dy[i] / dz[i]),
                core::array::from_fn(|i| 1.0 / dz[i]),
            ],
            k,
            wide,
        };
        Some((out, covered & lanes))
    }

    #[inline(always)]
    fn intersect_rays16(r: &ShearedRays16, v: &[Vec3; 3], out: &mut LaneHits<16>) {
        #[cfg(target_arch = "x86_64")]
        {
            let [k0, k1, k2] = r.k;
            let frame = |p: &Vec3| {
                let p = [p.x, p.y, p.z, 0.0];
                [p[k0 & 3], p[k1 & 3], p[k2 & 3]]
            };
            let v = [frame(&v[0]), frame(&v[1]), frame(&v[2])];
            crate::simd::rays16::watertight16(r.wide, &r.org, &r.s, &v, out);
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (r, v);
            (out.hit, out.redo) = (0, 0xFFFF);
        }
    }

    /// [`Watertight::prepare`] for four rays at once: the same axis choice (the largest
    /// direction component, ties to the lower axis) and the same divisions, per lane.
    #[inline(always)]
    fn prepare_rays4(org: [Vec4; 3], dir: [Vec4; 3]) -> Option<ShearedRays4> {
        let [ax, ay, az] = dir.map(Vec4::abs);
        let x_major = ax.cmpge(ay) & ax.cmpge(az);
        let y_major = !x_major & ay.cmpge(az);
        let kz = match (x_major.bitmask(), y_major.bitmask()) {
            (0xF, _) => 0,
            (0, 0xF) => 1,
            (0, 0) => 2,
            _ => return None,
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Swap to preserve the winding of the triangle: all four rays alike, or none.
        match dir[kz].cmplt(Vec4::ZERO).bitmask() {
            0xF => core::mem::swap(&mut kx, &mut ky),
            0 => {}
            _ => return None,
        }
        Some(ShearedRays4 {
            org: [org[kx], org[ky], org[kz]],
            sx: dir[kx] / dir[kz],
            sy: dir[ky] / dir[kz],
            sz: Vec4::ONE / dir[kz],
            k: [kx, ky, kz],
        })
    }

    /// [`Watertight::intersect`] with the four rays in SIMD lanes: per lane the same
    /// operations in the same order. A lane with an edge function of exactly zero is
    /// left to the scalar test (its double-precision recomputation).
    #[inline(always)]
    fn intersect_rays4(r: &ShearedRays4, v: &[Vec3; 3]) -> Rays4Result {
        // Vertex coordinates relative to each ray's origin, read in the rays' axis order
        // (x, y, z of the sheared frame) so that no register array is indexed by axis.
        let rel = |p: Vec3| -> [Vec4; 3] {
            // `& 3` into four entries: no bounds check per coordinate (a measurable
            // share of the test's instructions).
            let p = [p.x, p.y, p.z, 0.0];
            let ([k0, k1, k2], [o0, o1, o2]) = (r.k, r.org);
            [Vec4::splat(p[k0 & 3]) - o0, Vec4::splat(p[k1 & 3]) - o1, Vec4::splat(p[k2 & 3]) - o2]
        };
        lanes(rel(v[0]), rel(v[1]), rel(v[2]), [r.sx, r.sy, r.sz])
    }

    const SHARED8: bool = true;

    #[inline(always)]
    fn frame4(r: &ShearedRays4) -> u32 {
        frame_of(r.k)
    }

    /// `v − origin` once per triangle, in the frame's axis order: where every lane's
    /// origin is `origin`, lane by lane the subtraction of [`Watertight::intersect_rays4`].
    #[inline(always)]
    fn share(r: &ShearedRays4, origin: Vec3, v: &[Vec3; 3], into: &mut SharedTris, slot: usize) {
        let o = origin.to_array();
        for (rel, p) in into.rel.iter_mut().zip(v) {
            let p = p.to_array();
            for (axis, &k) in rel.iter_mut().zip(&r.k) {
                axis[slot % SharedTris::SLOTS] = p[k % 3] - o[k % 3];
            }
        }
    }

    /// [`Watertight::share`] for a block's four lanes at once: the same subtractions.
    #[inline(always)]
    fn share_block(r: &ShearedRays4, origin: Vec3, block: &TriBlock4, into: &mut SharedTris, half: usize) {
        let o = origin.to_array();
        let at = 4 * (half % 2);
        for (rel, v) in into.rel.iter_mut().zip(&block.v) {
            for (axis, &k) in rel.iter_mut().zip(&r.k) {
                let d = Vec4::from_array(v[k % 3]) - Vec4::splat(o[k % 3]);
                d.write_to_slice(&mut axis[at..at + 4]);
            }
        }
    }

    #[inline(always)]
    fn intersect_shared8(
        pairs: &[RayPair<'_, ShearedRays4>],
        tris: &SharedTris,
        n: usize,
        found: impl FnMut(usize, usize, &Hits8),
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = crate::simd::Avx::reported() {
            // Each pair's shear constants as eight lanes, once for all the triangles.
            let mut shear = heapless::Vec::<SharedShear, { crate::packet::MAX_PACKET / 8 }>::new();
            for p in pairs {
                // Cannot be full: a packet has at most `MAX_PACKET / 8` pairs.
                let _ = shear.push(SharedShear::pair(p.lo, p.hi, p.lanes));
            }
            crate::simd::watertight8::shared8(avx, tris, n.min(SharedTris::SLOTS), &shear, found);
            return true;
        }
        let _ = (pairs, tris, n, found);
        false
    }

    const BLOCKS: bool = true;

    /// [`Watertight::intersect`] with four triangles in SIMD lanes and the ray in all
    /// four: per lane the same operations in the same order as the one-triangle test.
    #[inline(always)]
    fn block_triangle(block: &TriBlock4, lane: usize) -> Option<[Vec3; 3]> {
        Some(block.v.map(|[x, y, z]| Vec3::new(x[lane & 3], y[lane & 3], z[lane & 3])))
    }

    #[inline(always)]
    fn intersect_block4(s: &ShearedRay, block: &TriBlock4) -> Rays4Result {
        let org = s.org.to_array();
        let k = [s.kx, s.ky, s.kz];
        // Vertex coordinates relative to the ray's origin, read in the ray's axis order
        // (x, y, z of the sheared frame) so that no register array is indexed by axis.
        // (`min(2)`: axis indices are below 3, and the compiler sees it there.)
        let rel = |v: &[[f32; 4]; 3]| -> [Vec4; 3] {
            k.map(|a| {
                let a = (a as usize).min(2);
                Vec4::from_array(v[a]) - Vec4::splat(org[a])
            })
        };
        let [v0, v1, v2] = &block.v;
        lanes(rel(v0), rel(v1), rel(v2), [s.sx, s.sy, s.sz].map(Vec4::splat))
    }

    #[inline(always)]
    fn fetch<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, probe: &mut P) -> [Vec3; 3] {
        scene.triangle(prim, probe)
    }

    #[inline]
    fn prepare(ray: &Ray) -> ShearedRay {
        let d = ray.dir;
        let [kx, ky, kz] = axis_order(d);
        ShearedRay {
            org: ray.origin,
            kx: kx as u8,
            ky: ky as u8,
            kz: kz as u8,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        }
    }

    #[inline(always)]
    fn intersect(s: &ShearedRay, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        // Arrays, not `Vec3` indexing: a plain bounds-checked load per coordinate.
        let a = (v[0] - s.org).to_array();
        let b = (v[1] - s.org).to_array();
        let c = (v[2] - s.org).to_array();
        // Below 3 by construction; `min(2)` lets the compiler see it (no bounds checks).
        let k = [s.kx, s.ky, s.kz].map(|a| (a as usize).min(2));
        let (sheared, e) = shear_edges(a, b, c, k, s.sx, s.sy);
        // An edge function of exactly 0: its true sign, from double precision (Woop et
        // al. 2013, section 3.3). Without the feature the 0 counts as inside.
        #[cfg(feature = "f64-fallback")]
        let e = if e.contains(&0.0) { edges(sheared.map(f64::from)).map(|e| e as f32) } else { e };
        #[cfg(not(feature = "f64-fallback"))]
        let _ = sheared;
        let [eu, ev, ew] = e;
        if (eu < 0.0 || ev < 0.0 || ew < 0.0) && (eu > 0.0 || ev > 0.0 || ew > 0.0) {
            return None;
        }
        let det = eu + ev + ew;
        if det == 0.0 {
            return None;
        }
        let kz = k[2];
        let t_scaled = scaled_distance([eu, ev, ew], [a[kz], b[kz], c[kz]], s.sz);
        let inv = 1.0 / det;
        Some((t_scaled * inv, ev * inv, ew * inv))
    }
}

/// Fig. 1, lines 15–29, on vertices `a`, `b`, `c` already relative to the ray origin:
/// the sheared 2D coordinates `[ax, ay, bx, by, cx, cy]` and the edge functions
/// `[U, V, W]`. Generic so that one ray (`f32`) and four (`Vec4` lanes) go through the
/// same operations in the same order, hence round alike.
#[inline(always)]
fn shear_edges<T: Copy + Sub<Output = T> + Mul<Output = T>>(
    a: [T; 3],
    b: [T; 3],
    c: [T; 3],
    [kx, ky, kz]: [usize; 3],
    sx: T,
    sy: T,
) -> ([T; 6], [T; 3]) {
    // Axis indices are below 3 (`ShearedRay`); `min(2)` shows the compiler too, so the
    // reads below have no bounds checks (a conditional move each, no panic path).
    let (kx, ky, kz) = (kx.min(2), ky.min(2), kz.min(2));
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let sheared = [ax, ay, bx, by, cx, cy];
    (sheared, edges(sheared))
}

/// The edge functions `[U, V, W]` of the sheared 2D vertices `[ax, ay, bx, by, cx, cy]`.
#[inline(always)]
fn edges<T: Copy + Sub<Output = T> + Mul<Output = T>>([ax, ay, bx, by, cx, cy]: [T; 6]) -> [T; 3] {
    [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax]
}

/// Fig. 1, lines 37–40: the hit distance scaled by the determinant, from the edge
/// functions `e` and the vertices' coordinates `z` along the ray's major axis.
#[inline(always)]
fn scaled_distance<T: Copy + Add<Output = T> + Mul<Output = T>>(e: [T; 3], z: [T; 3], sz: T) -> T {
    e[0] * (sz * z[0]) + e[1] * (sz * z[1]) + e[2] * (sz * z[2])
}

/// The four-lane test (four rays, or four triangles) on vertices `a`, `b`, `c` already
/// relative to the ray origins and in the rays' axis order (x, y, z of the sheared
/// frame): lane by lane [`Watertight::intersect`]'s operations, with the lanes whose
/// edge function is exactly zero left in `redo` for its double-precision recomputation.
#[inline(always)]
fn lanes(a: [Vec4; 3], b: [Vec4; 3], c: [Vec4; 3], [sx, sy, sz]: [Vec4; 3]) -> Rays4Result {
    let kz = 2;
    let (_, [eu, ev, ew]) = shear_edges(a, b, c, [0, 1, kz], sx, sy);
    let zero = Vec4::ZERO;
    let redo = (eu.cmpeq(zero) | ev.cmpeq(zero) | ew.cmpeq(zero)).bitmask();
    let neg = eu.cmplt(zero) | ev.cmplt(zero) | ew.cmplt(zero);
    let pos = eu.cmpgt(zero) | ev.cmpgt(zero) | ew.cmpgt(zero);
    let det = eu + ev + ew;
    let hit = (!(neg & pos) & det.cmpne(zero)).bitmask() & !redo;
    if hit == 0 {
        return Rays4Result { redo, ..Rays4Result::default() };
    }
    let t_scaled = scaled_distance([eu, ev, ew], [a[kz], b[kz], c[kz]], sz);
    let inv = Vec4::ONE / det;
    Rays4Result { t: (t_scaled * inv).to_array(), u: (ev * inv).to_array(), v: (ew * inv).to_array(), hit, redo }
}

/// The sheared frame's axes `[kx, ky, kz]` for direction `d` (paper, Fig. 1 lines 1–6):
/// `kz` where the direction is largest in magnitude (ties to the lower axis), `kx` and
/// `ky` the others, swapped where `d[kz]` is negative to keep the triangles' winding.
#[inline(always)]
fn axis_order(d: Vec3) -> [usize; 3] {
    let a = d.abs();
    let kz = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let mut kx = (kz + 1) % 3;
    let mut ky = (kx + 1) % 3;
    if d[kz] < 0.0 {
        core::mem::swap(&mut kx, &mut ky);
    }
    [kx, ky, kz]
}

/// An axis order as one number, to compare frames.
#[inline(always)]
fn frame_of([kx, ky, kz]: [usize; 3]) -> u32 {
    (kx | (ky << 2) | (kz << 4)) as u32
}

/// Four rays' shear constants as SIMD lanes (rays with one axis permutation).
#[derive(Clone, Copy, Debug)]
pub struct ShearedRays4 {
    // The origins in the rays' axis order `k` (x, y, z of the sheared frame).
    org: [Vec4; 3],
    pub(crate) sx: Vec4,
    pub(crate) sy: Vec4,
    pub(crate) sz: Vec4,
    k: [usize; 3],
}

impl ShearedRay {
    /// The ray's frame: its axis order `[kx, ky, kz]` (for tests).
    #[cfg(test)]
    pub(crate) fn kx_ky_kz(&self) -> [u8; 3] {
        [self.kx, self.ky, self.kz]
    }
}

/// Sixteen rays' shear constants as AVX-512 lanes (rays with one axis permutation), with
/// the token that lets the sixteen-lane test run.
#[derive(Clone, Copy, Debug)]
// Off x86-64 no constants are made (no AVX-512), and the test never reads them.
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub struct ShearedRays16 {
    // The origins in the rays' axis order `k`; the shear `sx`, `sy`, `sz`.
    org: [[f32; 16]; 3],
    s: [[f32; 16]; 3],
    k: [usize; 3],
    wide: crate::simd::Wide16,
}

impl ShearedRays16 {
    /// The same constants for the sixteen-lane test's form `wide` (tests compare the
    /// forms).
    #[cfg(test)]
    pub(crate) fn in_form(self, wide: crate::simd::Wide16) -> ShearedRays16 {
        ShearedRays16 { wide, ..self }
    }
}

/// The shear constants of two groups of four rays as the eight lanes of the AVX test.
#[cfg(target_arch = "x86_64")]
impl SharedShear {
    /// The constants of groups `lo` (lanes 0–3) and `hi` (lanes 4–7), with `lanes`.
    pub(crate) fn pair(lo: &ShearedRays4, hi: &ShearedRays4, lanes: u32) -> SharedShear {
        let eight = |a: Vec4, b: Vec4| {
            let (a, b) = (a.to_array(), b.to_array());
            [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
        };
        SharedShear { s: [eight(lo.sx, hi.sx), eight(lo.sy, hi.sy), eight(lo.sz, hi.sz)], lanes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_lcg::Lcg;

    /// Mostly small lattice values, so that components tie in magnitude, are zero or
    /// differ only in sign.
    fn coord(g: &mut Lcg) -> f32 {
        match (g.next() >> 33) % 4 {
            0 => ((g.next() >> 33) % 5) as f32 - 2.0,
            _ => ((g.next() >> 33) % 2001) as f32 / 1000.0 - 1.0,
        }
    }

    /// The four rays' one-ray constants in SIMD lanes, or `None` unless they share one
    /// axis order.
    fn gather(r: [&ShearedRay; 4]) -> Option<ShearedRays4> {
        let k = (r[0].kx, r[0].ky, r[0].kz);
        if r.iter().any(|s| (s.kx, s.ky, s.kz) != k) {
            return None;
        }
        let lanes = |f: fn(&ShearedRay) -> f32| Vec4::new(f(r[0]), f(r[1]), f(r[2]), f(r[3]));
        let org = [lanes(|s| s.org.x), lanes(|s| s.org.y), lanes(|s| s.org.z)];
        Some(ShearedRays4 {
            org: [org[k.0 as usize % 3], org[k.1 as usize % 3], org[k.2 as usize % 3]],
            sx: lanes(|s| s.sx),
            sy: lanes(|s| s.sy),
            sz: lanes(|s| s.sz),
            k: [k.0 as usize % 3, k.1 as usize % 3, k.2 as usize % 3],
        })
    }

    fn bits(v: Vec4) -> [u32; 4] {
        v.to_array().map(f32::to_bits)
    }

    /// The four-ray constants computed in SIMD lanes are, bit for bit, those of the
    /// one-ray constants gathered, and missing exactly when the gather refuses.
    #[test]
    fn four_ray_constants_match_the_one_ray_constants_gathered() {
        let mut g = Lcg(5);
        let (mut same, mut refused) = (0, 0);
        for case in 0..20_000 {
            let mut dir = || {
                let d = Vec3::new(coord(&mut g), coord(&mut g), coord(&mut g));
                if d == Vec3::ZERO {
                    Vec3::X
                } else {
                    d
                }
            };
            // Every other case: one direction for all four rays (negated in the last lane
            // every fourth case), as in a coherent packet.
            let shared = dir();
            let dirs: [Vec3; 4] = core::array::from_fn(|k| match (case % 4, k) {
                (0, 3) => -shared,
                (0 | 2, _) => shared,
                _ => dir(),
            });
            let rays = dirs.map(|d| Ray::new(Vec3::new(coord(&mut g), coord(&mut g), coord(&mut g)), d));
            let one = rays.map(|r| Watertight::prepare(&r));
            let gathered = gather([&one[0], &one[1], &one[2], &one[3]]);
            let lanes = |f: fn(&Ray) -> Vec3| -> [Vec4; 3] {
                let v = rays.map(|r| f(&r));
                core::array::from_fn(|a| Vec4::new(v[0][a], v[1][a], v[2][a], v[3][a]))
            };
            let direct = Watertight::prepare_rays4(lanes(|r| r.origin), lanes(|r| r.dir));
            match (gathered, direct) {
                (None, None) => refused += 1,
                (Some(a), Some(b)) => {
                    assert_eq!(a.k, b.k, "case {case}");
                    for (x, y) in
                        [(a.sx, b.sx), (a.sy, b.sy), (a.sz, b.sz)].into_iter().chain(a.org.into_iter().zip(b.org))
                    {
                        assert_eq!(bits(x), bits(y), "case {case}");
                    }
                    same += 1;
                }
                _ => panic!("case {case}: gathered {gathered:?}, direct {direct:?}"),
            }
        }
        assert!(same > 5000 && refused > 5000, "{same} alike, {refused} refused");
    }
}
