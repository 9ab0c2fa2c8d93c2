//! Wald's projection ray–triangle test (Wald 2004, "Realtime Ray Tracing and Interactive
//! Global Illumination", §7.1; Wald & Slusallek 2001): per triangle a precomputed
//! 48-byte record ([`WaldTriangle`]) holding the plane, projected to the triangle's
//! dominant axis, and the two barycentric weights as affine functions of the projected
//! hit point. The test needs one division and no cross products.
//!
//! An image built with `--triangles wald` stores the records; otherwise they are computed
//! here, by the same function the builder uses, so every structure meets bit-identical
//! records. Like Möller–Trumbore it is not watertight, and a ray within about 1e-5 (sine)
//! of the plane counts as parallel.

use glam::Vec3;

use crate::image::{SceneView, WaldTriangle};
use crate::intersect::moller_trumbore::PARALLEL_EPSILON;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;

/// The projection test with Wald's 48-byte triangles.
#[derive(Clone, Copy, Debug, Default)]
pub struct WaldProjection;

/// The record of a degenerate triangle: never hit.
const DEGENERATE: WaldTriangle = WaldTriangle {
    n_u: 0.0,
    n_v: 0.0,
    n_d: 0.0,
    k: 3,
    b_nu: 0.0,
    b_nv: 0.0,
    b_d: 0.0,
    n_scale: 1.0,
    c_nu: 0.0,
    c_nv: 0.0,
    c_d: 0.0,
    _pad: 0,
};

impl WaldTriangle {
    /// Precomputes the record of triangle `(a, b, c)` in single precision.
    pub fn from_vertices(v: &[Vec3; 3]) -> WaldTriangle {
        let (a, b, c) = (v[0], v[1], v[2]);
        let e1 = b - a;
        let e2 = c - a;
        let n = e1.cross(e2);
        let an = n.abs();
        let k = if an.x >= an.y && an.x >= an.z {
            0
        } else if an.y >= an.z {
            1
        } else {
            2
        };
        let (u, w) = ((k + 1) % 3, (k + 2) % 3);
        let det = e1[u] * e2[w] - e1[w] * e2[u];
        if n[k] == 0.0 || det == 0.0 || !n.is_finite() || !det.is_finite() {
            return DEGENERATE;
        }
        let n_u = n[u] / n[k];
        let n_v = n[w] / n[k];
        let rec = WaldTriangle {
            n_u,
            n_v,
            n_d: a[k] + n_u * a[u] + n_v * a[w],
            k: k as u32,
            b_nu: e2[w] / det,
            b_nv: -e2[u] / det,
            b_d: (a[w] * e2[u] - a[u] * e2[w]) / det,
            n_scale: libm::sqrtf(1.0 + n_u * n_u + n_v * n_v),
            c_nu: -e1[w] / det,
            c_nv: e1[u] / det,
            c_d: (a[u] * e1[w] - a[w] * e1[u]) / det,
            _pad: 0,
        };
        let vals = [rec.n_u, rec.n_v, rec.n_d, rec.b_nu, rec.b_nv, rec.b_d, rec.n_scale, rec.c_nu, rec.c_nv, rec.c_d];
        if vals.iter().all(|x| x.is_finite()) {
            rec
        } else {
            DEGENERATE
        }
    }
}

/// The ray and the length of its direction (for the parallelism test).
#[derive(Clone, Copy, Debug, Default)]
pub struct WaldRay {
    org: [f32; 3],
    dir: [f32; 3],
    dir_len: f32,
}

impl Intersector for WaldProjection {
    type Prepared = WaldRay;
    type Triangle = WaldTriangle;
    const NAME: &'static str = "wald";
    type Nodes = crate::traverse::boxes::datapath::FloatNodes;
    // No four-ray form: packets test ray by ray.
    type Prepared4 = ();
    type Prepared16 = ();

    #[inline]
    fn prepare(ray: &Ray) -> WaldRay {
        WaldRay { org: ray.origin.to_array(), dir: ray.dir.to_array(), dir_len: ray.dir.length() }
    }

    #[inline(always)]
    fn fetch<P: MemoryProbe>(scene: &SceneView<'_>, prim: u32, probe: &mut P) -> WaldTriangle {
        match scene.wald_triangle(prim, probe) {
            Some(t) => t,
            None => WaldTriangle::from_vertices(&scene.triangle(prim, probe)),
        }
    }

    #[inline(always)]
    fn intersect(r: &WaldRay, t: &WaldTriangle) -> Option<(f32, f32, f32)> {
        let k = t.k as usize;
        if k > 2 {
            return None;
        }
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let (o, d) = (&r.org, &r.dir);
        let nd = d[k] + t.n_u * d[u] + t.n_v * d[v];
        if nd.abs() <= PARALLEL_EPSILON * r.dir_len * t.n_scale || !nd.is_finite() {
            return None;
        }
        let f = (t.n_d - o[k] - t.n_u * o[u] - t.n_v * o[v]) / nd;
        let hu = o[u] + f * d[u];
        let hv = o[v] + f * d[v];
        let lambda = hu * t.b_nu + hv * t.b_nv + t.b_d;
        if lambda < 0.0 {
            return None;
        }
        let mue = hu * t.c_nu + hv * t.c_nv + t.c_d;
        if mue < 0.0 || lambda + mue > 1.0 {
            return None;
        }
        Some((f, lambda, mue))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intersect::watertight::Watertight;

    #[test]
    fn agrees_with_watertight_away_from_edges() {
        let tri = [Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.5), Vec3::new(0.0, 2.0, 0.5)];
        let rec = WaldTriangle::from_vertices(&tri);
        for (x, y) in [(0.3f32, 0.3f32), (0.9, 0.5), (0.2, 1.2)] {
            let r = Ray::new(Vec3::new(x, y, -3.0), Vec3::new(0.01, -0.02, 1.0));
            let w = WaldProjection::intersect(&WaldProjection::prepare(&r), &rec).unwrap();
            let s = Watertight::intersect(&Watertight::prepare(&r), &tri).unwrap();
            assert!((w.0 - s.0).abs() < 1e-5 && (w.1 - s.1).abs() < 1e-5 && (w.2 - s.2).abs() < 1e-5, "{w:?} {s:?}");
        }
        let miss = Ray::new(Vec3::new(1.5, 1.5, -3.0), Vec3::Z);
        assert_eq!(WaldProjection::intersect(&WaldProjection::prepare(&miss), &rec), None);
        let flat = WaldTriangle::from_vertices(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
        assert_eq!(flat.k, 3);
    }
}
