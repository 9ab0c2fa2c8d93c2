//! A walkthrough as Wald & Slusallek 2001 plot theirs (Figure 10): frames per second
//! and megabytes of data moved (bricks loaded after decompression, or bytes sent
//! between MPI ranks), frame by frame, on two axes. Drawn with plotters as SVG, rendered to PNG with resvg.

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use crate::output::chart_numbers::si;

/// The chart of `frames` — `(frames per second, megabytes)` per frame, the megabytes
/// named by `data` ("MB loaded") — as SVG.
pub fn walk_chart(frames: &[(f64, f64)], title: &str, data: &str) -> Result<String> {
    let mut svg = String::new();
    let draw = |svg: &mut String| -> std::result::Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::with_string(svg, (900, 480)).into_drawing_area();
        root.fill(&WHITE)?;
        let n = frames.len().max(2) as f64 - 1.0;
        let top = |f: &dyn Fn(&(f64, f64)) -> f64| frames.iter().map(f).fold(0.0f64, f64::max).max(1e-3) * 1.15;
        let (fps_top, mb_top) = (top(&|r| r.0), top(&|r| r.1));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .right_y_label_area_size(70)
            .build_cartesian_2d(0f64..n, 0f64..fps_top)?
            .set_secondary_coord(0f64..n, 0f64..mb_top);
        chart.configure_mesh().x_desc("frame").y_desc("frames/s").y_label_formatter(&|v| si(*v, 2)).draw()?;
        chart.configure_secondary_axes().y_desc(data).label_style(("sans-serif", 14)).draw()?;
        let blue = RGBColor(0x4e, 0x79, 0xa7);
        let orange = RGBColor(0xf2, 0x8e, 0x2b);
        chart
            .draw_series(LineSeries::new(
                frames.iter().enumerate().map(|(k, r)| (k as f64, r.0)),
                blue.stroke_width(2),
            ))?
            .label("frames/s")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], blue.stroke_width(2)));
        chart
            .draw_secondary_series(LineSeries::new(
                frames.iter().enumerate().map(|(k, r)| (k as f64, r.1)),
                orange.stroke_width(2),
            ))?
            .label(data)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], orange.stroke_width(2)));
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
        Ok(())
    };
    draw(&mut svg).map_err(|e| anyhow!("{e}"))?;
    Ok(svg)
}

/// Writes the chart of `frames` beside the walk's frames: `STEM-walk.png` for the output
/// `STEM.png`. Returns its path.
pub fn write_walk_chart(
    output: &std::path::Path,
    frames: &[(f64, f64)],
    title: &str,
    data: &str,
) -> Result<std::path::PathBuf> {
    let stem = output.file_stem().map_or("walk".into(), |s| s.to_string_lossy().into_owned());
    let chart = output.with_file_name(format!("{stem}-walk.png"));
    let svg = walk_chart(frames, title, data)?;
    crate::output::write_bytes(&chart, &crate::output::chart_raster::to_png(&svg)?)?;
    Ok(chart)
}
