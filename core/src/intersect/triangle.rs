//! The ray–triangle intersection interface and the one place a candidate hit is accepted.

use crate::hit::{keep_closest, Hit};
use glam::{Vec3, Vec4};

use crate::image::{SceneView, TriBlock4};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::NodeTests;

/// A ray–triangle test. `prepare` computes the per-ray constants once (the watertight
/// test's shear), `intersect` tests one triangle. The result depends only on the ray and
/// the three vertices, so every structure that tests the same triangle gets the same bits.
pub trait Intersector {
    /// Per-ray constants.
    type Prepared: Copy + Default;
    /// What the test reads of a triangle (its layout): the vertices, or a precomputed
    /// record.
    type Triangle: Copy;
    /// A short name for reports.
    const NAME: &'static str;
    /// The box tests that go with this test in the BVH walks: conservative for its
    /// rounding ([`crate::traverse::boxes::datapath`]).
    type Nodes: NodeTests;
    /// Computes the per-ray constants.
    fn prepare(ray: &Ray) -> Self::Prepared;
    /// Reads triangle `prim` in this test's layout (an observed read).
    fn fetch<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, probe: &mut P) -> Self::Triangle;
    /// `(t, u, v)` where `u` and `v` weight the second and third vertex, or `None`.
    /// `t` is not range-checked here; [`test_triangle`] does that.
    fn intersect(prep: &Self::Prepared, tri: &Self::Triangle) -> Option<(f32, f32, f32)>;
    /// Four rays' constants as SIMD lanes, for [`Intersector::intersect_rays4`].
    type Prepared4: Copy;
    /// Four rays' constants in SIMD lanes, computed from their origins and directions
    /// (one register per axis): lane by lane the bits [`Intersector::prepare`] gives.
    /// `None` where the four rays cannot share one form, or where the test has no
    /// four-ray form (the default: packets then test ray by ray).
    #[inline(always)]
    fn prepare_rays4(_org: [Vec4; 3], _dir: [Vec4; 3]) -> Option<Self::Prepared4> {
        None
    }
    /// One triangle against four rays at once: lane by lane the bits of
    /// [`Intersector::intersect`], except for the lanes in `redo`, which the caller tests
    /// with `intersect` (by default all four).
    #[inline(always)]
    fn intersect_rays4(_rays: &Self::Prepared4, _tri: &Self::Triangle) -> Rays4Result {
        Rays4Result { redo: 0xF, ..Rays4Result::default() }
    }
    /// Sixteen rays' constants as SIMD lanes, for [`Intersector::intersect_rays16`].
    type Prepared16: Copy;
    /// The constants of the rays of `lanes` among sixteen (origins `org` and directions
    /// `dir`, one row per axis) that share the first one's frame, as the lanes of the
    /// sixteen-ray form, with the lanes they cover: lane by lane the bits
    /// [`Intersector::prepare`] gives. `None` where the test has no such form (the
    /// default) or this CPU lacks it (it needs AVX-512).
    #[inline(always)]
    fn prepare_rays16(_org: &[[f32; 16]; 3], _dir: &[[f32; 16]; 3], _lanes: u32) -> Option<(Self::Prepared16, u32)> {
        None
    }
    /// One triangle against sixteen rays of many origins at once: lane by lane the bits
    /// of [`Intersector::intersect`], except for the lanes in `redo` (by default all),
    /// into `out` (its `hit` and `redo` always; the distances and barycentrics where a
    /// lane hits).
    #[inline(always)]
    fn intersect_rays16(_rays: &Self::Prepared16, _tri: &Self::Triangle, out: &mut LaneHits<16>) {
        (out.hit, out.redo) = (0, 0xFFFF);
    }
    /// True if this test has an eight-ray form on triangles made ready once for rays of
    /// one origin ([`Intersector::share`], [`Intersector::intersect_shared8`]).
    const SHARED8: bool = false;
    /// Which frame four rays' constants use (for the watertight test, the axis order):
    /// a triangle made ready by [`Intersector::share`] for rays of one frame serves every
    /// group of rays with that frame and the same origin.
    #[inline(always)]
    fn frame4(_rays: &Self::Prepared4) -> u32 {
        0
    }
    /// Makes a triangle ready for rays that have one origin `origin` (in all their lanes)
    /// and the frame of `rays`, into slot `slot` of `into`.
    #[inline(always)]
    fn share(_rays: &Self::Prepared4, _origin: Vec3, _tri: &Self::Triangle, _into: &mut SharedTris, _slot: usize) {}
    /// [`Intersector::share`] for the four triangles of a leaf block at once, into slots
    /// `4 · half .. 4 · half + 4` (TRI_BLOCKS holds copies of the vertices in lanes: the
    /// same bits, read in a row rather than through vertex indices, and made ready by
    /// four-lane operations).
    #[inline(always)]
    fn share_block(_rays: &Self::Prepared4, _origin: Vec3, _block: &TriBlock4, _into: &mut SharedTris, _half: usize) {}
    /// Pairs of groups of four rays (`lo`, then `hi` of each, all of one origin and one
    /// frame, with the lanes that take part) against each of the first `n` triangles of
    /// `tris` (made ready by [`Intersector::share`] for them): lane by lane the bits of
    /// [`Intersector::intersect_rays4`], handed to `found` with the triangle's slot and
    /// the pair's index where some lane taking part hits or is undecided (most tests hit
    /// nothing, and then write nothing). False, having tested nothing, where this CPU or
    /// this test has no such form.
    #[inline(always)]
    fn intersect_shared8(
        _pairs: &[RayPair<'_, Self::Prepared4>],
        _tris: &SharedTris,
        _n: usize,
        _found: impl FnMut(usize, usize, &Hits8),
    ) -> bool {
        false
    }
    /// True if this test has a one-ray, four-triangle form
    /// ([`Intersector::intersect_block4`]); only then do walks read TRI_BLOCKS.
    const BLOCKS: bool = false;
    /// One ray against the four triangles of a block (one per lane): lane by lane the
    /// bits of [`Intersector::intersect`] on that lane's vertices, except for the lanes in
    /// `redo`, which the caller tests with `intersect` (by default all four).
    #[inline(always)]
    fn intersect_block4(_prep: &Self::Prepared, _block: &TriBlock4) -> Rays4Result {
        Rays4Result { redo: 0xF, ..Rays4Result::default() }
    }
    /// Triangle `lane` of a leaf block in this test's form, where the test reads plain
    /// vertices (a block's are the image's, bit for bit); `None` by default.
    #[inline(always)]
    fn block_triangle(_block: &TriBlock4, _lane: usize) -> Option<Self::Triangle> {
        None
    }
}

/// Up to [`SharedTris::SLOTS`] triangles' vertices relative to the origin of rays that
/// share one, in their frame's axis order ([`Intersector::share`]): a packet of primary
/// rays makes each triangle of a leaf ready once, not once per group of rays. One lane
/// per triangle, as in a leaf block, so that a block is made ready four lanes at a time.
#[derive(Clone, Copy, Debug, Default)]
pub struct SharedTris {
    /// Per vertex, per axis of the frame, per slot.
    pub rel: [[[f32; SharedTris::SLOTS]; 3]; 3],
}

impl SharedTris {
    /// Triangles held (two leaf blocks).
    pub const SLOTS: usize = 8;
}

/// Two groups of four rays of one packet tested together by
/// [`Intersector::intersect_shared8`]: their constants, and the lanes that take part
/// (bits 0–3 for `lo`, 4–7 for `hi`).
#[derive(Clone, Copy, Debug)]
pub struct RayPair<'a, P> {
    /// Lanes 0–3.
    pub lo: &'a P,
    /// Lanes 4–7.
    pub hi: &'a P,
    /// The lanes taking part.
    pub lanes: u32,
}

/// The outcome of a test of `L` rays (or `L` triangles) at once, one per SIMD lane: per
/// lane `(t, u, v)` where `hit` has the lane's bit, and the lanes to test again one at a
/// time (`redo`: an edge function exactly zero, left to the one-ray test).
#[derive(Clone, Copy, Debug)]
pub struct LaneHits<const L: usize> {
    /// Distances.
    pub t: [f32; L],
    /// Barycentric weight of the second vertex.
    pub u: [f32; L],
    /// Barycentric weight of the third vertex.
    pub v: [f32; L],
    /// Lanes with a hit (range not checked).
    pub hit: u32,
    /// Lanes the multi-lane form cannot decide.
    pub redo: u32,
}

impl<const L: usize> Default for LaneHits<L> {
    fn default() -> Self {
        LaneHits { t: [0.0; L], u: [0.0; L], v: [0.0; L], hit: 0, redo: 0 }
    }
}

impl<const L: usize> LaneHits<L> {
    /// Lane `k`'s outcome on triangle `prim` as a hit of `ray` in its interval: the lane's
    /// own result, or, where the multi-lane form left it undecided, the one-ray test's
    /// with the ray's constants `prep()` on the triangle `tri()` (fetched only then).
    #[inline(always)]
    pub fn lane_hit<I: Intersector>(
        &self,
        k: usize,
        ray: &Ray,
        prim: u32,
        prep: impl FnOnce() -> I::Prepared,
        tri: impl FnOnce() -> I::Triangle,
    ) -> Option<Hit> {
        self.lane_hit_in::<I>(k, (ray.t_min, ray.t_max), prim, prep, tri)
    }

    /// [`LaneHits::lane_hit`] for a ray given by its interval `(t_min, t_max)` alone: all
    /// the test needs, so that a packet's lane is not gathered into a whole `Ray` (eight
    /// loads and a 32-byte record per hit lane).
    #[inline(always)]
    pub fn lane_hit_in<I: Intersector>(
        &self,
        k: usize,
        interval: (f32, f32),
        prim: u32,
        prep: impl FnOnce() -> I::Prepared,
        tri: impl FnOnce() -> I::Triangle,
    ) -> Option<Hit> {
        let k = k % L;
        let result = if self.redo & (1 << k) != 0 {
            I::intersect(&prep(), &tri())
        } else {
            Some((self.t[k], self.u[k], self.v[k]))
        };
        in_interval(interval, result, prim)
    }
}

/// The outcome of [`Intersector::intersect_rays4`] and [`Intersector::intersect_block4`].
pub type Rays4Result = LaneHits<4>;

/// The outcome of [`Intersector::intersect_shared8`] for one triangle.
pub type Hits8 = LaneHits<8>;

/// Tests triangle `prim` and keeps the hit if it lies in `[t_min, t_max]` and is closer
/// under the `(t, prim)` order. Returns true if `best` changed.
#[inline(always)]
pub fn test_triangle<I: Intersector>(
    prep: &I::Prepared,
    ray: &Ray,
    tri: &I::Triangle,
    prim: u32,
    best: &mut Option<Hit>,
) -> bool {
    match in_range(ray, I::intersect(prep, tri), prim) {
        Some(hit) => {
            let before = *best;
            keep_closest(best, hit);
            before != *best
        }
        None => false,
    }
}

/// An intersection result as a hit of triangle `prim`, if it lies in `[t_min, t_max]`.
#[inline(always)]
pub fn in_range(ray: &Ray, result: Option<(f32, f32, f32)>, prim: u32) -> Option<Hit> {
    in_interval((ray.t_min, ray.t_max), result, prim)
}

/// [`in_range`] for a ray given by its interval `(t_min, t_max)` alone.
#[inline(always)]
pub fn in_interval((t_min, t_max): (f32, f32), result: Option<(f32, f32, f32)>, prim: u32) -> Option<Hit> {
    let (t, u, v) = result?;
    // Written so NaN is rejected.
    (t >= t_min && t <= t_max).then_some(Hit { t, u, v, prim })
}
