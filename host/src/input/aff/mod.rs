//! BART's animated scenes (Lext, Assarsson & Möller 2001): AFF, which is Haines' NFF
//! plus includes, keyframed transforms and animated triangles, read into an instanced
//! scene that [`crate::build::dynamic`] animates.
//!
//! Every animated transform (`x name { … }`) becomes a *mover*: its geometry, with the
//! static transforms (`xs`) inside it folded in, is one bottom mesh in its own space,
//! placed by one instance whose map at time `t` is the product of its ancestors' static
//! maps and keyframed maps ([`AffScene::instance_transform`]). Geometry outside every
//! animated transform is one static bottom. The museum's animated triangles (`tpa`) are
//! a deforming bottom whose vertices are interpolated linearly between their keys
//! ([`AffScene::deformed`]). Identical bottoms (a robot's parts, included by each robot)
//! are stored once.
//!
//! NFF's materials carry an ambient colour; the global ambient light (`am`) times it is
//! each material's constant term, which raypipe stores as emission, scaled by
//! [`AMBIENT_SCALE`] (BART's `am 2.5` times the kitchen's ambient colours passes 1, which
//! would whiten every surface).

mod keyframes;
pub mod parser;
mod primitives;
pub mod shapes;
pub mod spline;
pub mod tokens;
pub mod track;

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Result};
use glam::{DMat4, DVec3, Vec3};
use raypipe_core::image::{CameraRecord, MaterialRecord};
use raypipe_core::math::affine::Affine34;

use crate::build::instanced::{affine_of, keep_used_textures, Instance, InstancedScene};
use crate::input::mesh::Mesh;
use parser::{AnimatedTriangle, Gathered, Mover, Parsed, View};
use track::Track;

/// How much of `am × Ka` a surface emits (see the module's documentation).
pub const AMBIENT_SCALE: f32 = 0.1;

/// A BART scene ready to animate.
pub struct AffScene {
    /// The meshes and instances, at the animation's start.
    pub scene: InstancedScene,
    /// Which meshes deform (the animated triangles').
    pub deforming: Vec<bool>,
    /// `(start, end, frames)`.
    pub animation: (f64, f64, u32),
    instance_mover: Vec<usize>,
    movers: Vec<Mover>,
    tracks: HashMap<String, Track>,
    animated: Vec<(u32, Vec<AnimatedTriangle>)>,
    view: View,
    background: [f32; 3],
}

/// Reads the BART scene whose entry file is `path`.
pub fn load_aff(path: &Path) -> Result<AffScene> {
    let parsed = parser::parse(path)?;
    assemble(path, parsed)
}

/// Reads a BART scene whose entry file `path` holds `text` (its includes and textures
/// are read beside `path`).
pub fn load_aff_text(path: &Path, text: &str) -> Result<AffScene> {
    let parsed = parser::parse_text(path, text)?;
    assemble(path, parsed)
}

/// The bytes that make two bottoms the same.
fn identity_of(g: &Gathered) -> Vec<u8> {
    let mut key = Vec::new();
    key.extend_from_slice(bytemuck::cast_slice(&g.positions));
    key.extend_from_slice(bytemuck::cast_slice(&g.triangles));
    key.extend_from_slice(bytemuck::cast_slice(&g.materials));
    key.extend_from_slice(bytemuck::cast_slice(&g.shading));
    key
}

fn assemble(path: &Path, p: Parsed) -> Result<AffScene> {
    let name = path.display().to_string();
    let Some(view) = p.view else { bail!("{name}: the scene has no view ('v')") };
    let am = p.ambient.map(|a| a as f32);
    let materials: Vec<MaterialRecord> = p
        .materials
        .iter()
        .map(|(ka, m)| MaterialRecord { emission: [0, 1, 2].map(|c| ka[c] * am[c] * AMBIENT_SCALE), ..*m })
        .collect();
    let mut scene = InstancedScene {
        name: name.clone(),
        lights: p.lights.clone(),
        warnings: p.warnings.clone(),
        ..Default::default()
    };
    let mut instance_mover = Vec::new();
    let mut shared: HashMap<Vec<u8>, u32> = HashMap::new();
    let mesh_of = |g: &Gathered| {
        let mut mesh = Mesh {
            positions: g.positions.clone(),
            triangles: g.triangles.clone(),
            tri_materials: g.materials.clone(),
            materials: materials.clone(),
            material_names: (0..materials.len()).map(|i| format!("material {i}")).collect(),
            textures: p.textures.clone(),
            ..Default::default()
        };
        if g.has_shading {
            mesh.shading = g.shading.clone();
        }
        keep_used_textures(&mut mesh);
        mesh
    };
    for (m, g) in p.geometry.iter().enumerate() {
        if g.triangles.is_empty() {
            continue;
        }
        let key = identity_of(g);
        let bottom = match shared.get(&key) {
            Some(&b) => b,
            None => {
                scene.bottoms.push(mesh_of(g));
                scene.bottom_names.push(if m == 0 {
                    "static geometry".into()
                } else {
                    format!("'{}'", p.movers[m].name)
                });
                shared.insert(key, scene.bottoms.len() as u32 - 1);
                scene.bottoms.len() as u32 - 1
            }
        };
        scene.instances.push(Instance { bottom, to_world: [0.0; 12], material: None });
        instance_mover.push(m);
    }
    let mut deforming = vec![false; scene.bottoms.len()];
    let mut animated = Vec::new();
    for (m, tris) in p.animated.into_iter().enumerate() {
        if tris.is_empty() {
            continue;
        }
        let g = Gathered {
            positions: vec![[0.0; 3]; 3 * tris.len()],
            triangles: (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            materials: tris.iter().map(|t| t.material).collect(),
            ..Default::default()
        };
        scene.bottoms.push(mesh_of(&g));
        scene.bottom_names.push("animated triangles".into());
        deforming.push(true);
        let bottom = scene.bottoms.len() as u32 - 1;
        scene.instances.push(Instance { bottom, to_world: [0.0; 12], material: None });
        instance_mover.push(m);
        animated.push((bottom, tris));
    }
    let animation = p.animation.unwrap_or((0.0, 0.0, 1));
    let mut aff = AffScene {
        scene,
        deforming,
        animation,
        instance_mover,
        movers: p.movers,
        tracks: p.tracks,
        animated,
        view,
        background: p.background.map(|c| c as f32),
    };
    if aff.tracks.values().any(|t| !t.visibility.is_empty()) {
        aff.scene.warnings.push(format!("{name}: visibility keys are read but every object stays visible"));
    }
    let t0 = aff.time(0);
    for i in 0..aff.scene.instances.len() {
        aff.scene.instances[i].to_world = aff.instance_transform(i, t0);
    }
    for (bottom, verts) in aff.deformed(t0) {
        aff.scene.bottoms[bottom as usize].positions = verts;
    }
    let camera = aff.camera(t0);
    aff.scene.camera = crate::input::camera_file::CameraSpec {
        eye: Some(camera.eye),
        look_at: Some(camera.look_at),
        up: Some(camera.up),
        fov: Some(camera.vfov_deg),
        size: Some((camera.width, camera.height)),
        background: Some(camera.background),
    };
    aff.scene.check()?;
    Ok(aff)
}

impl AffScene {
    /// Frames of the animation.
    pub fn frame_count(&self) -> u32 {
        self.animation.2
    }

    /// The time of frame `k`: BART steps `(end − start) / (frames − 1)`.
    pub fn time(&self, k: u32) -> f64 {
        let (start, end, n) = self.animation;
        if n <= 1 {
            start
        } else {
            start + (end - start) * k as f64 / (n - 1) as f64
        }
    }

    /// Mover `m`'s map to the world at `t`: its ancestors', then its static map, then
    /// its keyframes'.
    fn mover_matrix(&self, m: usize, t: f64) -> DMat4 {
        let mut out = DMat4::IDENTITY;
        let mut at = Some(m);
        while let Some(i) = at {
            let mover = &self.movers[i];
            let own = self.tracks.get(&mover.name).map_or(DMat4::IDENTITY, |tr| tr.matrix(t));
            out = mover.local * own * out;
            at = mover.parent;
        }
        out
    }

    /// Instance `i`'s object-to-world map at `t`.
    pub fn instance_transform(&self, i: usize, t: f64) -> Affine34 {
        let m = self.mover_matrix(self.instance_mover[i], t);
        affine_of(m.as_mat4())
    }

    /// Whether instance `i` moves at all (its mover or an ancestor has keyframes).
    pub fn instance_moves(&self, i: usize) -> bool {
        self.instance_mover.get(i).is_some_and(|&m| m != 0)
    }

    /// Each deforming bottom's vertices at `t`: every key-framed triangle's vertices
    /// interpolated linearly between the keys around `t`, held before the first and
    /// after the last.
    pub fn deformed(&self, t: f64) -> Vec<(u32, Vec<[f32; 3]>)> {
        self.animated
            .iter()
            .map(|(bottom, tris)| {
                let mut out = Vec::with_capacity(3 * tris.len());
                for tri in tris {
                    let k = tri.times.partition_point(|&k| k <= t);
                    let v = if k == 0 {
                        tri.verts[0]
                    } else if k >= tri.times.len() {
                        tri.verts[tri.times.len() - 1]
                    } else {
                        let (t0, t1) = (tri.times[k - 1], tri.times[k]);
                        let w = (t - t0) / (t1 - t0);
                        [0, 1, 2].map(|c| tri.verts[k - 1][c].lerp(tri.verts[k][c], w))
                    };
                    out.extend(v.iter().map(|p| p.as_vec3().to_array()));
                }
                (*bottom, out)
            })
            .collect()
    }

    /// The camera at `t`: the view, moved by the keyframes named `camera` (translation:
    /// the eye; rotation: the view direction, −z, and up, +y, of the rotated frame).
    pub fn camera(&self, t: f64) -> CameraRecord {
        let v = self.view;
        let (mut from, mut dir, mut up) = (v.from, v.at - v.from, v.up);
        if let Some(track) = self.tracks.get("camera") {
            if let Some(p) = &track.transl {
                from = p.at(t);
            }
            if track.rot.is_some() {
                let m = track.matrix(t);
                dir = -m.z_axis.truncate();
                up = m.y_axis.truncate();
            }
        }
        let at = from + dir.normalize_or(DVec3::NEG_Z);
        CameraRecord {
            eye: from.as_vec3().to_array(),
            vfov_deg: v.angle as f32,
            look_at: at.as_vec3().to_array(),
            width: v.resolution.0,
            up: up.as_vec3().normalize_or(Vec3::Y).to_array(),
            height: v.resolution.1,
            background: self.background,
            _pad: 0,
        }
    }
}
