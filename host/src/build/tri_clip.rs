//! The bounds of the parts of a triangle: inside a box (Sutherland–Hodgman clipping
//! against the box's six planes), or on either side of a plane. The BVH builder's split
//! references use them: a large triangle cut by early split clipping, and a reference
//! straddling a spatial split plane, keep the box of only their own part.

use glam::DVec3;

/// A triangle clipped by six planes has at most 3 + 6 vertices.
const MAX_VERTICES: usize = 9;

/// The box `(lo, hi)` of the part of triangle `v` inside the box `[lo, hi]`, or `None` if
/// the triangle misses the box. Never smaller than what the arithmetic produced and never
/// outside the box (rounding may put a clipped vertex a hair inside or outside the
/// plane; the BVH builder grows its node boxes by a margin that covers it).
pub fn clipped_bounds(v: &[DVec3; 3], lo: DVec3, hi: DVec3) -> Option<(DVec3, DVec3)> {
    let mut poly = [DVec3::ZERO; MAX_VERTICES];
    let mut next = [DVec3::ZERO; MAX_VERTICES];
    poly[..3].copy_from_slice(v);
    let mut n = 3;
    for axis in 0..3 {
        for (plane, keep_above) in [(lo[axis], true), (hi[axis], false)] {
            let inside = |p: &DVec3| if keep_above { p[axis] >= plane } else { p[axis] <= plane };
            let mut m = 0;
            for i in 0..n {
                let (p, q) = (poly[i], poly[(i + 1) % n]);
                let (ip, iq) = (inside(&p), inside(&q));
                // A convex polygon crossing a plane gains at most one vertex.
                if ip && m < MAX_VERTICES {
                    next[m] = p;
                    m += 1;
                }
                if ip != iq && m < MAX_VERTICES {
                    let t = (plane - p[axis]) / (q[axis] - p[axis]);
                    let mut x = p + (q - p) * t;
                    x[axis] = plane;
                    next[m] = x;
                    m += 1;
                }
            }
            if m == 0 {
                return None;
            }
            core::mem::swap(&mut poly, &mut next);
            n = m;
        }
    }
    let (mut out_lo, mut out_hi) = (poly[0], poly[0]);
    for p in &poly[1..n] {
        out_lo = out_lo.min(*p);
        out_hi = out_hi.max(*p);
    }
    Some((out_lo.max(lo), out_hi.min(hi)))
}

/// The boxes `(lo, hi)` of the parts of triangle `v` below and above the plane
/// `axis = pos` (Embree's `splitTriangle`): each vertex grows its side's box, each edge
/// crossing the plane grows both by its crossing point. A side the triangle does not
/// reach has an empty box (`lo > hi`). Three edges, no clipping loop: the spatial split
/// search calls this once per bin boundary a reference spans.
pub fn split_bounds(v: &[DVec3; 3], axis: usize, pos: f64) -> [(DVec3, DVec3); 2] {
    let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut sides = [empty; 2];
    let grow = |b: &mut (DVec3, DVec3), p: DVec3| {
        b.0 = b.0.min(p);
        b.1 = b.1.max(p);
    };
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let (dp, dq) = (p[axis] - pos, q[axis] - pos);
        if dp <= 0.0 {
            grow(&mut sides[0], p);
        }
        if dp >= 0.0 {
            grow(&mut sides[1], p);
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let mut x = p + (q - p) * (dp / (dp - dq));
            x[axis] = pos;
            grow(&mut sides[0], x);
            grow(&mut sides[1], x);
        }
    }
    sides
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_inside_the_box_keeps_its_own_bounds() {
        let v = [DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.9, 0.2, 0.3), DVec3::new(0.5, 0.8, 0.6)];
        let (lo, hi) = clipped_bounds(&v, DVec3::ZERO, DVec3::ONE).unwrap();
        assert_eq!((lo, hi), (DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.9, 0.8, 0.6)));
    }

    #[test]
    fn a_clipped_triangle_keeps_only_the_part_inside() {
        // The right triangle x + y <= 2 in z = 0, cut at x = 1: the part with x >= 1 spans
        // y in [0, 1].
        let v = [DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0)];
        let (lo, hi) = clipped_bounds(&v, DVec3::new(1.0, -5.0, -5.0), DVec3::splat(5.0)).unwrap();
        assert_eq!(lo, DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(hi, DVec3::new(2.0, 1.0, 0.0));
        let (lo, hi) = clipped_bounds(&v, DVec3::splat(-5.0), DVec3::new(1.0, 5.0, 5.0)).unwrap();
        assert_eq!((lo, hi), (DVec3::ZERO, DVec3::new(1.0, 2.0, 0.0)));
    }

    #[test]
    fn a_triangle_beside_the_box_has_no_part_in_it() {
        let v = [DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0)];
        // Inside the triangle's box but beyond its hypotenuse.
        assert_eq!(clipped_bounds(&v, DVec3::new(1.5, 1.5, -1.0), DVec3::splat(3.0)), None);
        assert_eq!(clipped_bounds(&v, DVec3::new(3.0, 0.0, 0.0), DVec3::splat(4.0)), None);
    }

    #[test]
    fn a_plane_split_gives_the_box_of_each_side() {
        let v = [DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 1.0)];
        let [below, above] = split_bounds(&v, 0, 1.0);
        assert_eq!(below, (DVec3::ZERO, DVec3::new(1.0, 2.0, 1.0)));
        assert_eq!(above, (DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.5)));
        // The same parts as clipping by the half spaces.
        let big = DVec3::splat(10.0);
        assert_eq!(clipped_bounds(&v, -big, DVec3::new(1.0, 10.0, 10.0)), Some(below));
        assert_eq!(clipped_bounds(&v, DVec3::new(1.0, -10.0, -10.0), big), Some(above));
        // A plane beside the triangle: one side is empty; a vertex on the plane is on both.
        let [below, above] = split_bounds(&v, 0, 3.0);
        assert_eq!(below, (DVec3::ZERO, DVec3::new(2.0, 2.0, 1.0)));
        assert!(above.0.x > above.1.x);
        let [below, above] = split_bounds(&v, 0, 2.0);
        assert_eq!(above, (DVec3::new(2.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0)));
        assert_eq!(below.1.x, 2.0);
    }

    #[test]
    fn a_box_cutting_every_corner_gives_a_many_sided_part() {
        // A big triangle whose every edge and corner a small centred box cuts.
        let v = [DVec3::new(-10.0, -10.0, 0.0), DVec3::new(10.0, -10.0, 0.0), DVec3::new(0.0, 10.0, 0.0)];
        let (lo, hi) = clipped_bounds(&v, DVec3::new(-6.0, -9.0, -1.0), DVec3::new(6.0, 9.0, 1.0)).unwrap();
        assert_eq!(lo, DVec3::new(-6.0, -9.0, 0.0));
        assert!(hi.x == 6.0 && hi.y == 9.0 && hi.z == 0.0, "{hi}");
    }
}
