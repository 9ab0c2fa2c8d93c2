//! `raypipe plot`: a sweep's rows as a line plot, a heatmap or stacked bars.

use anyhow::{anyhow, bail, Result};

use crate::output;
use crate::study::sweep_plot::{self, Plot};
use crate::study::sweep_table::{self, label};

use clap::Args;
use std::path::PathBuf;

/// `raypipe plot`.
#[derive(Args, Debug)]
pub struct PlotArgs {
    /// A sweep's rows (.jsonl, from `raypipe sweep` or `sweep merge`).
    #[arg(value_name = "SWEEP.jsonl")]
    pub rows: PathBuf,
    /// The plot: .svg, or .png (rendered from the SVG).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The parameter along the x axis.
    #[arg(long, value_name = "PARAM")]
    pub x: String,
    /// Line plot: the metric on the y axis (e.g. fps, bytes_per_ray.nodes,
    /// hit_rate.triangles); heatmap: the second parameter.
    #[arg(long, value_name = "NAME", required_unless_present = "stack")]
    pub y: Option<String>,
    /// Line plot: one line per value of this parameter.
    #[arg(long, value_name = "PARAM", conflicts_with_all = ["value", "stack"])]
    pub series: Option<String>,
    /// Heatmap: the metric coloured over the --x × --y grid.
    #[arg(long, value_name = "METRIC", conflicts_with = "stack")]
    pub value: Option<String>,
    /// Stacked bars: every metric PREFIX.<part> (e.g. stall.traversal, bytes_per_ray).
    #[arg(long, value_name = "PREFIX", conflicts_with = "y")]
    pub stack: Option<String>,
    /// Line plot: a logarithmic x axis (cache sizes, thread counts).
    #[arg(long)]
    pub log_x: bool,
    /// Only rows whose parameter KEY has VALUE (repeatable; `*` matches any run of
    /// characters, e.g. `scene=*bunny.obj`).
    #[arg(long = "where", value_name = "KEY=VALUE")]
    pub filters: Vec<String>,
    /// The title (default: what is plotted against what).
    #[arg(long)]
    pub title: Option<String>,
}

pub(crate) fn cmd_plot(a: PlotArgs) -> Result<()> {
    let png = match a.output.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("svg") => false,
        Some("png") => true,
        _ => bail!("{}: the plot is written as .svg or .png", a.output.display()),
    };
    output::check_writable(&a.output)?;
    let mut filters = Vec::new();
    for f in &a.filters {
        let (k, v) = f.split_once('=').ok_or_else(|| anyhow!("--where {f:?}: expected KEY=VALUE"))?;
        filters.push((k.trim().to_string(), v.trim().trim_matches('"').to_string()));
    }
    let rows: Vec<_> = sweep_table::read_rows(&a.rows)?
        .into_iter()
        .filter(|r| filters.iter().all(|(k, v)| label(r, k).is_some_and(|l| wildcard(v, &l))))
        .collect();
    let (plot, what) = match (&a.value, &a.stack, &a.y) {
        (Some(value), _, Some(y)) => (
            Plot::Heatmap { x: a.x.clone(), y: y.clone(), value: value.clone() },
            format!("{value} over {} × {y}", a.x),
        ),
        (None, Some(prefix), _) => {
            (Plot::Stacked { x: a.x.clone(), prefix: prefix.clone() }, format!("{prefix} by {}", a.x))
        }
        (None, None, Some(y)) => (
            Plot::Line { x: a.x.clone(), y: y.clone(), series: a.series.clone(), log_x: a.log_x },
            format!("{y} against {}", a.x),
        ),
        _ => bail!("plot: give --y METRIC (a line), --y PARAM --value METRIC (a heatmap) or --stack PREFIX (bars)"),
    };
    let title = a.title.clone().unwrap_or(what);
    let svg = sweep_plot::draw(&plot, &rows, &title).map_err(|e| anyhow!("{}: {e:#}", a.rows.display()))?;
    if png {
        output::write_bytes(&a.output, &crate::output::chart_raster::to_png(&svg)?)?;
    } else {
        output::write_bytes(&a.output, svg.as_bytes())?;
    }
    println!("{title}: {} rows -> {}", rows.len(), a.output.display());
    Ok(())
}

/// `pattern` matches `text`: equal, with `*` standing for any run of characters.
fn wildcard(pattern: &str, text: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == text;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !text.starts_with(first) || !text[first.len()..].ends_with(last) {
        return false;
    }
    let mut rest = &text[first.len()..text.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(i) => rest = &rest[i + part.len()..],
            None => return false,
        }
    }
    true
}

#[cfg(test)]
mod tests {
    #[test]
    fn wildcards_match_runs_of_characters() {
        use super::wildcard;
        assert!(wildcard("*bunny.obj", "../models/stanford-bunny.obj"));
        assert!(wildcard("kd", "kd") && !wildcard("kd", "kd2"));
        assert!(wildcard("a*b*c", "axxbyyc") && !wildcard("a*b*c", "axxcyyb"));
        assert!(!wildcard("ab*ba", "aba"));
    }
}
