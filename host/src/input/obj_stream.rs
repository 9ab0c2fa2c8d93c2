//! OBJ read as a stream, for scenes larger than memory. A first pass counts the
//! vertex tables, loads the material libraries and learns which tables the faces use;
//! the second keeps only the vertex tables (`v`, `vt`, `vn`) and hands each face on,
//! triangulated, as it is read. Materials, objects, triangle order and triangulation
//! are those of [`crate::input::obj`], which reads through tobj, so a streamed file
//! gives the same triangles with the same ids.
//!
//! One difference: the in-memory reader gives a whole object default normals (texture
//! coordinates) when some of its faces lack them; the stream gives each corner its own
//! or the default. Files that use `vn` (`vt`) on all of an object's faces or on none
//! read the same either way.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::{MaterialRecord, ShadingVertex};

use crate::input::mesh::Mesh;
use crate::input::obj::LoadNotes;

/// One triangle of the stream.
#[derive(Clone, Copy, Debug)]
pub struct ObjTriangle {
    /// Corner positions.
    pub p: [[f32; 3]; 3],
    /// Corner shading data (meaningful when [`ObjStream::shading`] is set).
    pub shading: [ShadingVertex; 3],
    /// Material index into [`ObjStream::tables`]' materials.
    pub material: u32,
    /// Object id: a new `o`/`g` name between faces starts the next one.
    pub object: u32,
}

/// An OBJ file's tables, ready to stream its faces.
pub struct ObjStream {
    name: String,
    path: PathBuf,
    /// Materials, their names and textures (the mesh holds nothing else).
    pub tables: Mesh,
    /// Warnings from the material libraries.
    pub notes: LoadNotes,
    /// Each `mtllib` line's material names, in file order (to resolve `usemtl` as the
    /// in-memory reader does: against the libraries read so far).
    libraries: Vec<Vec<String>>,
    /// The index of the default material, when some face (or the file's end) has none.
    default_material: Option<u32>,
    /// The faces use normals, texture coordinates or vertex colours.
    pub shading: bool,
    /// Some vertex has a colour.
    colours: bool,
    /// Vertex table sizes (`v`, `vt`, `vn`).
    counts: [u64; 3],
    /// Triangles the faces make.
    pub triangles: u64,
    /// Some face has an object id other than 0.
    pub objects: bool,
}

/// What the first pass learns.
#[derive(Default)]
struct Survey {
    counts: [u64; 3],
    colours: bool,
    corner_data: bool,
    triangles: u64,
    libraries: Vec<(PathBuf, tobj::MTLLoadResult)>,
    needs_default: bool,
    objects: Objects,
}

/// Object ids as faces arrive: a face under another `o`/`g` name than the face before
/// it starts the next object (tobj's models, merged by name, as the in-memory reader
/// numbers them).
struct Objects {
    current: String,
    last: Option<String>,
    id: u32,
}

impl Default for Objects {
    fn default() -> Objects {
        Objects { current: "unnamed_object".into(), last: None, id: 0 }
    }
}

impl Objects {
    /// The id of a face read now.
    fn face(&mut self) -> u32 {
        if self.last.as_ref() != Some(&self.current) {
            if self.last.is_some() {
                self.id += 1;
            }
            self.last = Some(self.current.clone());
        }
        self.id
    }
}

impl ObjStream {
    /// Surveys `path` (plain or `.obj.gz`), loads its material libraries, and checks
    /// that its vertex tables fit in `budget` bytes.
    pub fn open(path: &Path, budget: u64) -> Result<ObjStream> {
        let name = path.display().to_string();
        let gz = is_gz(path);
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let survey = survey(&name, open_lines(path)?, |lib| crate::input::obj::read_mtl(&dir, lib, gz))?;
        let mut notes = LoadNotes::default();
        let mut tables = Mesh::default();
        let mut libraries = Vec::new();
        let mut all = Vec::new();
        let mut last_error = None;
        for (_, result) in survey.libraries {
            match result {
                Ok((mats, _)) => {
                    libraries.push(mats.iter().map(|m| m.name.clone()).collect());
                    all.extend(mats);
                }
                Err(e) => {
                    libraries.push(Vec::new());
                    last_error = Some(e);
                }
            }
        }
        // As tobj: any material read wins over a library's error.
        match last_error.filter(|_| all.is_empty()) {
            None => {}
            Some(tobj::LoadError::OpenFileFailed) => {
                notes.warnings.push(format!("{name}: material library not found; using the default material"))
            }
            Some(e) => bail!("{name}: malformed MTL: {}", crate::input::obj::describe(&e)),
        }
        crate::input::obj::add_materials(&name, Some(&dir), &all, &mut tables, &mut notes);
        let default_material = survey.needs_default.then(|| {
            tables.materials.push(MaterialRecord::DEFAULT);
            tables.material_names.push("default".into());
            tables.materials.len() as u32 - 1
        });
        if survey.triangles == 0 {
            bail!("{name}: the mesh has no triangles");
        }
        crate::input::limits::check_vertices(&name, survey.counts[0])?;
        let s = ObjStream {
            name,
            path: path.to_path_buf(),
            tables,
            notes,
            libraries,
            default_material,
            shading: survey.corner_data || survey.colours,
            colours: survey.colours,
            counts: survey.counts,
            triangles: survey.triangles,
            objects: survey.objects.id > 0,
        };
        if s.resident_bytes() > budget {
            bail!(
                "{}: its vertex tables need {} MB in memory, more than the memory budget allows (raise --memory-budget)",
                s.name,
                s.resident_bytes() / 1_000_000
            );
        }
        Ok(s)
    }

    /// The file's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Bytes the vertex tables take while streaming.
    pub fn resident_bytes(&self) -> u64 {
        let [v, vt, vn] = self.counts;
        v * if self.colours { 24 } else { 12 } + vt * 8 + vn * 12
    }

    /// Reads the faces in file order, triangulated, and hands each triangle to `emit`.
    pub fn faces(&self, emit: &mut dyn FnMut(ObjTriangle) -> Result<()>) -> Result<()> {
        let name = &self.name;
        let mut lines = open_lines(&self.path)?;
        let mut tables = VertexTables::with_capacity(self.counts, self.colours);
        let mut materials = MaterialMap::default();
        let mut library = 0usize;
        let mut objects = Objects::default();
        let mut corners = Vec::new();
        let mut poly = Vec::new();
        while let Some((number, line)) = lines.next_line(name)? {
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v" | "vt" | "vn") => tables.push(name, number, line)?,
                Some("f" | "l") => {
                    parse_corners(name, number, words, tables.len(), &mut corners)?;
                    if corners.len() < 3 {
                        continue;
                    }
                    let object = objects.face();
                    let m = match materials.current {
                        Some(m) if m < self.tables.materials.len() => m as u32,
                        _ => self
                            .default_material
                            .ok_or_else(|| anyhow!("{name}: internal error: no default material"))?,
                    };
                    poly.clear();
                    poly.extend(0..corners.len() as u32);
                    let mut result = Ok(());
                    crate::input::polygon::triangulate(&poly, |t| {
                        if result.is_ok() {
                            let c = t.map(|k| corners[k as usize]);
                            result = emit(ObjTriangle {
                                p: c.map(|c: Corner| tables.positions[c.v]),
                                shading: c.map(|c| tables.shading(c)),
                                material: m,
                                object,
                            });
                        }
                    });
                    result?;
                }
                Some("o" | "g") => objects.current = group_name(line),
                Some("mtllib") => {
                    materials.library(self.libraries.get(library).into_iter().flatten().map(String::as_str));
                    library += 1;
                }
                Some("usemtl") => materials.use_line(name, number, line)?,
                _ => {}
            }
        }
        Ok(())
    }
}

/// `.obj.gz` (or any `.gz`).
fn is_gz(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// The first pass: table sizes, material libraries, and what the faces use.
fn survey(name: &str, mut lines: Lines, read_mtl: impl Fn(&Path) -> tobj::MTLLoadResult) -> Result<Survey> {
    let mut s = Survey::default();
    let mut materials = MaterialMap::default();
    while let Some((number, line)) = lines.next_line(name)? {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                s.counts[0] += 1;
                s.colours |= words.count() == 6;
            }
            Some("vt") => s.counts[1] += 1,
            Some("vn") => s.counts[2] += 1,
            Some("f" | "l") => {
                let (mut n, mut data) = (0u64, false);
                for w in words {
                    n += 1;
                    data |= w.split('/').skip(1).any(|part| !part.is_empty());
                }
                if n >= 3 {
                    s.triangles += n - 2;
                    s.corner_data |= data;
                    s.needs_default |= materials.current.is_none();
                    s.objects.face();
                }
            }
            Some("o" | "g") => s.objects.current = group_name(line),
            Some("mtllib") => {
                let lib = PathBuf::from(rest_of_line(line));
                let result = read_mtl(&lib);
                if let Ok((mats, _)) = &result {
                    materials.library(mats.iter().map(|m| m.name.as_str()));
                }
                s.libraries.push((lib, result));
            }
            Some("usemtl") => materials.use_line(name, number, line)?,
            _ => {}
        }
    }
    // The in-memory reader closes its last object at the end of the file, faces or
    // not, and gives it the default material if it has none.
    s.needs_default |= materials.current.is_none();
    Ok(s)
}

/// `usemtl` resolved as tobj resolves it: by name, against the material libraries read
/// so far (a later material of the same name wins); an unknown name leaves no material.
#[derive(Default)]
struct MaterialMap {
    index: HashMap<String, usize>,
    loaded: usize,
    /// The material faces read now take.
    current: Option<usize>,
}

impl MaterialMap {
    /// A library's materials, by name, in order.
    fn library<'a>(&mut self, names: impl Iterator<Item = &'a str>) {
        for n in names {
            self.index.insert(n.to_string(), self.loaded);
            self.loaded += 1;
        }
    }

    /// A `usemtl` line (line `number` of the file `name`).
    fn use_line(&mut self, name: &str, number: u64, line: &str) -> Result<()> {
        let n = rest_of_line(line);
        if n.is_empty() {
            bail!("{name}: malformed OBJ: line {number}: usemtl names no material");
        }
        self.current = self.index.get(n).copied();
        Ok(())
    }
}

/// What follows the keyword (tobj: after the first space, trimmed).
fn rest_of_line(line: &str) -> &str {
    line.split_once(' ').map_or("", |(_, r)| r).trim()
}

/// An `o`/`g` line's name, as tobj takes it.
fn group_name(line: &str) -> String {
    let first = line.chars().next().map_or(0, char::len_utf8);
    let n = line.get(first..).unwrap_or("").trim();
    if n.is_empty() {
        "unnamed_object".into()
    } else {
        n.to_string()
    }
}

/// A face corner: indices into the vertex tables (`None`: not given).
#[derive(Clone, Copy, Debug)]
struct Corner {
    v: usize,
    vt: Option<usize>,
    vn: Option<usize>,
}

/// Parses a face's corners: `v`, `v/vt`, `v//vn`, `v/vt/vn`, counting from 1, or back
/// from the newest when negative; each must name an element defined so far.
fn parse_corners<'a>(
    name: &str,
    number: u64,
    words: impl Iterator<Item = &'a str>,
    counts: [usize; 3],
    out: &mut Vec<Corner>,
) -> Result<()> {
    out.clear();
    for word in words {
        let mut idx = [None; 3];
        for (k, part) in word.split('/').enumerate() {
            if part.is_empty() {
                continue;
            }
            let what = ["vertex", "texture coordinate", "normal"];
            let (Some(slot), Ok(i)) = (idx.get_mut(k), part.parse::<i64>()) else {
                bail!("{name}: malformed OBJ: line {number}: '{word}' is not a face corner");
            };
            let count = counts[k] as i64;
            let resolved = if i < 0 { count + i } else { i - 1 };
            if i == 0 || !(0..count).contains(&resolved) {
                bail!("{name}: malformed OBJ: line {number}: the face names {} {i}, but {count} are defined", what[k]);
            }
            *slot = Some(resolved as usize);
        }
        let Some(v) = idx[0] else {
            bail!("{name}: malformed OBJ: line {number}: '{word}' names no vertex");
        };
        out.push(Corner { v, vt: idx[1], vn: idx[2] });
    }
    Ok(())
}

/// The vertex tables read so far.
struct VertexTables {
    positions: Vec<[f32; 3]>,
    colours: Option<Vec<[f32; 3]>>,
    uvs: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
}

impl VertexTables {
    fn with_capacity(counts: [u64; 3], colours: bool) -> VertexTables {
        let [v, vt, vn] = counts.map(|c| c as usize);
        VertexTables {
            positions: Vec::with_capacity(v),
            colours: colours.then(|| Vec::with_capacity(v)),
            uvs: Vec::with_capacity(vt),
            normals: Vec::with_capacity(vn),
        }
    }

    fn len(&self) -> [usize; 3] {
        [self.positions.len(), self.uvs.len(), self.normals.len()]
    }

    /// Reads a `v`, `vt` or `vn` line as tobj does: `v x y z [w | r g b]`, `vt u v`,
    /// `vn x y z`, extra numbers after `vt` and `vn` ignored.
    fn push(&mut self, name: &str, number: u64, line: &str) -> Result<()> {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let bad = || anyhow!("{name}: malformed OBJ: line {number}: cannot read the {key} line");
        let mut floats = |n: usize| -> Result<[f32; 3]> {
            let mut out = [0.0; 3];
            for slot in out.iter_mut().take(n) {
                *slot = words.next().and_then(|w| w.parse().ok()).ok_or_else(bad)?;
            }
            Ok(out)
        };
        match key {
            "vt" => {
                let [u, v, _] = floats(2)?;
                self.uvs.push([u, v]);
            }
            "vn" => self.normals.push(floats(3)?),
            _ => {
                let mut p = floats(3)?;
                let rest: Vec<&str> = words.collect();
                let mut colour = [1.0; 3];
                match rest.as_slice() {
                    [] => {}
                    [w] => {
                        let w: f32 = w.parse().map_err(|_| bad())?;
                        if w == 0.0 {
                            bail!("{name}: malformed OBJ: line {number}: the vertex's w is zero");
                        }
                        p = p.map(|c| c / w);
                    }
                    [r, g, b] => {
                        for (slot, c) in colour.iter_mut().zip([r, g, b]) {
                            *slot = c.parse().map_err(|_| bad())?;
                        }
                    }
                    _ => return Err(bad()),
                }
                self.positions.push(p);
                if let Some(c) = &mut self.colours {
                    c.push(colour);
                }
            }
        }
        Ok(())
    }

    /// A corner's shading data: its normal and texture coordinate, or the defaults.
    fn shading(&self, c: Corner) -> ShadingVertex {
        ShadingVertex {
            normal: c.vn.and_then(|i| self.normals.get(i)).copied().unwrap_or([0.0; 3]),
            uv: c.vt.and_then(|i| self.uvs.get(i)).copied().unwrap_or([0.0; 2]),
            color: self.colours.as_ref().and_then(|t| t.get(c.v)).copied().unwrap_or([1.0; 3]),
        }
    }
}

/// An OBJ's lines, numbered from 1, decompressed if it is gzip'd.
struct Lines {
    reader: Box<dyn BufRead + Send>,
    buf: Vec<u8>,
    text: String,
    number: u64,
}

fn open_lines(path: &Path) -> Result<Lines> {
    let (file, _) = crate::input::read_file::open_regular(path)?;
    let raw: Box<dyn Read + Send> =
        if is_gz(path) { Box::new(flate2::read::MultiGzDecoder::new(file)) } else { Box::new(file) };
    Ok(Lines {
        reader: Box::new(BufReader::with_capacity(1 << 20, raw)),
        buf: Vec::new(),
        text: String::new(),
        number: 0,
    })
}

impl Lines {
    /// The next line and its number, `None` at the end.
    fn next_line(&mut self, name: &str) -> Result<Option<(u64, &str)>> {
        self.buf.clear();
        let n = self.reader.read_until(b'\n', &mut self.buf).map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
        if n == 0 {
            return Ok(None);
        }
        self.number += 1;
        let number = self.number;
        self.text.clear();
        match std::str::from_utf8(&self.buf) {
            Ok(t) => self.text.push_str(t),
            Err(_) => bail!("{name}: malformed OBJ: line {number} is not UTF-8 text"),
        }
        Ok(Some((number, self.text.trim_end_matches(['\n', '\r']))))
    }
}
