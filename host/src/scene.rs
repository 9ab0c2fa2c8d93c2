//! Getting a scene image from what the user named: the built-in default, an OBJ file
//! (built in memory), or a compiled `.rpsi` image (read and validated in place).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use raypipe_core::image::{
    Bvh4Node, Bvh8Node, CameraRecord, LightRecord, TriBlock4, WideNode, FLAG_DEFAULT_LIGHT, MAGIC,
};
use raypipe_core::{NoProbe, Ray, RayCounters, SceneView, Watertight};

use crate::render::tracer::trace;

use crate::build::bvh::build_bvh;
use crate::build::grid::{build_grid, GridResolution};
use crate::build::image_writer::ImageWriter;
use crate::build::kdtree::{build_kdtree, KdParams};
use crate::build::sah::BvhParams;
use crate::build::wide_bvh::{align_leaves, build_wide_bvh};
use crate::input::camera_file::CameraSpec;
use crate::input::default_scene;
use crate::input::mesh::Mesh;
use crate::input::obj;
use crate::platform::image_bytes::ImageBytes;

/// Which acceleration structure to build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Accel {
    /// Purcell's uniform grid.
    #[default]
    Grid,
    /// kd-tree (SAH, Wald's 8-byte nodes).
    Kd,
    /// Bounding volume hierarchy (binned SAH, 32-byte nodes).
    Bvh,
    /// 4-wide BVH (the binary BVH collapsed, 128-byte nodes tested with SIMD).
    Bvh4,
    /// 8-wide BVH (the binary BVH collapsed, 256-byte nodes tested with SIMD).
    Bvh8,
    /// None: every ray tests every triangle (the reference).
    None,
}

/// Which triangle layout the intersection unit reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TriangleLayout {
    /// Vertex indices into positions (12 + 3·12 bytes, shared vertices): watertight or
    /// Möller–Trumbore.
    #[default]
    Indexed,
    /// Also Wald's 48-byte precomputed projection triangles, for `--intersector wald`.
    Wald,
    /// Also the leaf triangles' vertices in blocks of four SIMD lanes (144 bytes per four
    /// list entries, leaves aligned to blocks and priced by blocks): single rays through a
    /// 4- or 8-wide BVH test four triangles at a time with the watertight test. The
    /// larger leaves slow packets down, which test each triangle ray group by ray group.
    Blocks,
}

/// How to build a scene image from a mesh.
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Point, directional and sky lights to use instead of the default one (a dim
    /// ambient term is kept, emitters stay area lights).
    pub lights: Vec<LightRecord>,
    /// The camera that will render (a camera file and flags over the input's own): the
    /// image's default camera, and what the default light is chosen for.
    pub camera: CameraSpec,
    /// Acceleration structure.
    pub accel: Accel,
    /// Grid resolution.
    pub grid: GridResolution,
    /// kd-tree cost constants.
    pub kd: KdParams,
    /// BVH cost constants.
    pub bvh: BvhParams,
    /// Triangle layout.
    pub triangles: TriangleLayout,
}

/// What a build produced, for `raypipe build` and `bench`.
#[derive(Clone, Debug, Default)]
pub struct BuildReport {
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// Zero-area triangles.
    pub degenerate: usize,
    /// What lights the image has and why (one line).
    pub lights: String,
    /// Grid cells per axis (zero without a grid).
    pub dims: [u32; 3],
    /// Grid cells.
    pub cells: u64,
    /// Cells with a list.
    pub full_cells: u64,
    /// Triangle references in the lists.
    pub references: u64,
    /// List entries including terminators.
    pub list_entries: u64,
    /// Bytes of the image.
    pub image_bytes: usize,
    /// Seconds spent building the acceleration structure.
    pub grid_seconds: f64,
    /// Tree nodes (kd-tree or BVH).
    pub tree_nodes: usize,
    /// Depth of the tree.
    pub tree_depth: u32,
    /// Bytes of the acceleration structure (nodes or cells, and primitive lists).
    pub structure_bytes: usize,
    /// Warnings to show the user.
    pub warnings: Vec<String>,
}

impl BuildReport {
    /// Records a tree's size: `nodes` of `node_bytes` each, and its primitive list.
    fn tree(&mut self, nodes: usize, node_bytes: usize, depth: u32, prims: usize) {
        self.tree_nodes = nodes;
        self.tree_depth = depth;
        self.references = prims as u64;
        self.list_entries = prims as u64;
        self.structure_bytes = node_bytes * nodes + 4 * prims;
    }
}

/// A scene image in memory, with its name for messages.
pub struct Scene {
    /// What the user called it.
    pub name: String,
    /// The image bytes, 64-byte aligned: built in memory, or a file mapped in place.
    pub image: ImageBytes,
    /// Present when the image was built in this run.
    pub report: Option<BuildReport>,
}

impl Scene {
    /// The validated view.
    pub fn view(&self) -> Result<SceneView<'_>> {
        SceneView::parse(&self.image).map_err(|e| anyhow!("{}: {e}", self.name))
    }
}

/// What a scene argument names: a compiled image, or a mesh still to be built.
pub enum Source {
    /// A scene image read from disk.
    Image(Scene),
    /// A mesh with its name, load warnings and default camera settings.
    Mesh {
        /// Name for messages.
        name: String,
        /// The mesh.
        mesh: Mesh,
        /// Warnings from loading.
        warnings: Vec<String>,
        /// Default camera settings (from a sidecar `.camera` file).
        camera: CameraSpec,
    },
}

impl Source {
    /// Builds (or, for an image, returns) the scene.
    pub fn build(&self, opts: &BuildOptions) -> Result<Scene> {
        match self {
            Source::Image(scene) => Ok(Scene { name: scene.name.clone(), image: scene.image.clone(), report: None }),
            Source::Mesh { name, mesh, warnings, camera } => {
                build(name.clone(), mesh.clone(), warnings.clone(), *camera, opts)
            }
        }
    }
}

/// Reads what the user named (the built-in default when `path` is `None`) without
/// building anything yet.
pub fn load_source(path: Option<&Path>) -> Result<Source> {
    let Some(path) = path else {
        let (mesh, notes) =
            obj::load_obj_str(default_scene::NAME, default_scene::OBJ, &|_| Some(default_scene::MTL.into()))?;
        let camera = CameraSpec::parse(default_scene::NAME, default_scene::CAMERA)?;
        return Ok(Source::Mesh { name: default_scene::NAME.into(), mesh, warnings: notes.warnings, camera });
    };
    let name = path.display().to_string();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let file_name = path.file_name().and_then(|f| f.to_str()).unwrap_or("").to_ascii_lowercase();
    if crate::input::scene_file::is_scene_file(path) {
        let load_mesh = |child: &Path| match load_source(Some(child))? {
            Source::Mesh { mesh, warnings, .. } => Ok(Some((mesh, warnings))),
            Source::Image(_) => Ok(None),
        };
        let (mesh, warnings, camera) = crate::input::scene_file::load_scene_file(path, &load_mesh)?;
        return Ok(Source::Mesh { name, mesh, warnings, camera });
    }
    if file_name.ends_with(".ply") || file_name.ends_with(".ply.gz") {
        let (mesh, notes) = crate::input::ply::load_ply_file(path)?;
        let camera = sidecar_camera(path).map(|p| CameraSpec::load(&p)).transpose()?.unwrap_or_default();
        return Ok(Source::Mesh { name, mesh, warnings: notes.warnings, camera });
    }
    if ext == "gltf" || ext == "glb" {
        let (mesh, notes, own) = crate::input::gltf::load_gltf_file(path)?;
        // A camera file beside it wins over the file's own camera.
        let camera = match sidecar_camera(path) {
            Some(p) => own.merged(CameraSpec::load(&p)?),
            None => own,
        };
        return Ok(Source::Mesh { name, mesh, warnings: notes.warnings, camera });
    }
    let is_image = match ext.as_str() {
        "obj" | "gz" => false,
        "rpsi" => true,
        _ => starts_with_magic(path)?,
    };
    if is_image {
        let (file, len) = crate::input::read_file::open_regular(path)?;
        if len > crate::input::read_file::DATA_LIMIT {
            bail!("{name}: {len} bytes is more than any scene image holds");
        }
        if len < 64 {
            bail!("{name}: truncated: {len} bytes, a scene image has at least 64");
        }
        let image = ImageBytes::map(&file, len).map_err(|e| anyhow!("{name}: cannot map: {e}"))?;
        SceneView::parse(&image).map_err(|e| anyhow!("{name}: {e}"))?;
        return Ok(Source::Image(Scene { name, image, report: None }));
    }
    let (mesh, notes) = obj::load_obj_file(path)?;
    let camera = match sidecar_camera(path) {
        Some(p) => CameraSpec::load(&p)?,
        None => CameraSpec::default(),
    };
    Ok(Source::Mesh { name, mesh, warnings: notes.warnings, camera })
}

/// True if the file begins like a scene image (for names without a known extension).
fn starts_with_magic(path: &Path) -> Result<bool> {
    use std::io::Read;
    let name = path.display();
    let (mut f, _) = crate::input::read_file::open_regular(path)?;
    let mut head = [0u8; 8];
    let got = f.read(&mut head).map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
    Ok(got == head.len() && head == MAGIC)
}

/// Loads the scene the user named, or the built-in default when `path` is `None`.
pub fn load(path: Option<&Path>, opts: &BuildOptions) -> Result<Scene> {
    match load_source(path)? {
        Source::Image(scene) => Ok(scene),
        Source::Mesh { name, mesh, warnings, camera } => build(name, mesh, warnings, camera, opts),
    }
}

/// The built-in Cornell box.
pub fn load_default(opts: &BuildOptions) -> Result<Scene> {
    load(None, opts)
}

/// The camera of the `.camera` file beside `path`, or none.
pub fn sidecar_camera_spec(path: &Path) -> Result<CameraSpec> {
    Ok(sidecar_camera(path).map(|p| CameraSpec::load(&p)).transpose()?.unwrap_or_default())
}

/// `scene.camera` next to `scene.obj`, if it exists: the scene's default camera.
fn sidecar_camera(obj: &Path) -> Option<PathBuf> {
    let stem = obj.file_name()?.to_str()?;
    let stem = stem.strip_suffix(".gz").unwrap_or(stem);
    let p = obj.with_file_name(stem).with_extension("camera");
    p.is_file().then_some(p)
}

/// A camera that frames the whole scene from +z (OBJ's usual front), 45° vertical view.
pub fn framing_camera(lo: [f32; 3], hi: [f32; 3]) -> CameraRecord {
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let fov: f32 = 45.0;
    let dist = radius / (fov.to_radians() * 0.5).sin() * 1.05;
    CameraRecord {
        eye: (centre + Vec3::Z * dist).to_array(),
        vfov_deg: fov,
        look_at: centre.to_array(),
        width: 512,
        up: [0.0, 1.0, 0.0],
        height: 512,
        background: [0.05, 0.05, 0.08],
        _pad: 0,
    }
}

/// Settles `mesh`'s lights: the input's own (an MTL cannot give any today), else the
/// user's (`--light`, `--sun`, `--sky`) plus a dim ambient term and the emitters as area
/// lights, else the defaults for `camera` ([`crate::build::default_lights`]). Area lights go
/// last. Returns one line describing them.
/// The mesh's lights: the user's, the input's, or the default; also whether the default
/// point light was placed for `camera` (then the image says so: another view may place
/// it again).
pub(crate) fn choose_lights(
    name: &str,
    mesh: &mut Mesh,
    camera: &CameraRecord,
    user: &[LightRecord],
) -> Result<(String, bool)> {
    if user.is_empty() && mesh.lights.is_empty() {
        let (lights, note) = crate::build::default_lights::default_lights(mesh, camera);
        let for_camera = lights.iter().any(|l| l.kind == LightRecord::POINT);
        mesh.lights = lights;
        return Ok((note, for_camera));
    }
    if !user.is_empty() {
        check_user_lights(name, user)?;
        let areas = crate::build::default_lights::emitters(mesh);
        mesh.lights = user.to_vec();
        mesh.lights.push(LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 });
        let n = areas.len();
        mesh.lights.extend(areas);
        let note = format!("{} given light{}{}", user.len(), if user.len() == 1 { "" } else { "s" }, area_note(n));
        return Ok((note, false));
    }
    mesh.lights.sort_by_key(|l| l.kind == LightRecord::AREA);
    Ok((format!("{} lights from the input", mesh.lights.len()), false))
}

fn area_note(n: usize) -> String {
    if n == 0 {
        String::new()
    } else {
        format!("; {n} emissive triangles are area lights")
    }
}

/// What the command line's lights must be: a sun has a direction.
pub(crate) fn check_user_lights(name: &str, user: &[LightRecord]) -> Result<()> {
    for l in user {
        if l.kind == LightRecord::DIRECTIONAL && Vec3::from(l.position).length_squared() == 0.0 {
            bail!("{name}: --sun: the direction is zero");
        }
    }
    Ok(())
}

/// The image `scene` with its point, directional, sky and ambient lights replaced by
/// `user`'s (its emitters stay area lights): `--light` and friends on a built image.
pub fn relight(scene: &Scene, user: &[LightRecord]) -> Result<Scene> {
    check_user_lights(&scene.name, user)?;
    replace_shading_lights(scene, user, 0)
}

/// The image `scene`, whose point light is raypipe's default ([`FLAG_DEFAULT_LIGHT`]),
/// with that light placed again for `camera` (another view than the image's); `None`
/// when the image's light is not a default one. The note says where it went.
pub fn relight_for_camera(scene: &Scene, camera: &CameraRecord) -> Result<Option<(Scene, String)>> {
    let view = scene.view()?;
    if !view.has_default_light() {
        return Ok(None);
    }
    let (lo, hi) = view.bounds();
    let p = crate::build::default_lights::light_in_view(lo, hi, camera, |ray| {
        trace::<Watertight, _>(&view, ray, &mut NoProbe, &mut RayCounters::default()).map(|h| h.t)
    });
    let lights: Vec<LightRecord> = (0..view.shading_light_count())
        .map(|i| view.light(i, &mut NoProbe))
        .map(|l| if l.kind == LightRecord::POINT { LightRecord { position: p.to_array(), ..l } } else { l })
        .filter(|l| l.kind != LightRecord::AMBIENT)
        .collect();
    let out = replace_shading_lights(scene, &lights, FLAG_DEFAULT_LIGHT)?;
    Ok(Some((out, format!("point light at ({:.3}, {:.3}, {:.3}), chosen for the camera", p.x, p.y, p.z))))
}

/// The image `scene` with `lights`, a dim ambient term and its own area lights, and the
/// header flags `flags`.
fn replace_shading_lights(scene: &Scene, user: &[LightRecord], flags: u32) -> Result<Scene> {
    let view = scene.view()?;
    let first_area = view.shading_light_count();
    let areas: Vec<LightRecord> = (first_area..view.light_count()).map(|i| view.light(i, &mut NoProbe)).collect();
    let mut lights = user.to_vec();
    lights.push(LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 });
    lights.extend(areas.iter().copied());
    let power: Vec<f64> = areas
        .iter()
        .map(|l| {
            let [a, b, c] = view.triangle(l.triangle, &mut NoProbe);
            crate::build::light_distribution::triangle_power(a, b, c, l.color)
        })
        .collect();
    let image = ImageWriter::replace_lights(
        &scene.image,
        &lights,
        &crate::build::light_distribution::alias_table(&power),
        flags,
    )
    .map_err(|e| anyhow!("{}: {e}", scene.name))?;
    let out = Scene { name: scene.name.clone(), image: image.into(), report: scene.report.clone() };
    out.view().map_err(|e| anyhow!("internal error: relit an invalid image: {e}"))?;
    Ok(out)
}

/// Builds the binary BVH, collapses it into nodes of `N`'s width and adds it to the image.
fn build_wide<N: WideNode>(mesh: &Mesh, opts: &BuildOptions, report: &mut BuildReport, writer: &mut ImageWriter) {
    let blocks = opts.triangles == TriangleLayout::Blocks;
    let params = BvhParams { leaf_block: if blocks { TriBlock4::LANES } else { 1 }, ..opts.bvh };
    let mut bvh = build_wide_bvh::<N>(mesh, &params);
    if blocks {
        align_leaves(&mut bvh, TriBlock4::LANES);
    }
    report.tree(bvh.nodes.len(), std::mem::size_of::<N>(), bvh.depth, bvh.prims.len());
    writer.wide_bvh(&bvh);
    if blocks {
        writer.tri_blocks(mesh, &bvh.prims);
        report.structure_bytes += std::mem::size_of::<TriBlock4>() * bvh.prims.len().div_ceil(TriBlock4::LANES);
    }
}

/// Builds a scene image from a mesh.
pub fn build(
    name: String,
    mut mesh: Mesh,
    warnings: Vec<String>,
    camera: CameraSpec,
    opts: &BuildOptions,
) -> Result<Scene> {
    mesh.validate(&name)?;
    let (lo, hi) = mesh.bounds();
    let camera = camera.merged(opts.camera).apply(&framing_camera(lo, hi));
    let (lights_note, default_light) = choose_lights(&name, &mut mesh, &camera, &opts.lights)?;
    let mut report = BuildReport {
        triangles: mesh.triangles.len(),
        vertices: mesh.positions.len(),
        degenerate: mesh.degenerate_count(),
        warnings,
        lights: lights_note,
        ..Default::default()
    };
    let wide = matches!(opts.accel, Accel::Bvh4 | Accel::Bvh8);
    if opts.triangles == TriangleLayout::Blocks && !wide {
        report.warnings.push(
            "--triangles blocks applies to --accel bvh4 and bvh8 only; this image keeps indexed triangles".into(),
        );
    }
    let mut writer = ImageWriter::new(&mesh);
    if default_light {
        writer.flags |= FLAG_DEFAULT_LIGHT;
    }
    if opts.triangles == TriangleLayout::Wald {
        writer.wald_triangles(&mesh);
    }
    writer.camera(&camera);
    let start = Instant::now();
    add_structure(&name, &mesh, opts, &mut report, &mut writer)?;
    report.grid_seconds = start.elapsed().as_secs_f64();
    let image = writer.finish().map_err(|e| anyhow!("{name}: {e}"))?;
    report.image_bytes = image.len();
    let mut scene = Scene { name, image: image.into(), report: Some(report) };
    let view = match scene.view() {
        Ok(v) => v,
        Err(e) => bail!("internal error: built an invalid image: {e}"),
    };
    let enclosed = enclosed_lights(&view);
    if let Some(report) = scene.report.as_mut() {
        for (i, p) in enclosed {
            report.warnings.push(format!(
                "{}: light {i} at ({}, {}, {}) is inside closed geometry (every direction meets the back of a surface): it lights nothing outside",
                scene.name, p[0], p[1], p[2]
            ));
        }
    }
    Ok(scene)
}

/// Builds the acceleration structure `opts` asks for over `mesh` and adds it to the
/// image, recording its size in `report`.
pub fn add_structure(
    name: &str,
    mesh: &Mesh,
    opts: &BuildOptions,
    report: &mut BuildReport,
    writer: &mut ImageWriter,
) -> Result<()> {
    match opts.accel {
        Accel::Grid => {
            let grid = build_grid(mesh, opts.grid).map_err(|e| anyhow!("{name}: {e}"))?;
            report.dims = grid.record.dims;
            report.cells = grid.cells.len() as u64;
            report.full_cells = grid.full_cells;
            report.references = grid.references;
            report.list_entries = grid.lists.len() as u64;
            report.structure_bytes = 64 + 4 * (grid.cells.len() + grid.lists.len());
            writer.grid(&grid);
        }
        Accel::Kd => {
            let kd = build_kdtree(mesh, &opts.kd);
            report.tree(kd.nodes.len(), 8, kd.depth, kd.prims.len());
            writer.kdtree(&kd);
        }
        Accel::Bvh => {
            let bvh = build_bvh(mesh, &opts.bvh);
            report.tree(bvh.nodes.len(), 32, bvh.depth, bvh.prims.len());
            writer.bvh(&bvh);
        }
        Accel::Bvh4 => build_wide::<Bvh4Node>(mesh, opts, report, writer),
        Accel::Bvh8 => build_wide::<Bvh8Node>(mesh, opts, report, writer),
        Accel::None => {}
    }
    Ok(())
}

/// Point lights enclosed by geometry: every one of 14 rays from the light (axes and
/// diagonals) meets the back of a triangle first.
fn enclosed_lights(view: &SceneView<'_>) -> Vec<(u32, [f32; 3])> {
    let mut dirs = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0f32, 1.0] {
                dirs.push(Vec3::new(sx, sy, sz).normalize());
            }
        }
    }
    let mut out = Vec::new();
    for i in 0..view.light_count() {
        let l = view.light(i, &mut NoProbe);
        if l.kind != LightRecord::POINT {
            continue;
        }
        let p = Vec3::from(l.position);
        let backs = dirs
            .iter()
            .filter(|&&d| {
                let ray = Ray::new(p, d);
                trace::<Watertight, _>(view, &ray, &mut NoProbe, &mut RayCounters::default()).is_some_and(|h| {
                    let [a, b, c] = view.triangle(h.prim, &mut NoProbe);
                    (b - a).cross(c - a).dot(d) > 0.0
                })
            })
            .count();
        if backs == dirs.len() {
            out.push((i, l.position));
        }
    }
    out
}
