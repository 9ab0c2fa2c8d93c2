//! Reading instanced scenes: a compiled instanced file (`.rpsx`) mapped in place and
//! validated once, or a scene that places shared meshes — a scene file with
//! `[[instance]]` entries, or a glTF file whose nodes share meshes — built in memory.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::instanced::{InstancedView, INSTANCED_MAGIC};

use crate::build::instanced::InstancedScene;
use crate::platform::image_bytes::ImageBytes;
use crate::render::instanced::Instances;
use crate::scene::{BuildOptions, BuildReport};

/// An instanced scene's bytes with its name.
pub struct InstancedFile {
    /// What the user called it.
    pub name: String,
    /// The file's bytes, 64-byte aligned.
    pub bytes: ImageBytes,
    /// Present when it was built in this run.
    pub report: Option<BuildReport>,
}

impl InstancedFile {
    /// The validated index.
    pub fn view(&self) -> Result<InstancedView<'_>> {
        InstancedView::parse(&self.bytes).map_err(|e| anyhow!("{}: {e}", self.name))
    }

    /// The validated index and every bottom image's view.
    pub fn instances(&self) -> Result<Instances<'_>> {
        Instances::of(&self.view()?, &self.name)
    }
}

/// True if `path` names an instanced scene: a compiled one, or a scene file with
/// `[[instance]]` entries.
pub fn is_instanced(path: &Path) -> bool {
    use std::io::Read;
    if crate::input::scene_file::is_scene_file(path) {
        return crate::input::scene_file::has_instances(path);
    }
    let Ok(mut f) = std::fs::File::open(path) else { return false };
    let mut head = [0u8; 8];
    matches!(f.read(&mut head), Ok(8)) && head == INSTANCED_MAGIC
}

/// True if `path` is a glTF file (whose shared meshes `build --instances` keeps).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Reads the instances a source places: a scene file's `[[instance]]` entries or a glTF
/// file's nodes.
pub fn load_instanced_scene(path: &Path) -> Result<InstancedScene> {
    if is_gltf(path) {
        return crate::input::gltf::load_gltf_instanced(path);
    }
    if !crate::input::scene_file::is_scene_file(path) {
        bail!("{}: instances come from a scene file's [[instance]] entries or a glTF file's nodes", path.display());
    }
    let load_mesh = |child: &Path| match crate::scene::load_source(Some(child))? {
        crate::scene::Source::Mesh { mesh, warnings, .. } => Ok(Some((mesh, warnings))),
        crate::scene::Source::Image(_) => Ok(None),
    };
    crate::input::scene_file::load_instanced_scene_file(path, &load_mesh)
}

/// Opens the instanced scene at `path`: a compiled file is mapped and validated; a
/// source is built in memory with `opts`.
pub fn load_instanced(path: &Path, opts: &BuildOptions) -> Result<InstancedFile> {
    let name = path.display().to_string();
    if crate::input::scene_file::is_scene_file(path) || is_gltf(path) {
        let built = load_instanced_scene(path)?.build(opts)?;
        return Ok(InstancedFile { name, bytes: built.bytes.into(), report: Some(built.report) });
    }
    let (file, len) = crate::input::read_file::open_regular(path)?;
    if len > crate::input::read_file::DATA_LIMIT {
        bail!("{name}: {len} bytes is more than any scene holds");
    }
    let bytes = ImageBytes::map(&file, len).map_err(|e| anyhow!("{name}: cannot map: {e}"))?;
    let scene = InstancedFile { name, bytes, report: None };
    scene.instances()?;
    Ok(scene)
}
