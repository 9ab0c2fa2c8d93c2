//! PLY read as a stream, for scenes larger than memory: the vertices are kept (position
//! and, when the file has them, normal, texture coordinates and colour), the faces are
//! triangulated and handed on one by one, never held. ASCII and both binary byte orders,
//! optionally gzip-compressed; the same triangles, in the same order, with the same
//! shading data as [`crate::input::ply`] reads into memory.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::ShadingVertex;

/// How the file's data is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// A scalar type of the header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

/// A property: a scalar, or a list with its count's type.
#[derive(Clone, Debug)]
struct Prop {
    name: String,
    kind: Scalar,
    list: Option<Scalar>,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Prop>,
}

/// The vertices of a PLY file and a reader positioned at its faces.
pub struct PlyStream {
    name: String,
    reader: Box<dyn BufRead + Send>,
    format: Format,
    elements: Vec<Element>,
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading data (empty without normals, texture coordinates or colours).
    pub shading: Vec<ShadingVertex>,
    // Elements after the vertices, still to read.
    next: usize,
    vertex_count: u32,
    ascii_line: Vec<String>,
}

/// Bytes one vertex table entry takes in memory (position and shading data).
pub const VERTEX_BYTES: u64 = 12 + 32;

impl PlyStream {
    /// Opens `path`, reads the header and the vertices (at most `vertex_budget` bytes
    /// of them in memory).
    pub fn open(path: &Path, vertex_budget: u64) -> Result<PlyStream> {
        let name = path.display().to_string();
        let (file, _) = crate::input::read_file::open_regular(path)?;
        let raw: Box<dyn Read + Send> = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
            Box::new(flate2::read::MultiGzDecoder::new(file))
        } else {
            Box::new(file)
        };
        let mut reader: Box<dyn BufRead + Send> = Box::new(BufReader::with_capacity(1 << 20, raw));
        let (format, elements) = read_header(&name, &mut reader)?;
        let mut s = PlyStream {
            name,
            reader,
            format,
            elements,
            positions: Vec::new(),
            shading: Vec::new(),
            next: 0,
            vertex_count: 0,
            ascii_line: Vec::new(),
        };
        s.read_vertices(vertex_budget)?;
        Ok(s)
    }

    /// The file's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    fn read_vertices(&mut self, budget: u64) -> Result<()> {
        let name = self.name.clone();
        let Some(vi) = self.elements.iter().position(|e| e.name == "vertex") else {
            bail!("{name}: malformed PLY: no vertex element");
        };
        // Elements before the vertices are skipped.
        for k in 0..vi {
            self.skip_element(k)?;
        }
        let el = self.elements[vi].clone();
        let has = |keys: &[&str]| el.props.iter().any(|p| keys.contains(&p.name.as_str()));
        let shaded = has(&["nx"]) || has(&["u", "s", "texture_u"]) || has(&["red"]);
        let per = if shaded { VERTEX_BYTES } else { 12 };
        if el.count.saturating_mul(per) > budget {
            bail!(
                "{name}: {} vertices need {} MB in memory, more than the memory budget allows (raise --memory-budget)",
                el.count,
                el.count.saturating_mul(per) / 1_000_000
            );
        }
        crate::input::limits::check_vertices(&name, el.count)?;
        self.positions.reserve(el.count as usize);
        let byte_colour = el.props.iter().any(|p| p.name == "red" && p.kind == Scalar::U8);
        let mut values = vec![0.0f64; el.props.len()];
        for i in 0..el.count {
            for (k, p) in el.props.iter().enumerate() {
                if p.list.is_some() {
                    bail!("{name}: malformed PLY: vertex property {} is a list", p.name);
                }
                values[k] = self.scalar(p.kind)?;
            }
            let get = |keys: &[&str]| el.props.iter().position(|p| keys.contains(&p.name.as_str())).map(|k| values[k]);
            let (Some(x), Some(y), Some(z)) = (get(&["x"]), get(&["y"]), get(&["z"])) else {
                bail!("{name}: malformed PLY: vertex {i} lacks x, y or z");
            };
            self.positions.push([x as f32, y as f32, z as f32]);
            if shaded {
                self.shading.push(crate::input::ply::shading_vertex(get, byte_colour));
            }
        }
        self.next = vi + 1;
        self.vertex_count = self.positions.len() as u32;
        Ok(())
    }

    /// Reads the faces, triangulated, in file order: `emit` gets each triangle's vertex
    /// indices. Other elements are skipped.
    pub fn faces(&mut self, emit: &mut dyn FnMut([u32; 3]) -> Result<()>) -> Result<u64> {
        let name = self.name.clone();
        let nv = self.vertex_count;
        let mut faces = 0u64;
        let mut poly = Vec::new();
        while self.next < self.elements.len() {
            let k = self.next;
            self.next += 1;
            let el = self.elements[k].clone();
            if el.name != "face" {
                self.skip_element(k)?;
                continue;
            }
            let Some(li) = el.props.iter().position(|p| p.name == "vertex_indices" || p.name == "vertex_index") else {
                bail!("{name}: malformed PLY: faces have no vertex_indices list");
            };
            for i in 0..el.count {
                for (pi, p) in el.props.iter().enumerate() {
                    match p.list {
                        Some(count_kind) => {
                            let n = self.scalar(count_kind)?;
                            if !(0.0..=1e6).contains(&n) {
                                bail!("{name}: malformed PLY: face {i} has a list of {n} entries");
                            }
                            if pi == li {
                                poly.clear();
                            }
                            for _ in 0..n as usize {
                                let v = self.scalar(p.kind)?;
                                if pi == li {
                                    if !(0.0..u32::MAX as f64).contains(&v) || v.fract() != 0.0 {
                                        bail!("{name}: malformed PLY: face {i} has no vertex_indices list of non-negative integers");
                                    }
                                    poly.push(v as u32);
                                }
                            }
                        }
                        None => {
                            self.scalar(p.kind)?;
                        }
                    }
                }
                if poly.iter().any(|&v| v >= nv) {
                    bail!("{name}: malformed PLY: face {i} references a vertex that does not exist");
                }
                let mut err = Ok(());
                crate::input::polygon::triangulate(&poly, |t| {
                    if err.is_ok() {
                        err = emit(t);
                    }
                });
                err?;
                faces += 1;
            }
        }
        if faces == 0 {
            bail!("{name}: the PLY file has no faces (a point cloud cannot be ray traced)");
        }
        Ok(faces)
    }

    fn skip_element(&mut self, k: usize) -> Result<()> {
        let el = self.elements[k].clone();
        if el.props.is_empty() {
            // Nothing to read, however large the count: no loop over it.
            return Ok(());
        }
        for _ in 0..el.count {
            for p in &el.props {
                match p.list {
                    Some(c) => {
                        let n = self.scalar(c)?;
                        if !(0.0..=1e6).contains(&n) {
                            bail!("{}: malformed PLY: a list of {n} entries", self.name);
                        }
                        for _ in 0..n as usize {
                            self.scalar(p.kind)?;
                        }
                    }
                    None => {
                        self.scalar(p.kind)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The next scalar of the data.
    fn scalar(&mut self, kind: Scalar) -> Result<f64> {
        let trunc = || anyhow!("malformed PLY: the data ends early");
        if self.format == Format::Ascii {
            while self.ascii_line.is_empty() {
                let mut line = String::new();
                if self.reader.read_line(&mut line).map_err(|e| anyhow!("{}: cannot read: {e}", self.name))? == 0 {
                    return Err(trunc()).map_err(|e| anyhow!("{}: {e}", self.name));
                }
                self.ascii_line = line.split_whitespace().rev().map(str::to_string).collect();
            }
            let tok = self.ascii_line.pop().unwrap_or_default();
            // Parsed at the property's own type, as the in-memory reader does (a float
            // read as a double and then rounded can differ in the last bit).
            let v = match kind {
                Scalar::F32 => tok.parse::<f32>().map(f64::from).ok(),
                Scalar::F64 => tok.parse::<f64>().ok(),
                _ => tok.parse::<i64>().ok().map(|i| i as f64),
            };
            return v.ok_or_else(|| anyhow!("{}: malformed PLY: '{tok}' is not a number", self.name));
        }
        let mut b = [0u8; 8];
        let n = kind.size();
        self.reader.read_exact(&mut b[..n]).map_err(|_| anyhow!("{}: {}", self.name, trunc()))?;
        if self.format == Format::Big {
            b[..n].reverse();
        }
        Ok(match kind {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

/// Checks, before a parser reads a whole file's `bytes`, that the header's element
/// counts fit in the bytes after it: every element takes at least a byte (a line in
/// ASCII, its properties in binary), so a count larger than the file is a lie that
/// would otherwise have the parser build millions of empty elements.
pub(crate) fn check_counts_fit(name: &str, bytes: &[u8]) -> Result<()> {
    let mut r = bytes;
    let (format, elements) = read_header(name, &mut r)?;
    let mut need: u64 = 0;
    for el in &elements {
        let per = match format {
            Format::Ascii => el.props.len().max(1),
            Format::Little | Format::Big => {
                el.props.iter().map(|p| p.list.unwrap_or(p.kind).size()).sum::<usize>().max(1)
            }
        };
        need = need.saturating_add(el.count.saturating_mul(per as u64));
    }
    if need > r.len() as u64 {
        bail!(
            "{name}: malformed PLY: the header's element counts need at least {need} bytes, the file has {} after it",
            r.len()
        );
    }
    Ok(())
}

/// Reads the header: the format and the elements with their properties.
fn read_header(name: &str, r: &mut dyn BufRead) -> Result<(Format, Vec<Element>)> {
    let bad = |why: &str| anyhow!("{name}: malformed PLY: {why}");
    let mut line = String::new();
    let mut next_line = |line: &mut String| -> Result<()> {
        line.clear();
        if r.read_line(line).map_err(|e| anyhow!("{name}: cannot read: {e}"))? == 0 || line.len() > 4096 {
            return Err(bad("the header does not end"));
        }
        Ok(())
    };
    next_line(&mut line)?;
    if line.trim() != "ply" {
        return Err(bad("it does not start with 'ply'"));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for _ in 0..10_000 {
        next_line(&mut line)?;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["end_header"] => {
                let format = format.ok_or_else(|| bad("no format line"))?;
                return Ok((format, elements));
            }
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(bad("unknown format")),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", n, count] => {
                let count = count.parse().map_err(|_| bad("an element count is not a number"))?;
                elements.push(Element { name: n.to_string(), count, props: Vec::new() });
            }
            ["property", "list", c, t, n] => {
                let el = elements.last_mut().ok_or_else(|| bad("a property before any element"))?;
                let (c, t) = (Scalar::parse(c), Scalar::parse(t));
                let (Some(c), Some(t)) = (c, t) else { return Err(bad("unknown property type")) };
                el.props.push(Prop { name: n.to_string(), kind: t, list: Some(c) });
            }
            ["property", t, n] => {
                let el = elements.last_mut().ok_or_else(|| bad("a property before any element"))?;
                let t = Scalar::parse(t).ok_or_else(|| bad("unknown property type"))?;
                el.props.push(Prop { name: n.to_string(), kind: t, list: None });
            }
            _ => return Err(bad(&format!("unknown header line '{}'", line.trim()))),
        }
    }
    Err(bad("the header does not end"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle binary PLY after an element `junk` of `junk` entries with no properties.
    fn one_triangle(junk: u64) -> Vec<u8> {
        let mut file = format!(
            "ply\nformat binary_little_endian 1.0\nelement junk {junk}\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            file.extend(c.to_le_bytes());
        }
        file.push(3);
        [0i32, 1, 2].iter().for_each(|i| file.extend(i.to_le_bytes()));
        file
    }

    #[test]
    fn element_counts_bounded_by_the_data() {
        let lying = one_triangle(18_000_000_000_000_000_000);
        // Read whole, the lying count is refused before a parser sees it.
        let e = check_counts_fit("j.ply", &lying).unwrap_err().to_string();
        assert!(e.starts_with("j.ply: malformed PLY: the header's element counts"), "{e}");
        check_counts_fit("h.ply", &one_triangle(0)).unwrap();
        // Streamed, an element with nothing to read is skipped at once, however large its count.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("j.ply");
        std::fs::write(&path, &lying).unwrap();
        let mut s = PlyStream::open(&path, u64::MAX).unwrap();
        let mut tris = Vec::new();
        s.faces(&mut |t| {
            tris.push(t);
            Ok(())
        })
        .unwrap();
        assert_eq!((s.positions.len(), tris), (3, vec![[0, 1, 2]]));
    }
}
