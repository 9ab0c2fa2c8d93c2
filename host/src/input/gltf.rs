//! glTF 2.0 (`.gltf` with its buffers, or `.glb`) through the `gltf` crate: the default
//! scene's node hierarchy with every node's world transform applied, triangle
//! primitives (positions, normals, first texture coordinates, vertex colours), PBR
//! materials mapped onto raypipe's (base colour → diffuse, emissive × strength →
//! emission, base-colour texture → diffuse texture), and the first perspective camera.

use std::path::Path;

use anyhow::{anyhow, Result};
use glam::{Mat3, Mat4, Vec3};
use raypipe_core::image::{MaterialRecord, ShadingVertex, NULL_INDEX};

use crate::build::instanced::InstancedScene;
use crate::input::camera_file::CameraSpec;
use crate::input::mesh::Mesh;
use crate::input::obj::LoadNotes;
use crate::input::texture::TextureImage;
use crate::input::{gltf_checks, limits, read_file};

/// Loads a glTF file into a [`Mesh`] and the camera it holds (if any).
pub fn load_gltf_file(path: &Path) -> Result<(Mesh, LoadNotes, CameraSpec)> {
    let name = path.display().to_string();
    let bytes = read_file::read_bytes(path, read_file::DATA_LIMIT)?;
    let base = path.parent().unwrap_or(Path::new("."));
    crate::input::panic_guard::guarded(&name, "glTF", || load_gltf_bytes(&name, &bytes, base))
}

/// Loads a glTF file as an instanced scene: each mesh that a node places is one bottom
/// mesh in its own object space, and each node placing it one instance.
pub fn load_gltf_instanced(path: &Path) -> Result<InstancedScene> {
    let name = path.display().to_string();
    let bytes = read_file::read_bytes(path, read_file::DATA_LIMIT)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut scene = InstancedScene { name: name.clone(), ..Default::default() };
    let (_, notes, camera) = crate::input::panic_guard::guarded(&name, "glTF", || {
        load_gltf_document(&name, &bytes, base, Some(&mut scene))
    })?;
    scene.warnings = notes.warnings;
    scene.camera = camera;
    scene.check()?;
    Ok(scene)
}

/// Loads the glTF (or GLB) `bytes` of the file `name`, its other files in `base`.
pub fn load_gltf_bytes(name: &str, bytes: &[u8], base: &Path) -> Result<(Mesh, LoadNotes, CameraSpec)> {
    load_gltf_document(name, bytes, base, None)
}

/// Loads the document: as one mesh, or with `instanced`, as bottoms and instances (the
/// returned mesh then holds only the materials and textures).
fn load_gltf_document(
    name: &str,
    bytes: &[u8],
    base: &Path,
    mut instanced: Option<&mut InstancedScene>,
) -> Result<(Mesh, LoadNotes, CameraSpec)> {
    let malformed = |e: String| anyhow!("{name}: malformed glTF: {e}");
    gltf_checks::check_glb_header(bytes).map_err(malformed)?;
    gltf_checks::check_position_accessors(bytes).map_err(malformed)?;
    let gltf::Gltf { document: doc, blob } = gltf::Gltf::from_slice(bytes).map_err(|e| malformed(e.to_string()))?;
    let buffers = gltf_checks::read_buffers(&doc, base, blob, name)?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| anyhow!("{name}: the glTF file has no scene"))?;
    for m in doc.meshes() {
        for prim in m.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles) {
            gltf_checks::check_primitive(&prim, &buffers)
                .map_err(|e| anyhow!("{name}: malformed glTF: mesh {}: {e}", m.index()))?;
        }
    }
    // Counted before anything is read: each mesh once per node that places it.
    let (triangles, vertices) = gltf_checks::check_nodes(&doc, &scene).map_err(malformed)?;
    limits::check_triangles(name, triangles)?;
    limits::check_vertices(name, vertices)?;
    let mut mesh = Mesh::default();
    let mut notes = LoadNotes::default();
    let mut textures: Vec<Option<u32>> = vec![None; doc.images().len()];
    let images = Images { doc: &doc, buffers: &buffers, base };
    for m in doc.materials() {
        let record = material_of(&m, &images, &mut textures, &mut mesh, &mut notes, name);
        mesh.materials.push(record);
        mesh.material_names.push(m.name().unwrap_or("material").to_string());
    }
    let default_material = mesh.materials.len() as u32;
    mesh.materials.push(MaterialRecord::DEFAULT);
    mesh.material_names.push("default".into());

    let mut camera = CameraSpec::default();
    // A set of trees (checked above): every node is reached once.
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0usize;
    let mut objects = 0u32;
    let mut bottom_of: std::collections::HashMap<usize, u32> = Default::default();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let (Some(cam), None) = (node.camera(), camera.eye) {
            camera_of(&cam, world, &mut camera);
        }
        if let Some(m) = node.mesh() {
            // Each node that places a mesh is an object.
            let object = objects;
            objects += 1;
            if let Some(scene) = instanced.as_deref_mut() {
                let bottom = match bottom_of.get(&m.index()) {
                    Some(&b) => b,
                    None => {
                        let mut shape = Mesh { materials: mesh.materials.clone(), ..Default::default() };
                        shape.textures = mesh.textures.clone();
                        shape.material_names = mesh.material_names.clone();
                        let placed = Placement {
                            world: Mat4::IDENTITY,
                            normal_matrix: Mat3::IDENTITY,
                            object: 0,
                            default_material,
                            mesh_index: m.index(),
                        };
                        for prim in m.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles) {
                            add_primitive(&prim, &buffers, placed, &mut shape).map_err(|e| anyhow!("{name}: {e}"))?;
                        }
                        crate::build::instanced::keep_used_textures(&mut shape);
                        shape.objects.clear();
                        scene.bottoms.push(shape);
                        scene.bottom_names.push(format!("mesh {} ({})", m.index(), m.name().unwrap_or("unnamed")));
                        bottom_of.insert(m.index(), scene.bottoms.len() as u32 - 1);
                        scene.bottoms.len() as u32 - 1
                    }
                };
                let to_world = crate::build::instanced::affine_of(world);
                scene.instances.push(crate::build::instanced::Instance { bottom, to_world, material: None });
                skipped_modes += m.primitives().filter(|p| p.mode() != gltf::mesh::Mode::Triangles).count();
                stack.extend(node.children().map(|c| (c, world)));
                continue;
            }
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
    if instanced.is_some() {
        camera.check(name)?;
        return Ok((mesh, notes, camera));
    }
    mesh.validate(name)?;
    camera.check(name)?;
    notes.warnings.extend(mesh.degenerate_warning(name));
    Ok((mesh, notes, camera))
}

/// A material's record: base colour, emission, blending, and its base-colour texture
/// (converted once per image: `textures` maps images to the mesh's textures).
fn material_of(
    m: &gltf::Material<'_>,
    images: &Images<'_>,
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
                match images.read(image) {
                    Ok(t) => {
                        mesh.textures.push(t);
                        *slot = Some(mesh.textures.len() as u32 - 1);
                    }
                    Err(e) => notes.warnings.push(format!("{name}: image {image}: {e}; its base colour is used")),
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

/// Where a document's images are read from: its buffers, or files beside it.
struct Images<'a> {
    doc: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    base: &'a Path,
}

impl Images<'_> {
    /// Image `index` decoded as 8-bit RGBA texels (PNG or JPEG).
    fn read(&self, index: usize) -> Result<TextureImage, String> {
        let image = self.doc.images().nth(index).ok_or("no such image")?;
        match image.source() {
            gltf::image::Source::View { view, mime_type } => {
                let data = self.buffers.get(view.buffer().index()).ok_or("its buffer view has no buffer")?;
                let bytes = data
                    .0
                    .get(view.offset()..view.offset().saturating_add(view.length()))
                    .ok_or("its buffer view lies outside its buffer")?;
                crate::input::texture::decode(bytes, mime_type)
            }
            gltf::image::Source::Uri { uri, mime_type } => {
                let bytes = gltf_checks::read_uri(uri, self.base).map_err(|e| e.to_string())?;
                let ext = Path::new(uri).extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
                crate::input::texture::decode(&bytes, mime_type.unwrap_or(&ext))
            }
        }
    }
}
