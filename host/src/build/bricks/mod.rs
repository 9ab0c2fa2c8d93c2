//! Building a bricked scene (Wald & Slusallek 2001, §6.4): the triangles are partitioned
//! spatially into bricks of a target size, each brick is built into a self-contained
//! scene image with its own structure and compressed, and the file is laid out with the
//! top-level BVH over the bricks in front.

pub mod brick_image;
pub mod bricked_writer;
pub mod partition;
pub mod top_tree;
pub mod tri_record;

use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use rayon::prelude::*;
use raypipe_core::image::bricked::Codec;
use raypipe_core::image::{LightRecord, FLAG_DEFAULT_LIGHT, NULL_INDEX};

use self::brick_image::{build_brick, BrickContext};
use self::bricked_writer::{IndexParts, PayloadWriter};
use self::partition::partition;
use self::tri_record::TriRecord;
use crate::build::image_writer::ImageWriter;
use crate::input::bricked::codec::compress;
use crate::input::camera_file::CameraSpec;
use crate::input::mesh::Mesh;
use crate::output::progress;
use crate::scene::{choose_lights, framing_camera, Accel, BuildOptions, TriangleLayout};

/// How to brick a scene.
#[derive(Clone, Copy, Debug)]
pub struct BrickOptions {
    /// Target size of a brick's scene image, in bytes (before compression).
    pub brick_bytes: u64,
    /// The codec bricks are stored with.
    pub codec: Codec,
    /// Show progress bars.
    pub progress: bool,
}

/// What a bricked build produced.
#[derive(Clone, Debug, Default)]
pub struct BrickedReport {
    /// Triangles.
    pub triangles: u64,
    /// Bricks.
    pub bricks: u64,
    /// Vertices the bricks store (welded per brick).
    pub vertices: u64,
    /// Bytes of the bricks' scene images, summed.
    pub image_bytes: u64,
    /// Bytes of the bricks as stored (compressed), summed.
    pub stored_bytes: u64,
    /// The largest brick's image.
    pub largest_brick: u64,
    /// Bytes of the file.
    pub file_bytes: u64,
    /// Seconds spent partitioning, building and compressing bricks, and writing.
    pub seconds: [f64; 3],
    /// What lights the scene has (one line).
    pub lights: String,
    /// Warnings for the user.
    pub warnings: Vec<String>,
}

/// Scene-image bytes per triangle a brick of this structure takes, roughly (measured on
/// the generated building: the figure only sizes bricks, whose real sizes are reported).
fn bytes_per_triangle(opts: &BuildOptions, shading: bool) -> u64 {
    let structure = match opts.accel {
        Accel::None => 0,
        Accel::Grid => 40,
        Accel::Kd => 40,
        Accel::Bvh => 30,
        Accel::Bvh4 | Accel::Bvh8 => 35,
    };
    let layout = match opts.triangles {
        TriangleLayout::Indexed => 0,
        TriangleLayout::Wald => 48,
        TriangleLayout::Blocks => 40,
    };
    // Positions (about half a vertex per triangle) and indices.
    20 + structure + layout + if shading { 20 } else { 0 }
}

/// Bricks the mesh `name` into `out`.
pub fn build_bricked(
    name: &str,
    mut mesh: Mesh,
    warnings: Vec<String>,
    camera: CameraSpec,
    opts: &BuildOptions,
    bopts: &BrickOptions,
    out: &Path,
) -> Result<BrickedReport> {
    mesh.validate(name)?;
    let bounds = mesh.bounds();
    let camera = camera.merged(opts.camera).apply(&framing_camera(bounds.0, bounds.1));
    let (lights_note, default_light) = choose_lights(name, &mut mesh, &camera, &opts.lights)?;
    let mut report = BrickedReport { lights: lights_note, warnings, ..Default::default() };
    let shading_lights: Vec<LightRecord> =
        mesh.lights.iter().copied().filter(|l| l.kind != LightRecord::AREA).collect();
    let areas = mesh.lights.len() - shading_lights.len();
    if areas > 0 {
        report.warnings.push(format!(
            "{name}: {areas} emissive triangles are not area lights in a bricked scene (only path tracing samples them, and it needs the whole scene)"
        ));
    }
    let ctx = BrickContext {
        materials: std::mem::take(&mut mesh.materials),
        textures: std::mem::take(&mut mesh.textures),
        lights: shading_lights.clone(),
        shading: !mesh.shading.is_empty(),
        has_materials: !mesh.tri_materials.is_empty(),
        has_objects: mesh.objects.iter().any(|&o| o != 0),
        scene_bounds: bounds,
        build: opts.clone(),
    };
    let mut tris = mesh_records(&mesh);
    drop(mesh);
    let per_brick = (bopts.brick_bytes / bytes_per_triangle(opts, ctx.shading)).max(1) as usize;

    let start = Instant::now();
    let part = partition(&mut tris, per_brick, 0);
    let leaves = part.leaves();
    report.seconds[0] = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let dir = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let payload =
        tempfile::tempfile_in(dir).map_err(|e| anyhow!("{}: cannot create a spill file: {e}", dir.display()))?;
    let writer = Mutex::new(PayloadWriter::new(payload, leaves.len()));
    let boxes = Mutex::new(vec![([0.0f32; 3], [0.0f32; 3]); leaves.len()]);
    let totals = Mutex::new(BrickedReport::default());
    let bar = progress::bar(leaves.len() as u64, "bricks", bopts.progress);
    // Bricks are disjoint ranges of `tris`: each worker sorts and builds its own.
    let mut slices: Vec<(usize, &mut [TriRecord])> = Vec::with_capacity(leaves.len());
    let mut rest: &mut [TriRecord] = &mut tris;
    for (k, r) in leaves.iter().enumerate() {
        let (head, tail) = rest.split_at_mut(r.len());
        slices.push((k, head));
        rest = tail;
    }
    slices.into_par_iter().try_for_each(|(k, slice)| -> Result<()> {
        let built = build_brick(&ctx, slice).map_err(|e| anyhow!("{name}: brick {k}: {e}"))?;
        let stored = compress(bopts.codec, &built.image)?;
        lock(&writer)?.add(k, &stored, &built)?;
        lock(&boxes)?[k] = built.header_bounds;
        let mut t = lock(&totals)?;
        t.triangles += built.triangles as u64;
        t.vertices += built.vertices as u64;
        t.image_bytes += built.image.len() as u64;
        t.stored_bytes += stored.len() as u64;
        t.largest_brick = t.largest_brick.max(built.image.len() as u64);
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    drop(tris);
    report.seconds[1] = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let boxes = boxes.into_inner().map_err(|_| anyhow!("internal error: a brick worker panicked"))?;
    let nodes = top_tree::top_nodes(&part, &boxes);
    let list: Vec<u32> = (0..leaves.len() as u32).collect();
    let globals = globals_image(&shading_lights, &camera, default_light, bounds)?;
    let parts = IndexParts { codec: bopts.codec, bounds, nodes: &nodes, list: &list, globals: &globals };
    let bar = progress::bar(leaves.len() as u64, "write", bopts.progress);
    let writer = writer.into_inner().map_err(|_| anyhow!("internal error: a brick worker panicked"))?;
    let file_bytes = writer.finish(out, &parts, &bar)?;
    bar.finish_and_clear();
    report.seconds[2] = start.elapsed().as_secs_f64();

    let t = totals.into_inner().map_err(|_| anyhow!("internal error: a brick worker panicked"))?;
    Ok(BrickedReport {
        triangles: t.triangles,
        bricks: leaves.len() as u64,
        vertices: t.vertices,
        image_bytes: t.image_bytes,
        stored_bytes: t.stored_bytes,
        largest_brick: t.largest_brick,
        file_bytes,
        ..report
    })
}

fn lock<T>(m: &Mutex<T>) -> Result<std::sync::MutexGuard<'_, T>> {
    m.lock().map_err(|_| anyhow!("internal error: a brick worker panicked"))
}

/// The mesh's triangles as records, in face order (id = index).
fn mesh_records(mesh: &Mesh) -> Vec<TriRecord> {
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mut r = TriRecord::plain(t.map(|v| mesh.positions[v as usize]), i as u32);
            r.material = mesh.tri_materials.get(i).copied().unwrap_or(NULL_INDEX);
            r.object = mesh.objects.get(i).copied().unwrap_or(0);
            if !mesh.shading.is_empty() {
                r.shading = t.map(|v| mesh.shading[v as usize]);
            }
            r
        })
        .collect()
}

/// The globals image: no triangles; the scene's bounds, camera and shading lights.
fn globals_image(
    lights: &[LightRecord],
    camera: &raypipe_core::image::CameraRecord,
    default_light: bool,
    bounds: ([f32; 3], [f32; 3]),
) -> Result<Vec<u8>> {
    let mesh = Mesh { lights: lights.to_vec(), ..Default::default() };
    let mut w = ImageWriter::new(&mesh);
    w.set_bounds(bounds.0, bounds.1).camera(camera);
    if default_light {
        w.flags |= FLAG_DEFAULT_LIGHT;
    }
    let image = w.finish()?;
    if let Err(e) = raypipe_core::SceneView::parse(&image) {
        bail!("internal error: built an invalid globals image: {e}");
    }
    Ok(image.to_vec())
}
