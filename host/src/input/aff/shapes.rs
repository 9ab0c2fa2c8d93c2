//! The NFF primitives as triangles (Haines' Standard Procedural Databases, which AFF
//! extends): polygons and polygon patches as fans (they are convex), cylinders and cones
//! as open side surfaces, spheres as latitude–longitude meshes, all with smooth normals
//! where the primitive has them.

use glam::DVec3;

/// Segments around a cone or sphere (the BART scenes' few cones are table legs and
/// lamp stems: 24 keeps their silhouettes round at 800×600).
pub const AROUND: u32 = 24;
/// Rings from pole to pole of a sphere.
pub const RINGS: u32 = 12;

/// A primitive's triangles in its own coordinates.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Per-vertex normals, if the primitive has them.
    pub normals: Option<Vec<DVec3>>,
    /// Per-vertex texture coordinates, if it has them.
    pub uvs: Option<Vec<[f64; 2]>>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// A convex polygon as a fan from its first vertex.
pub fn polygon(verts: Vec<DVec3>, normals: Option<Vec<DVec3>>) -> Shape {
    let n = verts.len() as u32;
    let triangles = (1..n.saturating_sub(1)).map(|k| [0, k, k + 1]).collect();
    Shape { positions: verts, normals, uvs: None, triangles }
}

/// The side of a cone (or cylinder) from `base` (radius `r0`) to `apex` (radius `r1`),
/// without end caps.
pub fn cone(base: DVec3, r0: f64, apex: DVec3, r1: f64) -> Shape {
    let axis = apex - base;
    let len = axis.length();
    let w = axis / len.max(f64::MIN_POSITIVE);
    let u = w.any_orthonormal_vector();
    let v = w.cross(u);
    // The side's normal leans by the slope (r0 − r1) / length toward the apex.
    let slope = (r0 - r1) / len.max(f64::MIN_POSITIVE);
    let mut s = Shape { normals: Some(Vec::new()), ..Default::default() };
    for k in 0..AROUND {
        let a = std::f64::consts::TAU * k as f64 / AROUND as f64;
        let radial = u * a.cos() + v * a.sin();
        let n = (radial + w * slope).normalize_or_zero();
        s.positions.push(base + radial * r0);
        s.positions.push(apex + radial * r1);
        if let Some(ns) = s.normals.as_mut() {
            ns.push(n);
            ns.push(n);
        }
    }
    for k in 0..AROUND {
        let (a, b) = (2 * k, 2 * ((k + 1) % AROUND));
        s.triangles.push([a, b, a + 1]);
        s.triangles.push([b, b + 1, a + 1]);
    }
    s
}

/// A sphere of `radius` about `centre`.
pub fn sphere(centre: DVec3, radius: f64) -> Shape {
    let mut s = Shape { normals: Some(Vec::new()), ..Default::default() };
    for i in 0..=RINGS {
        let theta = std::f64::consts::PI * i as f64 / RINGS as f64;
        for k in 0..=AROUND {
            let phi = std::f64::consts::TAU * k as f64 / AROUND as f64;
            let n = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            s.positions.push(centre + n * radius);
            if let Some(ns) = s.normals.as_mut() {
                ns.push(n);
            }
        }
    }
    let row = AROUND + 1;
    for i in 0..RINGS {
        for k in 0..AROUND {
            let (a, b) = (i * row + k, (i + 1) * row + k);
            // The poles' rings collapse to a point: keep only the triangles with area.
            if i != 0 {
                s.triangles.push([a, a + 1, b]);
            }
            if i != RINGS - 1 {
                s.triangles.push([a + 1, b + 1, b]);
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_have_their_vertices_where_they_should() {
        let c = cone(DVec3::ZERO, 2.0, DVec3::new(0.0, 3.0, 0.0), 1.0);
        assert_eq!(c.triangles.len(), 2 * AROUND as usize);
        for p in &c.positions {
            let r = (p.x * p.x + p.z * p.z).sqrt();
            assert!(
                (p.y.abs() < 1e-12 && (r - 2.0).abs() < 1e-9) || ((p.y - 3.0).abs() < 1e-12 && (r - 1.0).abs() < 1e-9)
            );
        }
        let s = sphere(DVec3::new(1.0, 2.0, 3.0), 0.5);
        assert!(s.positions.iter().all(|p| ((*p - DVec3::new(1.0, 2.0, 3.0)).length() - 0.5).abs() < 1e-12));
        assert_eq!(s.triangles.len(), (2 * RINGS as usize - 2) * AROUND as usize);
        let p = polygon(vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y], None);
        assert_eq!(p.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }
}
