//! Eye-ray generation for a pinhole camera (Purcell 2002 §3.1.1, the eye-ray kernel).

use core::fmt;

use glam::{Vec3, Vec4};

use crate::image::CameraRecord;
use crate::pixel_filter::PixelSampler;
use crate::ray::Ray;
use crate::shade::ray_cone::RayCone;
use crate::traverse::boxes::clip::{clip_ray, clip_rays4};

/// A pinhole camera: where it is, what it looks at, which way is up, and the image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view, degrees, in `(0, 180)`.
    pub vfov_deg: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// Why a camera cannot produce rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// Width or height is zero.
    ZeroSize,
    /// Width × height is more than [`MAX_PIXELS`].
    TooLarge,
    /// A coordinate or the field of view is NaN or infinite.
    NonFinite,
    /// The field of view is not strictly between 0 and 180 degrees.
    BadFov,
    /// The eye is at the point it looks at.
    NoViewDirection,
    /// The view direction is parallel to the up vector (or up is zero).
    UpParallelToView,
}

/// The most pixels a camera may ask for (16384 × 16384).
pub const MAX_PIXELS: u64 = 1 << 28;

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CameraError::ZeroSize => "image size is zero",
            CameraError::TooLarge => "image size is more than 2^28 pixels",
            CameraError::NonFinite => "camera has a NaN or infinite value",
            CameraError::BadFov => "field of view must be strictly between 0 and 180 degrees",
            CameraError::NoViewDirection => "camera eye and look-at point coincide",
            CameraError::UpParallelToView => "camera looks along its up vector",
        })
    }
}

impl From<&CameraRecord> for Camera {
    fn from(r: &CameraRecord) -> Camera {
        Camera {
            eye: Vec3::from(r.eye),
            look_at: Vec3::from(r.look_at),
            up: Vec3::from(r.up),
            vfov_deg: r.vfov_deg,
            width: r.width,
            height: r.height,
        }
    }
}

/// A validated camera with its orthonormal frame precomputed: the eye-ray kernel's
/// constant registers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    half_w: f32,
    half_h: f32,
    inv_w: f32,
    inv_h: f32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Eye rays per pixel and where in the pixel they go.
    pub sampler: PixelSampler,
}

impl EyeRays {
    /// Validates the camera and derives its frame. The image's right is
    /// `forward × up` (right-handed), so the Cornell box's red wall is on the left.
    pub fn new(cam: &Camera) -> Result<EyeRays, CameraError> {
        if cam.width == 0 || cam.height == 0 {
            return Err(CameraError::ZeroSize);
        }
        // Whatever the camera came from (a file, an image, the command line), a frame is
        // something a driver can allocate and finish.
        if cam.width as u64 * cam.height as u64 > MAX_PIXELS {
            return Err(CameraError::TooLarge);
        }
        if !(cam.eye.is_finite() && cam.look_at.is_finite() && cam.up.is_finite() && cam.vfov_deg.is_finite()) {
            return Err(CameraError::NonFinite);
        }
        if !(cam.vfov_deg > 0.0 && cam.vfov_deg < 180.0) {
            return Err(CameraError::BadFov);
        }
        let view = cam.look_at - cam.eye;
        if view.length_squared() == 0.0 || !view.length_squared().is_finite() {
            return Err(CameraError::NoViewDirection);
        }
        let forward = view.normalize();
        let right = forward.cross(cam.up);
        // Parallel within about 0.06 degrees counts as parallel: the frame would be noise.
        if cam.up.length_squared() == 0.0 || right.length() <= 1e-3 * cam.up.length() {
            return Err(CameraError::UpParallelToView);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let half_h = crate::math::trig::tan(cam.vfov_deg.to_radians() * 0.5);
        let half_w = half_h * cam.width as f32 / cam.height as f32;
        Ok(EyeRays {
            eye: cam.eye,
            forward,
            right,
            up,
            half_w,
            half_h,
            inv_w: 1.0 / cam.width as f32,
            inv_h: 1.0 / cam.height as f32,
            width: cam.width,
            height: cam.height,
            sampler: PixelSampler::default(),
        })
    }

    /// The same view with `sampler`'s eye rays per pixel.
    pub fn with_sampler(self, sampler: PixelSampler) -> EyeRays {
        EyeRays { sampler: PixelSampler { samples: sampler.samples.max(1), ..sampler }, ..self }
    }

    /// The cone of an eye ray: no width at the eye, one pixel's angle of spread (the
    /// height of a pixel at unit distance; Akenine-Möller et al. 2019, eq. 30 in its
    /// small-angle form). Texture filtering reads it ([`crate::shade::ray_cone`]).
    #[inline]
    pub fn cone(&self) -> RayCone {
        RayCone { width: 0.0, spread: 2.0 * self.half_h * self.inv_h }
    }

    /// Eye rays per pixel.
    #[inline]
    pub fn samples(&self) -> u32 {
        self.sampler.samples
    }

    /// Offset of sample `s` of pixel `(x, y)` from the pixel's centre, in pixels.
    #[inline]
    pub fn sample_offset(&self, x: u32, y: u32, s: u32) -> (f32, f32) {
        self.sampler.offset(y.wrapping_mul(self.width).wrapping_add(x), s)
    }

    /// Eye ray `s` of pixel `(x, y)` ([`EyeRays::ray_at`] its offset).
    #[inline]
    pub fn sample_ray(&self, x: u32, y: u32, s: u32) -> Ray {
        self.ray_at(x, y, self.sample_offset(x, y, s))
    }

    /// [`EyeRays::ray_in_scene`] for eye ray `s` of pixel `(x, y)`.
    #[inline]
    pub fn sample_ray_in_scene(&self, x: u32, y: u32, s: u32, bounds_min: Vec3, bounds_max: Vec3) -> Option<Ray> {
        let ray = self.sample_ray(x, y, s);
        clip_ray(&ray, bounds_min, bounds_max).map(|_| ray)
    }

    /// The primary ray through the centre of pixel `(x, y)`, `y` growing downwards;
    /// its direction has unit length, so `t` is a distance.
    #[inline]
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        self.ray_at(x, y, (0.0, 0.0))
    }

    /// The primary ray through pixel `(x, y)`'s centre moved by `(dx, dy)` pixels (`y`
    /// down); with no offset, [`EyeRays::ray`] bit for bit.
    #[inline]
    pub fn ray_at(&self, x: u32, y: u32, (dx, dy): (f32, f32)) -> Ray {
        let sx = ((x as f32 + 0.5 + dx) * self.inv_w) * 2.0 - 1.0;
        let sy = 1.0 - ((y as f32 + 0.5 + dy) * self.inv_h) * 2.0;
        let d = self.forward + self.right * (sx * self.half_w) + self.up * (sy * self.half_h);
        Ray::new(self.eye, d.normalize())
    }

    /// The inverse of [`EyeRays::ray`] for a rasterizer: the continuous pixel coordinates
    /// of `p` (pixel centres at whole numbers, `y` downwards) and its depth along the view
    /// direction, or `None` if `p` is not in front of the eye.
    #[inline]
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let v = self.to_view(p);
        if v.z.is_nan() || v.z <= 0.0 {
            return None;
        }
        let (x, y) = self.view_to_pixel(v);
        Some((x as f32, y as f32, v.z))
    }

    /// `p` in the camera's frame: `(right, up, forward)` components of `p - eye`, so
    /// `z` is the view depth (a rasterizer clips against a plane of constant `z`).
    #[inline]
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        let v = p - self.eye;
        Vec3::new(v.dot(self.right), v.dot(self.up), v.dot(self.forward))
    }

    /// Continuous pixel coordinates (centres at whole numbers, `y` downwards) of a point
    /// in the camera's frame with `z > 0`, in `f64`: a vertex just past the near plane
    /// projects millions of pixels away, where `f32` would lose the edge's position.
    #[inline]
    pub fn view_to_pixel(&self, v: Vec3) -> (f64, f64) {
        let z = v.z as f64;
        let sx = v.x as f64 / (z * self.half_w as f64);
        let sy = v.y as f64 / (z * self.half_h as f64);
        ((sx + 1.0) * 0.5 * self.width as f64 - 0.5, (1.0 - sy) * 0.5 * self.height as f64 - 0.5)
    }

    /// Cosine between the ray through pixel `(x, y)` and the view direction: a ray's
    /// distance `t` is the view depth over it.
    #[inline]
    pub fn depth_per_distance(&self, x: u32, y: u32) -> f32 {
        self.ray(x, y).dir.dot(self.forward)
    }

    /// Cosine between `ray` (an eye ray of this view) and the view direction.
    #[inline]
    pub fn depth_per_distance_of(&self, ray: &Ray) -> f32 {
        ray.dir.dot(self.forward)
    }

    /// The eye rays of four pixels `(x[k], y[k])` as four SIMD lanes: their common origin
    /// and, per axis, their directions. Lane by lane the operations of [`EyeRays::ray`] in
    /// the same order, hence the same bits; four rays for about the cost of one (a
    /// packet's rays were half of `raypipe bench`'s time on the bunny).
    #[inline]
    pub fn rays4(&self, x: [u32; 4], y: [u32; 4]) -> (Vec3, [Vec4; 3]) {
        self.rays4_at(x, y, [(0.0, 0.0); 4])
    }

    /// [`EyeRays::rays4`] moved by per-lane offsets `d` in pixels: lane by lane
    /// [`EyeRays::ray_at`], bit for bit.
    #[inline]
    pub fn rays4_at(&self, x: [u32; 4], y: [u32; 4], d: [(f32, f32); 4]) -> (Vec3, [Vec4; 3]) {
        let xs = Vec4::from_array(x.map(|v| v as f32));
        let ys = Vec4::from_array(y.map(|v| v as f32));
        let (dx, dy) = (Vec4::from_array(d.map(|o| o.0)), Vec4::from_array(d.map(|o| o.1)));
        let sx = ((xs + 0.5 + dx) * self.inv_w) * 2.0 - 1.0;
        let sy = Vec4::ONE - ((ys + 0.5 + dy) * self.inv_h) * 2.0;
        let (a, b) = (sx * self.half_w, sy * self.half_h);
        let (f, r, u) = (self.forward.to_array(), self.right.to_array(), self.up.to_array());
        let d: [Vec4; 3] =
            core::array::from_fn(|c| (Vec4::splat(f[c]) + Vec4::splat(r[c]) * a) + Vec4::splat(u[c]) * b);
        // `Vec3::normalize`: the product by `1 / sqrt(dot)`, the dot summed x, y, then z.
        let recip = Vec4::ONE / ((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]).sqrt();
        (self.eye, d.map(|v| v * recip))
    }

    /// [`EyeRays::ray_in_scene`] for four pixels: [`EyeRays::rays4`], and bit `k` set
    /// where pixel `k`'s ray meets the scene's bounding box (its ray is then `Some`).
    #[inline]
    pub fn rays4_in_scene(
        &self,
        x: [u32; 4],
        y: [u32; 4],
        bounds_min: Vec3,
        bounds_max: Vec3,
    ) -> (Vec3, [Vec4; 3], u32) {
        let (origin, dirs) = self.rays4(x, y);
        let seen = clip_rays4(origin, dirs, Vec4::ZERO, Vec4::INFINITY, bounds_min, bounds_max);
        (origin, dirs, seen)
    }

    /// [`EyeRays::rays4_in_scene`] for eye ray `s` of each of the four pixels.
    #[inline]
    pub fn sample_rays4_in_scene(
        &self,
        x: [u32; 4],
        y: [u32; 4],
        s: u32,
        bounds_min: Vec3,
        bounds_max: Vec3,
    ) -> (Vec3, [Vec4; 3], u32) {
        let d = core::array::from_fn(|k| self.sample_offset(x[k], y[k], s));
        let (origin, dirs) = self.rays4_at(x, y, d);
        let seen = clip_rays4(origin, dirs, Vec4::ZERO, Vec4::INFINITY, bounds_min, bounds_max);
        (origin, dirs, seen)
    }

    /// Purcell 2002 §3.1.1: the eye-ray kernel also tests the ray against the scene's
    /// bounding box and ends a ray that misses it at once (`None`). The ray's own
    /// interval is left as it is, so traversal computes the same hits either way.
    #[inline]
    pub fn ray_in_scene(&self, x: u32, y: u32, bounds_min: Vec3, bounds_max: Vec3) -> Option<Ray> {
        let ray = self.ray(x, y);
        clip_ray(&ray, bounds_min, bounds_max).map(|_| ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera { eye: Vec3::new(0.0, 0.0, -5.0), look_at: Vec3::ZERO, up: Vec3::Y, vfov_deg: 90.0, width: 4, height: 2 }
    }

    #[test]
    fn centre_ray_looks_forward_and_corners_are_symmetric() {
        let e = EyeRays::new(&Camera { width: 3, height: 3, ..cam() }).unwrap();
        let r = e.ray(1, 1);
        assert!((r.dir - Vec3::Z).length() < 1e-6);
        let a = e.ray(0, 0).dir;
        let b = e.ray(2, 2).dir;
        assert!((a.x + b.x).abs() < 1e-6 && (a.y + b.y).abs() < 1e-6);
        // Top-left pixel looks up and to the left (+x is image-left for forward +z, up +y).
        assert!(a.y > 0.0 && a.x > 0.0);
    }

    #[test]
    fn projection_inverts_the_eye_ray() {
        let e = EyeRays::new(&Camera { width: 7, height: 5, ..cam() }).unwrap();
        for (x, y) in [(0, 0), (3, 2), (6, 4), (1, 3)] {
            let r = e.ray(x, y);
            let (px, py, z) = e.project(r.at(3.0)).unwrap();
            assert!((px - x as f32).abs() < 1e-4 && (py - y as f32).abs() < 1e-4, "{x},{y}: {px},{py}");
            assert!((z - 3.0 * e.depth_per_distance(x, y)).abs() < 1e-4);
        }
        assert_eq!(e.project(Vec3::new(0.0, 0.0, -6.0)), None, "behind the eye");
    }

    #[test]
    fn rejects_impossible_cameras() {
        assert_eq!(EyeRays::new(&Camera { width: 0, ..cam() }), Err(CameraError::ZeroSize));
        assert_eq!(EyeRays::new(&Camera { up: Vec3::Z, ..cam() }), Err(CameraError::UpParallelToView));
        assert_eq!(EyeRays::new(&Camera { look_at: cam().eye, ..cam() }), Err(CameraError::NoViewDirection));
        assert_eq!(EyeRays::new(&Camera { vfov_deg: 180.0, ..cam() }), Err(CameraError::BadFov));
        assert_eq!(EyeRays::new(&Camera { vfov_deg: f32::NAN, ..cam() }), Err(CameraError::NonFinite));
    }

    /// Four eye rays at once are, lane by lane, the one-ray kernel's rays bit for bit.
    #[test]
    fn four_eye_rays_are_the_single_rays() {
        let mut g = crate::test_lcg::Lcg(9);
        for (k, c) in [cam(), Camera { width: 1024, height: 768, vfov_deg: 37.0, ..cam() }].iter().enumerate() {
            let c = Camera { eye: c.eye + Vec3::new(0.3, -1.7, 0.25) * k as f32, ..*c };
            let e = EyeRays::new(&c).unwrap();
            for _ in 0..2000 {
                let x: [u32; 4] = core::array::from_fn(|_| (g.next() >> 40) as u32 % c.width);
                let y: [u32; 4] = core::array::from_fn(|_| (g.next() >> 40) as u32 % c.height);
                let (origin, d) = e.rays4(x, y);
                for lane in 0..4 {
                    let r = e.ray(x[lane], y[lane]);
                    assert_eq!(origin.to_array().map(f32::to_bits), r.origin.to_array().map(f32::to_bits));
                    let got = [d[0][lane], d[1][lane], d[2][lane]].map(f32::to_bits);
                    assert_eq!(got, r.dir.to_array().map(f32::to_bits), "pixel ({}, {})", x[lane], y[lane]);
                }
            }
        }
    }
}
