//! PLY (Stanford polygon files, ASCII or binary, optionally gzip-compressed) through the
//! `ply-rs-bw` crate: vertex positions, optional normals, texture coordinates and
//! colours, polygon faces (triangulated by [`crate::input::polygon`]), one default material.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use raypipe_core::image::{MaterialRecord, ShadingVertex};

use crate::input::mesh::Mesh;
use crate::input::obj::LoadNotes;

/// A scalar property as `f64` (`None` for a list).
fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

/// A list property of vertex indices (`None` if not a list or an index is negative).
fn indices(p: &Property) -> Option<Vec<u32>> {
    fn conv<T: Copy + TryInto<u32>>(v: &[T]) -> Option<Vec<u32>> {
        v.iter().map(|&i| i.try_into().ok()).collect()
    }
    match p {
        Property::ListChar(v) => conv(v),
        Property::ListUChar(v) => conv(v),
        Property::ListShort(v) => conv(v),
        Property::ListUShort(v) => conv(v),
        Property::ListInt(v) => conv(v),
        Property::ListUInt(v) => conv(v),
        _ => None,
    }
}

/// A vertex's shading data from its properties (`get` finds the first of some names):
/// normal, texture coordinates and colour, 8-bit colours (`byte_colour`, the usual)
/// scaled to [0, 1] and float colours kept; what is missing is 0 (white for colour).
pub(crate) fn shading_vertex(get: impl Fn(&[&str]) -> Option<f64>, byte_colour: bool) -> ShadingVertex {
    let n = [get(&["nx"]), get(&["ny"]), get(&["nz"])].map(|c| c.unwrap_or(0.0) as f32);
    let uv = [get(&["u", "s", "texture_u"]), get(&["v", "t", "texture_v"])].map(|c| c.unwrap_or(0.0) as f32);
    let c = [get(&["red"]), get(&["green"]), get(&["blue"])];
    let color = c.map(|c| c.map_or(1.0, |c| if byte_colour { c / 255.0 } else { c }) as f32);
    ShadingVertex { normal: n, uv, color }
}

/// Loads a `.ply` or `.ply.gz` file into a [`Mesh`].
pub fn load_ply_file(path: &Path) -> Result<(Mesh, LoadNotes)> {
    let name = path.display().to_string();
    let bytes = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
        crate::input::read_file::read_gzip(path, crate::input::read_file::DATA_LIMIT)?
    } else {
        crate::input::read_file::read_bytes(path, crate::input::read_file::DATA_LIMIT)?
    };
    crate::input::panic_guard::guarded(&name, "PLY", || parse_ply(&name, &bytes))
}

/// Parses the bytes of a PLY file; `name` is the input named in errors.
pub fn parse_ply(name: &str, bytes: &[u8]) -> Result<(Mesh, LoadNotes)> {
    crate::input::ply_stream::check_counts_fit(name, bytes)?;
    let parser = Parser::<DefaultElement>::new();
    let ply = parser.read_ply(&mut &bytes[..]).map_err(|e| {
        // The parser's messages run over several lines; the user gets one.
        anyhow!("{name}: malformed PLY: {}", e.to_string().split_whitespace().collect::<Vec<_>>().join(" "))
    })?;
    let vertices = ply.payload.get("vertex").ok_or_else(|| anyhow!("{name}: malformed PLY: no vertex element"))?;
    let faces = ply.payload.get("face").map(Vec::as_slice).unwrap_or_default();
    if faces.is_empty() {
        bail!("{name}: the PLY file has no faces (a point cloud cannot be ray traced)");
    }
    let mut mesh = Mesh::default();
    let mut notes = LoadNotes::default();
    let get = |v: &DefaultElement, keys: &[&str]| keys.iter().find_map(|k| v.get(*k).and_then(scalar));
    let has = |keys: &[&str]| vertices.first().is_some_and(|v| keys.iter().any(|k| v.contains_key(*k)));
    let (normals, uvs, colors) = (has(&["nx"]), has(&["u", "s", "texture_u"]), has(&["red"]));
    for (i, v) in vertices.iter().enumerate() {
        let p = [get(v, &["x"]), get(v, &["y"]), get(v, &["z"])];
        let [Some(x), Some(y), Some(z)] = p else { bail!("{name}: malformed PLY: vertex {i} lacks x, y or z") };
        mesh.positions.push([x as f32, y as f32, z as f32]);
        if normals || uvs || colors {
            let byte = matches!(v.get("red"), Some(Property::UChar(_)));
            mesh.shading.push(shading_vertex(|keys| get(v, keys), byte));
        }
    }
    let nv = mesh.positions.len() as u32;
    for (i, f) in faces.iter().enumerate() {
        let list = f.get("vertex_indices").or_else(|| f.get("vertex_index"));
        let Some(poly) = list.and_then(indices) else {
            bail!("{name}: malformed PLY: face {i} has no vertex_indices list of non-negative integers")
        };
        if poly.iter().any(|&k| k >= nv) {
            bail!("{name}: malformed PLY: face {i} references a vertex that does not exist");
        }
        crate::input::polygon::triangulate(&poly, |t| {
            mesh.triangles.push(t);
            mesh.tri_materials.push(0);
        });
    }
    mesh.materials.push(MaterialRecord::DEFAULT);
    mesh.material_names.push("default".into());
    mesh.validate(name)?;
    notes.warnings.extend(mesh.degenerate_warning(name));
    Ok((mesh, notes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_and_binary_quads_and_bad_input() {
        let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 255 0 0\n1 1 0 255 0 0\n0 1 0 255 0 0\n4 0 1 2 3\n";
        let (mesh, _) = parse_ply("q.ply", ascii.as_bytes()).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(mesh.shading[0].color, [1.0, 0.0, 0.0]);
        // The same quad in binary little endian, positions only.
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]] {
            p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
        }
        bin.push(4);
        [0u32, 1, 2, 3].iter().for_each(|i| bin.extend(i.to_le_bytes()));
        let (mesh, _) = parse_ply("q.ply", &bin).unwrap();
        assert_eq!((mesh.positions.len(), mesh.triangles.len(), mesh.shading.len()), (4, 2, 0));
        for (text, want) in [
            ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n", "no faces"),
            ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "does not exist"),
            ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n", "malformed PLY"),
            ("not a ply", "malformed PLY"),
            ("ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n0\n", "malformed PLY"),
            // A count with no properties behind it would have the parser build empty elements.
            ("ply\nformat binary_little_endian 1.0\nelement vertex 477777777\nend_header\nproperty list\n", "element counts need"),
        ] {
            let e = parse_ply("b.ply", text.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(want) && e.starts_with("b.ply") && !e.contains('\n'), "{want}: {e}");
        }
    }
}
