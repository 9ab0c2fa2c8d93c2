//! NumPy `.npy` files (format version 1.0/2.0/3.0): little-endian `float32` arrays of rays
//! in, a structured array of hits out — the formats simulation and research users
//! already have.

use std::path::Path;

use anyhow::{anyhow, bail, Result};

use crate::output::write_atomic;

/// A 2-D float32 array.
#[derive(Clone, Debug, PartialEq)]
pub struct Array2 {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Row-major data.
    pub data: Vec<f32>,
}

/// Reads a C-order, little-endian float32 array of two dimensions.
pub fn read_f32_2d(path: &Path) -> Result<Array2> {
    let name = path.display();
    let bytes = crate::input::read_file::read_bytes(path, crate::input::read_file::DATA_LIMIT)?;
    parse_f32_2d(&bytes).map_err(|e| anyhow!("{name}: {e}"))
}

/// Parses the bytes of a `.npy` file holding a 2-D float32 or float64 array (float64
/// values are rounded to float32, the precision raypipe traces in).
pub fn parse_f32_2d(bytes: &[u8]) -> Result<Array2> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        bail!("not a NumPy .npy file");
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize, 12),
        v => bail!("unsupported .npy version {v}"),
    };
    let header = bytes.get(start..start + header_len).ok_or_else(|| anyhow!("truncated .npy header"))?;
    let header = std::str::from_utf8(header).map_err(|_| anyhow!("malformed .npy header"))?;
    let descr = dict_value(header, "descr").ok_or_else(|| anyhow!("malformed .npy header: no descr"))?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    // float32 as is; float64 (NumPy's default) rounded to the nearest float32.
    let width = match descr {
        "<f4" | "=f4" | "f4" => 4,
        "<f8" | "=f8" | "f8" => 8,
        _ => bail!("array has dtype {descr}; expected float32 ('<f4') or float64 ('<f8')"),
    };
    if dict_value(header, "fortran_order").is_some_and(|v| v.trim() == "True") {
        bail!("array is in Fortran order; save it C-contiguous");
    }
    let shape = dict_value(header, "shape").ok_or_else(|| anyhow!("malformed .npy header: no shape"))?;
    let dims: Vec<usize> = shape
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>().map_err(|_| anyhow!("malformed .npy shape {shape}")))
        .collect::<Result<_>>()?;
    let [rows, cols] = dims[..] else { bail!("array has shape {shape}; expected two dimensions (N, 6) or (N, 8)") };
    let body = &bytes[start + header_len..];
    let need = rows.checked_mul(cols).and_then(|n| n.checked_mul(width)).ok_or_else(|| anyhow!("array too large"))?;
    if body.len() < need {
        bail!("truncated array: shape {shape} needs {need} bytes of data, file has {}", body.len());
    }
    // Fallible: an array the machine cannot hold is an error, not an abort.
    let mut data = Vec::new();
    data.try_reserve_exact(rows * cols).map_err(|_| anyhow!("array of shape {shape} does not fit in memory"))?;
    if width == 4 {
        data.extend(body[..need].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])));
    } else {
        data.extend(body[..need].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f32));
    }
    Ok(Array2 { rows, cols, data })
}

/// The text of `'key': value` in a NumPy header dict (value up to the next top-level comma).
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let at = header.find(&format!("'{key}'")).or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = &header[at + key.len() + 2..];
    let rest = rest.trim_start().strip_prefix(':')?.trim_start();
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' | '}' if depth == 0 => return Some(rest[..i].trim()),
            _ => {}
        }
    }
    None
}

fn header_bytes(dict: &str) -> Vec<u8> {
    // Version 1.0: magic, version, u16 header length; header padded with spaces to a
    // multiple of 64 bytes and ended by a newline.
    let mut h = dict.to_string();
    let total = 10 + h.len() + 1;
    h.push_str(&" ".repeat((64 - total % 64) % 64));
    h.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(h.len() as u16).to_le_bytes());
    out.extend_from_slice(h.as_bytes());
    out
}

/// Writes a 2-D float32 array atomically.
pub fn write_f32_2d(path: &Path, a: &Array2) -> Result<()> {
    write_f32_rows(path, a.rows, a.cols, |out| a.data.chunks(a.cols.max(1)).try_for_each(|row| out.push(row)))
}

/// The rows of an array being written by [`write_f32_rows`].
pub struct RowWriter<'a> {
    w: &'a mut dyn std::io::Write,
    cols: usize,
    rows: usize,
}

impl RowWriter<'_> {
    /// Appends one row (exactly the array's column count of values).
    pub fn push(&mut self, row: &[f32]) -> Result<()> {
        if row.len() != self.cols {
            bail!("internal error: a row of {} values in an array of {} columns", row.len(), self.cols);
        }
        for v in row {
            self.w.write_all(&v.to_le_bytes()).map_err(|e| anyhow!("cannot write: {e}"))?;
        }
        self.rows += 1;
        Ok(())
    }
}

/// Writes a `rows × cols` float32 array atomically, its rows produced by `fill` as they
/// are made (a batch of 268 M rays is never held in memory).
pub fn write_f32_rows(
    path: &Path,
    rows: usize,
    cols: usize,
    fill: impl FnOnce(&mut RowWriter<'_>) -> Result<()>,
) -> Result<()> {
    let header = header_bytes(&format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({rows}, {cols}), }}"));
    write_atomic(path, |w| {
        w.write_all(&header)?;
        let mut out = RowWriter { w, cols, rows: 0 };
        fill(&mut out)?;
        if out.rows != rows {
            bail!("internal error: {} rows written for a header of {rows}", out.rows);
        }
        Ok(())
    })
}

/// One hit record as written: `t`, `u`, `v` (float32) and `prim` (int32, −1 on a miss).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRecord {
    /// Distance (`inf` on a miss).
    pub t: f32,
    /// Barycentric weight of the second vertex.
    pub u: f32,
    /// Barycentric weight of the third vertex.
    pub v: f32,
    /// Triangle id in input face order, or −1.
    pub prim: i32,
}

/// Writes a structured array of `rows` records: `fields` as `(name, dtype)` (a dtype such
/// as `'<f4'`, or `('<f4', (3,))` for a sub-array), `data` the records packed in order.
pub fn write_records(path: &Path, fields: &[(&str, &str)], rows: usize, data: &[u8]) -> Result<()> {
    let descr: Vec<String> = fields.iter().map(|(n, t)| format!("('{n}', {t})")).collect();
    let header =
        header_bytes(&format!("{{'descr': [{}], 'fortran_order': False, 'shape': ({rows},), }}", descr.join(", ")));
    write_atomic(path, |w| {
        w.write_all(&header)?;
        w.write_all(data)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_rejections() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npy");
        let a = Array2 { rows: 2, cols: 6, data: (0..12).map(|i| i as f32 * 0.5).collect() };
        write_f32_2d(&p, &a).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!((bytes.len() - 12 * 4) % 64, 0, "header padded to 64 bytes");
        assert_eq!(parse_f32_2d(&bytes).unwrap(), a);
        // A float64 array, a 1-D array, a truncated body, junk.
        let edit = |from: &str, to: &str| {
            let at = bytes.windows(from.len()).position(|w| w == from.as_bytes()).unwrap();
            let mut b = bytes.clone();
            b.splice(at..at + from.len(), to.bytes());
            b
        };
        // float64 is read (and rounded); other dtypes are not.
        let mut f8 = edit("<f4", "<f8");
        f8.extend(std::iter::repeat_n(0u8, 12 * 4));
        let body = f8.len() - 12 * 8;
        for (i, v) in (0..12).map(|i| i as f64 * 0.5 * (1.0 + 1e-12)).enumerate() {
            f8[body + 8 * i..body + 8 * i + 8].copy_from_slice(&v.to_le_bytes());
        }
        assert_eq!(parse_f32_2d(&f8).unwrap(), a);
        assert!(parse_f32_2d(&edit("<f4", "<i4")).unwrap_err().to_string().contains("float64"));
        assert!(parse_f32_2d(&edit("(2, 6)", "(12,)  ")).unwrap_err().to_string().contains("two dimensions"));
        assert!(parse_f32_2d(&edit("False", "True ")).unwrap_err().to_string().contains("Fortran"));
        assert!(parse_f32_2d(&bytes[..bytes.len() - 4]).unwrap_err().to_string().contains("truncated"));
        assert!(parse_f32_2d(b"hello").is_err());
    }
}
