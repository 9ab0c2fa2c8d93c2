//! The subcommands, one file each: its arguments, then what it does (parse → call →
//! print); `args.rs` holds the flag groups several share, and this file the helpers
//! they share. [`crate::cli`] dispatches to them.
// The argument docs are `--help` text, written for a terminal: `[fixed]` and `<part>`
// there are TOML tables and placeholders, not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

pub mod animate;
pub mod args;
pub mod bench;
pub mod bench_updates;
pub mod bricked_study;
pub mod build;
pub mod cluster;
pub mod fixed_point;
pub mod info;
pub mod info_bricked;
pub mod info_instanced;
pub mod museum_art;
pub mod plot;
pub mod rays;
pub mod render;
pub mod render_bricked;
pub mod render_instanced;
pub mod report;
pub mod simulate;
mod simulate_animate;
mod simulate_instanced;
pub mod stats;
pub mod stream;
pub mod sweep;
pub mod trace;
pub mod trace_bricked;

use crate::scene::{self, Accel, Scene};
use anyhow::Result;
use args::{CameraArgs, StructureArgs};
use raypipe_core::image::{CameraRecord, LightRecord};
use std::path::Path;

pub(crate) fn warn(scene: &Scene) {
    if let Some(r) = &scene.report {
        crate::output::warnings::warnings(&scene.name, &r.warnings);
    }
}

pub(crate) fn accel_name(a: Accel) -> &'static str {
    match a {
        Accel::Grid => "grid",
        Accel::Kd => "kd-tree",
        Accel::Bvh => "BVH",
        Accel::Bvh4 => "BVH4",
        Accel::Bvh8 => "BVH8",
        Accel::None => "brute force",
    }
}

/// A short description of the structure a scene image holds.
pub(crate) fn structure_summary(view: &raypipe_core::SceneView<'_>) -> String {
    if let Some(g) = view.grid() {
        format!("grid {}x{}x{}", g.dims[0], g.dims[1], g.dims[2])
    } else if let Some(b) = view.bvh4() {
        format!("BVH4 {} nodes{}", b.node_count(), blocks_note(view))
    } else if let Some(b) = view.bvh8() {
        format!("BVH8 {} nodes{}", b.node_count(), blocks_note(view))
    } else if let Some(b) = view.bvh() {
        format!("BVH {} nodes", b.node_count())
    } else if let Some(k) = view.kdtree() {
        format!("kd {} nodes", k.node_count())
    } else {
        "none".to_string()
    }
}

pub(crate) fn blocks_note(view: &raypipe_core::SceneView<'_>) -> &'static str {
    if view.has_tri_blocks() {
        ", leaf blocks"
    } else {
        ""
    }
}

pub(crate) fn fmt_bytes(b: usize) -> String {
    if b >= 1 << 20 {
        format!("{:.2} MiB", b as f64 / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", b as f64 / 1024.0)
    }
}

/// The camera `args` make of the image's own (or the framing camera), unchecked.
pub(crate) fn camera_of(view: &raypipe_core::SceneView<'_>, args: &CameraArgs) -> Result<CameraRecord> {
    let base = match view.camera() {
        Some(c) => *c,
        None => {
            let (lo, hi) = view.bounds();
            scene::framing_camera(lo.to_array(), hi.to_array())
        }
    };
    args.resolve(&base)
}

pub(crate) fn camera_for(view: &raypipe_core::SceneView<'_>, args: &CameraArgs) -> Result<CameraRecord> {
    let cam = camera_of(view, args)?;
    // Each image's own rays are not checked one by one; its corners and centre stand
    // for them (they bound the directions, and share the eye).
    let eye = crate::render::eye_rays(&cam, "camera")?;
    let (w, h) = (eye.width.saturating_sub(1), eye.height.saturating_sub(1));
    let rays = [(0, 0), (w, 0), (0, h), (w, h), (w / 2, h / 2)].map(|(x, y)| eye.ray(x, y));
    warn_range(view, &rays, "camera rays (corners and centre)");
    if args.eye.is_some() && args.look_at.is_none() && args.camera.is_none() {
        let [x, y, z] = cam.look_at;
        crate::output::warnings::hint(&format!(
            "--eye without --look-at looks at the scene camera's point ({x:.3}, {y:.3}, {z:.3})"
        ));
    }
    if let Some(h) = crate::render::view_check::hint(view, &cam) {
        crate::output::warnings::hint(&h);
    }
    Ok(cam)
}

/// Warns about a scene or rays outside raypipe-core's guaranteed range.
pub(crate) fn warn_range(view: &raypipe_core::SceneView<'_>, rays: &[raypipe_core::Ray], what: &str) {
    for w in crate::input::range_check::warnings(view, rays, what) {
        crate::output::warnings::warning(&w);
    }
}

/// Loads the scene the user named for a view: an OBJ is built for the camera that will
/// render it (the default light is chosen for that camera); a built image gets the
/// command line's lights in place of its own, with a note, and a warning for each
/// structure flag it cannot apply; a built image whose default light was placed for its
/// own camera, rendered from another, gets it placed again, with a note.
pub(crate) fn load_scene(path: Option<&Path>, structure: &StructureArgs, camera: &CameraArgs) -> Result<Scene> {
    let mut opts = structure.options();
    opts.camera = camera.spec()?;
    let scene = scene::load(path, &opts)?;
    if scene.report.is_some() {
        return Ok(scene);
    }
    for flag in structure.flags_given() {
        crate::output::warnings::warning(&format!(
            "{}: {flag} applies when building from an OBJ; the image keeps its {}",
            scene.name,
            structure_summary(&scene.view()?)
        ));
    }
    if opts.lights.is_empty() {
        // An image whose point light raypipe placed for the image's own camera, rendered
        // from another view: place it again for this one.
        let view = scene.view()?;
        let own = view.camera().copied();
        let cam = camera_of(&view, camera)?;
        let moved = own.is_none_or(|c| (c.eye, c.look_at, c.up) != (cam.eye, cam.look_at, cam.up));
        if moved && view.has_default_light() {
            if let Some((relit, where_)) = scene::relight_for_camera(&scene, &cam)? {
                eprintln!("note: {}: the image's default light is placed again for this camera: {where_}", scene.name);
                return Ok(relit);
            }
        }
        return Ok(scene);
    }
    eprintln!("note: {}: the given lights replace the image's (its emitters stay area lights)", scene.name);
    scene::relight(&scene, &opts.lights)
}

/// One line on the scene's lights: what the build chose and why, or what an image holds.
pub(crate) fn lights_summary(scene: &Scene) -> Result<String> {
    if let Some(r) = scene.report.as_ref().filter(|r| !r.lights.is_empty()) {
        return Ok(r.lights.clone());
    }
    let view = scene.view()?;
    let mut counts = [0u32; LightRecord::MAX_KIND as usize + 1];
    for i in 0..view.light_count() {
        counts[view.light(i, &mut raypipe_core::NoProbe).kind as usize] += 1;
    }
    let parts: Vec<String> = (0..)
        .zip(counts)
        .filter(|(_, n)| *n > 0)
        .map(|(kind, n)| format!("{n} {}", LightRecord::kind_name(kind)))
        .collect();
    Ok(if parts.is_empty() { "none".into() } else { parts.join(", ") })
}

pub(crate) fn check_image_path(p: &Path) -> Result<()> {
    crate::output::ImageFormat::of(p).map(|_| ())
}
