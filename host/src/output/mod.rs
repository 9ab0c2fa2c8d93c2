//! Writing output files without ever leaving a half-written one, nor replacing what is
//! not a regular file ([`target`]), and all of a command's outputs or none ([`batch`]).

pub mod batch;
pub mod chart_numbers;
pub mod chart_raster;
pub mod progress;
pub mod target;
pub mod tone_map;
pub mod trace_events;
pub mod walk_chart;
pub mod warnings;
pub mod waveform;

use std::io::Write;
use std::path::Path;

use anyhow::{anyhow, Result};

pub use target::check_writable;

/// Writes `path` by calling `fill` on a temporary file beside it (or on the device it
/// names), then naming it (see [`target`] and [`batch`]).
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    let name = path.display();
    let mut file = target::Pending::create(path)?;
    {
        let mut w = std::io::BufWriter::new(file.file());
        fill(&mut w).map_err(|e| anyhow!("{name}: {e}"))?;
        w.flush().map_err(|e| anyhow!("{name}: cannot write: {e}"))?;
    }
    batch::finish(file)
}

/// Gives `file` the permissions a newly created file gets: 0666 less the umask.
#[cfg(unix)]
pub(crate) fn set_default_permissions(file: &std::fs::File) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    // The umask can only be read by setting it; put it straight back.
    // SAFETY: umask has no memory-safety preconditions.
    let mask = unsafe {
        let m = libc::umask(0o022);
        libc::umask(m);
        m
    };
    file.set_permissions(std::fs::Permissions::from_mode(0o666 & !(mask as u32)))
}

#[cfg(not(unix))]
pub(crate) fn set_default_permissions(_: &std::fs::File) -> std::io::Result<()> {
    Ok(())
}

/// The image formats a frame can be written as, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG, through the display transform.
    Png,
    /// OpenEXR, 32-bit float linear RGB.
    Exr,
    /// Portable float map, 32-bit float linear RGB.
    Pfm,
}

impl ImageFormat {
    /// The format `path`'s extension names, or an error naming the path.
    pub fn of(path: &Path) -> Result<ImageFormat> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            Some("pfm") => Ok(ImageFormat::Pfm),
            _ => Err(anyhow!("{}: output must be a .png, .exr or .pfm file", path.display())),
        }
    }
}

/// Writes a frame atomically in the format its extension names: PNG through `choice`
/// (returning what automatic exposure chose, if it was asked for), EXR and PFM as the
/// linear radiance.
pub fn write_frame(
    path: &Path,
    frame: &crate::render::Frame,
    choice: &crate::output::tone_map::DisplayChoice,
) -> Result<Option<crate::output::tone_map::AutoExposure>> {
    let format = ImageFormat::of(path)?;
    if format != ImageFormat::Png {
        write_image(path, format, frame, &Default::default())?;
        return Ok(None);
    }
    let (display, auto) = choice.for_frame(&frame.radiance);
    write_image(path, format, frame, &display)?;
    Ok(auto)
}

fn write_image(
    path: &Path,
    format: ImageFormat,
    frame: &crate::render::Frame,
    display: &crate::output::tone_map::Display,
) -> Result<()> {
    if format != ImageFormat::Png || !display.is_identity() {
        let n = frame.width as usize * frame.height as usize;
        if frame.radiance.len() != n {
            return Err(anyhow!("{}: internal error: the frame has no linear radiance", path.display()));
        }
    }
    match format {
        ImageFormat::Png if display.is_identity() => write_png(path, frame.width, frame.height, &frame.pixels),
        ImageFormat::Png => {
            let pixels: Vec<[u8; 3]> = frame.radiance.iter().map(|&c| display.pixel(glam::Vec3::from(c))).collect();
            write_png(path, frame.width, frame.height, &pixels)
        }
        ImageFormat::Exr => write_exr(path, frame.width, frame.height, &frame.radiance),
        ImageFormat::Pfm => write_pfm(path, frame.width, frame.height, &frame.radiance),
    }
}

/// Writes linear RGB as a single-part scanline OpenEXR file of 32-bit floats.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<()> {
    use exr::prelude::*;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let [r, g, b] = rgb[p.y() * w + p.x()];
        (r, g, b)
    });
    let image = Image::from_channels((w, height as usize), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| anyhow!("{}: cannot encode EXR: {e}", path.display()))?;
    write_bytes(path, bytes.get_ref())
}

/// Writes linear RGB as a little-endian portable float map (rows bottom to top).
pub fn write_pfm(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<()> {
    write_atomic(path, |w| {
        write!(w, "PF\n{width} {height}\n-1.0\n").map_err(|e| anyhow!("cannot write: {e}"))?;
        for row in rgb.chunks(width.max(1) as usize).rev() {
            for px in row {
                for c in px {
                    w.write_all(&c.to_le_bytes()).map_err(|e| anyhow!("cannot write: {e}"))?;
                }
            }
        }
        Ok(())
    })
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

/// The file of frame `k` of a walkthrough written to `path`: `OUT-0007.png` for
/// `OUT.png`.
pub fn frame_path(path: &Path, k: usize) -> std::path::PathBuf {
    let stem = path.file_stem().map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
    let name = match path.extension() {
        Some(ext) => format!("{stem}-{k:04}.{}", ext.to_string_lossy()),
        None => format!("{stem}-{k:04}"),
    };
    path.with_file_name(name)
}

/// A file written as it goes, that appears under its name only when complete.
pub struct Streamed(target::Pending);

impl Streamed {
    /// Starts `path`.
    pub fn create(path: &Path) -> Result<Streamed> {
        target::Pending::create(path).map(Streamed)
    }

    /// The file to write to.
    pub fn file(&mut self) -> &mut std::fs::File {
        self.0.file()
    }

    /// Gives the file its name (when the open [`batch::Batch`] commits, if there is one).
    pub fn commit(self) -> Result<()> {
        batch::finish(self.0)
    }
}
