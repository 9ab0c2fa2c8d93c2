//! Diffuse texture lookup: trilinear mipmap filtering — bilinear filtering of the four
//! nearest texels in linear colour (texels are stored as 8-bit sRGB) on the two levels
//! nearest the footprint's, blended — with repeat or clamp wrapping. OBJ's `v` runs
//! upwards, the texture's rows downwards.

use glam::Vec3;

use crate::image::{MaterialRecord, SceneView, TextureRecord, NULL_INDEX};
use crate::probe::MemoryProbe;
use crate::shade::color::srgb8_to_linear;

fn wrap(i: i64, n: u32, mode: u32) -> u32 {
    // `n >= 1` for a validated texture; `max(1)` lets the compiler see it too (no panic
    // path for an empty range or a remainder by zero).
    let n = n.max(1) as i64;
    if mode == TextureRecord::CLAMP {
        i.clamp(0, n - 1) as u32
    } else {
        i.rem_euclid(n) as u32
    }
}

/// On one axis of `n` texels, the texel at or before coordinate `u` (texel centres at
/// half-integers) and the weight of the one after it. In f32 (no f64 on firmware): with
/// repeat, the coordinate is first wrapped into [0, 1) — exact, and the weight keeps its
/// precision however far `u` lies from 0 — and with clamp, a position beyond the
/// texture, where both texels are the edge's, is first clamped to it (nothing overflows).
fn axis(u: f32, n: u32, mode: u32) -> (i64, f32) {
    let n = n.max(1) as f32;
    let x = if mode == TextureRecord::CLAMP { (u * n - 0.5).clamp(-1.0, n) } else { (u - libm::floorf(u)) * n - 0.5 };
    let x0 = libm::floorf(x);
    (x0 as i64, x - x0)
}

/// The texture a hit on a triangle of material `m` reads: the material's, when it has one
/// and the image has shading vertices (their texture coordinates). Shared by
/// [`crate::shade::surface::Surface::at`] and the drivers that count its work.
pub fn surface_texture(scene: &SceneView<'_>, m: &MaterialRecord) -> Option<TextureRecord> {
    if m.texture == NULL_INDEX || !scene.has_shading_vertices() {
        return None;
    }
    scene.texture(m.texture)
}

/// The linear RGB colour of texture `t` at texture coordinates `uv`, filtered for a
/// footprint of mipmap level `level` (from [`crate::shade::ray_cone::RayCone::level`]):
/// bilinear on level 0 at or below 0, trilinear between the two nearest levels above it
/// (Williams 1983), the coarsest level beyond the chain. `None` when the coordinates are
/// not finite.
pub fn sample<P: MemoryProbe>(
    scene: &SceneView<'_>,
    t: &TextureRecord,
    uv: [f32; 2],
    level: f32,
    probe: &mut P,
) -> Option<Vec3> {
    if !(uv[0].is_finite() && uv[1].is_finite()) {
        return None;
    }
    // Not above 0 (NaN included): the finest level alone.
    if level.is_nan() || level <= 0.0 {
        return Some(bilinear(scene, &t.level(0), uv, probe));
    }
    let last = t.levels.saturating_sub(1) as f32;
    let level = level.min(last);
    let k = libm::floorf(level);
    let f = level - k;
    let fine = bilinear(scene, &t.level(k as u32), uv, probe);
    if f > 0.0 {
        let coarse = bilinear(scene, &t.level(k as u32 + 1), uv, probe);
        Some(fine * (1.0 - f) + coarse * f)
    } else {
        Some(fine)
    }
}

/// Bilinear filtering of the four texels nearest `uv` on one level.
fn bilinear<P: MemoryProbe>(scene: &SceneView<'_>, t: &TextureRecord, uv: [f32; 2], probe: &mut P) -> Vec3 {
    // Rows from the top: the row coordinate is 1 − v, or −v where it wraps (the same
    // modulo 1, and exact).
    let row = if t.wrap == TextureRecord::CLAMP { 1.0 - uv[1] } else { -uv[1] };
    let ((x0, fx), (y0, fy)) = (axis(uv[0], t.width, t.wrap), axis(row, t.height, t.wrap));
    let mut texel = |dx: i64, dy: i64| {
        let c = scene.texel(t, wrap(x0 + dx, t.width, t.wrap), wrap(y0 + dy, t.height, t.wrap), probe);
        Vec3::new(srgb8_to_linear(c[0]), srgb8_to_linear(c[1]), srgb8_to_linear(c[2]))
    };
    let top = texel(0, 0) * (1.0 - fx) + texel(1, 0) * fx;
    let bottom = texel(0, 1) * (1.0 - fx) + texel(1, 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping() {
        assert_eq!(wrap(-1, 4, TextureRecord::REPEAT), 3);
        assert_eq!(wrap(5, 4, TextureRecord::REPEAT), 1);
        assert_eq!(wrap(-1, 4, TextureRecord::CLAMP), 0);
        assert_eq!(wrap(9, 4, TextureRecord::CLAMP), 3);
    }

    /// The f32 axis gives the blend of exact (f64) arithmetic: on a row of random
    /// texels, the interpolated value agrees within 1e-4 for coordinates in [−3, 3]
    /// (and the rows' `1 − v` and `−v` alike), and stays finite far outside.
    #[test]
    fn single_precision_texel_coordinates_blend_as_exact_ones() {
        let mut g = crate::test_lcg::Lcg(11);
        for case in 0..20_000 {
            let n = 1 + (g.next() >> 40) as u32 % 300;
            let mode = if case % 2 == 0 { TextureRecord::REPEAT } else { TextureRecord::CLAMP };
            let values: [f32; 300] = core::array::from_fn(|_| g.range(0.0, 1.0));
            let blend = |x0: i64, f: f32| {
                values[wrap(x0, n, mode) as usize] * (1.0 - f) + values[wrap(x0 + 1, n, mode) as usize] * f
            };
            let u = g.range(-3.0, 3.0);
            let exact = u as f64 * n as f64 - 0.5;
            let x0 = libm::floor(exact);
            let want = blend(x0 as i64, (exact - x0) as f32);
            let (x0, f) = axis(u, n, mode);
            assert!((blend(x0, f) - want).abs() < 1e-4, "case {case}: u {u} n {n}");
            // A row coordinate: 1 − v (clamp) or −v (repeat), against exact 1 − v.
            let exact = (1.0 - u as f64) * n as f64 - 0.5;
            let y0 = libm::floor(exact);
            let want = blend(y0 as i64, (exact - y0) as f32);
            let row = if mode == TextureRecord::CLAMP { 1.0 - u } else { -u };
            let (y0, f) = axis(row, n, mode);
            assert!((blend(y0, f) - want).abs() < 1e-4, "case {case}: v {u} n {n}");
        }
        for u in [1e30, -1e30, f32::MAX, -f32::MAX, 1e-30, -1e-45] {
            for mode in [TextureRecord::REPEAT, TextureRecord::CLAMP] {
                let (x0, f) = axis(u, 4096, mode);
                assert!((-1..=4096).contains(&x0) && (0.0..=1.0).contains(&f), "{u} {mode}: {x0} {f}");
            }
        }
    }
}
