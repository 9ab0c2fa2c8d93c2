//! Charts of a stream-machine report, drawn with plotters as SVG and rendered to PNG
//! with resvg (text in the system's sans-serif font; without fonts the PNG has no
//! labels but is still written): Figure 7 (instructions by kernel), Figure 8
//! (random-access words by data type), Figure 9 (bandwidth with and without the texture
//! cache, by data type) and the active rays after each pass.

use crate::output::chart_raster::to_png;
use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use raypipe_hw::stream::counters::PassKind;
use raypipe_hw::stream::StreamReport;

use crate::output;
use crate::output::chart_numbers::si;

const SIZE: (u32, u32) = (900, 520);

type Drawn = std::result::Result<(), Box<dyn std::error::Error>>;

/// Writes every chart as SVG and PNG into `dir` (created if missing); the number of
/// files written.
pub fn write_all(dir: &Path, r: &StreamReport) -> Result<usize> {
    std::fs::create_dir_all(dir).map_err(|e| anyhow!("{}: cannot create the charts directory: {e}", dir.display()))?;
    let charts = [
        ("fig7_instructions_by_kernel", fig7(r)),
        ("fig8_words_by_data_type", fig8(r)),
        ("fig9_texture_cache_bandwidth", fig9(r)),
        ("active_rays_per_pass", active_rays(r)),
    ];
    let mut n = 0;
    for (name, svg) in charts {
        let svg = svg.map_err(|e| anyhow!("chart {name}: {e}"))?;
        output::write_bytes(&dir.join(format!("{name}.svg")), svg.as_bytes())?;
        let png = to_png(&svg).map_err(|e| anyhow!("chart {name}: {e}"))?;
        output::write_bytes(&dir.join(format!("{name}.png")), &png)?;
        n += 2;
    }
    Ok(n)
}

fn label(r: &StreamReport) -> String {
    format!("{}x{}, {}", r.width, r.height, r.config.arch)
}

/// A bar chart: one bar per name; `overlay` draws a second, narrower bar per name.
fn bars(
    title: &str,
    y_desc: &str,
    names: &[String],
    values: &[f64],
    overlay: Option<(&str, &str, &[f64])>,
) -> Result<String> {
    let mut svg = String::new();
    let draw = |svg: &mut String| -> Drawn {
        let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let n = names.len().max(1) as u32;
        let top = values.iter().chain(overlay.iter().flat_map(|o| o.2.iter())).fold(0.0f64, |a, &b| a.max(b));
        let top = if top > 0.0 { top * 1.12 } else { 1.0 };
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(86)
            .build_cartesian_2d((0u32..n - 1).into_segmented(), 0f64..top)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_desc(y_desc)
            .y_label_formatter(&|v| si(*v, 2))
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                    names.get(*i as usize).cloned().unwrap_or_default()
                }
                SegmentValue::Last => String::new(),
            })
            .draw()?;
        let wide = RGBColor(0x4e, 0x79, 0xa7);
        let series = chart.draw_series(
            Histogram::vertical(&chart)
                .style(wide.filled())
                .margin(12)
                .data(values.iter().enumerate().map(|(i, &v)| (i as u32, v))),
        )?;
        if let Some((first, second, over)) = overlay {
            series.label(first).legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], wide.filled()));
            let narrow = RGBColor(0xf2, 0x8e, 0x2b);
            chart
                .draw_series(
                    Histogram::vertical(&chart)
                        .style(narrow.filled())
                        .margin(34)
                        .data(over.iter().enumerate().map(|(i, &v)| (i as u32, v))),
                )?
                .label(second)
                .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], narrow.filled()));
            chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.9)).draw()?;
        }
        root.present()?;
        Ok(())
    };
    draw(&mut svg).map_err(|e| anyhow!("{e}"))?;
    Ok(svg)
}

/// Figure 7: instructions by kernel.
fn fig7(r: &StreamReport) -> Result<String> {
    let names: Vec<String> = r.kernels.iter().map(|k| k.kernel.to_string()).collect();
    let v: Vec<f64> = r.kernels.iter().map(|k| k.totals.instructions as f64).collect();
    bars(&format!("Instructions by kernel ({})", label(r)), "instructions", &names, &v, None)
}

/// Figure 8: random-access words by data type.
fn fig8(r: &StreamReport) -> Result<String> {
    let names: Vec<String> = r.classes.iter().map(|c| c.class.to_string()).collect();
    let v: Vec<f64> = r.classes.iter().map(|c| c.words as f64).collect();
    bars(&format!("Random-access words by data type ({})", label(r)), "words", &names, &v, None)
}

/// Figure 9: bandwidth without and with the texture cache, by data type.
fn fig9(r: &StreamReport) -> Result<String> {
    let names: Vec<String> = r
        .classes
        .iter()
        .map(|c| match c.hit_rate {
            Some(h) => format!("{} ({:.0}% hits)", c.class, 100.0 * h),
            None => c.class.to_string(),
        })
        .collect();
    let without: Vec<f64> = r.classes.iter().map(|c| c.bytes_without_cache as f64).collect();
    let with: Vec<f64> = r.classes.iter().map(|c| c.bytes_with_cache as f64).collect();
    bars(
        &format!("Bandwidth by data type, cache {} ({})", r.config.cache, label(r)),
        "bytes",
        &names,
        &without,
        Some(("no cache", "with cache", &with)),
    )
}

/// Active rays (waiting to traverse or intersect) after each pass, marked by kind.
fn active_rays(r: &StreamReport) -> Result<String> {
    let mut svg = String::new();
    let draw = |svg: &mut String| -> Drawn {
        let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let n = r.passes.len().max(1) as u32;
        let top = r.passes.iter().map(|p| p.active_after).max().unwrap_or(0).max(1) as f64 * 1.08;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Active rays after each pass ({})", label(r)), ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(86)
            .build_cartesian_2d(0u32..n, 0f64..top)?;
        chart.configure_mesh().x_desc("pass").y_desc("active rays").y_label_formatter(&|v| si(*v, 2)).draw()?;
        chart.draw_series(LineSeries::new(
            r.passes.iter().enumerate().map(|(i, p)| (i as u32, p.active_after as f64)),
            BLACK.mix(0.4),
        ))?;
        for (kind, color, name) in [
            (PassKind::Traverse, RGBColor(0x4e, 0x79, 0xa7), "traversal pass"),
            (PassKind::Intersect, RGBColor(0xe1, 0x57, 0x59), "intersection pass"),
        ] {
            chart
                .draw_series(
                    r.passes
                        .iter()
                        .enumerate()
                        .filter(|(_, p)| p.kind == Some(kind))
                        .map(|(i, p)| Circle::new((i as u32, p.active_after as f64), 2, color.filled())),
                )?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 6, y), 4, color.filled()));
        }
        chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.9)).draw()?;
        root.present()?;
        Ok(())
    };
    draw(&mut svg).map_err(|e| anyhow!("{e}"))?;
    Ok(svg)
}
