//! `raypipe info` of an instanced scene: its instances, the meshes they share and each
//! mesh's structure, the top level, and the globals image's lights and camera.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use raypipe_core::image::{AccelKind, NULL_INDEX};

use super::fmt_bytes;
use crate::input::instanced::load_instanced;
use crate::scene::BuildOptions;

/// Prints the instanced scene at `path` (a source is built with `opts` first).
pub(crate) fn cmd_info_instanced(path: &Path, opts: &BuildOptions) -> Result<()> {
    let open = Instant::now();
    let scene = load_instanced(path, opts)?;
    let s = scene.instances()?;
    let opened = open.elapsed().as_secs_f64();
    let view = scene.view()?;
    let h = view.header();
    println!("scene       {} (instanced, format version {})", scene.name, h.version);
    println!("file        {} bytes ({}), index {} bytes", h.total_size, fmt_bytes(h.total_size as usize), h.index_size);
    if scene.report.is_none() {
        println!("open        {opened:.4} s (mapped; index and every mesh validated)");
    }
    println!(
        "bounds      ({}, {}, {}) .. ({}, {}, {})",
        h.bounds_min[0], h.bounds_min[1], h.bounds_min[2], h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]
    );
    println!(
        "triangles   {} drawn, {} stored ({:.1}× shared)",
        h.triangle_count,
        h.stored_triangles,
        h.triangle_count as f64 / h.stored_triangles.max(1) as f64
    );
    let overrides = s.top.instances().iter().filter(|i| i.material != NULL_INDEX).count();
    println!(
        "instances   {} of {} meshes ({overrides} with an override material); top-level BVH of {} nodes",
        h.instance_count, h.bottom_count, h.node_count
    );
    for (b, rec) in view.bottoms().iter().enumerate() {
        let uses = s.top.instances().iter().filter(|i| i.bottom == b as u32).count();
        let accel = AccelKind::from_u32(rec.accel).map_or("?".to_string(), |k| format!("{k:?}").to_lowercase());
        println!(
            "mesh {b:<6} {} triangles, {} vertices, {accel}, {}, placed {uses}×",
            rec.triangle_count,
            rec.vertex_count,
            fmt_bytes(rec.size as usize)
        );
    }
    for (i, inst) in s.top.instances().iter().enumerate().take(8) {
        let t = inst.to_world;
        println!(
            "instance {i:<2} mesh {}, translate ({}, {}, {}), linear [{} {} {}; {} {} {}; {} {} {}]{}",
            inst.bottom,
            t[3],
            t[7],
            t[11],
            t[0],
            t[1],
            t[2],
            t[4],
            t[5],
            t[6],
            t[8],
            t[9],
            t[10],
            if inst.material == NULL_INDEX { String::new() } else { format!(", material {}", inst.material) }
        );
    }
    if s.top.instances().len() > 8 {
        println!("…           {} more instances", s.top.instances().len() - 8);
    }
    println!("lights      {} in the globals image", s.globals.light_count());
    if let Some(c) = s.globals.camera() {
        println!(
            "camera      eye ({}, {}, {}), look at ({}, {}, {}), {}x{}",
            c.eye[0], c.eye[1], c.eye[2], c.look_at[0], c.look_at[1], c.look_at[2], c.width, c.height
        );
    }
    Ok(())
}
