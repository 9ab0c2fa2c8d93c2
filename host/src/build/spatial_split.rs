//! Spatial splits for the BVH builder (Stich, Friedrich & Dietrich 2009, "Spatial splits
//! in bounding volume hierarchies"): besides sending each reference whole to one side
//! of a plane (an object split), a node may cut the references that straddle the plane
//! in two, each half keeping the box of the triangle's part on its side. Where large or
//! long triangles make an object split's children overlap (floors, walls, pillars), the
//! children's boxes then shrink to what they hold, at the price of a triangle appearing
//! in more than one leaf. The kernels need nothing new: every part of a triangle is in
//! some leaf whose box holds it, which is all a conservative BVH promises.

use glam::DVec3;

use crate::build::sah::{children_cost, split_cost, Bounds, BvhParams, Ref, Sides, Split};
use crate::build::tri_clip::split_bounds;

/// The boxes of the parts of a reference's triangle below and above the plane `axis =
/// pos`, within the reference's box `b` (an empty box for a side without any).
fn split_box(v: &[DVec3; 3], b: &Bounds, axis: usize, pos: f64) -> (Bounds, Bounds) {
    let [below, above] = split_bounds(v, axis, pos);
    let clip = |(lo, hi): (DVec3, DVec3)| Bounds { lo: lo.max(b.lo), hi: hi.min(b.hi) };
    (clip(below), clip(above))
}

/// The best binned spatial split of a node's references (section 4.2, "chopped
/// binning"): `p.bins` equal bins over the node's box per axis; a reference counts as
/// entering its first bin and leaving its last, and the part of its triangle inside each
/// bin it spans grows that bin's box.
pub(crate) fn find_spatial_split(verts: &[[DVec3; 3]], refs: &[Ref], bounds: &Bounds, p: &BvhParams) -> Option<Split> {
    let parent_area = bounds.area().max(f64::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    for (axis, lo, hi) in bounds.extended_axes() {
        let width = (hi - lo) / p.bins as f64;
        let plane = |k: usize| if k == p.bins { hi } else { lo + k as f64 * width };
        let bin_of = |x: f64| (((x - lo) / width) as usize).min(p.bins - 1);
        let mut bin_bounds = vec![Bounds::EMPTY; p.bins];
        let (mut entries, mut exits) = (vec![0usize; p.bins], vec![0usize; p.bins]);
        for r in refs {
            let (first, last) = (bin_of(r.b.lo[axis]), bin_of(r.b.hi[axis]));
            entries[first] += 1;
            exits[last] += 1;
            if first == last {
                bin_bounds[first].grow(&r.b);
                continue;
            }
            // Cut the reference at each bin boundary it spans, left to right.
            let mut rest = r.b;
            for (k, bin) in bin_bounds.iter_mut().enumerate().take(last).skip(first) {
                let (below, above) = split_box(&verts[r.tri as usize], &rest, axis, plane(k + 1));
                if !below.is_empty() {
                    bin.grow(&below);
                }
                rest = above;
            }
            if !rest.is_empty() {
                bin_bounds[last].grow(&rest);
            }
        }
        // Sweep from the right, then from the left: a plane between bins k − 1 and k has
        // on its left every reference entering before k, on its right every one leaving
        // at k or after.
        let mut right = vec![(Bounds::EMPTY, 0usize); p.bins];
        let (mut acc, mut n) = (Bounds::EMPTY, 0);
        for k in (1..p.bins).rev() {
            acc.grow(&bin_bounds[k]);
            n += exits[k];
            right[k] = (acc, n);
        }
        let (mut left, mut nl) = (Bounds::EMPTY, 0);
        for k in 1..p.bins {
            left.grow(&bin_bounds[k - 1]);
            nl += entries[k - 1];
            let (right_box, nr) = right[k];
            if nl == 0 || nr == 0 {
                continue;
            }
            let cost = split_cost(p, parent_area, (left.area(), nl), (right_box.area(), nr));
            if best.is_none_or(|b| cost < b.cost) {
                let spatial = Some(Sides { left: (left, nl), right: (right_box, nr) });
                best = Some(Split { axis, pos: plane(k), cost, overlap: 0.0, spatial });
            }
        }
    }
    best
}

/// Divides references at the plane `axis = pos`: a reference wholly on one side goes
/// there, one that straddles it becomes two, each with the box of its triangle's part
/// on its side (one new reference taken from `spare`) — unless keeping it whole on one
/// side costs less by the SAH ("reference unsplitting", section 4.3: the child's box
/// grows to hold it, the other child tests one triangle fewer), or no spare is left (it
/// goes whole to the side of its centroid). A reference whose triangle has a part on
/// one side only goes there with that part's box. `sides`: the children as binned.
pub(crate) fn split_references(
    verts: &[[DVec3; 3]],
    refs: Vec<Ref>,
    axis: usize,
    pos: f64,
    sides: &Sides,
    p: &BvhParams,
    spare: &mut usize,
) -> (Vec<Ref>, Vec<Ref>) {
    let ((left_box, nl), (right_box, nr)) = (sides.left, sides.right);
    let (al, ar) = (left_box.area(), right_box.area());
    let cost = |a_left: f64, n_left: usize, a_right: f64, n_right: usize| {
        children_cost(p, (a_left, n_left), (a_right, n_right))
    };
    let split_cost = cost(al, nl, ar, nr);
    let (mut left, mut right) = (Vec::with_capacity(refs.len()), Vec::with_capacity(refs.len()));
    for r in refs {
        if r.b.hi[axis] <= pos {
            left.push(r);
        } else if r.b.lo[axis] >= pos {
            right.push(r);
        } else {
            let (l, h) = split_box(&verts[r.tri as usize], &r.b, axis, pos);
            let (l, h) = ((!l.is_empty()).then_some(l), (!h.is_empty()).then_some(h));
            let whole = |side: &Bounds| {
                let mut b = *side;
                b.grow(&r.b);
                b.area()
            };
            match (l, h) {
                (Some(_), Some(_)) if cost(whole(&left_box), nl, ar, nr.saturating_sub(1)) <= split_cost => {
                    left.push(r)
                }
                (Some(_), Some(_)) if cost(al, nl.saturating_sub(1), whole(&right_box), nr) <= split_cost => {
                    right.push(r)
                }
                (Some(l), Some(h)) if *spare > 0 => {
                    *spare -= 1;
                    left.push(Ref { b: l, tri: r.tri });
                    right.push(Ref { b: h, tri: r.tri });
                }
                (Some(l), None) => left.push(Ref { b: l, tri: r.tri }),
                (None, Some(h)) => right.push(Ref { b: h, tri: r.tri }),
                _ if r.centroid()[axis] < pos => left.push(r),
                _ => right.push(r),
            }
        }
    }
    (left, right)
}
