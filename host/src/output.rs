//! Writing output files without ever leaving a half-written one: write a temporary file
//! in the target directory, then rename it over the target.

use std::io::Write;
use std::path::Path;

use anyhow::{anyhow, Result};

/// The directory `path` is written in (`.` for a bare file name).
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks that `path`'s directory exists, so that a command writing several outputs can
/// refuse before it writes any (issue 18, D13: `simulate --report <bad dir>` left the PNG
/// behind).
pub fn check_dir(path: &Path) -> Result<()> {
    let dir = dir_of(path);
    if !dir.is_dir() {
        return Err(anyhow!("{}: directory {} does not exist", path.display(), dir.display()));
    }
    Ok(())
}

/// Writes `path` atomically by calling `fill` on a temporary file next to it.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let name = path.display();
    check_dir(path)?;
    let dir = dir_of(path);
    let mut tmp = tempfile::Builder::new()
        .prefix(".raypipe-")
        .tempfile_in(dir)
        .map_err(|e| anyhow!("{name}: cannot create a file in {}: {e}", dir.display()))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(|e| anyhow!("{name}: {e}"))?;
        w.flush().map_err(|e| anyhow!("{name}: cannot write: {e}"))?;
    }
    tmp.persist(path).map_err(|e| anyhow!("{name}: cannot write: {}", e.error))?;
    Ok(())
}

/// Writes an 8-bit RGB PNG atomically.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[[u8; 3]]) -> Result<()> {
    write_atomic(path, |w| {
        let mut enc = png::Encoder::new(w, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header().map_err(|e| anyhow!("cannot write PNG: {e}"))?;
        writer.write_image_data(rgb.as_flattened()).map_err(|e| anyhow!("cannot write PNG: {e}"))?;
        writer.finish().map_err(|e| anyhow!("cannot write PNG: {e}"))?;
        Ok(())
    })
}

/// Writes raw bytes atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes).map_err(|e| anyhow!("cannot write: {e}")))
}
