//! Möller–Trumbore ray–triangle intersection ("Fast, Minimum Storage Ray/Triangle
//! Intersection", JGT 1997), for comparison with the watertight default. It is not
//! watertight: a ray through a shared edge can slip between two triangles.

use glam::Vec3;

use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// Relative determinant below which a ray counts as parallel to the triangle.
pub const PARALLEL_EPSILON: f32 = 1e-5;

/// The Möller–Trumbore test.
#[derive(Clone, Copy, Debug, Default)]
pub struct MollerTrumbore;

/// The ray itself is all Möller–Trumbore needs.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlainRay {
    org: Vec3,
    dir: Vec3,
}

impl Intersector for MollerTrumbore {
    type Prepared = PlainRay;
    type Triangle = [Vec3; 3];
    const NAME: &'static str = "moller-trumbore";
    type Nodes = crate::traverse::boxes::datapath::FloatNodes;
    // No four-ray form: packets test ray by ray.
    type Prepared4 = ();
    type Prepared16 = ();

    #[inline(always)]
    fn fetch<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, probe: &mut P) -> [Vec3; 3] {
        scene.triangle(prim, probe)
    }

    #[inline]
    fn prepare(ray: &Ray) -> PlainRay {
        PlainRay { org: ray.origin, dir: ray.dir }
    }

    #[inline]
    fn intersect(r: &PlainRay, v: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let p = r.dir.cross(e2);
        let det = e1.dot(p);
        // Scale-free parallelism test: the classic fixed epsilon, made relative. Rays this
        // close to the plane (and near-degenerate triangles) give a `t` whose error can
        // exceed the grid's margin, so they count as parallel; that keeps the result
        // consistent whatever structure delivers the triangle.
        let scale = r.dir.length() * e1.length() * e2.length();
        if det.abs() <= PARALLEL_EPSILON * scale || !det.is_finite() || !scale.is_finite() {
            return None;
        }
        let inv = 1.0 / det;
        let s = r.org - v[0];
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let w = r.dir.dot(q) * inv;
        if w < 0.0 || u + w > 1.0 {
            return None;
        }
        Some((e2.dot(q) * inv, u, w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intersect::watertight::Watertight;

    fn tri() -> [Vec3; 3] {
        [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]
    }

    type Tuv = Option<(f32, f32, f32)>;

    fn both(o: Vec3, d: Vec3) -> (Tuv, Tuv) {
        let r = Ray::new(o, d);
        (
            MollerTrumbore::intersect(&MollerTrumbore::prepare(&r), &tri()),
            Watertight::intersect(&Watertight::prepare(&r), &tri()),
        )
    }

    #[test]
    fn both_tests_agree_on_a_clear_hit() {
        let (m, w) = both(Vec3::new(0.25, 0.25, 0.0), Vec3::Z);
        let (m, w) = (m.unwrap(), w.unwrap());
        assert_eq!(m.0, 1.0);
        assert!((w.0 - 1.0).abs() < 1e-6);
        assert!((m.1 - 0.25).abs() < 1e-6 && (w.1 - 0.25).abs() < 1e-6);
        assert!((m.2 - 0.25).abs() < 1e-6 && (w.2 - 0.25).abs() < 1e-6);
    }

    #[test]
    fn both_miss_outside_and_parallel() {
        assert_eq!(both(Vec3::new(0.8, 0.8, 0.0), Vec3::Z), (None, None));
        assert_eq!(both(Vec3::new(0.1, 0.1, 1.0), Vec3::X), (None, None));
    }

    #[test]
    fn degenerate_triangle_never_hits() {
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let r = Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z);
        assert_eq!(Watertight::intersect(&Watertight::prepare(&r), &line), None);
        assert_eq!(MollerTrumbore::intersect(&MollerTrumbore::prepare(&r), &line), None);
    }
}
