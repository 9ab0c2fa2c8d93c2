//! PPM textures (Netpbm `P6` binary and `P3` text, 8 or 16 bits per sample), the format
//! BART's scenes keep their textures in: converted to 8-bit RGBA texels like every other
//! texture, the size checked from the header before any texel is allocated.

use raypipe_core::image::TextureRecord;

use crate::input::texture::{check_size, TextureImage};

/// The header's next number, skipping whitespace and `#` comments; returns it and the
/// position after it.
fn header_number(bytes: &[u8], mut at: usize) -> Result<(u32, usize), String> {
    loop {
        match bytes.get(at) {
            Some(b'#') => {
                while bytes.get(at).is_some_and(|&c| c != b'\n') {
                    at += 1;
                }
            }
            Some(c) if c.is_ascii_whitespace() => at += 1,
            Some(_) => break,
            None => return Err("truncated header".into()),
        }
    }
    let start = at;
    while bytes.get(at).is_some_and(u8::is_ascii_digit) {
        at += 1;
    }
    let text = std::str::from_utf8(&bytes[start..at]).map_err(|_| "malformed header".to_string())?;
    let v = text.parse::<u32>().map_err(|_| format!("malformed header number '{text}'"))?;
    Ok((v, at))
}

/// Decodes a PPM file.
pub fn decode_ppm(bytes: &[u8]) -> Result<TextureImage, String> {
    let binary = match bytes.get(..2) {
        Some(b"P6") => true,
        Some(b"P3") => false,
        _ => return Err("not a PPM file (P6 or P3)".into()),
    };
    let (width, at) = header_number(bytes, 2)?;
    let (height, at) = header_number(bytes, at)?;
    let (maxval, at) = header_number(bytes, at)?;
    check_size(width, height)?;
    if maxval == 0 || maxval > 65535 {
        return Err(format!("impossible maximum value {maxval}"));
    }
    let samples = 3 * width as usize * height as usize;
    let scale = |v: u32| ((v.min(maxval) as u64 * 255 + maxval as u64 / 2) / maxval as u64) as u8;
    let mut values = Vec::with_capacity(samples);
    if binary {
        // One whitespace byte ends the header.
        let data = bytes.get(at + 1..).ok_or("truncated header")?;
        let wide = maxval > 255;
        let need = samples * if wide { 2 } else { 1 };
        if data.len() < need {
            return Err(format!("truncated: {} bytes of texels, {need} needed", data.len()));
        }
        if wide {
            values.extend(data[..need].chunks_exact(2).map(|b| scale(u32::from(u16::from_be_bytes([b[0], b[1]])))));
        } else {
            values.extend(data[..need].iter().map(|&b| scale(u32::from(b))));
        }
    } else {
        let mut pos = at;
        for _ in 0..samples {
            let (v, next) = header_number(bytes, pos).map_err(|_| "truncated or malformed texels".to_string())?;
            values.push(scale(v));
            pos = next;
        }
    }
    let mut rgba = Vec::with_capacity(samples / 3 * 4);
    for px in values.chunks_exact(3) {
        rgba.extend_from_slice(&[px[0], px[1], px[2], 255]);
    }
    Ok(TextureImage { width, height, rgba, wrap: TextureRecord::REPEAT })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_and_text_ppm_decode_alike_and_bad_ones_are_refused() {
        let mut p6 = b"P6\n# a comment\n2 1\n255\n".to_vec();
        p6.extend_from_slice(&[255, 0, 0, 0, 128, 255]);
        let p3 = b"P3 2 1 255\n255 0 0\n0 128 255\n";
        let a = decode_ppm(&p6).unwrap();
        let b = decode_ppm(p3).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.rgba, vec![255, 0, 0, 255, 0, 128, 255, 255]);
        let wide = [b"P6 1 1 65535\n".to_vec(), vec![0xff, 0xff, 0x80, 0x00, 0, 0]].concat();
        assert_eq!(decode_ppm(&wide).unwrap().rgba, vec![255, 128, 0, 255]);
        assert!(decode_ppm(b"P6 2 1 255\n\x01\x02").unwrap_err().contains("truncated"));
        assert!(decode_ppm(b"P5 1 1 255\n\x00").unwrap_err().contains("not a PPM"));
        assert!(decode_ppm(b"P6 99999 99999 255\n").unwrap_err().contains("impossible size"));
        assert!(decode_ppm(b"P3 1 1 0\n0 0 0").unwrap_err().contains("maximum"));
    }
}
