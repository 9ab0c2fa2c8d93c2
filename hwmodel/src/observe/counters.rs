//! The report's counters — every figure that adds up over time (cycles, rays, unit
//! cycles by activity and stall reason, FIFO pushes and occupancy cycles, cache lookups,
//! memory bytes and requests, DRAM bank counters) — as one flat, named list. Interval
//! statistics are differences of these between two moments, so the rows of a frame sum
//! to its report; ratios (hit rates, means, frames per second) are recomputed from them,
//! never summed.

use crate::observe::report::Report;

/// The counters of `r`, named by dotted path as in the report's JSON.
pub fn counters(r: &Report) -> Vec<(String, u64)> {
    let mut c: Vec<(String, u64)> = vec![
        ("cycles".into(), r.cycles),
        ("rays".into(), r.rays),
        ("traversal_steps".into(), r.traversal_steps),
        ("triangle_tests".into(), r.triangle_tests),
    ];
    c.extend(r.rays_by_kind.iter().map(|(k, n)| (format!("rays_by_kind.{k}"), *n)));
    for u in &r.units {
        let n = &u.name;
        c.push((format!("units.{n}.busy_cycles"), u.busy_cycles));
        c.push((format!("units.{n}.stall_cycles"), u.stall_cycles));
        c.push((format!("units.{n}.idle_cycles"), u.idle_cycles));
        c.push((format!("units.{n}.issues"), u.issues));
        c.push((format!("units.{n}.active_lanes"), u.active_lanes));
        c.push((format!("units.{n}.bytes"), u.bytes));
        c.extend(u.stall_reasons.iter().map(|(k, v)| (format!("units.{n}.stall_reasons.{k}"), *v)));
    }
    for f in &r.fifos {
        let n = &f.name;
        c.push((format!("fifos.{n}.pushes"), f.stats.pushes));
        c.push((format!("fifos.{n}.pops"), f.stats.pops));
        c.push((format!("fifos.{n}.full_stall_cycles"), f.stats.full_stall_cycles));
        c.push((format!("fifos.{n}.empty_stall_cycles"), f.stats.empty_stall_cycles));
        c.extend(f.stats.occupancy.iter().enumerate().map(|(k, v)| (format!("fifos.{n}.occupancy.{k}"), *v)));
    }
    for cache in &r.caches {
        for (class, k) in &cache.classes {
            let n = format!("caches.{}.classes.{class}", cache.name);
            c.push((format!("{n}.hits"), k.hits));
            c.push((format!("{n}.merged"), k.merged));
            c.push((format!("{n}.misses"), k.misses));
        }
    }
    c.extend(r.memory.bytes.iter().map(|(k, v)| (format!("memory.bytes.{k}"), *v)));
    c.push(("memory.total_bytes".into(), r.memory.total_bytes));
    c.push(("memory.requests".into(), r.memory.requests));
    c.extend(r.memory.l2.iter().map(|(k, v)| (format!("memory.l2.{k}"), *v)));
    if let Some(d) = &r.memory.dram {
        for (i, b) in d.banks.iter().enumerate() {
            c.push((format!("memory.dram.banks.{i}.accesses"), b.accesses));
            c.push((format!("memory.dram.banks.{i}.row_hits"), b.row_hits));
            c.push((format!("memory.dram.banks.{i}.row_empty"), b.row_empty));
            c.push((format!("memory.dram.banks.{i}.row_conflicts"), b.row_conflicts));
        }
    }
    c
}

/// `now − before`, counter by counter (a counter missing from `before` counts from 0:
/// a cache class first seen in this interval).
pub fn delta(now: &[(String, u64)], before: &[(String, u64)]) -> Vec<(String, u64)> {
    let old: std::collections::HashMap<&str, u64> = before.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    now.iter().map(|(k, v)| (k.clone(), v.saturating_sub(old.get(k.as_str()).copied().unwrap_or(0)))).collect()
}
