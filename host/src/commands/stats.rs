//! `raypipe stats`: Purcell's scene statistics for a view.

use std::path::Path;

use crate::render::packets::PacketSize;
use crate::render::tracer::IntersectorKind;
use crate::render::{Algorithm, RenderOptions};
use crate::study::batch_stats::{gather_batch, BatchQuery};
use crate::study::scene_stats;
use anyhow::Result;
use raypipe_core::image::CameraRecord;
use raypipe_core::DataClass;
use raypipe_core::SceneView;

use super::{camera_for, lights_summary, load_scene, structure_summary, warn};

use super::args::AlgoArgs;
use super::args::CameraArgs;
use super::args::RunArgs;
use super::args::StructureArgs;
use super::trace::Query;
use clap::Args;
use std::path::PathBuf;

/// `raypipe stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Also trace the view as packets of this many rays and report their SIMD efficiency.
    #[arg(long, value_enum, default_value_t = PacketSize::Single)]
    pub packet: PacketSize,
    /// Also report what an algorithm costs against ray casting (rays per pixel by kind,
    /// traversal steps, triangle tests, shading, scene bytes).
    #[command(flatten)]
    pub algo: AlgoArgs,
    /// An OBJ file or a scene image; the built-in Cornell box when omitted.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub camera: CameraArgs,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Per-pixel cost heatmaps of the primary rays: PREFIX-steps.png (nodes visited),
    /// PREFIX-tests.png (triangle tests), PREFIX-bytes.png (scene bytes read).
    #[arg(long, value_name = "PREFIX")]
    pub cost_image: Option<PathBuf>,
    #[command(flatten)]
    pub cache: super::args::CacheArgs,
    /// The statistics of a ray batch instead of the view's primary rays: a .npy array
    /// as `trace --rays` reads it (N × 6 or N × 8), each ray traced alone by the kernel
    /// `trace` runs on single rays.
    #[arg(long, value_name = "NPY", conflicts_with_all = ["cost_image", "packet"])]
    pub rays: Option<PathBuf>,
    /// With --rays: what each ray asks (the any-hit query keeps the shadow cache, as
    /// `trace --query any` does).
    #[arg(long, value_enum, default_value_t = Query::Closest, requires = "rays")]
    pub query: Query,
}

pub(crate) fn cmd_stats(a: StatsArgs) -> Result<()> {
    a.run.check()?;
    if let Some(path) = a.scene.as_deref().filter(|p| crate::input::bricked::is_bricked(p)) {
        if a.rays.is_some() {
            anyhow::bail!("{}: --rays needs a scene image or a mesh, not a bricked scene", path.display());
        }
        return super::bricked_study::stats(path, &a.camera, &a.run, &a.cache, a.packet);
    }
    let scene = load_scene(a.scene.as_deref(), &a.structure, &a.camera)?;
    warn(&scene);
    let view = scene.view()?;
    if let Some(rays) = &a.rays {
        return batch_stats(&scene.name, &view, rays, a.query, &a.run);
    }
    let cam = camera_for(&view, &a.camera)?;
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let opts = RenderOptions {
        threads: a.run.threads,
        intersector: kind,
        progress: false,
        packet: a.packet,
        ..Default::default()
    };
    if let Some(prefix) = &a.cost_image {
        crate::output::check_writable(prefix)?;
    }
    let s = scene_stats::gather(&view, &cam, &opts)?;
    if let Some(prefix) = &a.cost_image {
        write_cost_images(prefix, &view, &cam, &opts)?;
    }
    println!("scene                     {} ({} triangles)", scene.name, view.triangle_count());
    println!("structure                 {}", structure_summary(&view));
    println!("lights                    {}", lights_summary(&scene)?);
    let (node, leaf) = if view.grid().is_some() { ("voxels", "non-empty voxels") } else { ("nodes", "leaves") };
    println!("view                      {}x{} = {} primary rays", cam.width, cam.height, s.rays);
    println!("rays that hit             {:.2}%", 100.0 * s.hits as f64 / s.rays.max(1) as f64);
    println!("rays missing scene bounds {:.2}%", 100.0 * s.missed_bounds as f64 / s.rays.max(1) as f64);
    println!("{:<25} avg {:.2}, max {}", format!("{node} visited per ray"), s.per_ray(s.total.nodes), s.max_nodes);
    println!("{:<25} avg {:.2}", format!("{leaf} per ray"), s.per_ray(s.total.leaves));
    println!("triangles tested per ray  avg {:.2}, max {}", s.per_ray(s.total.tri_tests), s.max_tri_tests);
    println!(
        "list entries read         {} total, {:.2} per ray",
        s.total.list_entries,
        s.per_ray(s.total.list_entries)
    );
    let classes: Vec<String> =
        DataClass::ALL.iter().map(|c| format!("{} {:.1}", c.name(), s.per_ray(s.bytes.bytes[*c as usize]))).collect();
    println!("bytes read per ray        {}", classes.join(", "));
    print_packets(&view, &cam, &opts, a.packet, s.rays)?;
    if a.algo.algo != Algorithm::Cast {
        let mut algo_opts = opts;
        a.algo.apply(&mut algo_opts)?;
        print_algorithm(&view, &cam, &algo_opts)?;
    }
    Ok(())
}

/// `stats --rays`: the counters of a ray batch, per ray.
fn batch_stats(name: &str, view: &SceneView<'_>, path: &Path, query: Query, run: &RunArgs) -> Result<()> {
    let (rays, invalid) = crate::render::batch::read_rays(path)?;
    let kind = IntersectorKind::resolve(run.intersector, view);
    let q = match query {
        Query::Closest => BatchQuery::Closest,
        Query::Any => BatchQuery::Any,
    };
    let s = gather_batch(view, &rays, &invalid, q, kind, run.threads)?;
    let not_rays = invalid.iter().filter(|b| **b).count();
    let (node, leaf) = if view.grid().is_some() { ("voxels", "non-empty voxels") } else { ("nodes", "leaves") };
    let what = if q == BatchQuery::Any { "rays blocked" } else { "rays that hit" };
    println!("scene                     {name} ({} triangles)", view.triangle_count());
    println!("structure                 {}", structure_summary(view));
    println!("rays                      {} from {} ({not_rays} rows are not rays)", s.rays, path.display());
    println!("{what:<25} {:.2}%", 100.0 * s.hits as f64 / s.rays.max(1) as f64);
    println!("{:<25} avg {:.2}, max {}", format!("{node} visited per ray"), s.per_ray(s.total.nodes), s.max_nodes);
    println!("{:<25} avg {:.2}", format!("{leaf} per ray"), s.per_ray(s.total.leaves));
    println!("triangles tested per ray  avg {:.2}, max {}", s.per_ray(s.total.tri_tests), s.max_tri_tests);
    let per_class = |v: &[u64; 4]| -> Vec<String> {
        DataClass::ALL.iter().map(|c| format!("{} {:.2}", c.name(), s.per_ray(v[*c as usize]))).collect()
    };
    println!("reads per ray             {}", per_class(&s.bytes.reads).join(", "));
    println!("bytes read per ray        {}", per_class(&s.bytes.bytes).join(", "));
    Ok(())
}

/// Writes the host's cost images: nodes, triangle tests and scene bytes per pixel.
fn write_cost_images(prefix: &Path, view: &SceneView<'_>, cam: &CameraRecord, opts: &RenderOptions) -> Result<()> {
    let c = scene_stats::cost_image(view, cam, opts)?;
    let images = [
        ("steps", "nodes visited per pixel"),
        ("tests", "triangle tests per pixel"),
        ("bytes", "scene bytes read per pixel"),
    ];
    for (k, (what, title)) in images.into_iter().enumerate() {
        let values: Vec<f64> = c.iter().map(|v| v[k]).collect();
        crate::study::cost_image::write(
            &crate::study::cost_image::path(prefix, what),
            cam.width,
            cam.height,
            &values,
            title,
        )?;
    }
    Ok(())
}

/// Prints the packets' figures (`packet` lanes; `rays` primary rays traced).
fn print_packets(
    view: &SceneView<'_>,
    cam: &CameraRecord,
    opts: &RenderOptions,
    packet: PacketSize,
    rays: u64,
) -> Result<()> {
    if packet != PacketSize::Single && !crate::render::tracer::has_packet_kernel(view) {
        println!("packets {:<17} none: the structure has no packet kernel (rays traced one by one)", packet.label());
    } else if packet != PacketSize::Single {
        let p = scene_stats::gather_packets(view, cam, opts, packet)?;
        let n = packet.rays() as f64;
        println!(
            "packets {:<17} {} packets, {:.1} node visits per packet, SIMD efficiency {:.1}%, {:.2} triangle tests per ray",
            packet.label(),
            p.packets,
            p.counters.visits as f64 / p.packets.max(1) as f64,
            100.0 * p.counters.active_lanes as f64 / (p.counters.visits.max(1) as f64 * n),
            p.counters.tri_tests as f64 / rays.max(1) as f64
        );
    }
    Ok(())
}

/// Prints what the algorithm of `algo_opts` costs against ray casting.
fn print_algorithm(view: &SceneView<'_>, cam: &CameraRecord, algo_opts: &RenderOptions) -> Result<()> {
    let cast = scene_stats::algorithm_costs(view, cam, &RenderOptions { algo: Algorithm::Cast, ..*algo_opts })?;
    let c = scene_stats::algorithm_costs(view, cam, algo_opts)?;
    let px = c.pixels.max(1) as f64;
    let kinds: Vec<String> = raypipe_core::shade::ray_record::RayKind::ALL
        .iter()
        .map(|k| format!("{} {:.2}", k.name(), c.rays[*k as usize] as f64 / px))
        .collect();
    let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    println!("algorithm                 {:?}", algo_opts.algo);
    println!("rays per pixel            {}; total {:.2}", kinds.join(", "), c.rays.iter().sum::<u64>() as f64 / px);
    println!(
        "relative to ray casting   traversal steps x{:.2}, triangle tests x{:.2}, shading x{:.2}, scene bytes x{:.2}",
        ratio(c.steps, cast.steps),
        ratio(c.tests, cast.tests),
        ratio(c.shades, cast.shades),
        ratio(c.bytes, cast.bytes)
    );
    if algo_opts.algo == Algorithm::Shadow {
        let m = scene_stats::coverage_mismatch(view, cam, algo_opts)?;
        let pct = |n: u64| 100.0 * n as f64 / m.pixels.max(1) as f64;
        println!(
            "shadow caster coverage    rasterization and ray casting disagree at {:.4}% of pixels ({} of {}); {:.4}% at another depth, {} where both see the same point of overlapping coplanar triangles; {} triangles clipped at the near plane",
            pct(m.differ),
            m.differ,
            m.pixels,
            pct(m.differ - m.coplanar),
            m.coplanar,
            m.clipped
        );
    }
    Ok(())
}
