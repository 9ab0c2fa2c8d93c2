//! glTF 2.0 (`.gltf` with its buffers, or `.glb`) through the `gltf` crate: the default
//! scene's node hierarchy with every node's world transform applied, triangle
//! primitives (positions, normals, first texture coordinates, vertex colours), PBR
//! materials mapped onto raypipe's (base colour → diffuse, emissive × strength →
//! emission, base-colour texture → diffuse texture), and the first perspective camera.

use std::path::Path;

use anyhow::{anyhow, Result};
use glam::{Mat3, Mat4, Vec3};
use raypipe_core::image::{MaterialRecord, ShadingVertex, TextureRecord, NULL_INDEX};

use crate::input::camera_file::CameraSpec;
use crate::input::mesh::Mesh;
use crate::input::obj::LoadNotes;
use crate::input::texture::TextureImage;

/// Loads a glTF file into a [`Mesh`] and the camera it holds (if any).
pub fn load_gltf_file(path: &Path) -> Result<(Mesh, LoadNotes, CameraSpec)> {
    let name = path.display().to_string();
    let (doc, buffers, images) = gltf::import(path).map_err(|e| anyhow!("{name}: malformed glTF: {e}"))?;
    let mut mesh = Mesh::default();
    let mut notes = LoadNotes::default();
    let mut textures: Vec<Option<u32>> = vec![None; images.len()];
    for m in doc.materials() {
        let record = material_of(&m, &images, &mut textures, &mut mesh, &mut notes, &name);
        mesh.materials.push(record);
        mesh.material_names.push(m.name().unwrap_or("material").to_string());
    }
    let default_material = mesh.materials.len() as u32;
    mesh.materials.push(MaterialRecord::DEFAULT);
    mesh.material_names.push("default".into());

    let mut camera = CameraSpec::default();
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| anyhow!("{name}: the glTF file has no scene"))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0usize;
    let mut visited = 0usize;
    let mut objects = 0u32;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > doc.nodes().len() * 4 + 16 {
            return Err(anyhow!("{name}: malformed glTF: the node hierarchy has a cycle"));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let (Some(cam), None) = (node.camera(), camera.eye) {
            camera_of(&cam, world, &mut camera);
        }
        if let Some(m) = node.mesh() {
            // Each node that places a mesh is an object.
            let object = objects;
            objects += 1;
            let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
            for prim in m.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    skipped_modes += 1;
                    continue;
                }
                let placed = Placement { world, normal_matrix, object, default_material, mesh_index: m.index() };
                add_primitive(&prim, &buffers, placed, &mut mesh).map_err(|e| anyhow!("{name}: {e}"))?;
            }
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if skipped_modes > 0 {
        notes.warnings.push(format!("{name}: {skipped_modes} primitives of points, lines or strips left out"));
    }
    mesh.validate(&name)?;
    notes.warnings.extend(mesh.degenerate_warning(&name));
    Ok((mesh, notes, camera))
}

/// A material's record: base colour, emission, blending, and its base-colour texture
/// (converted once per image: `textures` maps images to the mesh's textures).
fn material_of(
    m: &gltf::Material<'_>,
    images: &[gltf::image::Data],
    textures: &mut [Option<u32>],
    mesh: &mut Mesh,
    notes: &mut LoadNotes,
    name: &str,
) -> MaterialRecord {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let strength = m.emissive_strength().unwrap_or(1.0);
    let mut record = MaterialRecord {
        diffuse: [r, g, b],
        emission: m.emissive_factor().map(|e| e * strength),
        dissolve: if m.alpha_mode() == gltf::material::AlphaMode::Blend { a } else { 1.0 },
        texture: NULL_INDEX,
        ..MaterialRecord::DEFAULT
    };
    if let Some(info) = pbr.base_color_texture() {
        let image = info.texture().source().index();
        if let Some(slot) = textures.get_mut(image) {
            if slot.is_none() {
                match images.get(image).map(to_rgba) {
                    Some(Ok(t)) => {
                        mesh.textures.push(t);
                        *slot = Some(mesh.textures.len() as u32 - 1);
                    }
                    Some(Err(e)) => notes.warnings.push(format!("{name}: image {image}: {e}; its base colour is used")),
                    None => {}
                }
            }
            if let Some(t) = *slot {
                record.texture = t;
            }
        }
    }
    record
}

/// The first perspective camera's eye, aim, up and field of view, placed by `world`.
fn camera_of(cam: &gltf::Camera<'_>, world: Mat4, camera: &mut CameraSpec) {
    if let gltf::camera::Projection::Perspective(p) = cam.projection() {
        let eye = world.transform_point3(Vec3::ZERO);
        let ahead = world.transform_point3(-Vec3::Z);
        camera.eye = Some(eye.to_array());
        camera.look_at = Some(ahead.to_array());
        camera.up = Some(world.transform_vector3(Vec3::Y).normalize_or_zero().to_array());
        camera.fov = Some(p.yfov().to_degrees());
    }
}

/// Where a mesh's primitives go: the node's transform (and its normals'), the object the
/// node makes, and the material of primitives without one.
#[derive(Clone, Copy)]
struct Placement {
    world: Mat4,
    normal_matrix: Mat3,
    object: u32,
    default_material: u32,
    /// The mesh's index in the document (for messages).
    mesh_index: usize,
}

/// Appends a triangle primitive's vertices (placed in the world), shading data and
/// triangles to `mesh`.
fn add_primitive(
    prim: &gltf::Primitive<'_>,
    buffers: &[gltf::buffer::Data],
    placed: Placement,
    mesh: &mut Mesh,
) -> Result<()> {
    let Placement { world, normal_matrix, object, default_material, mesh_index } = placed;
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = reader.read_positions() else { return Ok(()) };
    let base = mesh.positions.len() as u32;
    let positions: Vec<[f32; 3]> = positions.map(|p| world.transform_point3(Vec3::from(p)).to_array()).collect();
    let n = positions.len();
    mesh.positions.extend(positions);
    let normals: Option<Vec<[f32; 3]>> = reader
        .read_normals()
        .map(|ns| ns.map(|v| (normal_matrix * Vec3::from(v)).normalize_or_zero().to_array()).collect());
    let uvs: Option<Vec<[f32; 2]>> =
        reader.read_tex_coords(0).map(|t| t.into_f32().map(|[u, v]| [u, 1.0 - v]).collect());
    let colors: Option<Vec<[f32; 3]>> = reader.read_colors(0).map(|c| c.into_rgb_f32().collect());
    for i in 0..n {
        mesh.shading.push(ShadingVertex {
            normal: normals.as_ref().and_then(|v| v.get(i).copied()).unwrap_or([0.0; 3]),
            uv: uvs.as_ref().and_then(|v| v.get(i).copied()).unwrap_or([0.0; 2]),
            color: colors.as_ref().and_then(|v| v.get(i).copied()).unwrap_or([1.0; 3]),
        });
    }
    let material = prim.material().index().map_or(default_material, |i| i as u32);
    let indices: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    if indices.iter().any(|&i| i as usize >= n) {
        return Err(anyhow!("malformed glTF: a primitive of mesh {mesh_index} indexes a missing vertex"));
    }
    for t in indices.chunks_exact(3) {
        mesh.triangles.push([t[0] + base, t[1] + base, t[2] + base]);
        mesh.tri_materials.push(material);
        mesh.objects.push(object);
    }
    Ok(())
}

/// A glTF image as 8-bit RGBA texels.
fn to_rgba(d: &gltf::image::Data) -> Result<TextureImage, String> {
    use gltf::image::Format;
    let channels = match d.format {
        Format::R8 => 1,
        Format::R8G8 => 2,
        Format::R8G8B8 => 3,
        Format::R8G8B8A8 => 4,
        other => return Err(format!("unsupported pixel format {other:?}")),
    };
    let mut rgba = Vec::with_capacity(d.pixels.len() / channels * 4);
    for px in d.pixels.chunks_exact(channels) {
        rgba.extend_from_slice(&match channels {
            1 => [px[0], px[0], px[0], 255],
            2 => [px[0], px[0], px[0], px[1]],
            3 => [px[0], px[1], px[2], 255],
            _ => [px[0], px[1], px[2], px[3]],
        });
    }
    if d.width == 0 || d.height == 0 || rgba.len() != (d.width * d.height * 4) as usize {
        return Err(format!("impossible size {}x{}", d.width, d.height));
    }
    Ok(TextureImage { width: d.width, height: d.height, rgba, wrap: TextureRecord::REPEAT })
}
