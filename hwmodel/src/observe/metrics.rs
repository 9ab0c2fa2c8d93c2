//! A report's headline figures as one flat list of named numbers — what a sweep row, a
//! plot axis or a report diff speaks of: frame rate and cycles, the bottleneck's
//! ingredients (busy share and stall reasons per kind of unit), bytes per ray by data
//! class, cache hit rates by class, SIMD efficiency, and energy. Names are stable: they
//! are CSV column names and `--y` arguments of `raypipe plot`.

use crate::memory::traffic::{CLASS_NAMES, FRAMEBUFFER};
use crate::observe::report::{Report, UnitReport};
use crate::observe::stall::Stall;

/// The kinds of unit the metrics aggregate over, with the report's name prefix.
pub const UNIT_KINDS: [(&str, &str); 4] = [
    ("traversal", "traversal"),
    ("intersection", "intersection"),
    ("shading", "rgs.shade"),
    ("generate", "rgs.generate"),
];

/// The report's headline figures, in a fixed order.
pub fn metrics(r: &Report) -> Vec<(String, f64)> {
    let mut m: Vec<(String, f64)> = vec![
        ("fps".into(), r.frames_per_second),
        ("cycles".into(), r.cycles as f64),
        ("rays".into(), r.rays as f64),
        ("mrays_per_s".into(), r.rays_per_second / 1e6),
        ("traversal_steps".into(), r.traversal_steps as f64),
        ("ray_steps".into(), r.ray_steps as f64),
        ("steps_per_ray".into(), r.steps_per_ray),
        ("triangle_tests".into(), r.triangle_tests as f64),
        ("tests_per_ray".into(), r.tests_per_ray),
        ("memory_utilization".into(), r.memory.utilization),
        ("bytes_per_ray".into(), r.memory.bytes_per_ray),
    ];
    let rays = r.rays.max(1) as f64;
    for name in CLASS_NAMES {
        let b = r.memory.bytes.get(name).copied().unwrap_or(0);
        m.push((format!("bytes_per_ray.{name}"), b as f64 / rays));
    }
    // Framebuffer writes are posted straight to memory: no cache sees them.
    for name in &CLASS_NAMES[..FRAMEBUFFER] {
        let (mut hits, mut all) = (0u64, 0u64);
        for c in &r.caches {
            if let Some(k) = c.classes.get(*name) {
                hits += k.hits;
                all += k.hits + k.merged + k.misses;
            }
        }
        // A class no cache saw (no accesses) has no hit rate; NaN keeps the column.
        m.push((format!("hit_rate.{name}"), if all > 0 { hits as f64 / all as f64 } else { f64::NAN }));
    }
    let l2 = |k: &str| r.memory.l2.get(k).copied().unwrap_or(0);
    let l2_all = l2("hits") + l2("merged") + l2("misses");
    m.push(("hit_rate.l2".into(), if l2_all > 0 { l2("hits") as f64 / l2_all as f64 } else { f64::NAN }));
    for (kind, prefix) in UNIT_KINDS {
        let units: Vec<&UnitReport> = r.units.iter().filter(|u| u.name.starts_with(prefix)).collect();
        let ticked: u64 = units.iter().map(|u| u.busy_cycles + u.stall_cycles + u.idle_cycles).sum();
        let share = |n: u64| if ticked > 0 { n as f64 / ticked as f64 } else { f64::NAN };
        let busy: u64 = units.iter().map(|u| u.busy_cycles).sum();
        let stall: u64 = units.iter().map(|u| u.stall_cycles).sum();
        m.push((format!("busy.{kind}"), share(busy)));
        m.push((format!("stall.{kind}"), share(stall)));
        let (issues, eff): (u64, f64) =
            units.iter().fold((0, 0.0), |(n, e), u| (n + u.issues, e + u.simd_efficiency * u.issues as f64));
        m.push((format!("simd.{kind}"), if issues > 0 { eff / issues as f64 } else { f64::NAN }));
        if kind == "generate" {
            continue;
        }
        for s in Stall::ALL {
            let n: u64 = units.iter().map(|u| u.stall_reasons.get(s.name()).copied().unwrap_or(0)).sum();
            m.push((format!("stall.{kind}.{}", s.name()), share(n)));
        }
    }
    if let Some(d) = &r.memory.dram {
        m.push(("dram.row_hit_rate".into(), d.row_hit_rate));
    }
    if let Some(d) = &r.memory.dramsim3 {
        m.push(("dramsim3.bandwidth_gb_s".into(), d.bandwidth_gb_s));
        m.push(("dramsim3.read_latency_ns".into(), d.read_latency_ns[0]));
        m.push(("dramsim3.read_latency_p99_ns".into(), d.read_latency_ns[2]));
        m.push(("dramsim3.row_hit_rate".into(), d.row_hit_rate));
        m.push(("dramsim3.refreshes".into(), d.refreshes as f64));
        m.push(("dramsim3.energy_mj".into(), d.energy_nj * 1e-6));
    }
    if let Some(e) = &r.energy {
        m.push(("energy_per_frame_mj".into(), e.joules_per_frame * 1e3));
        m.push(("energy_per_ray_nj".into(), e.joules_per_ray * 1e9));
        m.push(("power_w".into(), e.watts));
        m.push(("area_mm2".into(), e.area_mm2));
        m.extend(e.joules.iter().map(|(k, j)| (format!("energy_mj.{k}"), j * 1e3)));
    }
    m
}

/// The metric `name` of `r`, if there is one.
pub fn metric(r: &Report, name: &str) -> Option<f64> {
    metrics(r).into_iter().find(|(n, _)| n == name).map(|(_, v)| v)
}
