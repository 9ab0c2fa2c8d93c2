//! A scene description file (TOML): meshes from OBJ, PLY or glTF files with transforms
//! and material overrides, lights and a camera, merged into one mesh and built into one
//! scene image — a scene assembled from several files without a hand-written merger.
//!
//! ```toml
//! [camera]                    # optional; the camera file's keys
//! eye = [0, 1, 4]
//! look_at = [0, 0.5, 0]
//! fov = 45
//! size = [800, 600]
//!
//! [[mesh]]
//! file = "bunny.obj"          # relative to this file
//! translate = [0, 0, 0]
//! rotate = [0, 90, 0]         # degrees about x, then y, then z
//! scale = 2.0                 # or [sx, sy, sz]
//! material = "gold"           # every triangle of this mesh gets it
//!
//! [materials.gold]            # MTL's fields: diffuse, specular, shininess, emission,
//! diffuse = [0.8, 0.6, 0.2]   # ior, dissolve, illum
//! specular = [0.9, 0.8, 0.5]
//! shininess = 200
//! illum = 2
//!
//! [[instance]]                # a copy that shares the file's geometry: the scene is
//! file = "tree.obj"           # built as an instanced scene (one bottom-level image per
//! translate = [3, 0, 0]       # file, the [[mesh]] entries merged into one more), with
//! rotate = [0, 45, 0]         # the same keys as [[mesh]]
//!
//! [[light]]                   # point (position), sun (direction), sky (horizon, zenith)
//! kind = "sun"
//! direction = [0.3, 1, 0.2]
//! color = [2, 2, 2]
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use crate::input::limits::MAX_TRIANGLES;
use anyhow::{anyhow, bail, Result};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};
use raypipe_core::image::{LightRecord, MaterialRecord, ShadingVertex, NULL_INDEX};
use serde::Deserialize;

use crate::build::instanced::{affine_of, Instance, InstancedScene};
use crate::input::camera_file::CameraSpec;
use crate::input::mesh::Mesh;

/// Largest number of meshes a scene file may list.
const MAX_MESHES: usize = 4096;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    camera: Option<CameraTable>,
    #[serde(default)]
    mesh: Vec<MeshEntry>,
    #[serde(default)]
    instance: Vec<MeshEntry>,
    #[serde(default)]
    materials: BTreeMap<String, MaterialTable>,
    #[serde(default)]
    light: Vec<LightTable>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    eye: Option<[f32; 3]>,
    look_at: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    size: Option<[u32; 2]>,
    background: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshEntry {
    file: String,
    #[serde(default)]
    translate: Option<[f32; 3]>,
    #[serde(default)]
    rotate: Option<[f32; 3]>,
    #[serde(default)]
    scale: Option<Scale>,
    #[serde(default)]
    material: Option<String>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct MaterialTable {
    diffuse: Option<[f32; 3]>,
    specular: Option<[f32; 3]>,
    shininess: Option<f32>,
    emission: Option<[f32; 3]>,
    ior: Option<f32>,
    dissolve: Option<f32>,
    illum: Option<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightTable {
    kind: String,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    color: Option<[f32; 3]>,
    horizon: Option<[f32; 3]>,
    zenith: Option<[f32; 3]>,
}

/// True if `path` names a scene description file.
pub fn is_scene_file(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// A mesh file's loader for the meshes a scene file lists: the mesh and its warnings, or
/// `None` for a file that is a scene image (which a scene file cannot list).
pub type MeshLoader<'a> = &'a dyn Fn(&Path) -> Result<Option<(Mesh, Vec<String>)>>;

/// Reads a scene file: the merged mesh (with its lights, if the file lists any, followed
/// by a dim ambient term and the emitters as area lights), warnings, and the camera.
/// Each listed file is read by `load_mesh`, whatever its format.
pub fn load_scene_file(path: &Path, load_mesh: MeshLoader<'_>) -> Result<(Mesh, Vec<String>, CameraSpec)> {
    let name = path.display().to_string();
    let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_scene_file(&name, &text, dir, load_mesh)
}

/// Parses the text of the scene file `name`, whose meshes are named relative to `dir`.
pub fn parse_scene_file(
    name: &str,
    text: &str,
    dir: &Path,
    load_mesh: MeshLoader<'_>,
) -> Result<(Mesh, Vec<String>, CameraSpec)> {
    let name = name.to_string();
    let file: SceneFile = toml::from_str(text)
        .map_err(|e| anyhow!("{name}: {}", e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")))?;
    if file.mesh.is_empty() && file.instance.is_empty() {
        bail!("{name}: the scene file lists no [[mesh]] or [[instance]]");
    }
    if !file.instance.is_empty() {
        // Read as one flat mesh: every copy placed (`load_instanced_scene_file` keeps them
        // as instances).
        let inst = instanced_scene(&name, file, dir, load_mesh)?;
        let mut mesh = inst.flatten();
        if !inst.lights.is_empty() {
            mesh.lights.extend(crate::build::default_lights::emitters(&mesh));
        }
        mesh.validate(&name)?;
        return Ok((mesh, inst.warnings, inst.camera));
    }
    if file.mesh.len() + file.instance.len() > MAX_MESHES {
        bail!("{name}: {} meshes and instances is more than {MAX_MESHES}", file.mesh.len() + file.instance.len());
    }
    merged_meshes(&name, &file, dir, load_mesh)
}

/// The `[[mesh]]` entries merged into one mesh, with the file's lights and camera.
fn merged_meshes(
    name: &str,
    file: &SceneFile,
    dir: &Path,
    load_mesh: MeshLoader<'_>,
) -> Result<(Mesh, Vec<String>, CameraSpec)> {
    let name = name.to_string();
    let mut warnings = Vec::new();
    // Each file is read once, however often it is listed, and every copy is counted
    // against the scene's limit before any is made (a small scene file can name a big
    // mesh thousands of times).
    let mut loaded: std::collections::HashMap<std::path::PathBuf, Mesh> = Default::default();
    let mut total = 0u64;
    for (i, entry) in file.mesh.iter().enumerate() {
        let what = format!("{name}: mesh {} ({})", i + 1, entry.file);
        let child = dir.join(&entry.file);
        if !loaded.contains_key(&child) {
            let (mesh, w) = listed_mesh(&what, &child, load_mesh)?;
            warnings.extend(w);
            loaded.insert(child.clone(), mesh);
        }
        total += loaded[&child].triangles.len() as u64;
        if total > MAX_TRIANGLES {
            bail!(
                "{what}: brings the scene to {total} triangles, more than {MAX_TRIANGLES}, the most one scene may hold"
            );
        }
    }
    let mut merged = Mesh::default();
    for (i, entry) in file.mesh.iter().enumerate() {
        let what = format!("{name}: mesh {} ({})", i + 1, entry.file);
        let transform = transform_of(entry).map_err(|e| anyhow!("{what}: {e}"))?;
        let material = match &entry.material {
            Some(m) => {
                let table =
                    file.materials.get(m).ok_or_else(|| anyhow!("{what}: material '{m}' is not in [materials]"))?;
                Some((m.clone(), material_of(table)))
            }
            None => None,
        };
        append(&mut merged, loaded[&dir.join(&entry.file)].clone(), transform, material);
    }
    let lights = lights_of(&name, file)?;
    if !lights.is_empty() {
        merged.lights = lights;
        merged.lights.push(ambient());
        merged.lights.extend(crate::build::default_lights::emitters(&merged));
    }
    let camera = camera_of(file);
    merged.validate(&name)?;
    camera.check(&name)?;
    Ok((merged, warnings, camera))
}

/// Reads the mesh file `child` that entry `what` lists: a mesh, not another scene file
/// or a scene image.
fn listed_mesh(what: &str, child: &Path, load_mesh: MeshLoader<'_>) -> Result<(Mesh, Vec<String>)> {
    if is_scene_file(child) {
        bail!("{what}: a scene file cannot include another");
    }
    match load_mesh(child)? {
        Some(loaded) => Ok(loaded),
        None => bail!("{what}: is a scene image; a scene file lists meshes (OBJ, PLY, glTF)"),
    }
}

/// The dim ambient term added to a scene file's own lights.
fn ambient() -> LightRecord {
    LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 }
}

fn lights_of(name: &str, file: &SceneFile) -> Result<Vec<LightRecord>> {
    file.light
        .iter()
        .enumerate()
        .map(|(i, l)| light_of(l).map_err(|e| anyhow!("{name}: light {}: {e}", i + 1)))
        .collect()
}

fn camera_of(file: &SceneFile) -> CameraSpec {
    file.camera.as_ref().map_or_else(CameraSpec::default, |c| CameraSpec {
        eye: c.eye,
        look_at: c.look_at,
        up: c.up,
        fov: c.fov,
        size: c.size.map(|[w, h]| (w, h)),
        background: c.background,
    })
}

/// True if the scene file at `path` lists an `[[instance]]` (a file that cannot be read
/// or parsed is not: reading it as a flat scene reports why).
pub fn has_instances(path: &Path) -> bool {
    let Ok(text) = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT) else { return false };
    toml::from_str::<SceneFile>(&text).is_ok_and(|f| !f.instance.is_empty())
}

/// Reads a scene file as an instanced scene: one bottom mesh per file its
/// `[[instance]]` entries name (each read once), placed by them; the `[[mesh]]`
/// entries merged into one more bottom placed once as it is.
pub fn load_instanced_scene_file(path: &Path, load_mesh: MeshLoader<'_>) -> Result<InstancedScene> {
    let name = path.display().to_string();
    let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let file: SceneFile = toml::from_str(&text)
        .map_err(|e| anyhow!("{name}: {}", e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")))?;
    if file.instance.is_empty() {
        bail!("{name}: the scene file lists no [[instance]]");
    }
    instanced_scene(&name, file, dir, load_mesh)
}

fn instanced_scene(name: &str, mut file: SceneFile, dir: &Path, load_mesh: MeshLoader<'_>) -> Result<InstancedScene> {
    if file.mesh.len() + file.instance.len() > MAX_MESHES {
        bail!("{name}: {} meshes and instances is more than {MAX_MESHES}", file.mesh.len() + file.instance.len());
    }
    let mut scene = InstancedScene { name: name.to_string(), ..Default::default() };
    let lights = lights_of(name, &file)?;
    if !lights.is_empty() {
        scene.lights = lights;
        scene.lights.push(ambient());
    }
    scene.camera = camera_of(&file);
    scene.camera.check(name)?;
    let mut bottom_of: std::collections::HashMap<std::path::PathBuf, u32> = Default::default();
    let mut drawn = 0u64;
    for (i, entry) in file.instance.iter().enumerate() {
        let what = format!("{name}: instance {} ({})", i + 1, entry.file);
        let child = dir.join(&entry.file);
        let bottom = match bottom_of.get(&child) {
            Some(&b) => b,
            None => {
                let (mesh, w) = listed_mesh(&what, &child, load_mesh)?;
                scene.warnings.extend(w);
                scene.bottoms.push(mesh);
                scene.bottom_names.push(entry.file.clone());
                bottom_of.insert(child.clone(), scene.bottoms.len() as u32 - 1);
                scene.bottoms.len() as u32 - 1
            }
        };
        drawn += scene.bottoms[bottom as usize].triangles.len() as u64;
        if drawn > crate::input::limits::MAX_DRAWN_TRIANGLES {
            bail!(
                "{what}: brings the scene to {drawn} drawn triangles, more than {}",
                crate::input::limits::MAX_DRAWN_TRIANGLES
            );
        }
        let transform = transform_of(entry).map_err(|e| anyhow!("{what}: {e}"))?;
        let material = match &entry.material {
            Some(m) => {
                let table =
                    file.materials.get(m).ok_or_else(|| anyhow!("{what}: material '{m}' is not in [materials]"))?;
                scene.materials.push(material_of(table));
                scene.material_names.push(m.clone());
                Some(scene.materials.len() as u32 - 1)
            }
            None => None,
        };
        scene.instances.push(Instance { bottom, to_world: affine_of(transform), material });
    }
    if !file.mesh.is_empty() {
        // The [[mesh]] entries, merged as a flat scene file would, are one more bottom.
        file.light.clear();
        let (mesh, warnings, _) = merged_meshes(name, &file, dir, load_mesh)?;
        scene.warnings.extend(warnings);
        scene.bottoms.push(mesh);
        scene.bottom_names.push("the [[mesh]] entries".into());
        let bottom = scene.bottoms.len() as u32 - 1;
        scene.instances.push(Instance { bottom, to_world: raypipe_core::math::affine::IDENTITY, material: None });
    }
    scene.check()?;
    Ok(scene)
}

/// The entry's transform: scale, then rotation (x, y, z in degrees), then translation.
fn transform_of(e: &MeshEntry) -> Result<Mat4, String> {
    let scale = match e.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(s),
        Some(Scale::Axes(a)) => Vec3::from(a),
    };
    let rotate = Vec3::from(e.rotate.unwrap_or([0.0; 3]));
    let translate = Vec3::from(e.translate.unwrap_or([0.0; 3]));
    if !(scale.is_finite() && rotate.is_finite() && translate.is_finite()) {
        return Err("a transform value is NaN or infinite".into());
    }
    if scale.abs().min_element() == 0.0 {
        return Err("a scale of zero flattens the mesh".into());
    }
    let r = Quat::from_euler(EulerRot::ZYX, rotate.z.to_radians(), rotate.y.to_radians(), rotate.x.to_radians());
    Ok(Mat4::from_scale_rotation_translation(scale, r, translate))
}

fn material_of(t: &MaterialTable) -> MaterialRecord {
    let d = MaterialRecord::DEFAULT;
    MaterialRecord {
        diffuse: t.diffuse.unwrap_or(d.diffuse),
        specular: t.specular.unwrap_or(d.specular),
        shininess: t.shininess.unwrap_or(d.shininess),
        emission: t.emission.unwrap_or(d.emission),
        ior: t.ior.unwrap_or(d.ior),
        dissolve: t.dissolve.unwrap_or(d.dissolve),
        illum: t.illum.unwrap_or(d.illum),
        texture: NULL_INDEX,
        ..d
    }
}

fn light_of(l: &LightTable) -> Result<LightRecord, String> {
    let color = l.color.unwrap_or([1.0; 3]);
    let (kind, position, color) = match l.kind.as_str() {
        "point" => (LightRecord::POINT, l.position.ok_or("a point light needs a position")?, color),
        "sun" | "directional" => {
            let d = l.direction.ok_or("a sun needs a direction")?;
            if Vec3::from(d).length_squared() == 0.0 {
                return Err("the direction is zero".into());
            }
            (LightRecord::DIRECTIONAL, d, color)
        }
        "sky" | "environment" => {
            let zenith = l.zenith.or(l.color).ok_or("a sky needs a zenith (or color)")?;
            (LightRecord::ENVIRONMENT, l.horizon.unwrap_or(zenith), zenith)
        }
        other => return Err(format!("unknown kind '{other}' (point, sun, sky)")),
    };
    if !position.iter().chain(&color).all(|v| v.is_finite()) || color.iter().any(|c| *c < 0.0) {
        return Err("values must be finite and colours not negative".into());
    }
    Ok(LightRecord { position, kind, color, triangle: 0 })
}

/// Appends `mesh`, transformed, to `merged` (a material override replaces all of its
/// materials); indices, materials and textures are renumbered.
fn append(merged: &mut Mesh, mut mesh: Mesh, m: Mat4, material: Option<(String, MaterialRecord)>) {
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    let base = merged.positions.len() as u32;
    // Shading data: all or nothing across the merged mesh.
    if !mesh.shading.is_empty() && merged.shading.is_empty() {
        merged.shading =
            vec![ShadingVertex { normal: [0.0; 3], uv: [0.0; 2], color: [1.0; 3] }; merged.positions.len()];
    }
    if mesh.shading.is_empty() && !merged.shading.is_empty() {
        mesh.shading = vec![ShadingVertex { normal: [0.0; 3], uv: [0.0; 2], color: [1.0; 3] }; mesh.positions.len()];
    }
    merged.positions.extend(mesh.positions.iter().map(|&p| m.transform_point3(Vec3::from(p)).to_array()));
    merged.shading.extend(mesh.shading.iter().map(|s| ShadingVertex {
        normal: (normal_matrix * Vec3::from(s.normal)).normalize_or_zero().to_array(),
        ..*s
    }));
    // Each listed mesh's objects follow the ones before it.
    let object_base = merged.objects.iter().max().map_or(0, |&o| o + 1);
    let objects =
        if mesh.objects.len() == mesh.triangles.len() { mesh.objects.clone() } else { vec![0; mesh.triangles.len()] };
    merged.objects.extend(objects.iter().map(|&o| o + object_base));
    merged.triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
    let material_base = merged.materials.len() as u32;
    match material {
        Some((name, record)) => {
            merged.materials.push(record);
            merged.material_names.push(name);
            merged.tri_materials.extend(std::iter::repeat_n(material_base, mesh.triangles.len()));
        }
        None => {
            let texture_base = merged.textures.len() as u32;
            merged.textures.append(&mut mesh.textures);
            if mesh.materials.is_empty() {
                mesh.materials.push(MaterialRecord::DEFAULT);
                mesh.material_names.push("default".into());
            }
            for mut r in mesh.materials {
                if r.texture != NULL_INDEX {
                    r.texture += texture_base;
                }
                merged.materials.push(r);
            }
            merged.material_names.extend(mesh.material_names);
            let ids = if mesh.tri_materials.len() == mesh.triangles.len() {
                mesh.tri_materials
            } else {
                vec![0; mesh.triangles.len()]
            };
            merged.tri_materials.extend(ids.iter().map(|&id| id + material_base));
        }
    }
}
