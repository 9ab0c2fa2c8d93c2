//! Building a bricked scene (Wald & Slusallek 2001, §6.4): the triangles are partitioned
//! spatially into bricks of a target size, each brick is built into a self-contained
//! scene image with its own structure and compressed, and the file is laid out with the
//! top-level BVH over the bricks in front.

pub mod brick_image;
pub mod bricked_writer;
pub mod out_of_core;
pub mod partition;
pub mod region;
pub mod source;
pub mod spill;
pub mod top_tree;
pub mod tri_record;

use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use rayon::prelude::*;
use raypipe_core::image::bricked::Codec;
use raypipe_core::image::{LightRecord, FLAG_DEFAULT_LIGHT};

use self::brick_image::{build_brick, BrickContext};
use self::bricked_writer::{IndexParts, PayloadWriter};
use self::out_of_core::partition_file;
use self::partition::{partition, LeafPart, Part, MAX_GROWTH};
use self::region::{clipped_bounds, Region};
use self::source::{streamed_lights, MeshSource, SourceTables, TriangleSource};
use self::spill::{SpillFile, SpillWriter};
use self::tri_record::TriRecord;
use crate::build::emitter_sums::EmitterSums;
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
    /// Bytes of memory the build may use (`None`: no limit; all records in memory).
    pub memory_budget: Option<u64>,
    /// Copies of the input laid side by side (1: the input as it is).
    pub copies: u32,
}

impl BrickOptions {
    /// Bricks of `brick_bytes` stored with `codec`, no budget, one copy, no progress bar.
    pub fn new(brick_bytes: u64, codec: Codec) -> BrickOptions {
        BrickOptions { brick_bytes, codec, progress: false, memory_budget: None, copies: 1 }
    }
}

/// What a bricked build produced.
#[derive(Clone, Debug, Default)]
pub struct BrickedReport {
    /// Triangles, each counted once.
    pub triangles: u64,
    /// Triangles the bricks hold, summed (a triangle shared by bricks counts in each).
    pub references: u64,
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
    /// The process's peak resident memory after the build, if known.
    pub peak_rss: Option<u64>,
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
    mesh: Mesh,
    warnings: Vec<String>,
    camera: CameraSpec,
    opts: &BuildOptions,
    bopts: &BrickOptions,
    out: &Path,
) -> Result<BrickedReport> {
    mesh.validate(name)?;
    let mut source = MeshSource { name: name.to_string(), mesh };
    build_bricked_from(&mut source, warnings, camera, opts, bopts, out)
}

/// Memory a build keeps besides triangle records: the program, buffers, and the bricks
/// being built at once (each several times its image: records, mesh, structure,
/// image, compressed copy).
pub fn working_memory(bopts: &BrickOptions) -> u64 {
    64 * (1 << 20) + rayon::current_num_threads() as u64 * 8 * bopts.brick_bytes.max(1 << 16)
}

/// Bricks the triangles of `source` into `out`: streamed to a spill file (and copied
/// side by side, `--replicate`), lit, partitioned within the memory budget, each part's
/// bricks built in parallel, and the file laid out.
pub fn build_bricked_from(
    source: &mut dyn TriangleSource,
    warnings: Vec<String>,
    camera: CameraSpec,
    opts: &BuildOptions,
    bopts: &BrickOptions,
    out: &Path,
) -> Result<BrickedReport> {
    let name = source.name().to_string();
    let budget = bopts.memory_budget.unwrap_or(u64::MAX);
    let work = working_memory(bopts);
    if budget < work + source.resident_bytes() {
        bail!(
            "{name}: a memory budget of {} MB is too small to build in: it needs {} MB for the input's vertices and {} MB to work",
            budget / 1_000_000,
            source.resident_bytes() / 1_000_000,
            work / 1_000_000
        );
    }
    let scratch = crate::output::target::scratch_dir(out)?;
    let tables = source.tables();
    let mut report = BrickedReport { warnings, ..Default::default() };

    let start = Instant::now();
    let all = spill_source(source, &tables, bopts, scratch.path())?;
    let bounds = all.bounds;
    let camera = camera.merged(opts.camera).apply(&framing_camera(bounds.0, bounds.1));
    let (shading_lights, default_light) = scene_lights(source, &all, &tables, &camera, (opts, bopts), &mut report)?;
    source.release();
    let ctx = BrickContext {
        materials: tables.materials,
        textures: tables.textures,
        lights: shading_lights.clone(),
        shading: tables.shading,
        has_materials: tables.has_materials,
        has_objects: tables.has_objects,
        scene_bounds: bounds,
        build: opts.clone(),
    };
    let per_brick = (bopts.brick_bytes / bytes_per_triangle(opts, ctx.shading)).max(1) as usize;
    report.seconds[0] = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let payload = tempfile::tempfile_in(scratch.path())
        .map_err(|e| anyhow!("{}: cannot create a spill file: {e}", scratch.path().display()))?;
    let mut bricks = BrickSink {
        ctx: &ctx,
        codec: bopts.codec,
        name: &name,
        writer: PayloadWriter::new(payload, 0),
        boxes: Vec::new(),
        totals: BrickedReport::default(),
    };
    // A fifth of the rest is left for the allocator's slack and the kernel's buffers.
    let records_memory = budget.saturating_sub(work) / 5 * 4;
    let bar = progress::bar(all.count, "bricks", bopts.progress);
    let unique = all.count;
    let root = Region { lo: bounds.0, hi: bounds.1 };
    let part = partition_file(
        all,
        (root, MAX_GROWTH),
        per_brick,
        records_memory,
        &mut |records, region, allowance| bricks.build_part(records, (region, allowance), per_brick, &bar),
        &bar,
    )?;
    bar.finish_and_clear();
    report.seconds[1] = start.elapsed().as_secs_f64();

    let start = Instant::now();
    let n = bricks.boxes.len();
    let nodes = top_tree::top_nodes(&part, &bricks.boxes);
    let list: Vec<u32> = (0..n as u32).collect();
    let globals = globals_image(&shading_lights, &camera, default_light, bounds)?;
    let parts =
        IndexParts { codec: bopts.codec, bounds, nodes: &nodes, list: &list, globals: &globals, triangles: unique };
    let bar = progress::bar(n as u64, "write", bopts.progress);
    let file_bytes = bricks.writer.finish(out, &parts, &bar)?;
    bar.finish_and_clear();
    report.seconds[2] = start.elapsed().as_secs_f64();
    drop(scratch);
    let t = bricks.totals;
    Ok(BrickedReport {
        triangles: unique,
        references: t.triangles,
        bricks: n as u64,
        vertices: t.vertices,
        image_bytes: t.image_bytes,
        stored_bytes: t.stored_bytes,
        largest_brick: t.largest_brick,
        file_bytes,
        peak_rss: crate::platform::memory::peak_rss(),
        ..report
    })
}

/// The scene's lights as a flat build would choose them (a mesh in memory exactly so;
/// a streamed source by the same rule over the spill file), less its area lights, which
/// bricks do not carry (a warning says so); and whether the point light is the default
/// one placed for the camera.
fn scene_lights(
    source: &mut dyn TriangleSource,
    all: &SpillFile,
    tables: &SourceTables,
    camera: &raypipe_core::image::CameraRecord,
    (opts, bopts): (&BuildOptions, &BrickOptions),
    report: &mut BrickedReport,
) -> Result<(Vec<LightRecord>, bool)> {
    let name = source.name().to_string();
    let (lights, note, default_light, areas) = match source.mesh().filter(|_| bopts.copies == 1) {
        Some(mesh) => {
            let (note, default_light) = choose_lights(&name, mesh, camera, &opts.lights)?;
            let areas = mesh.lights.iter().filter(|l| l.kind == LightRecord::AREA).count() as u64;
            (mesh.lights.clone(), note, default_light, areas)
        }
        None => {
            let sums = emitter_sums(all, &tables.materials)?;
            let (lights, note, default_light) =
                streamed_lights(&opts.lights, all.bounds, camera, &sums, |ray| first_hit(all, ray));
            (lights, note, default_light, sums.count)
        }
    };
    report.lights = note;
    let shading: Vec<LightRecord> = lights.iter().copied().filter(|l| l.kind != LightRecord::AREA).collect();
    if areas > 0 {
        report.warnings.push(format!(
            "{name}: {areas} emissive triangles are not area lights in a bricked scene (only path tracing samples them, and it needs the whole scene)"
        ));
    }
    Ok((shading, default_light))
}

/// Streams `source` into a spill file in `scratch` (copied side by side when asked),
/// checking every coordinate and the count.
fn spill_source(
    source: &mut dyn TriangleSource,
    tables: &SourceTables,
    bopts: &BrickOptions,
    scratch: &Path,
) -> Result<SpillFile> {
    let name = source.name().to_string();
    let bar = progress::bar(source.triangle_hint() * bopts.copies as u64, "read", bopts.progress);
    let mut spill = SpillWriter::create(&scratch.join("all"), tables.shading)?;
    let mut bad = None;
    source.stream(&mut |r| {
        if bad.is_none() {
            let limit = crate::input::mesh::MAX_COORDINATE;
            bad = r.p.iter().flatten().find(|c| !c.is_finite() || c.abs() > limit).copied();
        }
        bar.inc(1);
        spill.push(&r)
    })?;
    let mut all = spill.finish()?;
    if let Some(c) = bad {
        bail!(
            "{name}: a vertex has the coordinate {c}, NaN, infinite or beyond ±{:e}",
            crate::input::mesh::MAX_COORDINATE
        );
    }
    if all.count == 0 {
        bail!("{name}: the mesh has no triangles");
    }
    if bopts.copies > 1 {
        all = replicate(&all, bopts.copies, &bar)?;
    }
    // Scene-wide ids are 32-bit; each brick is a flat image within the usual limits.
    if all.count >= u32::MAX as u64 {
        bail!("{name}: {} triangles is more than a bricked scene's 32-bit triangle ids hold", all.count);
    }
    bar.finish_and_clear();
    Ok(all)
}

/// Builds the bricks of the parts that fit in memory, as the partition hands them over.
struct BrickSink<'a> {
    ctx: &'a BrickContext,
    codec: Codec,
    name: &'a str,
    writer: PayloadWriter,
    boxes: Vec<([f32; 3], [f32; 3])>,
    totals: BrickedReport,
}

impl BrickSink<'_> {
    /// Partitions `records` of `region` in memory (within the growth `allowance`) and
    /// builds their bricks in parallel; the bricks take the next ids. Returns the
    /// part's tree.
    fn build_part(
        &mut self,
        records: Vec<TriRecord>,
        (region, allowance): (Region, f64),
        per_brick: usize,
        bar: &indicatif::ProgressBar,
    ) -> Result<Part> {
        let mut leaves = Vec::new();
        let part = partition(records, region, per_brick, allowance, &mut leaves);
        let base = self.boxes.len();
        let margin =
            crate::build::bvh::box_margin(&Mesh { margin_bounds: Some(self.ctx.scene_bounds), ..Default::default() });
        let slices: Vec<(usize, LeafPart)> = leaves.into_iter().enumerate().map(|(k, l)| (base + k, l)).collect();
        let n = slices.len();
        let (ctx, codec, name) = (self.ctx, self.codec, self.name);
        self.writer.grow(base + n);
        self.boxes.resize(base + n, ([0.0; 3], [0.0; 3]));
        // Each brick is stored as soon as it is built and its image let go: the part's
        // records are the only large thing held.
        let sink = std::sync::Mutex::new((&mut self.writer, &mut self.boxes, &mut self.totals));
        slices.into_par_iter().try_for_each(|(k, mut leaf)| -> Result<()> {
            // The top level's box: the brick's share of space, not its triangles' reach.
            let top_box = clipped_bounds(&leaf.region, &leaf.records, margin);
            let built = build_brick(ctx, &mut leaf.records).map_err(|e| anyhow!("{name}: brick {k}: {e}"))?;
            drop(leaf);
            let stored = compress(codec, &built.image)?;
            bar.inc(built.triangles as u64);
            let mut guard = sink.lock().map_err(|_| anyhow!("internal error: a brick worker panicked"))?;
            let (writer, boxes, t) = &mut *guard;
            writer.add(k, &stored, &built)?;
            boxes[k] = top_box;
            t.triangles += built.triangles as u64;
            t.vertices += built.vertices as u64;
            t.image_bytes += built.image.len() as u64;
            t.stored_bytes += stored.len() as u64;
            t.largest_brick = t.largest_brick.max(built.image.len() as u64);
            Ok(())
        })?;
        Ok(part)
    }
}

/// `copies` copies of `all`'s records side by side along x, each shifted by 1.25 times
/// the scene's extent; ids continue from copy to copy.
fn replicate(all: &SpillFile, copies: u32, bar: &indicatif::ProgressBar) -> Result<SpillFile> {
    let (lo, hi) = all.bounds;
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
    let shift = 1.25 * extent.max(f32::MIN_POSITIVE);
    let path = all.path.with_extension("copies");
    let mut w = SpillWriter::create(&path, all.shading)?;
    for copy in 0..copies as u64 {
        let dx = shift * copy as f32;
        let base = copy * all.count;
        all.for_each(|mut r| {
            for p in &mut r.p {
                p[0] += dx;
            }
            r.id = u32::try_from(base + r.id as u64)
                .map_err(|_| anyhow!("{copies} copies hold more than 2^32 triangles"))?;
            bar.inc(1);
            w.push(&r)
        })?;
    }
    all.remove();
    w.finish()
}

/// The emitters' sums over every record of `file`, in id order.
fn emitter_sums(file: &SpillFile, materials: &[raypipe_core::image::MaterialRecord]) -> Result<EmitterSums> {
    let mut sums = EmitterSums::default();
    file.for_each(|r| {
        sums.add(r.p, materials.get(r.material as usize).map_or([0.0; 3], |m| m.emission));
        Ok(())
    })?;
    Ok(sums)
}

/// The nearest triangle along `ray` over every record of `file`: the default light's
/// rays, brute force as a flat build's before any structure exists.
fn first_hit(file: &SpillFile, ray: &raypipe_core::Ray) -> Option<f32> {
    let mut nearest = crate::build::default_lights::NearestHit::new(ray);
    let _ = file.for_each(|r| {
        nearest.test(r.p.map(glam::Vec3::from));
        Ok(())
    });
    nearest.t()
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
