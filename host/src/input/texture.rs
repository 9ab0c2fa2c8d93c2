//! Diffuse texture maps (`map_Kd`) for the scene image: PNG (png crate) and baseline
//! JPEG (jpeg-decoder), converted to 8-bit sRGB RGBA texels. A texture that is missing,
//! unreadable or in another format is left out with one warning, and its material keeps
//! its diffuse colour — never an error.

use std::path::Path;

use raypipe_core::image::TextureRecord;

/// A decoded texture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGBA, 8-bit sRGB, row-major from the top row.
    pub rgba: Vec<u8>,
    /// [`TextureRecord::REPEAT`] or [`TextureRecord::CLAMP`].
    pub wrap: u32,
}

/// Largest texture side accepted (a 16k × 16k texture is already 1 GiB of texels).
const MAX_SIDE: u32 = 16384;

/// Loads `file` (as named by `map_Kd`, which may carry options such as `-clamp on`)
/// relative to `dir`.
pub fn load(dir: &Path, spec: &str) -> Result<TextureImage, String> {
    let (file, wrap) = parse_spec(spec);
    let path = dir.join(&file);
    let bytes = crate::input::read_file::read_bytes(&path, crate::input::read_file::DATA_LIMIT)
        .map_err(|e| format!("texture {e}"))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let mut img = decode(&bytes, &ext).map_err(|e| format!("texture {}: {e}", path.display()))?;
    img.wrap = wrap;
    Ok(img)
}

/// Decodes a PNG or JPEG (`kind`: an extension or MIME type), refusing a size beyond
/// `MAX_SIDE` (16384) from the header, before the texels are allocated.
pub fn decode(bytes: &[u8], kind: &str) -> Result<TextureImage, String> {
    match kind {
        "png" | "image/png" => decode_png(bytes),
        "jpg" | "jpeg" | "image/jpeg" => decode_jpeg(bytes),
        "ppm" | "image/x-portable-pixmap" => crate::input::ppm::decode_ppm(bytes),
        _ => Err("unsupported image format (PNG, JPEG and PPM are read)".to_string()),
    }
}

pub(crate) fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!("impossible size {width}x{height}"));
    }
    Ok(())
}

/// The file name of a `map_Kd` value and its wrap mode (`-clamp on`); other options are
/// skipped with their arguments.
fn parse_spec(spec: &str) -> (String, u32) {
    let words: Vec<&str> = spec.split_whitespace().collect();
    let mut wrap = TextureRecord::REPEAT;
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') && words.len() - i > 1 {
        let args = match words[i] {
            "-clamp" => {
                if words.get(i + 1) == Some(&"on") {
                    wrap = TextureRecord::CLAMP;
                }
                1
            }
            "-o" | "-s" | "-t" => 3,
            "-mm" => 2,
            _ => 1,
        };
        i += 1 + args;
    }
    (words[i.min(words.len().saturating_sub(1))..].join(" "), wrap)
}

fn decode_png(bytes: &[u8]) -> Result<TextureImage, String> {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().map_err(|e| e.to_string())?;
    check_size(reader.info().width, reader.info().height)?;
    let size = reader.output_buffer_size().ok_or("image too large")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = info.color_type.samples();
    let rgba = to_rgba(&buf[..info.buffer_size()], channels)?;
    Ok(TextureImage { width: info.width, height: info.height, rgba, wrap: TextureRecord::REPEAT })
}

fn decode_jpeg(bytes: &[u8]) -> Result<TextureImage, String> {
    let mut dec = jpeg_decoder::Decoder::new(bytes);
    dec.read_info().map_err(|e| e.to_string())?;
    let info = dec.info().ok_or("no image information")?;
    check_size(info.width as u32, info.height as u32)?;
    let pixels = dec.decode().map_err(|e| e.to_string())?;
    let info = dec.info().ok_or("no image information")?;
    let channels = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        other => return Err(format!("unsupported JPEG pixel format {other:?}")),
    };
    let rgba = to_rgba(&pixels, channels)?;
    Ok(TextureImage { width: info.width as u32, height: info.height as u32, rgba, wrap: TextureRecord::REPEAT })
}

fn to_rgba(data: &[u8], channels: usize) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(data.len() / channels.max(1) * 4);
    for px in data.chunks_exact(channels.max(1)) {
        match channels {
            1 => out.extend_from_slice(&[px[0], px[0], px[0], 255]),
            2 => out.extend_from_slice(&[px[0], px[0], px[0], px[1]]),
            3 => out.extend_from_slice(&[px[0], px[1], px[2], 255]),
            4 => out.extend_from_slice(px),
            n => return Err(format!("unsupported channel count {n}")),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_kd_options() {
        assert_eq!(parse_spec("wood.png"), ("wood.png".to_string(), TextureRecord::REPEAT));
        assert_eq!(parse_spec("-clamp on wood.png"), ("wood.png".to_string(), TextureRecord::CLAMP));
        assert_eq!(parse_spec("-s 2 2 1 -bm 0.5 my wood.jpg"), ("my wood.jpg".to_string(), TextureRecord::REPEAT));
    }
}
