//! Directions around a surface normal: a local frame, and the cosine-weighted
//! distribution of the diffuse bounce (Malley's method: a uniform point on the disk,
//! lifted onto the hemisphere).

use glam::Vec3;

/// The direction with coordinates `(x, y, z)` in a frame whose third axis is unit `n`
/// (the first two axes are an orthonormal pair chosen from `n` alone).
#[inline]
pub fn around(n: Vec3, x: f32, y: f32, z: f32) -> Vec3 {
    let helper = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let t = helper.cross(n).normalize_or_zero();
    let b = n.cross(t);
    t * x + b * y + n * z
}

/// A direction around unit `n` with density `cos θ / π` from two uniform numbers.
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = libm::sqrtf(u1);
    let phi = 2.0 * core::f32::consts::PI * u2;
    let (sin, cos) = crate::math::trig::sin_cos(phi);
    around(n, r * cos, r * sin, libm::sqrtf((1.0 - u1).max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shade::rng::uniform;

    #[test]
    fn cosine_directions_stay_in_the_hemisphere_and_follow_the_cosine() {
        for n in [Vec3::Z, Vec3::new(1.0, 2.0, -0.5).normalize(), Vec3::X, -Vec3::Y] {
            let mut mean_cos = 0.0;
            let k = 4096;
            for i in 0..k {
                let d = cosine_direction(n, uniform(i, 0, 0, 0), uniform(i, 0, 0, 1));
                assert!((d.length() - 1.0).abs() < 1e-4);
                assert!(d.dot(n) >= -1e-6);
                mean_cos += d.dot(n) / k as f32;
            }
            // E[cos θ] under the cosine density is 2/3.
            assert!((mean_cos - 2.0 / 3.0).abs() < 0.02, "{mean_cos}");
        }
    }
}
