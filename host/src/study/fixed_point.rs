//! `raypipe fixed-point`: how far the fixed-point datapath's hits are from the `f32`
//! datapath's on a scene. The same rays go through both — a view's eye rays and, from
//! each eye ray's `f32` hit, one diffuse bounce (the path tracer's cosine-weighted
//! direction from the surface) — and each ray's two hits are compared: the same triangle,
//! another triangle, a hit in one datapath only; the distance between the two hit points
//! where the triangle is the same (in scene units and in units of the format); and the
//! nodes and triangles each datapath visits per ray (the fixed-point box test rounds
//! outward, so it may visit more).

use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::math::fixed_point::QFormat;
use raypipe_core::shade::hemisphere::cosine_direction;
use raypipe_core::shade::rng::uniform;
use raypipe_core::shade::surface::Surface;
use raypipe_core::{Hit, Intersector, NoProbe, Ray, RayCounters, SceneView, Watertight};
use raypipe_hw::Datapath;

use crate::render::tracer::trace;
use crate::with_datapath;

/// Which rays a row of the report covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Eye rays.
    Primary,
    /// One diffuse bounce from each eye ray's `f32` hit.
    Bounce,
}

impl RayKind {
    /// Name in the report.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Bounce => "bounce",
        }
    }
}

/// One datapath against `f32` on one kind of ray.
#[derive(Clone, Debug, Default)]
pub struct Agreement {
    /// Rays traced.
    pub rays: u64,
    /// Neither datapath hits.
    pub both_miss: u64,
    /// Both hit the same triangle.
    pub same_triangle: u64,
    /// Both hit, different triangles.
    pub other_triangle: u64,
    /// Only `f32` hits.
    pub f32_only: u64,
    /// Only the fixed-point datapath hits.
    pub fixed_only: u64,
    /// Distances between the two hit points on the same triangle, scene units, sorted.
    pub offsets: Vec<f32>,
    /// Nodes (and leaves) visited, `f32` and fixed point.
    pub visits: [u64; 2],
    /// Triangle tests, `f32` and fixed point.
    pub tests: [u64; 2],
}

impl Agreement {
    /// Rays whose verdict and triangle agree, in percent.
    pub fn agree_percent(&self) -> f64 {
        100.0 * (self.both_miss + self.same_triangle) as f64 / self.rays.max(1) as f64
    }

    /// The `q`-quantile of the hit-point offsets (0 when there are none).
    pub fn offset(&self, q: f64) -> f32 {
        if self.offsets.is_empty() {
            return 0.0;
        }
        let i = ((self.offsets.len() - 1) as f64 * q).round() as usize;
        self.offsets[i.min(self.offsets.len() - 1)]
    }

    fn add(&mut self, f: Option<Hit>, x: Option<Hit>, ray: &Ray, c: [RayCounters; 2]) {
        self.rays += 1;
        match (f, x) {
            (None, None) => self.both_miss += 1,
            (Some(f), Some(x)) if f.prim == x.prim => {
                self.same_triangle += 1;
                self.offsets.push(((f.t - x.t) * ray.dir.length()).abs());
            }
            (Some(_), Some(_)) => self.other_triangle += 1,
            (Some(_), None) => self.f32_only += 1,
            (None, Some(_)) => self.fixed_only += 1,
        }
        for (k, c) in c.iter().enumerate() {
            self.visits[k] += u64::from(c.nodes) + u64::from(c.leaves);
            self.tests[k] += u64::from(c.tri_tests);
        }
    }

    fn merge(mut self, o: Agreement) -> Agreement {
        self.rays += o.rays;
        self.both_miss += o.both_miss;
        self.same_triangle += o.same_triangle;
        self.other_triangle += o.other_triangle;
        self.f32_only += o.f32_only;
        self.fixed_only += o.fixed_only;
        self.offsets.extend(o.offsets);
        for k in 0..2 {
            self.visits[k] += o.visits[k];
            self.tests[k] += o.tests[k];
        }
        self
    }
}

/// Where the scene sits in a format: the largest coordinate magnitude of its bounds and
/// of the camera's eye, and whether the format holds it.
pub fn fits(view: &SceneView<'_>, eye: &EyeRays, format: QFormat) -> (f32, bool) {
    let (lo, hi) = view.bounds();
    let largest = lo.abs().max(hi.abs()).max(eye.ray(0, 0).origin.abs()).max_element();
    (largest, format.holds(largest) && format.holds(-largest))
}

/// The rays of the comparison: the view's eye rays inside the scene's bounds, and one
/// bounce ray from each `f32` hit.
pub fn rays(view: &SceneView<'_>, eye: &EyeRays) -> (Vec<Ray>, Vec<Ray>) {
    let (lo, hi) = view.test_bounds();
    let pixels: Vec<(u32, u32)> = (0..eye.height).flat_map(|y| (0..eye.width).map(move |x| (x, y))).collect();
    let primary: Vec<(u32, Ray)> = pixels
        .par_iter()
        .filter_map(|&(x, y)| eye.ray_in_scene(x, y, lo, hi).map(|r| (y * eye.width + x, r)))
        .collect();
    let bounce = primary
        .par_iter()
        .filter_map(|&(pixel, ray)| {
            let hit = trace::<Watertight, _>(view, &ray, &mut NoProbe, &mut RayCounters::default())?;
            let s = Surface::at(view, &ray, &hit, eye.cone(), &mut NoProbe);
            if s.normal == raypipe_core::Vec3::ZERO {
                return None;
            }
            let d = cosine_direction(s.normal, uniform(pixel, 0, 1, 0), uniform(pixel, 0, 1, 1));
            Some(s.ray_along(d))
        })
        .collect();
    (primary.into_iter().map(|(_, r)| r).collect(), bounce)
}

/// `rays` through `f32` (watertight) and through `datapath`, compared.
pub fn compare(view: &SceneView<'_>, rays: &[Ray], datapath: Datapath) -> Agreement {
    with_datapath!(datapath, I => compare_with::<I>(view, rays), f32 => compare_with::<Watertight>(view, rays))
}

fn compare_with<I: Intersector>(view: &SceneView<'_>, rays: &[Ray]) -> Agreement {
    let mut a = rays
        .par_chunks(4096)
        .map(|chunk| {
            let mut a = Agreement::default();
            for r in chunk {
                let mut c = [RayCounters::default(); 2];
                let f = trace::<Watertight, _>(view, r, &mut NoProbe, &mut c[0]);
                let x = trace::<I, _>(view, r, &mut NoProbe, &mut c[1]);
                a.add(f, x, r, c);
            }
            a
        })
        .reduce(Agreement::default, Agreement::merge);
    a.offsets.sort_by(f32::total_cmp);
    a
}
