//! Random triangle soups and rays for the equivalence suites: soups on a coarse lattice
//! (shared vertices and edges, common planes, flat scenes, duplicated triangles) and rays
//! of the kinds that break structures (free, axis-aligned, aimed at features, starting on
//! a grid cell's boundary).

use proptest::prelude::*;
use raypipe_core::{Ray, SceneView, Vec3};

/// Coordinates: mostly from a coarse lattice (so triangles share vertices and edges, lie
/// in common planes and on cell boundaries), sometimes arbitrary.
pub fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5),
        1 => -2.0f32..2.0,
    ]
}

/// A point of three [`coord`]s.
pub fn point() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

/// A random soup: vertices, triangles by vertex index, and the axis on which every
/// vertex was flattened, if one was.
#[derive(Clone, Debug)]
pub struct Soup {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub flat_axis: Option<usize>,
}

/// A soup of 3–23 vertices and 1–39 triangles, sometimes flat, sometimes with triangles
/// repeated (same and reversed winding).
pub fn soup() -> impl Strategy<Value = Soup> {
    (
        prop::collection::vec(point(), 3..24),
        prop::collection::vec(
            (any::<prop::sample::Index>(), any::<prop::sample::Index>(), any::<prop::sample::Index>()),
            1..40,
        ),
        prop::option::weighted(0.15, 0usize..3),
        0u8..4,
    )
        .prop_map(|(mut positions, picks, flat_axis, dup)| {
            if let Some(a) = flat_axis {
                // A flat scene: bounds zero-thick on one axis.
                for p in &mut positions {
                    p[a] = 0.25;
                }
            }
            let n = positions.len();
            let mut triangles: Vec<[u32; 3]> =
                picks.iter().map(|(a, b, c)| [a.index(n) as u32, b.index(n) as u32, c.index(n) as u32]).collect();
            // Duplicated triangles (same and reversed winding).
            for i in 0..dup as usize {
                let t = triangles[i % triangles.len()];
                triangles.push(if i % 2 == 0 { t } else { [t[2], t[1], t[0]] });
            }
            Soup { positions, triangles, flat_axis }
        })
}

/// How a ray is made (see [`make_ray`]).
#[derive(Clone, Debug)]
pub enum RayKind {
    /// Random origin and direction. Origins reach ten scene extents away: exactness holds
    /// while the rounding of the ray itself (an ulp of its origin) stays below the grid's
    /// margin, about a hundred scene extents (see docs/scene-format.md).
    Free([f32; 3], [f32; 3]),
    /// Axis-aligned direction.
    Axis([f32; 3], usize, bool),
    /// Aimed at a vertex, an edge midpoint or a triangle's centroid (shared edges/vertices).
    AtFeature([f32; 3], prop::sample::Index, u8),
    /// Origin exactly on a grid cell boundary.
    OnCellBoundary([u8; 3], [f32; 3]),
}

/// Any [`RayKind`].
pub fn ray_kind() -> impl Strategy<Value = RayKind> {
    let far = || [-40.0f32..40.0, -40.0f32..40.0, -40.0f32..40.0];
    let dir = || [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0];
    prop_oneof![
        far().prop_flat_map(move |o| dir().prop_map(move |d| RayKind::Free(o, d))),
        (point(), 0usize..3, any::<bool>()).prop_map(|(o, a, s)| RayKind::Axis(o, a, s)),
        (far(), any::<prop::sample::Index>(), 0u8..3).prop_map(|(o, i, f)| RayKind::AtFeature(o, i, f)),
        ([any::<u8>(), any::<u8>(), any::<u8>()], dir()).prop_map(|(c, d)| RayKind::OnCellBoundary(c, d)),
    ]
}

/// The ray of `kind` for `soup`, whose scene image is `view` (a grid for
/// [`RayKind::OnCellBoundary`]), with the interval `t_range`.
pub fn make_ray(kind: &RayKind, soup: &Soup, view: &SceneView<'_>, t_range: (f32, f32)) -> Ray {
    let (origin, dir) = match kind {
        RayKind::Free(o, d) => (Vec3::from(*o), Vec3::from(*d)),
        RayKind::Axis(o, a, s) => {
            let mut d = Vec3::ZERO;
            d[*a] = if *s { 1.0 } else { -1.0 };
            let mut o = Vec3::from(*o);
            o[*a] = if *s { -5.0 } else { 5.0 };
            (o, d)
        }
        RayKind::AtFeature(o, i, f) => {
            let t = soup.triangles[i.index(soup.triangles.len())];
            let v = t.map(|k| Vec3::from(soup.positions[k as usize]));
            let target = match f {
                0 => v[0],
                1 => (v[0] + v[1]) * 0.5,
                _ => (v[0] + v[1] + v[2]) / 3.0,
            };
            (Vec3::from(*o), target - Vec3::from(*o))
        }
        RayKind::OnCellBoundary(c, d) => {
            let g = view.grid().expect("grid");
            let cell = Vec3::new(
                (c[0] as u32 % (g.dims[0] + 1)) as f32,
                (c[1] as u32 % (g.dims[1] + 1)) as f32,
                (c[2] as u32 % (g.dims[2] + 1)) as f32,
            );
            (g.min + cell * g.cell_size, Vec3::from(*d))
        }
    };
    Ray { origin, dir, t_min: t_range.0, t_max: t_range.1 }
}
