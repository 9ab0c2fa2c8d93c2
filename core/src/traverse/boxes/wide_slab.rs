//! The wide nodes' box test: the ray as a 4- or 8-wide node test reads it
//! ([`NodeRay`]: slab constants and the planes its octant enters first) and the test
//! every wide node implements ([`WideSlab`]).

use core::ops::{Index, IndexMut};

use glam::Vec3A;

use crate::image::WideNode;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;

/// The ray as the wide node tests read it: its slab constants, and per axis which of a
/// box's two planes is entered first (the ray's octant). Each axis then costs one
/// subtraction and one product per plane and no min/max (the sign trick of Williams et
/// al. 2005, as in Embree). The node tests splat the origin and reciprocal direction
/// themselves (the compiler hoists that out of a walk's loop), so the record stays small:
/// the hardware model keeps one per ray in flight. The 8-wide AVX test reads its rows by
/// byte offset, and whether it may run is decided here, once per ray: per node, the
/// index arithmetic and the two checks took 11 of about 90 instructions (Sponza).
#[derive(Clone, Copy, Debug)]
pub struct NodeRay {
    /// Which rows of a node hold each axis' near and far planes.
    pub(crate) rows: OctantRows,
    /// The scalar slab constants (and the zero-direction axes).
    pub(crate) rb: RayBox,
    /// The 8-wide node test may take its AVX form (the token, where the CPU has AVX and
    /// no direction component is zero). Decided once per ray rather than at each node.
    // Read by the x86-64 node tests only.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    pub(crate) avx8: Option<crate::simd::Avx>,
    /// The 8-wide node test may take its fused form (AVX and FMA, no zero direction
    /// component, and the origin's products finite): see [`FusedOffsets`].
    pub(crate) fma8: Option<crate::simd::AvxFma>,
    /// For the AVX forms, as eight lanes each (x, y, z of each): rows 0–2 the origin (the
    /// fused form: the near planes' offsets), 3–5 `inv` and 6–8 `inv_far` of [`RayBox`],
    /// 9–11 the far planes' offsets (fused form only), written once per ray: the node
    /// test takes them as memory operands, where splatting them at each node took nine
    /// of its instructions. Only on x86-64 (384 bytes a ray that an embedded stack need
    /// not carry).
    #[cfg(target_arch = "x86_64")]
    pub(crate) lanes8: [Lanes8; 12],
}

/// The fused node test's per-ray offsets: a plane `p` at distance `p·inv − o·inv`, one
/// multiply-subtract (Embree's form), where `(p − o)·inv` takes a subtraction and a
/// product. The product `o·inv` is rounded once, an error absolute in the distance (up
/// to half an ulp of `o·inv`, however near the plane), where the other roundings are
/// relative: so the near planes' offset is raised and the far planes' lowered by
/// `|o·inv|·2⁻²¹`, at least twice that error after its own rounding, and the relative
/// roundings — the reciprocal and the fused operation's one, against the subtraction and
/// product's two — stay within the far side's growth (`inv_far`, Ize 2013). A box the
/// ray touches is never rejected; the entry distances differ from the unfused test's in
/// the last bits, so the walk may visit a node more, never a hit less.
// Read by the x86-64 node test only (no other target makes an `AvxFma` token).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct FusedOffsets {
    pub(crate) near: Vec3A,
    pub(crate) far: Vec3A,
}

impl FusedOffsets {
    /// The offsets for `rb`, or `None` where a product is not finite (a far origin with
    /// a nearly axis-parallel direction: the unfused test then).
    #[inline(always)]
    pub(crate) fn new(rb: &RayBox) -> Option<FusedOffsets> {
        const PAD: f32 = 1.0 / (1u32 << 21) as f32;
        let (n, f) = (rb.origin * rb.inv, rb.origin * rb.inv_far);
        let (near, far) = (n + n.abs() * PAD, f - f.abs() * PAD);
        (near.is_finite() && far.is_finite()).then_some(FusedOffsets { near, far })
    }
}

/// Eight copies of one value, aligned as one AVX register.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub(crate) struct Lanes8(pub(crate) [f32; 8]);

/// For one octant of directions, the node rows (min x, y, z, then max x, y, z) of each
/// axis' near and far planes, as indices and as byte offsets in an 8-wide node (32 bytes
/// a row, read as they are by the AVX test, with no index arithmetic per node).
#[derive(Clone, Copy, Debug)]
pub(crate) struct OctantRows {
    /// Per axis, the row of the near plane.
    pub(crate) near: [u32; 3],
    /// Per axis, the row of the far plane.
    pub(crate) far: [u32; 3],
    /// `near` in bytes in an 8-wide node.
    pub(crate) near8: [u32; 3],
    /// `far` in bytes in an 8-wide node.
    pub(crate) far8: [u32; 3],
}

/// [`OctantRows`] of the eight octants (bit `a` of the index: the direction is negative
/// on axis `a`), so that a ray copies its row rather than computing it (that took 43
/// instructions per ray, a tenth of a bunny ray's).
pub(crate) const OCTANTS: [OctantRows; 8] = {
    let mut table = [OctantRows { near: [0; 3], far: [0; 3], near8: [0; 3], far8: [0; 3] }; 8];
    let mut octant = 0;
    while octant < 8 {
        let mut axis = 0;
        while axis < 3 {
            let neg = (octant >> axis) & 1;
            let (near, far) = (axis + 3 * neg, axis + 3 * (1 - neg));
            let t = &mut table[octant as usize];
            (t.near[axis as usize], t.far[axis as usize]) = (near, far);
            (t.near8[axis as usize], t.far8[axis as usize]) = (32 * near, 32 * far);
            axis += 1;
        }
        octant += 1;
    }
    table
};

impl NodeRay {
    /// Precomputes the slab constants and the octant.
    #[inline]
    pub fn new(ray: &Ray) -> NodeRay {
        NodeRay::with_fma(ray, crate::simd::AvxFma::reported())
    }

    /// [`NodeRay::new`] with the fused node test allowed by `fma` (the tests compare the
    /// forms on one ray).
    #[inline(always)]
    pub(crate) fn with_fma(ray: &Ray, fma: Option<crate::simd::AvxFma>) -> NodeRay {
        let rb = RayBox::new(ray);
        let neg = rb.inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let avx8 = crate::simd::Avx::reported().filter(|_| rb.zero_axes == 0);
        let fused = fma.filter(|_| rb.zero_axes == 0).and_then(|f| FusedOffsets::new(&rb).map(|o| (f, o)));
        #[cfg(target_arch = "x86_64")]
        let lanes8 = {
            let (inv, far) = (rb.inv, rb.inv_far);
            let (o, p) = match &fused {
                Some((_, off)) => (off.near, off.far),
                None => (rb.origin, Vec3A::ZERO),
            };
            [o.x, o.y, o.z, inv.x, inv.y, inv.z, far.x, far.y, far.z, p.x, p.y, p.z].map(|v| Lanes8([v; 8]))
        };
        NodeRay {
            rows: OCTANTS[neg & 7],
            rb,
            avx8,
            fma8: fused.map(|(f, _)| f),
            #[cfg(target_arch = "x86_64")]
            lanes8,
        }
    }

    /// The ray's octant (bit `a`: the direction is negative on axis `a`), the index of
    /// its [`OCTANTS`] entry.
    #[inline]
    pub(crate) fn octant(&self) -> usize {
        self.rb.inv.cmplt(Vec3A::ZERO).bitmask() as usize & 7
    }
}

/// A wide node's slab test: the entry distances of the ray into each child box within
/// `[t0, t1]`, and the bit mask of the children it hits (never an empty slot). It must
/// never reject a box the ray touches (see [`crate::traverse::boxes::slab`]).
pub trait WideSlab: WideNode {
    /// Entry distances, one per slot.
    type Dist: Copy + Default + Index<usize, Output = f32> + IndexMut<usize>;
    /// The node test: the entry distances into `tn`, the mask returned.
    fn slab(&self, r: &NodeRay, t0: f32, t1: f32, tn: &mut Self::Dist) -> u32;
    /// True where the node test has forms for rays of one octant ([`WideSlab::slab_in`]).
    const OCTANT_FORMS: bool = false;
    /// [`WideSlab::slab`] for a ray of octant `O` (`O < 8`, `NodeRay::octant`), where
    /// [`WideSlab::OCTANT_FORMS`]: the same bits.
    #[inline(always)]
    fn slab_in<const O: usize>(&self, r: &NodeRay, t0: f32, t1: f32, tn: &mut Self::Dist) -> u32 {
        self.slab(r, t0, t1, tn)
    }
}
