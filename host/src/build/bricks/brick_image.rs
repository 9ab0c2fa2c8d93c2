//! One brick's scene image from its triangles: vertices welded again (exactly equal
//! position and shading data), the triangles in scene-wide id order with those ids in
//! TRIANGLE_IDS, the materials and textures they use, the scene's shading lights, and
//! the brick's own acceleration structure — a complete, self-contained scene image
//! (Wald & Slusallek 2001, §6.3: "each voxel contains the complete intersection and
//! shading data for all of its triangles as well as a low-level BSP").

use std::collections::HashMap;

use anyhow::{anyhow, Result};
use raypipe_core::image::{LightRecord, MaterialRecord, NULL_INDEX};
use raypipe_core::SceneView;

use super::tri_record::TriRecord;
use crate::build::image_writer::ImageWriter;
use crate::input::mesh::Mesh;
use crate::input::texture::TextureImage;
use crate::platform::aligned::AlignedBytes;
use crate::scene::{add_structure, BuildOptions, BuildReport, TriangleLayout};

/// What every brick shares: the scene's tables and how to build.
pub struct BrickContext {
    /// The scene's materials (each brick keeps the table whole, so indices stay).
    pub materials: Vec<MaterialRecord>,
    /// The scene's textures (a brick keeps those its materials use).
    pub textures: Vec<TextureImage>,
    /// The scene's point, directional, sky and ambient lights (area lights are the
    /// whole scene's and stay out of bricks).
    pub lights: Vec<LightRecord>,
    /// The scene has per-vertex shading data.
    pub shading: bool,
    /// The scene has materials.
    pub has_materials: bool,
    /// The scene has more than one object.
    pub has_objects: bool,
    /// The whole scene's bounds: every brick's margins are sized from them.
    pub scene_bounds: ([f32; 3], [f32; 3]),
    /// Structure and triangle layout of every brick.
    pub build: BuildOptions,
}

/// A built brick.
pub struct BuiltBrick {
    /// Its scene image.
    pub image: AlignedBytes,
    /// Its triangles.
    pub triangles: u32,
    /// Its welded vertices.
    pub vertices: u32,
    /// The box of its vertices.
    pub bounds: ([f32; 3], [f32; 3]),
    /// The header's bounds (the vertices' box grown by the scene's margin).
    pub header_bounds: ([f32; 3], [f32; 3]),
}

/// Builds the brick of `tris` (any order; sorted here by id).
pub fn build_brick(ctx: &BrickContext, tris: &mut [TriRecord]) -> Result<BuiltBrick> {
    tris.sort_unstable_by_key(|t| t.id);
    let (mesh, ids) = brick_mesh(ctx, tris);
    let mut writer = ImageWriter::new(&mesh);
    if ctx.build.triangles == TriangleLayout::Wald {
        writer.wald_triangles(&mesh);
    }
    writer.triangle_ids(&ids).scene_bounds(ctx.scene_bounds.0, ctx.scene_bounds.1);
    let mut report = BuildReport::default();
    add_structure("brick", &mesh, &ctx.build, &mut report, &mut writer)?;
    let image = writer.finish()?;
    let view = SceneView::parse(&image).map_err(|e| anyhow!("internal error: built an invalid brick: {e}"))?;
    let h = view.header();
    Ok(BuiltBrick {
        triangles: mesh.triangles.len() as u32,
        vertices: mesh.positions.len() as u32,
        bounds: mesh.bounds(),
        header_bounds: (h.bounds_min, h.bounds_max),
        image,
    })
}

/// The brick's mesh (vertices welded, textures renumbered) and its triangles' ids.
fn brick_mesh(ctx: &BrickContext, tris: &[TriRecord]) -> (Mesh, Vec<u32>) {
    let mut mesh = Mesh { margin_bounds: Some(ctx.scene_bounds), ..Default::default() };
    // A vertex is its position's and shading data's bits: equal bits weld, so every
    // kernel reads exactly the flat image's values.
    let mut index: HashMap<[u32; 11], u32> = HashMap::with_capacity(tris.len());
    for t in tris {
        let mut tri = [0u32; 3];
        for (k, p) in t.p.iter().enumerate() {
            let mut key = [0u32; 11];
            for a in 0..3 {
                key[a] = p[a].to_bits();
            }
            if ctx.shading {
                key[3..].copy_from_slice(bytemuck::cast_slice(std::slice::from_ref(&t.shading[k])));
            }
            let next = mesh.positions.len() as u32;
            let v = *index.entry(key).or_insert(next);
            if v == next {
                mesh.positions.push(*p);
                if ctx.shading {
                    mesh.shading.push(t.shading[k]);
                }
            }
            tri[k] = v;
        }
        mesh.triangles.push(tri);
        if ctx.has_materials {
            mesh.tri_materials.push(t.material);
        }
        if ctx.has_objects {
            mesh.objects.push(t.object);
        }
    }
    if ctx.has_materials {
        let (materials, textures) = used_textures(ctx, &mesh.tri_materials);
        mesh.materials = materials;
        mesh.textures = textures;
    }
    mesh.lights = ctx.lights.clone();
    (mesh, tris.iter().map(|t| t.id).collect())
}

/// The scene's material table with texture indices renumbered to the textures this
/// brick's triangles use (the others' textures dropped: no triangle here shades with
/// them), and those textures.
fn used_textures(ctx: &BrickContext, tri_materials: &[u32]) -> (Vec<MaterialRecord>, Vec<TextureImage>) {
    let mut used = vec![false; ctx.materials.len()];
    for &m in tri_materials {
        if let Some(u) = used.get_mut(m as usize) {
            *u = true;
        }
    }
    let mut renumber: HashMap<u32, u32> = HashMap::new();
    let mut textures = Vec::new();
    let materials = ctx
        .materials
        .iter()
        .zip(&used)
        .map(|(m, &u)| {
            let texture = if u && (m.texture as usize) < ctx.textures.len() {
                *renumber.entry(m.texture).or_insert_with(|| {
                    textures.push(ctx.textures[m.texture as usize].clone());
                    textures.len() as u32 - 1
                })
            } else {
                NULL_INDEX
            };
            MaterialRecord { texture, ..*m }
        })
        .collect();
    (materials, textures)
}
