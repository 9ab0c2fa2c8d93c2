//! Diffuse texture lookup: bilinear filtering of the four nearest texels in linear
//! colour (texels are stored as 8-bit sRGB), with repeat or clamp wrapping. OBJ's `v`
//! runs upwards, the texture's rows downwards.

use glam::Vec3;

use crate::image::{SceneView, TextureRecord};
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

/// The linear RGB colour of texture `index` at texture coordinates `uv`, or `None` when
/// the image has no such texture or the coordinates are not finite.
pub fn sample<P: MemoryProbe>(scene: &SceneView<'_>, index: u32, uv: [f32; 2], probe: &mut P) -> Option<Vec3> {
    let t = scene.texture(index)?;
    if !(uv[0].is_finite() && uv[1].is_finite()) {
        return None;
    }
    // Texel centres at half-integers; rows from the top.
    let x = uv[0] as f64 * t.width as f64 - 0.5;
    let y = (1.0 - uv[1] as f64) * t.height as f64 - 0.5;
    let (x0, y0) = (libm::floor(x), libm::floor(y));
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    // Far outside the texture the integer part is irrelevant once wrapped; keep it small.
    let (x0, y0) = (x0.clamp(-1e15, 1e15) as i64, y0.clamp(-1e15, 1e15) as i64);
    let mut texel = |dx: i64, dy: i64| {
        let c = scene.texel(&t, wrap(x0 + dx, t.width, t.wrap), wrap(y0 + dy, t.height, t.wrap), probe);
        Vec3::new(srgb8_to_linear(c[0]), srgb8_to_linear(c[1]), srgb8_to_linear(c[2]))
    };
    let top = texel(0, 0) * (1.0 - fx) + texel(1, 0) * fx;
    let bottom = texel(0, 1) * (1.0 - fx) + texel(1, 1) * fx;
    Some(top * (1.0 - fy) + bottom * fy)
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
}
