//! The chip's report as a terminal summary: the frame, the units, the FIFOs, the caches,
//! the memory and energy, and the bottleneck, for `raypipe simulate`.

use raypipe_hw::Report;

/// The chip's report as the summary `raypipe simulate` prints on the terminal.
pub fn summary(report: &Report) -> String {
    let mut out = String::new();
    let mut line = |s: String| {
        out.push_str(&s);
        out.push('\n');
    };
    if !report.run.scene.is_empty() {
        line(format!(
            "run            {} ({} {}, {}), scene {}",
            report.run.scene, report.run.structure, report.run.algorithm, report.run.intersector, report.run.scene_hash
        ));
    }
    line(format!("bottleneck     {}", report.bottleneck));
    line(format!(
        "frame          {}x{}, {} rays in packets of {}, {} cycles",
        report.width, report.height, report.rays, report.config.packet_size, report.cycles
    ));
    line(format!(
        "at {} MHz      {:.2} frames/s, {:.2} Mrays/s",
        report.config.clock_mhz,
        report.frames_per_second,
        report.rays_per_second / 1e6
    ));
    line(format!(
        "work           {} packet steps = {} ray steps ({:.2} per ray, SIMD {:.0}%), {} ray-triangle tests ({:.2} per ray)",
        report.traversal_steps,
        report.ray_steps,
        report.steps_per_ray,
        100.0 * report.traversal_simd_efficiency,
        report.triangle_tests,
        report.tests_per_ray
    ));
    let kinds: Vec<String> =
        report.rays_by_kind.iter().filter(|(_, &n)| n > 0).map(|(k, n)| format!("{k} {n}")).collect();
    line(format!("rays by kind   {} (stream peak {} records)", kinds.join(", "), report.ray_stream_peak));
    line("unit                busy  stall   idle   SIMD".to_string());
    for u in &report.units {
        let all = (u.busy_cycles + u.stall_cycles + u.idle_cycles).max(1) as f64;
        line(format!(
            "  {:<16} {:>5.1}% {:>5.1}% {:>5.1}% {:>5.1}%",
            u.name,
            100.0 * u.busy_cycles as f64 / all,
            100.0 * u.stall_cycles as f64 / all,
            100.0 * u.idle_cycles as f64 / all,
            100.0 * u.simd_efficiency
        ));
        let mut reasons: Vec<(&String, &u64)> = u.stall_reasons.iter().filter(|(_, &n)| n > 0).collect();
        reasons.sort_by(|a, b| b.1.cmp(a.1));
        if !reasons.is_empty() {
            let parts: Vec<String> =
                reasons.iter().take(3).map(|(k, n)| format!("{k} {:.1}%", 100.0 * **n as f64 / all)).collect();
            line(format!("    stalls: {}", parts.join(", ")));
        }
    }
    let (full, empty): (u64, u64) =
        report.fifos.iter().fold((0, 0), |(a, b), f| (a + f.stats.full_stall_cycles, b + f.stats.empty_stall_cycles));
    line(format!("fifos          {} full-stall cycles, {} empty-stall cycles in all", full, empty));
    for c in &report.caches {
        let parts: Vec<String> = c
            .classes
            .iter()
            .map(|(k, r)| format!("{k} {:.1}% hit ({} misses)", 100.0 * r.hit_rate, r.misses))
            .collect();
        if !parts.is_empty() {
            line(format!("cache {:<26} {}", c.name, parts.join(", ")));
        }
    }
    let m = &report.memory;
    let by_class: Vec<String> = m.bytes.iter().filter(|(_, &b)| b > 0).map(|(k, b)| format!("{k} {b}")).collect();
    line(format!(
        "memory         {}: {} bytes ({:.1} per ray; {}), {:.1}% busy",
        m.model,
        m.total_bytes,
        m.bytes_per_ray,
        by_class.join(", "),
        100.0 * m.utilization
    ));
    if let Some(d) = &m.dramsim3 {
        let [mean, _, p99, _] = d.read_latency_ns;
        line(format!(
            "dramsim3       {} ({}): {:.2} of {:.1} GB/s, reads {mean:.1} ns mean / {p99:.1} ns p99, \
             {:.1}% row hits, {} refreshes, {:.1} µJ",
            d.config.rsplit('/').next().unwrap_or(&d.config),
            d.protocol,
            d.bandwidth_gb_s,
            d.peak_gb_s,
            100.0 * d.row_hit_rate,
            d.refreshes,
            d.energy_nj / 1e3
        ));
    }
    let b = &report.bounds;
    let parts: Vec<String> = b.cycles.iter().map(|(k, c)| format!("{k} {c:.0}")).collect();
    line(format!(
        "lower bounds   {} cycles; achieved {:.2}x the largest ({})",
        parts.join(", "),
        b.achieved_over_largest,
        b.largest
    ));
    line(format!(
        "scene traffic  {:.2}x the {} distinct bytes read",
        m.traffic_over_compulsory, m.distinct_scene_bytes
    ));
    if let Some(e) = &report.energy {
        let mut parts: Vec<(&String, &f64)> = e.joules.iter().filter(|(_, j)| **j > 0.0).collect();
        parts.sort_by(|a, b| b.1.total_cmp(a.1));
        let parts: Vec<String> =
            parts.iter().map(|(k, j)| format!("{k} {:.0}%", 100.0 * **j / e.joules_per_frame.max(1e-30))).collect();
        line(format!(
            "energy         {:.4} mJ/frame, {:.2} nJ/ray, {:.3} W at {} MHz ({}); area {:.2} mm² ({} nm figures)",
            e.joules_per_frame * 1e3,
            e.joules_per_ray * 1e9,
            e.watts,
            report.config.clock_mhz,
            parts.join(", "),
            e.area_mm2,
            e.process_nm
        ));
    }
    out
}
