//! `raypipe stream`: Purcell's stream machine (raypipe_hw::stream) on a scene and a view.
//! The frame's image is checked against the host renderer's; the report comes as
//! terminal tables in the paper's shape (Table 2, kernel costs, Figures 7–9's numbers,
//! Table 3 against ray casting), JSON and charts.

use anyhow::{anyhow, Result};
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::{Intersector, SceneView, Vec3};
use raypipe_hw::stream::{CostModel, StreamConfig, StreamMachine, StreamReport};

use crate::hw::frame_setup::FrameSetup;
use crate::output::progress;
use crate::render::gbuffer::gbuffer_visibility;
use crate::render::{eye_rays, Frame};
use crate::with_intersector;

/// One frame on the stream machine: the image and the report.
pub fn run_stream(
    scene: &SceneView<'_>,
    camera: &CameraRecord,
    cfg: &StreamConfig,
    costs: &CostModel,
    setup: &FrameSetup,
) -> Result<(Frame, StreamReport)> {
    let eye = eye_rays(camera, "camera")?.with_sampler(setup.sampler);
    let background = Vec3::from(camera.background);
    with_intersector!(setup.intersector, I => run_with::<I>(scene, eye, background, cfg, costs, setup))
}

fn run_with<I: Intersector>(
    scene: &SceneView<'_>,
    eye: EyeRays,
    background: Vec3,
    cfg: &StreamConfig,
    costs: &CostModel,
    setup: &FrameSetup,
) -> Result<(Frame, StreamReport)> {
    let FrameSetup { shader, shadow_caster, show_progress, .. } = *setup;
    let mut m = StreamMachine::<I>::new(*scene, eye, background, shader, cfg, costs.clone()).map_err(|e| anyhow!(e))?;
    if shadow_caster {
        // Visibility from the host's rasterizer (the G-buffer pass), as on the host.
        m.set_visibility((0..eye.samples()).flat_map(|s| gbuffer_visibility::<I>(scene, &eye, s)).collect());
    }
    let bar = progress::bar(0, "stream", show_progress);
    m.run(|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })
    .map_err(|e| anyhow!("stream machine: {e}"))?;
    bar.finish_and_clear();
    let (width, height) = m.size();
    Ok((Frame::from_radiance(width, height, m.radiance_image()), m.report()))
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or("-".into(), |v| format!("{v:.digits$}"))
}

fn si(x: f64) -> String {
    let a = x.abs();
    if a >= 1e9 {
        format!("{:.2}G", x / 1e9)
    } else if a >= 1e6 {
        format!("{:.2}M", x / 1e6)
    } else if a >= 1e3 {
        format!("{:.1}k", x / 1e3)
    } else {
        format!("{x:.0}")
    }
}

/// Table 2's row as the paper lays it out.
pub fn table2(r: &StreamReport, label: &str) -> String {
    let t = &r.table2;
    let mut s = String::new();
    let h = ["Tr", "In", "other", "passes", "maxTr", "maxIn", "optimal", "ratio", "SIMDt", "SIMDi", "SIMD", "paper"];
    s += &format!(
        "{:<28} {:>6} {:>6} {:>6} {:>7} {:>6} {:>6} {:>7} {:>6}  {:>5} {:>5} {:>5} {:>6}\n",
        "Table 2", h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8], h[9], h[10], h[11]
    );
    s += &format!(
        "{:<28} {:>6} {:>6} {:>6} {:>7} {:>6} {:>6} {:>7} {:>6}  {:>5} {:>5} {:>5} {:>6}\n",
        label,
        t.traverse_passes,
        t.intersect_passes,
        t.other_passes,
        t.total_passes,
        t.max_steps,
        t.max_intersections,
        t.optimal_passes,
        opt(t.ratio_to_optimal, 2),
        opt(t.simd_traverse, 2),
        opt(t.simd_intersect, 2),
        opt(t.simd_overall, 2),
        opt(t.simd_screen, 3)
    );
    s
}

/// The kernel table (Table 1's columns, per invocation) with each kernel's totals
/// (Figure 7).
pub fn kernel_table(r: &StreamReport) -> String {
    let mut s = format!(
        "{:<12} {:>7} {:>4} {:>4} {:>7}   {:>10} {:>10} {:>6} {:>10} {:>10}   (costs: {})\n",
        "kernel", "instr", "R", "W", "M", "invoked", "instr", "share", "state wds", "random wds", r.costs.source
    );
    let total = r.instructions.max(1) as f64;
    for k in &r.kernels {
        s += &format!(
            "{:<12} {:>7} {:>4} {:>4} {:>7.2}   {:>10} {:>10} {:>5.1}% {:>10} {:>10}\n",
            k.kernel,
            k.instructions,
            k.r,
            k.w,
            k.m,
            si(k.totals.invocations as f64),
            si(k.totals.instructions as f64),
            100.0 * k.totals.instructions as f64 / total,
            si((k.totals.state_read + k.totals.state_written) as f64),
            si(k.totals.random_words),
        );
    }
    s
}

/// Data types (Figures 8 and 9): words, cache hit rates, bandwidth with and without the
/// cache.
pub fn class_table(r: &StreamReport) -> String {
    let mut s = format!(
        "{:<13} {:>10} {:>9} {:>12} {:>12}   (cache: {})\n",
        "data type", "words", "hit rate", "no cache", "with cache", r.config.cache
    );
    for c in &r.classes {
        s += &format!(
            "{:<13} {:>10} {:>9} {:>11}B {:>11}B\n",
            c.class,
            si(c.words as f64),
            c.hit_rate.map_or("-".into(), |h| format!("{:.1}%", 100.0 * h)),
            si(c.bytes_without_cache as f64),
            si(c.bytes_with_cache as f64)
        );
    }
    s
}

/// The frame on the machine.
pub fn frame_lines(r: &StreamReport) -> String {
    let f = &r.frame_time;
    let t = &r.traffic;
    format!(
        "traffic       random {}B (no cache {}B), state {}B ({} words read, {} written), stencil {}B ({} reads, {} writes)\n\
         machine       {}: {} instructions = {:.2} ms, {}B = {:.2} ms -> frame {:.2} ms, {} bound\n",
        si(t.random as f64),
        si(t.random_uncached as f64),
        si(t.state as f64),
        si(r.state_read as f64),
        si(r.state_written as f64),
        si(t.stencil as f64),
        si(r.stencil_reads as f64),
        si(r.stencil_writes as f64),
        r.config.machine,
        si(r.instructions as f64),
        f.compute_s * 1e3,
        si(t.total as f64),
        f.memory_s * 1e3,
        f.frame_s * 1e3,
        match f.bound {
            raypipe_hw::stream::gpu::Bound::Compute => "compute",
            raypipe_hw::stream::gpu::Bound::Bandwidth => "bandwidth",
        }
    )
}

/// Table 3's row: an algorithm's instructions and bandwidth relative to ray casting,
/// beside the paper's (Purcell 2002 Table 3: the bunny on the branching machine).
pub fn table3(algo: &str, r: &StreamReport, cast: &StreamReport) -> String {
    let ratio = |a: u64, b: u64| if b > 0 { format!("{:.2}", a as f64 / b as f64) } else { "-".into() };
    let paper = match algo {
        "shadow" => "0.85 / 1.15",
        "whitted" => "2.62 / 3.00",
        "path" => "3.24 / 4.06",
        _ => "-",
    };
    format!(
        "{:<28} {:>12} {:>12} {:>14}\n{:<28} {:>12} {:>12} {:>14}\n",
        "Table 3 (relative to cast)",
        "instructions",
        "bandwidth",
        "paper (i / b)",
        algo,
        ratio(r.instructions, cast.instructions),
        ratio(r.traffic.total, cast.traffic.total),
        paper
    )
}
