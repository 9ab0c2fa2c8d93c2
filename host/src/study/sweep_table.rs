//! A sweep's results: one row per point — its number, identity and parameters, the
//! bottleneck verdict, the report's headline metrics ([`raypipe_hw::observe::metrics`]) or the
//! error that stopped it — as JSON lines and as CSV. Rows are written in point order
//! whatever order they finished in, so a run, a resumed run and merged shards write the
//! same bytes.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Result};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::study::sweep::{value_text, Point};

/// One point's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The point's number in the whole sweep.
    pub index: usize,
    /// The point's identity (`key=value, …`): what resuming matches rows by.
    pub point: String,
    /// Parameters, in spec order.
    pub params: Map<String, Value>,
    /// The report's one-line verdict (empty on error).
    pub bottleneck: String,
    /// Headline metrics, in [`raypipe_hw::observe::metrics::metrics`] order (`null`: not defined
    /// for this run, e.g. the hit rate of a class no cache saw).
    pub metrics: Map<String, Value>,
    /// Why the point has no metrics.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl Row {
    /// The row of a finished point.
    pub fn of(point: &Point, report: &raypipe_hw::Report) -> Row {
        let metrics = raypipe_hw::observe::metrics::metrics(report)
            .into_iter()
            .map(|(k, v)| (k, serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)))
            .collect();
        Row { bottleneck: report.bottleneck.clone(), metrics, ..Row::bare(point) }
    }

    /// The row of a point that failed.
    pub fn failed(point: &Point, error: String) -> Row {
        Row { error: Some(error), ..Row::bare(point) }
    }

    fn bare(point: &Point) -> Row {
        let params = point.params.iter().map(|(k, v)| (k.clone(), toml_to_json(v))).collect();
        Row {
            index: point.index,
            point: point.id(),
            params,
            bottleneck: String::new(),
            metrics: Map::new(),
            error: None,
        }
    }

    /// One JSON line (without the newline).
    pub fn to_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

fn toml_to_json(v: &toml::Value) -> Value {
    match v {
        toml::Value::String(s) => Value::String(s.clone()),
        toml::Value::Integer(i) => Value::from(*i),
        toml::Value::Float(f) => serde_json::Number::from_f64(*f).map_or(Value::Null, Value::Number),
        toml::Value::Boolean(b) => Value::Bool(*b),
        v => Value::String(value_text(v)),
    }
}

/// Reads the rows of a JSON-lines file. A line that does not parse is skipped when it is
/// the last one (a run stopped while writing it) and an error otherwise.
pub fn read_rows(path: &Path) -> Result<Vec<Row>> {
    let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let mut rows = Vec::new();
    for (n, line) in lines.iter().enumerate() {
        match serde_json::from_str::<Row>(line) {
            Ok(r) => rows.push(r),
            Err(_) if n + 1 == lines.len() && !text.ends_with('\n') => {
                eprintln!(
                    "note: {}: its last line was cut short (a stopped run); that point runs again",
                    path.display()
                );
            }
            Err(e) => return Err(anyhow!("{}: line {}: not a sweep row: {e}", path.display(), n + 1)),
        }
    }
    Ok(rows)
}

/// Rows in point order, one per point (the first of duplicates).
pub fn normalize(mut rows: Vec<Row>) -> Vec<Row> {
    rows.sort_by_key(|r| r.index);
    rows.dedup_by_key(|r| r.index);
    rows
}

/// The two output files of a sweep called `prefix`.
pub fn outputs(prefix: &Path) -> (PathBuf, PathBuf) {
    let with = |ext: &str| {
        let mut s = prefix.as_os_str().to_owned();
        s.push(ext);
        PathBuf::from(s)
    };
    (with(".jsonl"), with(".csv"))
}

/// Writes `rows` (normalized) as `prefix.jsonl` and `prefix.csv`, each atomically.
pub fn write(prefix: &Path, rows: &[Row]) -> Result<()> {
    let (jsonl, csv) = outputs(prefix);
    crate::output::write_atomic(&jsonl, |w| {
        for r in rows {
            writeln!(w, "{}", r.to_line())?;
        }
        Ok(())
    })?;
    crate::output::write_bytes(&csv, to_csv(rows).as_bytes())
}

/// The rows as CSV: `index`, the parameters, `bottleneck`, `error`, then the metrics;
/// columns in the order rows first name them.
pub fn to_csv(rows: &[Row]) -> String {
    let mut params: Vec<&String> = Vec::new();
    let mut metrics: Vec<&String> = Vec::new();
    for r in rows {
        for k in r.params.keys() {
            if !params.contains(&k) {
                params.push(k);
            }
        }
        for k in r.metrics.keys() {
            if !metrics.contains(&k) {
                metrics.push(k);
            }
        }
    }
    let mut out = String::new();
    let header: Vec<String> = std::iter::once("index".to_string())
        .chain(params.iter().map(|k| csv_field(k)))
        .chain(["bottleneck".to_string(), "error".to_string()])
        .chain(metrics.iter().map(|k| csv_field(k)))
        .collect();
    out.push_str(&header.join(","));
    out.push('\n');
    let cell = |v: Option<&Value>| match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => csv_field(s),
        Some(v) => csv_field(&v.to_string()),
    };
    for r in rows {
        let fields: Vec<String> = std::iter::once(r.index.to_string())
            .chain(params.iter().map(|k| cell(r.params.get(*k))))
            .chain([csv_field(&r.bottleneck), csv_field(r.error.as_deref().unwrap_or(""))])
            .chain(metrics.iter().map(|k| cell(r.metrics.get(*k))))
            .collect();
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// RFC 4180: quoted when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A row's value for `name`: a parameter or a metric, as a number when it is one.
pub fn number(row: &Row, name: &str) -> Option<f64> {
    match row.params.get(name).or_else(|| row.metrics.get(name))? {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.parse().ok(),
        Value::Bool(b) => Some(*b as u8 as f64),
        _ => None,
    }
}

/// A row's value for `name` as a label (parameters and metrics alike).
pub fn label(row: &Row, name: &str) -> Option<String> {
    match row.params.get(name).or_else(|| row.metrics.get(name))? {
        Value::String(s) => Some(s.clone()),
        Value::Null => None,
        v => Some(v.to_string()),
    }
}
