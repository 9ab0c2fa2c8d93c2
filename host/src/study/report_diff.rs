//! What changed between two JSON reports (`simulate --report`, `stream --report`, a sweep
//! point's report): the configuration and run keys that differ, then every number with
//! its ratio, largest effect first. Reports are compared as JSON, flattened to dotted
//! paths; arrays of named records (units, FIFOs, caches) are keyed by their names, so
//! `units.traversal0.stall_cycles` means the same unit in both.

use serde_json::Value;

/// A flattened report: dotted path → leaf value, in document order.
pub fn flatten(v: &Value) -> Vec<(String, Value)> {
    let mut out = Vec::new();
    walk(v, String::new(), &mut out);
    out
}

fn walk(v: &Value, path: String, out: &mut Vec<(String, Value)>) {
    let join = |k: &str| if path.is_empty() { k.to_string() } else { format!("{path}.{k}") };
    match v {
        Value::Object(m) => m.iter().for_each(|(k, v)| walk(v, join(k), out)),
        Value::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                let key = item.get("name").and_then(Value::as_str).map_or(i.to_string(), str::to_string);
                walk(item, join(&key), out);
            }
        }
        leaf => out.push((path, leaf.clone())),
    }
}

/// One number that changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Change {
    /// Dotted path.
    pub path: String,
    /// Value in the first report.
    pub a: f64,
    /// Value in the second report.
    pub b: f64,
}

impl Change {
    /// `b / a` (infinite when only `b` is non-zero).
    pub fn ratio(&self) -> f64 {
        if self.a == 0.0 {
            if self.b == 0.0 {
                1.0
            } else {
                f64::INFINITY
            }
        } else {
            self.b / self.a
        }
    }

    /// How large the change is: the symmetric relative change `|b − a| / (|a| + |b|)`
    /// (0 to 1) times the number's order of magnitude `ln(1 + max(|a|, |b|))`, so that a
    /// small counter going 4 → 0 (1 × 1.6) ranks below a frame's cycles doubling
    /// (⅓ × 14 at a million cycles), and a counter appearing at 10⁶ ranks first.
    pub fn effect(&self) -> f64 {
        let (a, b) = (self.a.abs(), self.b.abs());
        if a + b == 0.0 {
            return 0.0;
        }
        let relative = if self.a * self.b < 0.0 { 1.0 } else { (self.b - self.a).abs() / (a + b) };
        relative * (1.0 + a.max(b)).ln()
    }
}

/// The comparison of two reports.
#[derive(Debug, Default)]
pub struct Diff {
    /// Settings (`config.*`, `run.*`, and any other non-number) that differ: path, first,
    /// second (`None`: absent there).
    pub settings: Vec<(String, Option<String>, Option<String>)>,
    /// Numbers outside the configuration that differ, largest effect first.
    pub changes: Vec<Change>,
    /// Numbers that are equal.
    pub unchanged: usize,
    /// Records or values only in the first report, then only in the second (by their
    /// record: `units.traversal1`, `fifos.rays1`, …).
    pub only: [Vec<String>; 2],
}

/// The record a path belongs to: its first two components.
fn record(path: &str) -> String {
    path.splitn(3, '.').take(2).collect::<Vec<_>>().join(".")
}

/// The headline: figures that compare across chips of any packet size, frame size or
/// clock, in this order (packet-step counts are not among them: a 64-ray packet step
/// and a single ray's step are not the same work).
pub const HEADLINE: [&str; 12] = [
    "frames_per_second",
    "cycles",
    "rays_per_second",
    "steps_per_ray",
    "tests_per_ray",
    "traversal_simd_efficiency",
    "memory.bytes_per_ray",
    "memory.utilization",
    "memory.traffic_over_compulsory",
    "energy.joules_per_ray",
    "energy.watts",
    "energy.area_mm2",
];

/// Whether `path` is a headline figure.
pub fn is_headline(path: &str) -> bool {
    HEADLINE.contains(&path)
}

fn text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        v => v.to_string(),
    }
}

/// Compares report `a` with report `b`.
pub fn diff(a: &Value, b: &Value) -> Diff {
    let (fa, fb) = (flatten(a), flatten(b));
    let mut d = Diff::default();
    let mut paths: Vec<&String> = fa.iter().map(|(k, _)| k).collect();
    for (k, _) in &fb {
        if !paths.contains(&k) {
            paths.push(k);
        }
    }
    let fb_map: std::collections::HashMap<&str, &Value> = fb.iter().map(|(k, v)| (k.as_str(), v)).collect();
    let fa_map: std::collections::HashMap<&str, &Value> = fa.iter().map(|(k, v)| (k.as_str(), v)).collect();
    for p in paths {
        let (va, vb) = (fa_map.get(p.as_str()).copied(), fb_map.get(p.as_str()).copied());
        let is_setting = p.starts_with("config.") || p.starts_with("run.") || p == "schema";
        match (va.and_then(Value::as_f64), vb.and_then(Value::as_f64)) {
            (Some(x), Some(y)) if !is_setting => {
                if x == y {
                    d.unchanged += 1;
                } else {
                    d.changes.push(Change { path: p.clone(), a: x, b: y });
                }
            }
            _ if !is_setting && (va.is_none() || vb.is_none()) => {
                let side = usize::from(va.is_none());
                let other = if side == 0 { &fb } else { &fa };
                // The whole record when the other report has none of it, else the value.
                let rec = record(p);
                let r = if other.iter().any(|(k, _)| k.starts_with(&format!("{rec}."))) { p.clone() } else { rec };
                if !d.only[side].contains(&r) {
                    d.only[side].push(r);
                }
            }
            _ => {
                if va != vb {
                    d.settings.push((p.clone(), va.map(text), vb.map(text)));
                }
            }
        }
    }
    d.changes.sort_by(|x, y| y.effect().total_cmp(&x.effect()).then_with(|| x.path.cmp(&y.path)));
    d
}

/// A number as a person reads it: integers whole, others to 4 significant figures.
pub fn show(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 9) as usize;
        format!("{v:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_counters_vanishing_rank_below_large_figures_changing() {
        let c = |a: f64, b: f64| Change { path: String::new(), a, b };
        assert!(c(1e6, 2e6).effect() > c(4.0, 0.0).effect());
        assert!(c(0.0, 1e6).effect() > c(1e6, 2e6).effect());
        assert_eq!(c(3.0, 3.0).effect(), 0.0);
        assert_eq!(c(0.0, 0.0).effect(), 0.0);
    }

    #[test]
    fn the_headline_holds_per_ray_figures_not_packet_steps() {
        assert!(is_headline("steps_per_ray") && is_headline("traversal_simd_efficiency"));
        assert!(!is_headline("traversal_steps") && !is_headline("triangle_tests"));
    }
}
