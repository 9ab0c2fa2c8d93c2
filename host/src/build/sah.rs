//! The surface area heuristic's pieces that the BVH builder and its spatial splits share
//! (Wald 2007; Stich, Friedrich & Dietrich 2009): the cost constants and limits, boxes
//! in double precision, triangle references, and split candidates with their costs.

use glam::DVec3;
use raypipe_core::image::MAX_TREE_DEPTH;

use crate::build::tri_clip::clipped_bounds;

/// The SAH cost constants and limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhParams {
    /// Bins per axis.
    pub bins: usize,
    /// Cost of visiting a node, relative to one triangle test.
    pub traversal_cost: f64,
    /// Cost of one triangle test.
    pub intersection_cost: f64,
    /// Largest leaf (a larger one is split even if the SAH prefers not to).
    pub max_leaf: usize,
    /// Early split clipping (Ernst & Greiner 2007): a triangle whose box is longer than
    /// this fraction of the scene's extent is cut into pieces with tight boxes, so that
    /// large triangles (floors, walls) do not bloat the nodes they fall in. 0 disables.
    /// Spatial splits do the same where the SAH gains by it, but the two together took
    /// 5% fewer instructions per ray than spatial splits alone on the conference room
    /// (3% more on Sponza), averaged over four views of each.
    pub presplit_extent: f64,
    /// Spatial splits (Stich et al. 2009, "Spatial splits in bounding volume
    /// hierarchies"): tried at a node whose best object split leaves children overlapping
    /// by more than this fraction of the root's surface area. 0 disables.
    pub spatial_alpha: f64,
    /// At most this many references per triangle on average, whatever the splitting.
    pub max_refs_per_triangle: f64,
    /// Triangles a leaf tests at once (4 with TRI_BLOCKS): the SAH prices a leaf by its
    /// blocks, `ceil(n / leaf_block)`, as Embree does for its four-triangle leaves.
    pub leaf_block: usize,
    /// Deepest the binary tree may grow (root = 1): deeper, a node becomes a leaf.
    pub max_depth: u32,
}

impl Default for BvhParams {
    fn default() -> Self {
        BvhParams {
            bins: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            max_leaf: 8,
            presplit_extent: 1.0 / 32.0,
            spatial_alpha: 1e-5,
            max_refs_per_triangle: 3.0,
            leaf_block: 1,
            max_depth: MAX_TREE_DEPTH - 4,
        }
    }
}

/// An axis-aligned box in f64 (empty when `lo > hi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
}

impl Bounds {
    pub(crate) const EMPTY: Bounds = Bounds { lo: DVec3::splat(f64::INFINITY), hi: DVec3::splat(f64::NEG_INFINITY) };

    pub(crate) fn grow(&mut self, o: &Bounds) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }

    pub(crate) fn area(&self) -> f64 {
        let e = (self.hi - self.lo).max(DVec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// A node's f32 box.
    pub(crate) fn of_box(lo: [f32; 3], hi: [f32; 3]) -> Bounds {
        Bounds { lo: DVec3::from(lo.map(f64::from)), hi: DVec3::from(hi.map(f64::from)) }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }

    /// The axes along which the box has a positive extent: `(axis, lo, hi)`.
    pub(crate) fn extended_axes(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        (0..3).filter(|&a| self.hi[a] > self.lo[a]).map(|a| (a, self.lo[a], self.hi[a]))
    }

    pub(crate) fn intersection(&self, o: &Bounds) -> Bounds {
        Bounds { lo: self.lo.max(o.lo), hi: self.hi.min(o.hi) }
    }

    /// The box of the part of triangle `v` inside this box, if any.
    pub(crate) fn clip(&self, v: &[DVec3; 3]) -> Option<Bounds> {
        clipped_bounds(v, self.lo, self.hi).map(|(lo, hi)| Bounds { lo, hi })
    }
}

/// A build reference: a triangle, and the box of the part of it this reference stands
/// for (the whole triangle's box, or a piece's after a split).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ref {
    pub(crate) b: Bounds,
    pub(crate) tri: u32,
}

impl Ref {
    pub(crate) fn centroid(&self) -> DVec3 {
        (self.b.lo + self.b.hi) * 0.5
    }
}

/// A leaf's cost: its blocks of `leaf_block` triangles, each one intersection.
pub(crate) fn leaf_cost(n: usize, p: &BvhParams) -> f64 {
    p.intersection_cost * n.div_ceil(p.leaf_block.max(1)) as f64
}

/// The SAH cost of splitting a node of surface area `parent_area` into children of
/// `(area, references)` `left` and `right`: one traversal step, then each child's leaf
/// cost weighted by the chance a ray through the parent enters it.
pub(crate) fn split_cost(p: &BvhParams, parent_area: f64, left: (f64, usize), right: (f64, usize)) -> f64 {
    p.traversal_cost + children_cost(p, left, right) / parent_area
}

/// The area-weighted leaf costs of two children `(area, references)`.
pub(crate) fn children_cost(p: &BvhParams, (al, nl): (f64, usize), (ar, nr): (f64, usize)) -> f64 {
    al * leaf_cost(nl, p) + ar * leaf_cost(nr, p)
}

/// A candidate split: the plane, its SAH cost, and (object splits) how much the two
/// children's boxes overlap.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Split {
    pub(crate) axis: usize,
    pub(crate) pos: f64,
    pub(crate) cost: f64,
    pub(crate) overlap: f64,
    /// A spatial split cuts the references that straddle the plane (`Some`: the
    /// children's boxes and reference counts as binned); an object split sends each
    /// reference to the side of its centroid.
    pub(crate) spatial: Option<Sides>,
}

/// A spatial split's two children as its binning saw them: box and reference count.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sides {
    pub(crate) left: (Bounds, usize),
    pub(crate) right: (Bounds, usize),
}
