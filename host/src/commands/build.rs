//! `raypipe build`: an OBJ file (or a generated scene) into a scene image.

use crate::output;
use crate::render;
use crate::scene::{self, Accel};
use anyhow::{anyhow, bail, Result};
use std::time::Instant;

use super::{accel_name, fmt_bytes, warn};

use super::args::CameraArgs;
use super::args::StructureArgs;
use clap::Args;
use std::path::PathBuf;

/// `raypipe build`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// The OBJ file to compile (or --generate).
    #[arg(required_unless_present = "generate", conflicts_with = "generate")]
    pub scene: Option<PathBuf>,
    /// Generate a scene instead: building[:floors=F,rooms=R,seed=S] (a Soda Hall
    /// stand-in, ~1M triangles) or forest[:trees=T,leaves=L,seed=S] (~1M triangles).
    #[arg(long, value_name = "NAME[:PARAMS]")]
    pub generate: Option<String>,
    /// The generated scene's view, the image's default camera: building: outside,
    /// inside; forest: top, inside.
    #[arg(long, value_name = "NAME", requires = "generate")]
    pub view: Option<String>,
    /// Where to write the scene image (.rpsi).
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub bricks: BrickArgs,
    /// Keep shared geometry shared: write an instanced scene (.rpsx) — each mesh built
    /// once (--accel) and placed by instances under a top-level BVH. A glTF file's nodes
    /// that share a mesh become instances; a scene file with [[instance]] entries is
    /// always built this way.
    #[arg(long, conflicts_with_all = ["bricks", "generate"])]
    pub instances: bool,
    /// Threads the build may use (default: all cores): BVH builds split their large
    /// subtrees over them. The output is the same for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

/// How `build --bricks` stores a scene larger than memory.
#[derive(Args, Debug)]
pub struct BrickArgs {
    /// Write a bricked scene (.rpsb): self-contained bricks, each with its own structure
    /// (--accel), compressed, under a top-level BVH; rendered with a brick cache.
    #[arg(long)]
    pub bricks: bool,
    /// Target size of one brick's scene image before compression (e.g. 256K).
    #[arg(long, value_name = "SIZE", default_value = "256K", value_parser = super::args::parse_byte_size, requires = "bricks")]
    pub brick_size: u64,
    /// How bricks are stored.
    #[arg(long, value_name = "CODEC", default_value = "lz4", value_parser = crate::input::bricked::codec::parse_codec, requires = "bricks")]
    pub codec: raypipe_core::image::bricked::Codec,
    /// Memory the build may use (e.g. 4G): records beyond it are partitioned on disk, in
    /// spill files beside the output. Default: no limit.
    #[arg(long, value_name = "SIZE", value_parser = super::args::parse_byte_size, requires = "bricks")]
    pub memory_budget: Option<u64>,
    /// Lay N copies of the input side by side along x (Wald's four power plants).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024), requires = "bricks")]
    pub replicate: u32,
}

pub(crate) fn cmd_build(a: BuildArgs) -> Result<()> {
    // Every build's parallel work (the BVH's subtrees, the bricks) on the threads asked for.
    let threads = a.threads.map(|n| n as usize);
    crate::render::in_pool(threads, || build_any(a))?
}

/// [`cmd_build`] on the current thread pool.
fn build_any(a: BuildArgs) -> Result<()> {
    if a.bricks.bricks {
        return cmd_build_bricked(a);
    }
    if a.instances || a.scene.as_deref().is_some_and(crate::input::instanced::is_instanced) {
        return cmd_build_instanced(a);
    }
    let start = Instant::now();
    let (input, scene) = build_flat(&a)?;
    warn(&scene);
    let what = a.camera.camera.as_ref().map_or("camera".to_string(), |p| p.display().to_string());
    let view = scene.view()?;
    let camera = view.camera().ok_or_else(|| anyhow!("internal error: built image lacks a camera"))?;
    render::eye_rays(camera, &what)?;
    let elapsed = start.elapsed().as_secs_f64();
    output::write_bytes(&a.output, &scene.image)?;
    let r = scene.report.as_ref().ok_or_else(|| anyhow!("internal error: no build report"))?;
    println!("scene        {input}");
    println!("triangles    {} ({} degenerate), vertices {}", r.triangles, r.degenerate, r.vertices);
    match a.structure.accel() {
        Accel::Kd | Accel::Bvh | Accel::Bvh4 | Accel::Bvh8 => {
            println!(
                "{:<12} {} nodes, depth {}, {} triangle references ({:.2} per triangle)",
                accel_name(a.structure.accel()),
                r.tree_nodes,
                r.tree_depth,
                r.references,
                r.references as f64 / r.triangles.max(1) as f64
            );
            println!(
                "build        {:.3} s, structure {} bytes ({:.1} bytes/triangle)",
                r.grid_seconds,
                r.structure_bytes,
                r.structure_bytes as f64 / r.triangles.max(1) as f64
            );
        }
        Accel::None => {}
        Accel::Grid => {
            let [x, y, z] = r.dims;
            println!(
                "grid         {x} x {y} x {z} = {} cells, {} non-empty ({:.1}%)",
                r.cells,
                r.full_cells,
                100.0 * r.full_cells as f64 / r.cells.max(1) as f64
            );
            println!(
                "lists        {} entries ({} triangle references, {:.2} per triangle)",
                r.list_entries,
                r.references,
                r.references as f64 / r.triangles.max(1) as f64
            );
            println!("grid build   {:.3} s", r.grid_seconds);
        }
    }
    println!(
        "image        {} bytes ({}), {:.1} bytes/triangle",
        r.image_bytes,
        fmt_bytes(r.image_bytes),
        r.image_bytes as f64 / r.triangles.max(1) as f64
    );
    println!("total        {elapsed:.3} s -> {}", a.output.display());
    Ok(())
}

/// The flat scene `a` asks for, read or generated and built: what it was, and the scene.
fn build_flat(a: &BuildArgs) -> Result<(String, scene::Scene)> {
    Ok(match (&a.generate, &a.scene) {
        (Some(spec), _) => {
            let g = crate::input::generate::generate(spec, a.view.as_deref())?;
            let scene = scene::build(
                g.name.clone(),
                g.mesh,
                Vec::new(),
                g.camera.merged(a.camera.spec()?),
                &a.structure.options(),
            )?;
            (format!("generated {}", g.name), scene)
        }
        (None, Some(path)) => {
            let scene::Source::Mesh { name, mesh, warnings, camera } = scene::load_source(Some(path))? else {
                bail!("{}: is already a scene image; build takes an OBJ file", path.display());
            };
            // The camera file and flags, over the OBJ's sidecar camera, become the image's default.
            let scene = scene::build(name, mesh, warnings, camera.merged(a.camera.spec()?), &a.structure.options())?;
            (path.display().to_string(), scene)
        }
        (None, None) => bail!("build: name an OBJ file or --generate a scene"),
    })
}

/// `raypipe build --bricks`.
fn cmd_build_bricked(a: BuildArgs) -> Result<()> {
    use crate::build::bricks::source::{MeshSource, ObjSource, PlySource, PowerPlantSource, TriangleSource};
    let start = Instant::now();
    let bopts = crate::build::bricks::BrickOptions {
        brick_bytes: a.bricks.brick_size,
        codec: a.bricks.codec,
        progress: true,
        memory_budget: a.bricks.memory_budget,
        copies: a.bricks.replicate,
    };
    let camera_flags = a.camera.spec()?;
    let streamed = match &a.generate {
        Some(spec) => crate::input::generate::generate_stream(spec, a.view.as_deref())?,
        None => None,
    };
    let (mut source, warnings, camera): (Box<dyn TriangleSource>, Vec<String>, _) = match (&a.generate, &a.scene) {
        (Some(spec), _) if streamed.is_some() => {
            let Some((plant, camera)) = streamed else { bail!("internal error: no stream") };
            (Box::new(PowerPlantSource { name: format!("generated {spec}"), plant }), Vec::new(), camera)
        }
        (Some(spec), _) => {
            let g = crate::input::generate::generate(spec, a.view.as_deref())?;
            g.mesh.validate(&g.name)?;
            (Box::new(MeshSource { name: format!("generated {}", g.name), mesh: g.mesh }), Vec::new(), g.camera)
        }
        (None, Some(path)) if has_suffix(path, &[".ply", ".ply.gz"]) => {
            // A PLY is streamed: only its vertices are held, within the budget.
            let budget = a.bricks.memory_budget.unwrap_or(u64::MAX);
            let ply = crate::input::ply_stream::PlyStream::open(path, budget)?;
            (Box::new(PlySource { ply }), Vec::new(), scene::sidecar_camera_spec(path)?)
        }
        (None, Some(path)) if has_suffix(path, &[".obj", ".obj.gz"]) => {
            // An OBJ is streamed too: only its vertex tables are held.
            let budget = a.bricks.memory_budget.unwrap_or(u64::MAX);
            let obj = crate::input::obj_stream::ObjStream::open(path, budget)?;
            let warnings = obj.notes.warnings.clone();
            (Box::new(ObjSource { obj }), warnings, scene::sidecar_camera_spec(path)?)
        }
        (None, Some(path)) => {
            let scene::Source::Mesh { name, mesh, warnings, camera } = scene::load_source(Some(path))? else {
                bail!("{}: is already a scene image; build takes an OBJ file", path.display());
            };
            mesh.validate(&name)?;
            (Box::new(MeshSource { name, mesh }), warnings, camera)
        }
        (None, None) => bail!("build: name an OBJ file or --generate a scene"),
    };
    let name = source.name().to_string();
    let camera = camera.merged(camera_flags);
    let r = crate::build::bricks::build_bricked_from(
        source.as_mut(),
        warnings,
        camera,
        &a.structure.options(),
        &bopts,
        &a.output,
    )?;
    crate::output::warnings::warnings(&name, &r.warnings);
    let per_tri = |b: u64| b as f64 / r.triangles.max(1) as f64;
    println!("scene        {name}");
    println!(
        "triangles    {} ({} in bricks, {:.3} per triangle), vertices {} in {} bricks ({})",
        r.triangles,
        r.references,
        r.references as f64 / r.triangles.max(1) as f64,
        r.vertices,
        r.bricks,
        accel_name(a.structure.accel())
    );
    println!(
        "bricks       {} decompressed ({:.1} bytes/triangle), largest {}",
        fmt_bytes(r.image_bytes as usize),
        per_tri(r.image_bytes),
        fmt_bytes(r.largest_brick as usize)
    );
    println!(
        "stored       {} with {} ({:.2}:1, {:.1} bytes/triangle)",
        fmt_bytes(r.stored_bytes as usize),
        a.bricks.codec.name(),
        r.image_bytes as f64 / r.stored_bytes.max(1) as f64,
        per_tri(r.stored_bytes)
    );
    let [p, b, w] = r.seconds;
    println!("phases       partition {p:.3} s, bricks {b:.3} s, write {w:.3} s");
    println!("lights       {}", r.lights);
    if let Some(peak) = r.peak_rss {
        let budget =
            a.bricks.memory_budget.map_or("no budget".to_string(), |b| format!("budget {}", fmt_bytes(b as usize)));
        println!("memory       peak resident {} ({budget})", fmt_bytes(peak as usize));
    }
    println!(
        "total        {:.3} s -> {} ({})",
        start.elapsed().as_secs_f64(),
        a.output.display(),
        fmt_bytes(r.file_bytes as usize)
    );
    Ok(())
}

/// True if the file's name ends with one of `suffixes` (lower case), in any case.
fn has_suffix(path: &std::path::Path, suffixes: &[&str]) -> bool {
    let f = path.file_name().and_then(|f| f.to_str()).unwrap_or("").to_ascii_lowercase();
    suffixes.iter().any(|s| f.ends_with(s))
}

/// `raypipe build --instances`, or of a scene file with `[[instance]]` entries.
fn cmd_build_instanced(a: BuildArgs) -> Result<()> {
    let start = Instant::now();
    let path = a.scene.as_deref().ok_or_else(|| anyhow!("build --instances: name a scene file or glTF file"))?;
    let mut scene = crate::input::instanced::load_instanced_scene(path)?;
    scene.camera = scene.camera.merged(a.camera.spec()?);
    let built = scene.build(&a.structure.options())?;
    for w in &built.report.warnings {
        eprintln!("warning: {w}");
    }
    let view = raypipe_core::image::instanced::InstancedView::parse(&built.bytes)
        .map_err(|e| anyhow!("internal error: built an invalid instanced scene: {e}"))?;
    let camera = view.globals().camera().ok_or_else(|| anyhow!("internal error: built scene lacks a camera"))?;
    render::eye_rays(camera, "camera")?;
    output::write_bytes(&a.output, &built.bytes)?;
    let (h, r) = (view.header(), &built.report);
    println!("scene        {} (instanced)", path.display());
    println!(
        "instances    {} of {} meshes: {} triangles drawn, {} stored ({:.1}× shared)",
        h.instance_count,
        h.bottom_count,
        h.triangle_count,
        h.stored_triangles,
        h.triangle_count as f64 / h.stored_triangles.max(1) as f64
    );
    println!(
        "{:<12} in each mesh, {} nodes in all; top level {} nodes over the instances",
        accel_name(a.structure.accel()),
        r.tree_nodes,
        h.node_count
    );
    println!("lights       {}", r.lights);
    println!(
        "image        {} ({}) in {:.3} s (structures {:.3} s)",
        a.output.display(),
        fmt_bytes(built.bytes.len()),
        start.elapsed().as_secs_f64(),
        r.grid_seconds
    );
    Ok(())
}
