//! Per-pixel cost images: a value per pixel (cycles, traversal steps, triangle tests,
//! bytes) as a viridis heatmap PNG with a colour bar, so where a frame's time and
//! traffic go can be seen on the image itself.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};

use crate::output;
use crate::output::chart_raster::{to_pixmap, viridis};

/// The file of the cost `what` for a prefix: `PREFIX-what.png`.
pub fn path(prefix: &Path, what: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_owned();
    s.push(format!("-{what}.png"));
    PathBuf::from(s)
}

/// Writes `values` (row-major, `width` × `height`) as a heatmap titled `title`.
pub fn write(path: &Path, width: u32, height: u32, values: &[f64], title: &str) -> Result<()> {
    if values.len() != (width * height) as usize || width == 0 {
        bail!("{}: {} values for a {width}x{height} image", path.display(), values.len());
    }
    let max = values.iter().copied().filter(|v| v.is_finite()).fold(0.0f64, f64::max);
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    // Small frames are drawn larger, whole pixels per pixel.
    let scale = (384 / width).clamp(1, 16);
    let (w, h) = (width * scale, height * scale);
    let (bar_w, pad) = (170u32, 16u32);
    let total_w = w + bar_w + 2 * pad;
    let total_h = h.max(220) + 2 * pad + 28;
    let top = pad + 28;
    let bar = (w + 2 * pad + 10, top, 22u32, h.max(220) - 10);
    let mut stops = String::new();
    for k in 0..=10 {
        let c = viridis(1.0 - k as f64 / 10.0);
        stops.push_str(&format!("<stop offset=\"{}\" stop-color=\"rgb({},{},{})\"/>", k as f64 / 10.0, c.0, c.1, c.2));
    }
    let label = |v: f64| crate::output::chart_numbers::si(v, 3);
    let svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{total_w}" height="{total_h}">
<rect width="100%" height="100%" fill="white"/>
<text x="{pad}" y="{ty}" font-family="sans-serif" font-size="15">{title} (mean {mean_l}, max {max_l})</text>
<defs><linearGradient id="g" x1="0" y1="0" x2="0" y2="1">{stops}</linearGradient></defs>
<rect x="{bx}" y="{by}" width="{bw}" height="{bh}" fill="url(#g)" stroke="black" stroke-width="0.5"/>
<text x="{lx}" y="{l0}" font-family="sans-serif" font-size="12">{max_l}</text>
<text x="{lx}" y="{l1}" font-family="sans-serif" font-size="12">{mid_l}</text>
<text x="{lx}" y="{l2}" font-family="sans-serif" font-size="12">0</text>
</svg>"##,
        ty = pad + 14,
        mean_l = label(mean),
        max_l = label(max),
        mid_l = label(max / 2.0),
        bx = bar.0,
        by = bar.1,
        bw = bar.2,
        bh = bar.3,
        lx = bar.0 + bar.2 + 6,
        l0 = bar.1 + 10,
        l1 = bar.1 + bar.3 / 2 + 4,
        l2 = bar.1 + bar.3,
    );
    let mut pixmap = to_pixmap(&svg)?;
    let stride = pixmap.width() as usize * 4;
    let data = pixmap.data_mut();
    for y in 0..h {
        for x in 0..w {
            let v = values[((y / scale) * width + x / scale) as usize];
            let c = viridis(if max > 0.0 { v / max } else { 0.0 });
            let at = (top + y) as usize * stride + (pad + x) as usize * 4;
            if let Some(px) = data.get_mut(at..at + 4) {
                px.copy_from_slice(&[c.0, c.1, c.2, 255]);
            }
        }
    }
    let png = pixmap.encode_png().map_err(|e| anyhow!("{}: cannot encode the PNG: {e}", path.display()))?;
    output::write_bytes(path, &png)
}
