//! Ray cones for texture filtering (Akenine-Möller et al., "Texture Level of Detail
//! Strategies for Real-Time Ray Tracing", Ray Tracing Gems, 2019, ch. 20): each ray
//! carries the width of the cone of space its pixel sample stands for, growing linearly
//! along the ray. At a hit the width, over the texel's size on the surface and the
//! incidence cosine, picks the mipmap level (§20.3.4, eq. 34).
//!
//! An eye ray's cone starts at width zero with the angle of one pixel. A reflected,
//! refracted or bounced ray starts with the width the cone reached at the hit and keeps
//! its spread: the surface's curvature, which would widen or narrow it, is left out
//! (the chapter's β; flat surfaces have none), and a diffuse bounce, whose true
//! footprint is wider, filters as finely as a mirror would — it samples the texture at
//! random points anyway.

use glam::Vec3;

/// A cone around a ray: its width at the origin and its growth per unit of distance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayCone {
    /// Width at the ray's origin (world units).
    pub width: f32,
    /// Width added per unit distance travelled (the spread angle, small-angle form).
    pub spread: f32,
}

impl RayCone {
    /// A cone of no width: textures are read at their finest level.
    pub const POINT: RayCone = RayCone { width: 0.0, spread: 0.0 };

    /// The cone's width at parameter `t` of a ray of direction `dir`.
    #[inline]
    pub fn width_at(&self, t: f32, dir: Vec3) -> f32 {
        self.width + self.spread * t * dir.length()
    }

    /// The cone continuing from a hit at parameter `t` of a ray of direction `dir`.
    #[inline]
    pub fn at_hit(&self, t: f32, dir: Vec3) -> RayCone {
        RayCone { width: self.width_at(t, dir), spread: self.spread }
    }

    /// The mipmap level for a cone of width `width` meeting, at incidence cosine
    /// `cos_incidence`, a triangle whose texture-space area is `texel_area` texels and
    /// whose world-space area is `world_area` (eq. 34 with Δ = ½ log₂(tₐ / pₐ)): the log
    /// of the texels the footprint covers along one side; −∞ (the finest level) for a
    /// point-like cone.
    pub fn level(width: f32, cos_incidence: f32, texel_area: f32, world_area: f32) -> f32 {
        let texels_per_unit = crate::math::exp_log::log2(texel_area / world_area) * 0.5;
        let footprint = crate::math::exp_log::log2(width) - crate::math::exp_log::log2(cos_incidence.abs());
        let level = texels_per_unit + footprint;
        if level.is_nan() {
            f32::NEG_INFINITY
        } else {
            level
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of side 2 facing the cone, textured once by 256 × 256 texels: a footprint
    /// of width w covers 128·w texels, so the level is log₂(128·w); at 60° incidence the
    /// footprint is twice as long.
    #[test]
    fn the_level_is_the_log_of_the_texels_the_footprint_covers() {
        let (texel_area, world_area) = (256.0 * 256.0, 4.0);
        for w in [1.0 / 128.0, 1.0 / 32.0, 0.25] {
            let want = libm::log2(128.0 * w as f64) as f32;
            assert!((RayCone::level(w, 1.0, texel_area, world_area) - want).abs() < 1e-5);
            assert!((RayCone::level(w, 0.5, texel_area, world_area) - want - 1.0).abs() < 1e-5);
        }
        assert_eq!(RayCone::level(0.0, 1.0, texel_area, world_area), f32::NEG_INFINITY);
        assert_eq!(RayCone::level(0.1, 1.0, 0.0, 0.0), f32::NEG_INFINITY);
        let cone = RayCone { width: 0.5, spread: 0.01 };
        assert_eq!(cone.width_at(100.0, Vec3::new(0.0, 2.0, 0.0)), 2.5);
        assert_eq!(cone.at_hit(100.0, Vec3::X), RayCone { width: 1.5, spread: 0.01 });
    }
}
