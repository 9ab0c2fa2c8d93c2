//! The report's one-line bottleneck verdict: the memory when it is busy most of the
//! time, else the unit kind that works most, else what the traversal units wait for.
//! Every percentage in the sentence is of the same base — the cycles of the units it
//! names — and a "most" names a reason of the group it follows, so the sentence cannot
//! contradict itself (a full output FIFO is not a memory wait).

use std::collections::BTreeMap;

use crate::observe::report::UnitReport;
use crate::observe::stall::Stall;

/// The stall cycles of one unit kind, by group.
struct Waits {
    /// Busy cycles over those.
    busy: f64,
    /// Group → (its share of the cycles, its largest reason and that reason's share),
    /// largest group first.
    groups: Vec<(&'static str, f64, String, f64)>,
}

impl Waits {
    fn of(units: &[UnitReport], prefix: &str) -> Option<Waits> {
        let us: Vec<&UnitReport> = units.iter().filter(|u| u.name.starts_with(prefix)).collect();
        if us.is_empty() {
            return None;
        }
        let cycles: f64 =
            us.iter().map(|u| (u.busy_cycles + u.stall_cycles + u.idle_cycles) as f64).sum::<f64>().max(1.0);
        let busy = us.iter().map(|u| u.busy_cycles as f64).sum::<f64>() / cycles;
        let mut reasons: BTreeMap<&str, u64> = BTreeMap::new();
        for (k, v) in us.iter().flat_map(|u| u.stall_reasons.iter()) {
            *reasons.entry(k.as_str()).or_default() += v;
        }
        let mut groups: BTreeMap<&'static str, (u64, String, u64)> = BTreeMap::new();
        for (name, n) in reasons {
            let group = Stall::ALL.iter().find(|s| s.name() == name).map_or("other reasons", |s| s.group());
            let g = groups.entry(group).or_default();
            g.0 += n;
            if n > g.2 {
                (g.1, g.2) = (name.to_string(), n);
            }
        }
        let mut groups: Vec<_> =
            groups.into_iter().map(|(g, (n, top, t))| (g, n as f64 / cycles, top, t as f64 / cycles)).collect();
        groups.sort_by(|a, b| b.1.total_cmp(&a.1));
        Some(Waits { busy, groups })
    }

    fn share(&self, group: &str) -> f64 {
        self.groups.iter().find(|g| g.0 == group).map_or(0.0, |g| g.1)
    }

    /// "wait on memory 29% of their cycles (most: node_data 20%), on a full output FIFO
    /// 39% (most: output_fifo_full 39%)": the groups above 5%, largest first.
    fn clause(&self) -> String {
        let parts: Vec<String> = self
            .groups
            .iter()
            .filter(|g| g.1 >= 0.05)
            .map(|(g, share, top, t)| format!("on {g} {:.0}% (most: {top} {:.0}%)", 100.0 * share, 100.0 * t))
            .collect();
        if parts.is_empty() {
            format!("busy {:.0}%, hardly waiting", 100.0 * self.busy)
        } else {
            format!("busy {:.0}%, waiting {} of their cycles", 100.0 * self.busy, parts.join(", "))
        }
    }
}

/// The verdict for a frame's unit reports and memory utilization.
pub fn verdict(units: &[UnitReport], utilization: f64) -> String {
    let trav = Waits::of(units, "traversal");
    let isect = Waits::of(units, "intersection");
    let shade = Waits::of(units, "rgs.shade");
    let transform = Waits::of(units, "transform");
    let about =
        |w: &Option<Waits>, what: &str| w.as_ref().map_or(String::new(), |w| format!("; {what} {}", w.clause()));
    if utilization >= 0.8 {
        return format!(
            "memory-bound: memory {:.0}% busy{}{}",
            100.0 * utilization,
            about(&trav, "traversal units"),
            about(&isect, "intersection units")
        );
    }
    let mut best = ("traversal", trav.as_ref().map_or(0.0, |k| k.busy));
    for (name, k) in [("intersection", &isect), ("shading", &shade), ("transform", &transform)] {
        let b = k.as_ref().map_or(0.0, |k| k.busy);
        if b > best.1 {
            best = (name, b);
        }
    }
    if best.1 >= 0.6 {
        return format!("{}-bound: its datapath busy {:.0}% of cycles", best.0, 100.0 * best.1);
    }
    match &trav {
        Some(t) if t.share("memory") >= 0.3 => {
            format!("latency-bound: memory {:.0}% busy; traversal units {}", 100.0 * utilization, t.clause())
        }
        Some(t) => {
            format!("no dominant bound: memory {:.0}% busy; traversal units {}", 100.0 * utilization, t.clause())
        }
        None => "no traversal units".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(name: &str, busy: u64, reasons: &[(&str, u64)]) -> UnitReport {
        let stall: u64 = reasons.iter().map(|r| r.1).sum();
        UnitReport {
            name: name.into(),
            busy_cycles: busy,
            stall_cycles: stall,
            idle_cycles: 1000 - busy - stall,
            issues: 0,
            simd_efficiency: 1.0,
            active_lanes: 0,
            stall_reasons: reasons.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            node_reads_per_step: None,
            thread_states: None,
            transform: None,
            bytes: 0,
        }
    }

    /// The sentence the audit found ("wait on memory 29% … (most: output_fifo_full
    /// 39%)"): now each "most" belongs to its group and is at most the group's share.
    #[test]
    fn a_full_fifo_is_not_a_memory_wait() {
        let units = [unit("traversal0", 200, &[("node_data", 200), ("mshr", 90), ("output_fifo_full", 390)])];
        let v = verdict(&units, 0.95);
        assert!(v.contains("on memory 29% (most: node_data 20%)"), "{v}");
        assert!(v.contains("on a full output FIFO 39% (most: output_fifo_full 39%)"), "{v}");
        let at = |s: &str| v.find(s).unwrap();
        assert!(at("output FIFO") < at("on memory"), "largest group first: {v}");
    }

    #[test]
    fn the_verdicts_name_their_bound() {
        let busy = [unit("traversal0", 700, &[("step_latency", 100)])];
        assert_eq!(verdict(&busy, 0.1), "traversal-bound: its datapath busy 70% of cycles");
        let waiting = [unit("traversal0", 200, &[("node_data", 400)])];
        assert!(verdict(&waiting, 0.5).starts_with("latency-bound: memory 50% busy; traversal units busy 20%"));
        assert_eq!(verdict(&[], 0.1), "no traversal units");
    }
}
