//! `raypipe info`: what a scene is — bounds, triangles, materials, lights, camera, the
//! structure's statistics and the image's sections — without rendering anything.

use anyhow::Result;
use raypipe_core::image::{LightRecord, SectionEntry, SectionKind};
use raypipe_core::NoProbe;

use super::{lights_summary, load_scene, structure_summary, warn};

use super::args::CameraArgs;
use super::args::StructureArgs;
use clap::Args;
use std::path::PathBuf;

/// `raypipe info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Bricked scenes: measure each codec on a sample of the bricks (ratio, compression
    /// and decompression rates).
    #[arg(long)]
    pub codecs: bool,
}

pub(crate) fn cmd_info(a: InfoArgs) -> Result<()> {
    let opened = std::time::Instant::now();
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::bricked::is_bricked(p)) {
        return super::info_bricked::cmd_info_bricked(path, a.codecs);
    }
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::instanced::is_instanced(p)) {
        return super::info_instanced::cmd_info_instanced(path, &a.structure.options());
    }
    let scene = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
    warn(&scene);
    let view = scene.view()?;
    let open_secs = opened.elapsed().as_secs_f64();
    let (lo, hi) = view.bounds();
    let size = hi - lo;
    println!("scene       {}", scene.name);
    println!("image       {} bytes, format version {}", view.bytes().len(), raypipe_core::image::FORMAT_VERSION);
    if scene.report.is_none() {
        println!("open        {open_secs:.4} s (mapped and validated in place)");
    }
    println!(
        "bounds      ({}, {}, {}) .. ({}, {}, {}), size {} x {} x {}",
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, size.x, size.y, size.z
    );
    println!(
        "triangles   {} ({} vertices, {} object{})",
        view.triangle_count(),
        view.vertex_count(),
        view.object_count(),
        if view.object_count() == 1 { "" } else { "s" }
    );
    let materials = view.materials();
    let emissive = materials.iter().filter(|m| m.emission.iter().any(|&e| e > 0.0)).count();
    let textured = materials.iter().filter(|m| m.texture != raypipe_core::image::NULL_INDEX).count();
    let glossy = materials.iter().filter(|m| m.specular.iter().any(|&s| s > 0.0)).count();
    println!(
        "materials   {} ({} emissive, {} with a specular colour, {} textured; {} textures)",
        materials.len(),
        emissive,
        glossy,
        textured,
        view.texture_count()
    );
    println!("lights      {}", lights_summary(&scene)?);
    for i in 0..view.shading_light_count() {
        let l = view.light(i, &mut NoProbe);
        println!("  light {i}   {} position {:?} colour {:?}", LightRecord::kind_name(l.kind), l.position, l.color);
    }
    match view.camera() {
        Some(c) => println!(
            "camera      eye {:?} look-at {:?} up {:?} fov {}° {}x{}",
            c.eye, c.look_at, c.up, c.vfov_deg, c.width, c.height
        ),
        None => println!("camera      none (renders frame the scene from +z)"),
    }
    println!("structure   {}", structure_summary(&view));
    if let Some(r) = &scene.report {
        println!(
            "build       {:.3} s, {} triangle references ({:.2} per triangle), structure {} bytes",
            r.grid_seconds,
            r.references,
            r.references as f64 / r.triangles.max(1) as f64,
            r.structure_bytes
        );
        if r.tree_nodes > 0 {
            println!("tree        {} nodes, depth {}", r.tree_nodes, r.tree_depth);
        }
    }
    println!("sections    {:<18} {:>10} {:>12} {:>10}", "kind", "offset", "bytes", "records");
    for e in sections(view.bytes()) {
        let name = SectionKind::from_u32(e.kind).map_or("?", |k| k.name());
        println!("            {:<18} {:>10} {:>12} {:>10}", name, e.offset, e.size, e.count);
    }
    Ok(())
}

/// The section table of a valid image, in file order.
fn sections(bytes: &[u8]) -> Vec<SectionEntry> {
    let n = u32::from_le_bytes(bytes[20..24].try_into().unwrap_or([0; 4])) as usize;
    (0..n)
        .filter_map(|k| bytes.get(64 + 16 * k..80 + 16 * k))
        .map(bytemuck::pod_read_unaligned::<SectionEntry>)
        .collect()
}
