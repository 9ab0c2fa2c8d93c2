//! What every chart shares once drawn: SVG rendered to pixels or PNG bytes, and the
//! colour map of heatmaps (the sweep plots', the cost images').

use anyhow::{anyhow, Result};
use plotters::style::RGBColor;

/// Renders an SVG to PNG bytes.
pub fn to_png(svg: &str) -> Result<Vec<u8>> {
    to_pixmap(svg)?.encode_png().map_err(|e| anyhow!("cannot encode the PNG: {e}"))
}

/// Renders an SVG to pixels.
pub fn to_pixmap(svg: &str) -> Result<resvg::tiny_skia::Pixmap> {
    let mut opt = resvg::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    // plotters asks for "sans-serif": map it to a sans face the system has.
    let family = db
        .faces()
        .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
        .filter(|n| n.contains("Sans") || n.contains("Arial") || n.contains("Helvetica"))
        .min_by_key(|n| (!n.contains("DejaVu Sans"), n.len()));
    if let Some(family) = family {
        db.set_sans_serif_family(family.clone());
        opt.font_family = family;
    }
    let tree = resvg::usvg::Tree::from_str(svg, &opt).map_err(|e| anyhow!("cannot read the SVG: {e}"))?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        resvg::tiny_skia::Pixmap::new(size.width(), size.height()).ok_or_else(|| anyhow!("empty chart"))?;
    resvg::render(&tree, resvg::tiny_skia::Transform::default(), &mut pixmap.as_mut());
    Ok(pixmap)
}

/// Viridis at `t` in 0..=1 (five anchors, linear between them).
pub fn viridis(t: f64) -> RGBColor {
    const A: [(f64, f64, f64); 5] =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let mix = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    RGBColor(mix(A[i].0, A[i + 1].0), mix(A[i].1, A[i + 1].1), mix(A[i].2, A[i + 1].2))
}
