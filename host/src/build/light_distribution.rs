//! The area lights' power distribution for the path tracer: Walker's alias method (Walker
//! 1977; Vose 1991's stable construction), so next-event estimation picks one emitting
//! triangle with probability proportional to its power in two memory reads, however many
//! emitters the scene has.

use glam::Vec3;
use raypipe_core::image::{LightAlias, LightRecord};

use crate::input::mesh::Mesh;

/// The power of an area light: luminance of its radiance `Ke` times its area (the
/// constant π of a Lambertian emitter is common to all and left out).
pub fn area_light_power(mesh: &Mesh, light: &LightRecord) -> f64 {
    let t = mesh.triangles.get(light.triangle as usize).copied().unwrap_or([0; 3]);
    let [a, b, c] = t.map(|i| Vec3::from(mesh.positions.get(i as usize).copied().unwrap_or([0.0; 3])));
    triangle_power(a, b, c, light.color)
}

/// The power of a triangle `a b c` emitting radiance `ke` (see [`area_light_power`]).
pub fn triangle_power(a: Vec3, b: Vec3, c: Vec3, ke: [f32; 3]) -> f64 {
    luminance(ke) * triangle_area(a, b, c)
}

/// The area of triangle `a b c`, in f64.
pub fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    let [a, b, c] = [a, b, c].map(|p| p.as_dvec3());
    0.5 * (b - a).cross(c - a).length()
}

/// The alias table of `mesh`'s area lights (in LIGHTS order), empty without any.
pub fn mesh_alias_table(mesh: &Mesh) -> Vec<LightAlias> {
    let power: Vec<f64> =
        mesh.lights.iter().filter(|l| l.kind == LightRecord::AREA).map(|l| area_light_power(mesh, l)).collect();
    alias_table(&power)
}

/// Rec. 709 luminance of a linear RGB colour.
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// The alias table of `weights` (non-negative; all zero or empty: uniform). Entry `i`
/// keeps `i` with probability `keep`, else gives `alias`; each carries the selection
/// probabilities of both outcomes so the shader divides by the right one.
pub fn alias_table(weights: &[f64]) -> Vec<LightAlias> {
    let n = weights.len();
    if n == 0 {
        return Vec::new();
    }
    let total: f64 = weights.iter().filter(|w| w.is_finite() && **w > 0.0).sum();
    let p: Vec<f64> = if total > 0.0 {
        weights.iter().map(|&w| if w.is_finite() && w > 0.0 { w / total } else { 0.0 }).collect()
    } else {
        vec![1.0 / n as f64; n]
    };
    // Vose: scaled probabilities split into those below and above the mean.
    let mut scaled: Vec<f64> = p.iter().map(|&x| x * n as f64).collect();
    let mut keep = vec![1.0f64; n];
    let mut alias: Vec<u32> = (0..n as u32).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        keep[s] = scaled[s];
        alias[s] = l as u32;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left holds its own column (rounding leaves values a hair from 1).
    (0..n)
        .map(|i| LightAlias {
            keep: keep[i] as f32,
            alias: alias[i],
            pdf: p[i] as f32,
            alias_pdf: p[alias[i] as usize] as f32,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probability the table gives each entry is its weight's share.
    #[test]
    fn the_table_reproduces_the_distribution() {
        for weights in [
            vec![1.0],
            vec![1.0, 1.0, 1.0],
            vec![0.1, 5.0, 0.0, 2.5, 0.4],
            (1..40).map(|i| (i * i % 17) as f64).collect::<Vec<_>>(),
            vec![0.0, 0.0],
        ] {
            let t = alias_table(&weights);
            let n = weights.len();
            let mut got = vec![0.0f64; n];
            for (i, e) in t.iter().enumerate() {
                got[i] += e.keep as f64 / n as f64;
                got[e.alias as usize] += (1.0 - e.keep as f64) / n as f64;
            }
            let total: f64 = weights.iter().sum();
            for i in 0..n {
                let want = if total > 0.0 { weights[i] / total } else { 1.0 / n as f64 };
                assert!((got[i] - want).abs() < 1e-6, "{weights:?}: {i}: {} vs {want}", got[i]);
                assert!((t[i].pdf as f64 - want).abs() < 1e-6);
                assert_eq!(t[i].alias_pdf, t[t[i].alias as usize].pdf);
            }
        }
    }
}
