//! The glossy lobe of MTL's `illum 2` (highlights on): Blinn–Phong, `Ks` times the
//! normalised distribution `c(n) (N·H)^n` of the half vector `H` (Blinn 1977), with
//! `n = Ns` and the exact normalisation `c(n) = (n + 2)(n + 4) / (8π (2^(−n/2) + n))`,
//! which makes the lobe reflect exactly `Ks` of light arriving along the normal
//! (F. Giesen, "Derivation of Phong and Blinn-Phong BRDF normalization factors", 2009).
//!
//! A material's diffuse and glossy parts together must not reflect more than arrives: when
//! `Kd + Ks` exceeds 1 in some channel (the glossy Cornell box's sphere has 0.49 + 0.9) both
//! are scaled down by that sum ([`lobes`]).
//!
//! Whitted's shader adds the highlight of each point light; the path tracer also samples
//! the lobe for its bounce: the half vector from `(N·H)^n` (density `(n + 1)/(2π) (N·H)^n`),
//! mirrored about it, so the weight `f cos θ / pdf` stays bounded whatever `Ns` is.

use glam::Vec3;

use crate::image::MaterialRecord;
use crate::shade::hemisphere::around;

/// Specular exponents beyond this are clamped (MTL's range is 0 to 1000; a larger one
/// is a mirror for every purpose, and `(N·H)^n` would underflow everywhere).
pub const MAX_EXPONENT: f32 = 1.0e4;

/// A glossy lobe: reflectance `Ks` and exponent `Ns`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlinnPhong {
    /// Specular reflectance, each channel in `[0, 1]`.
    pub ks: Vec3,
    /// Specular exponent `n >= 0`.
    pub exponent: f32,
}

/// True for a material with a glossy lobe: `illum 2` and some `Ks` above zero. Mirrors
/// and glass (`illum` 3 to 7) reflect through [`crate::shade::specular`] instead.
pub fn is_glossy(m: &MaterialRecord) -> bool {
    m.illum == 2 && m.specular.iter().any(|&k| k > 0.0)
}

/// The diffuse reflectance and the glossy lobe of material `m` whose diffuse reflectance
/// at the hit is `diffuse` (`Kd` times texture and vertex colour): both scaled by
/// `1 / max(Kd + Ks)` when that sum exceeds 1, so that together they conserve energy.
pub fn lobes(m: &MaterialRecord, diffuse: Vec3) -> (Vec3, Option<BlinnPhong>) {
    if !is_glossy(m) {
        return (diffuse, None);
    }
    let ks = Vec3::from(m.specular).clamp(Vec3::ZERO, Vec3::ONE);
    let exponent = if m.shininess.is_finite() { m.shininess.clamp(0.0, MAX_EXPONENT) } else { 0.0 };
    let scale = 1.0 / (diffuse + ks).max_element().max(1.0);
    (diffuse * scale, Some(BlinnPhong { ks: ks * scale, exponent }))
}

impl BlinnPhong {
    /// The normalisation `c(n)` times π: the lobe's value relative to a Lambertian
    /// `Kd / π` of the same reflectance.
    fn pi_norm(&self) -> f32 {
        let n = self.exponent;
        (n + 2.0) * (n + 4.0) / (8.0 * (crate::math::exp_log::exp2(-0.5 * n) + n))
    }

    /// π times the BRDF for light arriving from unit `to_light` and leaving toward unit
    /// `to_eye`, about unit normal `normal` — what multiplies a light's colour and the
    /// cosine, as `Kd` does for a Lambertian surface (raypipe's point lights carry
    /// π × intensity). Zero when either direction is below the surface.
    pub fn eval_pi(&self, normal: Vec3, to_light: Vec3, to_eye: Vec3) -> Vec3 {
        if normal.dot(to_light) <= 0.0 || normal.dot(to_eye) <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (to_light + to_eye).normalize_or_zero();
        let cos_h = normal.dot(h).max(0.0);
        self.ks * (self.pi_norm() * crate::math::exp_log::pow(cos_h, self.exponent))
    }

    /// The solid-angle density with which [`BlinnPhong::sample`] picks unit `dir`: the
    /// half-vector density `(n + 1)/(2π) (N·H)^n` over the reflection's Jacobian
    /// `4 (V·H)` (zero below the surface).
    pub fn pdf(&self, normal: Vec3, dir: Vec3, to_eye: Vec3) -> f32 {
        if normal.dot(dir) <= 0.0 || normal.dot(to_eye) <= 0.0 {
            return 0.0;
        }
        let h = (dir + to_eye).normalize_or_zero();
        let (cos_h, eye_h) = (normal.dot(h).max(0.0), to_eye.dot(h));
        if eye_h <= 0.0 {
            return 0.0;
        }
        let n = self.exponent;
        (n + 1.0) / (2.0 * core::f32::consts::PI) * crate::math::exp_log::pow(cos_h, n) / (4.0 * eye_h)
    }

    /// A bounce direction for light leaving toward unit `to_eye` from a surface with unit
    /// normal `normal`, from two uniform numbers, and its weight `f cos θ / pdf` (times
    /// `Ks`); `None` when the sample falls below the surface (that light is lost: the lobe
    /// is clipped by the horizon).
    pub fn sample(&self, normal: Vec3, to_eye: Vec3, u1: f32, u2: f32) -> Option<(Vec3, Vec3)> {
        let n = self.exponent;
        let cos_h = crate::math::exp_log::pow(u1, 1.0 / (n + 1.0));
        let sin_h = libm::sqrtf((1.0 - cos_h * cos_h).max(0.0));
        let (sin, cos) = crate::math::trig::sin_cos(2.0 * core::f32::consts::PI * u2);
        let h = around(normal, sin_h * cos, sin_h * sin, cos_h);
        let eye_h = to_eye.dot(h);
        let dir = h * (2.0 * eye_h) - to_eye;
        let cos_o = normal.dot(dir);
        if eye_h <= 0.0 || cos_o <= 0.0 || normal.dot(to_eye) <= 0.0 {
            return None;
        }
        // f cos / pdf = Ks c(n) (N·H)^n cos_o · 4 (V·H) / ((n + 1)/(2π) (N·H)^n).
        let w = self.pi_norm() * 8.0 / (n + 1.0) * eye_h * cos_o;
        Some((dir, self.ks * w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shade::rng::uniform;

    fn lobe(exponent: f32) -> BlinnPhong {
        BlinnPhong { ks: Vec3::ONE, exponent }
    }

    /// The directional albedo by importance sampling: the mean weight of the samples.
    fn albedo(l: &BlinnPhong, to_eye: Vec3, k: u32) -> f32 {
        (0..k)
            .filter_map(|i| l.sample(Vec3::Z, to_eye, uniform(i, 1, 0, 0), uniform(i, 1, 0, 1)))
            .map(|(_, w)| w.x)
            .sum::<f32>()
            / k as f32
    }

    /// Energy: along the normal the lobe reflects all of `Ks` (the normalisation is
    /// exact), and at every other angle no more.
    #[test]
    fn the_lobe_reflects_ks_at_normal_incidence_and_never_more() {
        for n in [0.0, 1.0, 10.0, 40.0, 200.0, 1000.0] {
            let a = albedo(&lobe(n), Vec3::Z, 200_000);
            assert!((a - 1.0).abs() < 0.01, "n {n}: albedo at normal incidence {a}");
            for deg in [20.0f32, 45.0, 70.0, 85.0] {
                let r = deg.to_radians();
                let v = Vec3::new(r.sin(), 0.0, r.cos());
                let a = albedo(&lobe(n), v, 100_000);
                assert!(a <= 1.01, "n {n} at {deg}°: albedo {a}");
            }
        }
    }

    /// The sampled weight is the evaluated BRDF over the sampling density: estimating the
    /// albedo by uniform hemisphere sampling of `eval_pi` agrees with importance sampling.
    #[test]
    fn sampling_agrees_with_evaluation() {
        for n in [0.0, 5.0, 40.0] {
            let l = lobe(n);
            let v = Vec3::new(0.5, 0.1, 0.8).normalize();
            let k = 400_000;
            let mut uniform_est = 0.0f64;
            for i in 0..k {
                let (u1, u2) = (uniform(i, 2, 0, 0), uniform(i, 2, 0, 1));
                let z = u1;
                let r = libm::sqrtf((1.0 - z * z).max(0.0));
                let (s, c) = crate::math::trig::sin_cos(2.0 * core::f32::consts::PI * u2);
                let d = Vec3::new(r * c, r * s, z);
                // f cos / (1 / 2π), with f = eval_pi / π.
                uniform_est += (l.eval_pi(Vec3::Z, d, v).x * z * 2.0) as f64;
            }
            let uniform_est = (uniform_est / k as f64) as f32;
            let importance = albedo(&l, v, 200_000);
            assert!((uniform_est - importance).abs() < 0.02, "n {n}: {uniform_est} vs {importance}");
        }
    }

    /// The density is the one `sample` draws from: the sampled weight equals the
    /// evaluated BRDF times the cosine over `pdf`.
    #[test]
    fn pdf_matches_the_sampled_weight() {
        for n in [1.0, 10.0, 80.0] {
            let l = lobe(n);
            let v = Vec3::new(0.3, -0.2, 0.9).normalize();
            for i in 0..2000 {
                let Some((d, w)) = l.sample(Vec3::Z, v, uniform(i, 3, 0, 0), uniform(i, 3, 0, 1)) else { continue };
                let expected = l.eval_pi(Vec3::Z, d, v).x / core::f32::consts::PI * d.z / l.pdf(Vec3::Z, d, v);
                assert!((w.x - expected).abs() <= 1e-3 * expected.max(1.0), "n {n}: {} vs {expected}", w.x);
            }
        }
    }

    #[test]
    fn lobes_conserve_energy_and_leave_matte_materials_alone() {
        let mut m = MaterialRecord {
            diffuse: [0.486, 0.631, 0.663],
            specular: [0.9; 3],
            shininess: 40.0,
            illum: 2,
            ..MaterialRecord::DEFAULT
        };
        let (d, g) = lobes(&m, Vec3::from(m.diffuse));
        let g = g.expect("glossy");
        assert!(((d + g.ks).max_element() - 1.0).abs() < 1e-6);
        assert!((g.ks.x / d.z - 0.9 / 0.663).abs() < 1e-4, "the ratio of the two is kept");
        m.illum = 3;
        assert_eq!(lobes(&m, Vec3::splat(0.5)), (Vec3::splat(0.5), None));
        m.illum = 2;
        m.specular = [0.0; 3];
        assert_eq!(lobes(&m, Vec3::splat(0.5)), (Vec3::splat(0.5), None));
        m.specular = [0.2; 3];
        m.shininess = f32::NAN;
        assert_eq!(lobes(&m, Vec3::splat(0.5)).1.map(|g| g.exponent), Some(0.0));
    }
}
