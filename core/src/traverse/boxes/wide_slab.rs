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
    pub(crate) avx8: Option<crate::simd::Avx>,
    /// For that form, the origin, `inv` and `inv_far` of [`RayBox`] as eight lanes each
    /// (x, y, z of each), written once per ray: the node test takes them as memory
    /// operands, where splatting them at each node took nine of its instructions. Only
    /// on x86-64 (288 bytes a ray that an embedded stack need not carry).
    #[cfg(target_arch = "x86_64")]
    pub(crate) lanes8: [Lanes8; 9],
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
        let rb = RayBox::new(ray);
        let neg = rb.inv.cmplt(Vec3A::ZERO).bitmask() as usize;
        let avx8 = crate::simd::Avx::reported().filter(|_| rb.zero_axes == 0);
        #[cfg(target_arch = "x86_64")]
        let lanes8 = {
            let (o, inv, far) = (rb.origin, rb.inv, rb.inv_far);
            [o.x, o.y, o.z, inv.x, inv.y, inv.z, far.x, far.y, far.z].map(|v| Lanes8([v; 8]))
        };
        NodeRay {
            rows: OCTANTS[neg & 7],
            rb,
            avx8,
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
