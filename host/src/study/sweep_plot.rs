//! Plots of a sweep's rows, drawn with plotters as SVG (PNG through resvg): a line plot
//! (a metric against one parameter, one line per value of another), a heatmap (a metric
//! over two parameters) and stacked bars (the metrics under one prefix — stall reasons,
//! bytes per ray by class — against one parameter).

use crate::output::warnings::warning;
use anyhow::{anyhow, bail, Result};
use plotters::prelude::*;

use crate::output::chart_numbers::si;
use crate::output::chart_raster::viridis;
use crate::study::sweep_table::{label, number, Row};

const SIZE: (u32, u32) = (960, 600);

type Drawn = std::result::Result<(), Box<dyn std::error::Error>>;

/// The most series a line chart draws: beyond this the colours repeat and the legend
/// outgrows the chart.
const MAX_SERIES: usize = 40;

/// Tableau 10, the series colours.
const PALETTE: [RGBColor; 10] = [
    RGBColor(0x4e, 0x79, 0xa7),
    RGBColor(0xf2, 0x8e, 0x2b),
    RGBColor(0xe1, 0x57, 0x59),
    RGBColor(0x76, 0xb7, 0xb2),
    RGBColor(0x59, 0xa1, 0x4f),
    RGBColor(0xed, 0xc9, 0x48),
    RGBColor(0xb0, 0x7a, 0xa1),
    RGBColor(0xff, 0x9d, 0xa7),
    RGBColor(0x9c, 0x75, 0x5f),
    RGBColor(0xba, 0xb0, 0xac),
];

/// What to draw.
#[derive(Clone, Debug)]
pub enum Plot {
    /// `y` against `x`, one line per value of `series`.
    Line { x: String, y: String, series: Option<String>, log_x: bool },
    /// `value` over the `x` × `y` grid of parameter values.
    Heatmap { x: String, y: String, value: String },
    /// Every metric named `prefix.*`, stacked, against `x`.
    Stacked { x: String, prefix: String },
}

/// The values one parameter takes, in order: numerically when all are numbers.
fn axis_values(rows: &[&Row], key: &str) -> Result<Vec<String>> {
    let mut vals: Vec<String> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for r in rows {
        let v = label(r, key).ok_or_else(|| anyhow!("no row has a value for {key:?}"))?;
        if seen.insert(v.clone()) {
            vals.push(v);
        }
    }
    if vals.iter().all(|v| v.parse::<f64>().is_ok()) {
        vals.sort_by(|a, b| a.parse::<f64>().unwrap_or(0.0).total_cmp(&b.parse::<f64>().unwrap_or(0.0)));
    }
    Ok(vals)
}

/// Refuses rows that the plot's own keys cannot tell apart (they differ in a parameter
/// the plot does not show): the user narrows them with `--where`.
fn check_unique(rows: &[&Row], keys: &[&str]) -> Result<()> {
    let mut at: std::collections::HashMap<Vec<Option<String>>, &Row> = std::collections::HashMap::new();
    for b in rows {
        let place: Vec<Option<String>> = keys.iter().map(|k| label(b, k)).collect();
        if let Some(a) = at.insert(place, b) {
            let differ: Vec<&String> = a.params.keys().filter(|k| a.params.get(*k) != b.params.get(*k)).collect();
            bail!(
                "points {} and {} fall on the same place of the plot; they differ in {}: pick one with --where KEY=VALUE",
                a.index,
                b.index,
                differ.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
            );
        }
    }
    Ok(())
}

/// Draws `plot` of `rows` (those without an error) as SVG.
pub fn draw(plot: &Plot, rows: &[Row], title: &str) -> Result<String> {
    let rows: Vec<&Row> = rows.iter().filter(|r| r.error.is_none()).collect();
    if rows.is_empty() {
        bail!("no rows to plot (every point failed, or --where matched none)");
    }
    let mut svg = String::new();
    let result = match plot {
        Plot::Line { x, y, series, log_x } => {
            let mut keys = vec![x.as_str()];
            keys.extend(series.as_deref());
            check_unique(&rows, &keys)?;
            line(&mut svg, &rows, x, y, series.as_deref(), *log_x, title)
        }
        Plot::Heatmap { x, y, value } => {
            check_unique(&rows, &[x, y])?;
            heatmap(&mut svg, &rows, x, y, value, title)
        }
        Plot::Stacked { x, prefix } => {
            check_unique(&rows, &[x])?;
            stacked(&mut svg, &rows, x, prefix, title)
        }
    };
    result.map_err(|e| anyhow!("{e}"))?;
    Ok(svg)
}

/// The top of a y axis holding data up to `top` with room above it for a legend of
/// `entries` lines in the upper right corner, so the legend never covers a point.
fn above_legend(top: f64, entries: usize) -> f64 {
    // About 20 px per entry and 24 px of frame, in a plot area of about 480 px.
    let share = ((entries as f64 * 20.0 + 24.0) / 480.0).min(0.6);
    top / (1.0 - share)
}

fn metric_of(r: &Row, name: &str) -> Result<f64, String> {
    number(r, name).ok_or_else(|| format!("point {} has no number {name:?}", r.index))
}

fn line(svg: &mut String, rows: &[&Row], x: &str, y: &str, series: Option<&str>, log_x: bool, title: &str) -> Drawn {
    let xs = axis_values(rows, x)?;
    let numeric = xs.iter().all(|v| v.parse::<f64>().is_ok());
    let groups = match series {
        Some(s) => axis_values(rows, s)?,
        None => vec![String::new()],
    };
    if groups.len() > MAX_SERIES {
        return Err(format!(
            "{} series ({} has that many values) is more than the {MAX_SERIES} a chart can tell apart; \
             choose another series",
            groups.len(),
            series.unwrap_or_default()
        )
        .into());
    }
    // One pass over the rows, each to its series and its x position.
    let group_of: std::collections::HashMap<&str, usize> =
        groups.iter().enumerate().map(|(i, g)| (g.as_str(), i)).collect();
    let x_of: std::collections::HashMap<&str, usize> = xs.iter().enumerate().map(|(i, v)| (v.as_str(), i)).collect();
    let mut points: Vec<Vec<(f64, f64)>> = vec![Vec::new(); groups.len()];
    let mut missing = Vec::new();
    for r in rows {
        let g = match series {
            Some(s) => match label(r, s).and_then(|l| group_of.get(l.as_str()).copied()) {
                Some(g) => g,
                None => continue,
            },
            None => 0,
        };
        let xv = label(r, x).unwrap_or_default();
        let px = if numeric { xv.parse::<f64>()? } else { x_of.get(xv.as_str()).copied().unwrap_or(0) as f64 };
        // A point without the metric (a hit rate of a cache it does not have) is left
        // out, and said so below.
        match number(r, y) {
            Some(v) if v.is_finite() => points[g].push((px, v)),
            _ => missing.push(r.index),
        }
    }
    if !missing.is_empty() {
        let which: Vec<String> = missing.iter().take(5).map(|i| i.to_string()).collect();
        warning(&format!(
            "plot: {} point{} without a value of {y:?} left out (point {}{})",
            missing.len(),
            if missing.len() == 1 { "" } else { "s" },
            which.join(", "),
            if missing.len() > 5 { ", …" } else { "" }
        ));
    }
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (g, mut pts) in groups.iter().zip(points) {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let name = series.map_or(y.to_string(), |s| format!("{s} = {g}"));
        lines.push((name, pts));
    }
    let all = lines.iter().flat_map(|(_, p)| p.iter());
    let (mut x0, mut x1, mut y1) = (f64::MAX, f64::MIN, 0.0f64);
    for &(a, b) in all {
        x0 = x0.min(a);
        x1 = x1.max(a);
        y1 = y1.max(b);
    }
    if x0 > x1 {
        return Err(format!("no finite value of {y:?} to plot").into());
    }
    if x0 == x1 {
        (x0, x1) = (x0 - 1.0, x1 + 1.0);
    }
    let y1 = above_legend(if y1 > 0.0 { y1 * 1.05 } else { 1.0 }, lines.len());
    if log_x && !(numeric && x0 > 0.0) {
        warning(&format!(
            "plot: --log-x needs positive numbers on x; {x:?} has {}: drawn on a linear axis",
            if numeric { "zero or negative values" } else { "names" }
        ));
    }
    let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut builder = ChartBuilder::on(&root);
    builder.caption(title, ("sans-serif", 22)).margin(16).x_label_area_size(48).y_label_area_size(90);
    let labels = |v: &f64| -> String {
        if numeric {
            si(*v, 3)
        } else {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                xs.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        }
    };
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(x)
                .y_desc(y)
                .x_label_formatter(&labels)
                .y_label_formatter(&|v| si(*v, 3))
                .x_labels(if numeric { 10 } else { xs.len() })
                .draw()?;
            for (i, (name, pts)) in lines.iter().enumerate() {
                let c = PALETTE[i % PALETTE.len()];
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
                    .label(name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .border_style(BLACK)
                .background_style(WHITE.mix(0.9))
                .draw()?;
        }};
    }
    if log_x && numeric && x0 > 0.0 {
        finish!(builder.build_cartesian_2d((x0 / 1.2..x1 * 1.2).log_scale(), 0f64..y1)?);
    } else {
        let pad = (x1 - x0) * 0.04;
        finish!(builder.build_cartesian_2d(x0 - pad..x1 + pad, 0f64..y1)?);
    }
    root.present()?;
    Ok(())
}

/// The label of a categorical axis at `v`: category `k` is drawn over `k..k + 1`, so
/// its label sits at `k + 0.5`; other ticks are blank.
fn category_at(vals: &[String], v: f64) -> String {
    let i = v - 0.5;
    if (i - i.round()).abs() < 1e-6 && i >= 0.0 {
        vals.get(i.round() as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

fn heatmap(svg: &mut String, rows: &[&Row], x: &str, y: &str, value: &str, title: &str) -> Drawn {
    let xs = axis_values(rows, x)?;
    let ys = axis_values(rows, y)?;
    let mut cells = Vec::new();
    for r in rows {
        let (cx, cy) = (label(r, x).unwrap_or_default(), label(r, y).unwrap_or_default());
        let i = xs.iter().position(|v| *v == cx).unwrap_or(0);
        let j = ys.iter().position(|v| *v == cy).unwrap_or(0);
        cells.push((i, j, metric_of(r, value)?));
    }
    let finite = cells.iter().map(|c| c.2).filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (main, bar) = root.split_horizontally(SIZE.0 - 130);
    let mut chart = ChartBuilder::on(&main)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(100)
        .build_cartesian_2d(0f64..xs.len() as f64, 0f64..ys.len() as f64)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(x)
        .y_desc(y)
        .x_labels(xs.len() * 2 + 1)
        .y_labels(ys.len() * 2 + 1)
        .x_label_formatter(&|v| category_at(&xs, *v))
        .y_label_formatter(&|v| category_at(&ys, *v))
        .draw()?;
    chart.draw_series(cells.iter().map(|&(i, j, v)| {
        let c = if v.is_finite() { viridis((v - lo) / span) } else { RGBColor(0xdd, 0xdd, 0xdd) };
        Rectangle::new([(i as f64, j as f64), (i as f64 + 1.0, j as f64 + 1.0)], c.filled())
    }))?;
    chart.draw_series(cells.iter().map(|&(i, j, v)| {
        let dark = v.is_finite() && (v - lo) / span > 0.6;
        let style = ("sans-serif", 15).into_font().color(if dark { &BLACK } else { &WHITE });
        Text::new(si(v, 3), (i as f64 + 0.38, j as f64 + 0.55), style)
    }))?;
    // The colour bar.
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(60)
        .margin_bottom(64)
        .margin_right(12)
        .y_label_area_size(64)
        .caption(value, ("sans-serif", 14))
        .build_cartesian_2d(0f64..1.0, lo..lo + span)?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_style(("sans-serif", 13))
        .y_label_formatter(&|v| si(*v, 3))
        .draw()?;
    let steps = 64;
    scale.draw_series((0..steps).map(|k| {
        let (a, b) = (lo + span * k as f64 / steps as f64, lo + span * (k + 1) as f64 / steps as f64);
        Rectangle::new([(0.0, a), (1.0, b)], viridis(k as f64 / (steps - 1) as f64).filled())
    }))?;
    root.present()?;
    Ok(())
}

fn stacked(svg: &mut String, rows: &[&Row], x: &str, prefix: &str, title: &str) -> Drawn {
    let xs = axis_values(rows, x)?;
    let start = format!("{prefix}.");
    let mut parts: Vec<String> = Vec::new();
    for r in rows {
        for (k, v) in &r.metrics {
            let nonzero = v.as_f64().is_some_and(|v| v != 0.0);
            // Only the leaves directly under the prefix (`stall.traversal.node_data`, not
            // deeper names), and only those some row has.
            if k.starts_with(&start) && !k[start.len()..].contains('.') && nonzero && !parts.contains(k) {
                parts.push(k.clone());
            }
        }
    }
    if parts.is_empty() {
        return Err(format!("no metric under {prefix:?} is non-zero (names look like {prefix}.<part>)").into());
    }
    let mut bars: Vec<Vec<f64>> = vec![vec![0.0; parts.len()]; xs.len()];
    for r in rows {
        let i = xs.iter().position(|v| Some(v) == label(r, x).as_ref()).unwrap_or(0);
        for (p, name) in parts.iter().enumerate() {
            bars[i][p] = number(r, name).filter(|v| v.is_finite()).unwrap_or(0.0);
        }
    }
    let top = bars.iter().map(|b| b.iter().sum::<f64>()).fold(0.0f64, f64::max);
    let top = above_legend(if top > 0.0 { top * 1.05 } else { 1.0 }, parts.len());
    let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(90)
        .build_cartesian_2d(0f64..xs.len() as f64, 0f64..top)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_desc(x)
        .y_desc(prefix)
        .x_labels(xs.len() * 2 + 1)
        .x_label_formatter(&|v| category_at(&xs, *v))
        .y_label_formatter(&|v| si(*v, 3))
        .draw()?;
    for (p, name) in parts.iter().enumerate() {
        let c = PALETTE[p % PALETTE.len()];
        chart
            .draw_series(bars.iter().enumerate().map(|(i, b)| {
                let below: f64 = b[..p].iter().sum();
                let x0 = i as f64 + 0.15;
                Rectangle::new([(x0, below), (x0 + 0.7, below + b[p])], c.filled())
            }))?
            .label(name[start.len()..].to_string())
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], c.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    root.present()?;
    Ok(())
}
