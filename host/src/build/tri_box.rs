//! Exact triangle/box overlap by the separating axis theorem (Akenine-Möller, "Fast 3D
//! Triangle-Box Overlap Testing", JGT 2001): 3 box normals, the triangle normal and the
//! 9 edge cross products. Evaluated in f64 on f32 inputs, so it is exact up to the margin
//! the grid builder adds to every box.

use glam::DVec3;

/// True if triangle `v` overlaps the box with centre `c` and half-extent `h` (touching
/// counts as overlapping). Degenerate triangles fall back to the tests that still have a
/// meaning, so they are never wrongly dropped.
pub fn overlaps(v: [DVec3; 3], c: DVec3, h: DVec3) -> bool {
    let v = v.map(|p| p - c);
    // Box normals: the triangle's bounding box against the box.
    for a in 0..3 {
        let lo = v[0][a].min(v[1][a]).min(v[2][a]);
        let hi = v[0][a].max(v[1][a]).max(v[2][a]);
        if lo > h[a] || hi < -h[a] {
            return false;
        }
    }
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // Triangle normal: the plane against the box.
    let n = e[0].cross(e[1]);
    if separated(n, &v, h) {
        return false;
    }
    // Edge × box-axis cross products.
    for edge in e {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            if separated(edge.cross(axis), &v, h) {
                return false;
            }
        }
    }
    true
}

/// Is `axis` a separating axis? A zero axis separates nothing.
fn separated(axis: DVec3, v: &[DVec3; 3], h: DVec3) -> bool {
    let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
    let r = h.x * axis.x.abs() + h.y * axis.y.abs() + h.z * axis.z.abs();
    let lo = p[0].min(p[1]).min(p[2]);
    let hi = p[0].max(p[1]).max(p[2]);
    lo > r || hi < -r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    #[test]
    fn triangle_across_the_box_overlaps_and_one_beside_it_does_not() {
        let tri = [d(-1.0, -1.0, 0.0), d(3.0, -1.0, 0.0), d(-1.0, 3.0, 0.0)];
        assert!(overlaps(tri, DVec3::ZERO, DVec3::splat(0.5)));
        // Box near the hypotenuse's far side: inside the triangle's bounding box but
        // separated by the edge axis — a bounding-box test would wrongly accept it.
        assert!(!overlaps(tri, d(1.9, 1.9, 0.0), DVec3::splat(0.5)));
        assert!(!overlaps(tri, d(0.0, 0.0, 2.0), DVec3::splat(0.5)));
    }

    #[test]
    fn touching_counts_and_degenerate_triangles_are_kept() {
        let tri = [d(0.5, 0.0, 0.0), d(0.5, 1.0, 0.0), d(0.5, 0.0, 1.0)];
        assert!(overlaps(tri, DVec3::ZERO, DVec3::splat(0.5)));
        let point = [d(0.1, 0.1, 0.1); 3];
        assert!(overlaps(point, DVec3::ZERO, DVec3::splat(0.5)));
        let line = [d(-2.0, 0.0, 0.0), d(2.0, 0.0, 0.0), d(0.0, 0.0, 0.0)];
        assert!(overlaps(line, DVec3::ZERO, DVec3::splat(0.5)));
    }
}
