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

    /// How large the change is: |ln ratio| (sign changes and appearances rank first).
    pub fn effect(&self) -> f64 {
        let r = self.ratio();
        if r.is_finite() && r > 0.0 {
            r.ln().abs()
        } else {
            f64::INFINITY
        }
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

/// The headline numbers: the report's top-level figures and its memory and energy
/// totals (shown before the rest).
pub fn is_headline(path: &str) -> bool {
    !path.contains('.')
        || matches!(
            path,
            "memory.total_bytes" | "memory.bytes_per_ray" | "memory.utilization" | "memory.traffic_over_compulsory"
        )
        || path.starts_with("energy.") && path.matches('.').count() == 1
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
