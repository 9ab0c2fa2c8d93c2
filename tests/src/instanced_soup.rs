//! Random two-level scenes for the property suites: triangle soups on a coarse lattice
//! (so that edges, shared vertices and coplanar triangles are common) placed by random
//! affine instances (uniform or not, rotated, moved).

use glam::{EulerRot, Mat4, Quat, Vec3};
use proptest::prelude::*;
use raypipe::build::instanced::{affine_of, Instance, InstancedScene};
use raypipe::input::mesh::Mesh;

/// Positions and triangles of one soup.
pub type Soup = (Vec<[f32; 3]>, Vec<[u32; 3]>);

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![3 => (-4i32..=4).prop_map(|i| i as f32 * 0.5), 1 => -2.0f32..2.0]
}

/// 3 to 19 vertices and 1 to 19 triangles over them.
pub fn soup() -> impl Strategy<Value = Soup> {
    (
        prop::collection::vec([coord(), coord(), coord()], 3..20),
        prop::collection::vec(any::<[prop::sample::Index; 3]>(), 1..20),
    )
        .prop_map(|(positions, picks)| {
            let n = positions.len();
            (positions, picks.iter().map(|t| t.map(|i| i.index(n) as u32)).collect())
        })
}

/// Scale (uniform or not), rotation about three axes, translation.
pub fn transform() -> impl Strategy<Value = Mat4> {
    (
        [0.4f32..2.5, 0.4f32..2.5, 0.4f32..2.5],
        any::<bool>(),
        [-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2],
        [-6.0f32..6.0, -6.0f32..6.0, -6.0f32..6.0],
    )
        .prop_map(|(s, uniform, r, t)| {
            let s = if uniform { Vec3::splat(s[0]) } else { Vec3::from(s) };
            Mat4::from_scale_rotation_translation(s, Quat::from_euler(EulerRot::ZYX, r[0], r[1], r[2]), Vec3::from(t))
        })
}

/// The soups as meshes, placed by `placed` (each names a soup by index).
pub fn scene_of(bottoms: &[Soup], placed: &[(prop::sample::Index, Mat4)]) -> InstancedScene {
    InstancedScene {
        name: "soup".into(),
        bottoms: bottoms
            .iter()
            .map(|(p, t)| Mesh { positions: p.clone(), triangles: t.clone(), ..Default::default() })
            .collect(),
        bottom_names: (0..bottoms.len()).map(|b| format!("soup {b}")).collect(),
        instances: placed
            .iter()
            .map(|(b, m)| Instance { bottom: b.index(bottoms.len()) as u32, to_world: affine_of(*m), material: None })
            .collect(),
        ..Default::default()
    }
}
