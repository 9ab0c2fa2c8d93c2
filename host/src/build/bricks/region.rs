//! The region of space a part of the partition answers for (Wald & Slusallek 2001
//! §6.4: a voxel of the high-level BSP). A triangle belongs to every region its box
//! reaches into; a split plane sends a triangle that straddles it to both sides, so
//! neighbouring regions share it instead of one brick's box growing over the other's
//! space. A brick's top-level box is its triangles' boxes clipped to its region.
//!
//! Why the closest hit is still found: a triangle is sent to a side whenever its box,
//! clipped to the region, reaches into that side's open half, and to the side its box
//! lies in otherwise; so every point of a triangle lies in (the closure of) some leaf
//! region whose brick holds the triangle, and that brick's box — clipped to the
//! region, grown by the scene's margin — holds the point. A ray reaching the hit point
//! has entered that box by then, so the top level never skips the brick that holds the
//! hit, and a triangle found in two bricks gives the same `(t, id)` in both.

use super::tri_record::TriRecord;

/// An axis-aligned region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// Lower corner.
    pub lo: [f32; 3],
    /// Upper corner.
    pub hi: [f32; 3],
}

/// Where a triangle goes at a split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Below the plane only.
    Left,
    /// At or above the plane only.
    Right,
    /// Both: its clipped box reaches across the plane.
    Both,
}

/// A triangle's vertex box.
pub fn tri_box(r: &TriRecord) -> ([f32; 3], [f32; 3]) {
    let lo = std::array::from_fn(|a| r.p[0][a].min(r.p[1][a]).min(r.p[2][a]));
    let hi = std::array::from_fn(|a| r.p[0][a].max(r.p[1][a]).max(r.p[2][a]));
    (lo, hi)
}

impl Region {
    /// The triangle's box clipped to the region.
    pub fn clip(&self, r: &TriRecord) -> ([f32; 3], [f32; 3]) {
        let (lo, hi) = tri_box(r);
        (std::array::from_fn(|a| lo[a].max(self.lo[a])), std::array::from_fn(|a| hi[a].min(self.hi[a])))
    }

    /// The centre of the triangle's clipped box on `axis`: the partition's sort key,
    /// always inside the region.
    pub fn key(&self, r: &TriRecord, axis: usize) -> f64 {
        let (lo, hi) = tri_box(r);
        let (lo, hi) = (lo[axis].max(self.lo[axis]), hi[axis].min(self.hi[axis]));
        (f64::from(lo) + f64::from(hi)) * 0.5
    }

    /// Which side of the plane `axis = plane` the triangle goes to.
    pub fn side(&self, r: &TriRecord, axis: usize, plane: f32) -> Side {
        let (lo, hi) = tri_box(r);
        let (lo, hi) = (lo[axis].max(self.lo[axis]), hi[axis].min(self.hi[axis]));
        if lo < plane && hi > plane {
            Side::Both
        } else if (f64::from(lo) + f64::from(hi)) * 0.5 < f64::from(plane) {
            Side::Left
        } else {
            Side::Right
        }
    }

    /// The two halves of the region at `axis = plane`.
    pub fn halves(&self, axis: usize, plane: f32) -> (Region, Region) {
        let (mut left, mut right) = (*self, *self);
        left.hi[axis] = plane;
        right.lo[axis] = plane;
        (left, right)
    }

    /// Whether `plane` lies strictly inside the region on `axis` (a split there can
    /// make progress).
    pub fn splits_at(&self, axis: usize, plane: f32) -> bool {
        self.lo[axis] < plane && plane < self.hi[axis]
    }

    /// The axis along which the keys of `tris` spread most, with that spread.
    pub fn widest_key_axis(&self, tris: &[TriRecord]) -> (usize, f64) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for t in tris {
            for a in 0..3 {
                let k = self.key(t, a);
                lo[a] = lo[a].min(k);
                hi[a] = hi[a].max(k);
            }
        }
        let axis = super::partition::widest(lo, hi);
        (axis, hi[axis] - lo[axis])
    }
}

/// A box that holds every point of the triangles `tris` inside `region`, as a computed
/// hit point may lie: their clipped boxes' union grown by `margin` (outwards, as the
/// flat image's boxes are).
pub fn clipped_bounds(region: &Region, tris: &[TriRecord], margin: f64) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for t in tris {
        let (a, b) = region.clip(t);
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    }
    crate::build::bvh::grow_by_margin((lo, hi), margin)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(x0: f32, x1: f32) -> TriRecord {
        TriRecord::plain([[x0, 0.0, 0.0], [x1, 0.0, 0.0], [x0, 1.0, 0.0]], 0)
    }

    #[test]
    fn straddlers_go_both_ways_and_touching_ones_one_way() {
        let r = Region { lo: [0.0; 3], hi: [10.0; 3] };
        assert_eq!(r.side(&tri(1.0, 9.0), 0, 5.0), Side::Both);
        assert_eq!(r.side(&tri(1.0, 5.0), 0, 5.0), Side::Left);
        assert_eq!(r.side(&tri(5.0, 9.0), 0, 5.0), Side::Right);
        // Flat in the plane: one side (its points lie in both halves' closure).
        assert_eq!(r.side(&tri(5.0, 5.0), 0, 5.0), Side::Right);
        // Reaching across the plane only outside the region: clipped first.
        let inner = Region { lo: [0.0; 3], hi: [4.0, 10.0, 10.0] };
        assert_eq!(inner.side(&tri(1.0, 9.0), 0, 4.0), Side::Left);
    }

    #[test]
    fn clipped_bounds_stay_in_the_region_and_cover_its_part_of_each_triangle() {
        let r = Region { lo: [0.0; 3], hi: [5.0, 10.0, 10.0] };
        let (lo, hi) = clipped_bounds(&r, &[tri(1.0, 9.0)], 0.0);
        assert!(lo[0] < 1.0 && hi[0] > 5.0 && hi[0] < 5.001, "{lo:?} {hi:?}");
        assert!(hi[1] >= 1.0);
    }
}
