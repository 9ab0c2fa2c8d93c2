//! What a glTF file must satisfy before any of its geometry is read, so that the `gltf`
//! crate's readers never meet what they would panic on or read past, and a small file
//! cannot multiply into more geometry than a scene may hold:
//!
//! - its buffers are read here, from the file's own BIN chunk, a `data:` URI or a
//!   regular file beside it (never a device), each at least as long as it says;
//! - every accessor a triangle primitive is read through lies inside its buffer view and
//!   the view inside its buffer, with the component types and shapes the glTF 2.0
//!   specification allows for that attribute (§3.7.2.1, §3.7.2.2);
//! - the node hierarchy is a set of trees (§3.5.3: no cycles, at most one parent);
//! - the triangles and vertices the scene places — each mesh once per node that places
//!   it — are within [`crate::input::limits`].

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Semantic;
use gltf::{Accessor, Document};

use crate::input::read_file;

/// A GLB's header, if `bytes` is one: its declared length must cover at least the
/// 12-byte header itself (the `gltf` crate subtracts the header's size from it
/// unchecked: an overflow panic where overflow checks are on; found by the `gltf` fuzz
/// target).
pub fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) else { return Ok(()) };
    let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
    if length < 12 {
        return Err(format!("its GLB header declares {length} bytes, fewer than the header's own 12"));
    }
    Ok(())
}

/// Every primitive's POSITION accessor exists. The `gltf` crate's validation indexes the
/// accessors by it unchecked (a panic on a file that names a missing one; found by the
/// `gltf` fuzz target), so the JSON is read without validation and checked first.
pub fn check_position_accessors(bytes: &[u8]) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let json = if bytes.starts_with(b"glTF") {
        gltf::Glb::from_slice(bytes).map_err(|e| e.to_string())?.json.into_owned()
    } else {
        bytes.to_vec()
    };
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(&json).map_err(|e| e.to_string())?;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let Some(a) = prim.attributes.get(&Checked::Valid(gltf::json::mesh::Semantic::Positions)) else { continue };
            if a.value() >= root.accessors.len() {
                return Err(format!(
                    "mesh {m} primitive {p}: POSITION names accessor {}, of {} accessors",
                    a.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    Ok(())
}

/// The buffers of `doc`, read from `blob` (a `.glb`'s BIN chunk), `data:` URIs or files
/// in `base`; `name` is the file named in errors.
pub fn read_buffers(
    doc: &Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
    name: &str,
) -> Result<Vec<gltf::buffer::Data>> {
    let mut out = Vec::new();
    for b in doc.buffers() {
        let what = format!("{name}: buffer {}", b.index());
        let mut data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| anyhow!("{what}: the file has no BIN chunk"))?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, base).map_err(|e| anyhow!("{what}: {e}"))?,
        };
        if data.len() < b.length() {
            bail!("{what}: holds {} bytes of the {} it declares", data.len(), b.length());
        }
        // The readers expect 4-byte alignment of the whole (as the crate's own import).
        data.resize(data.len().next_multiple_of(4), 0);
        out.push(gltf::buffer::Data(data));
    }
    Ok(out)
}

/// The bytes a URI names: a base64 `data:` URI, or a file relative to `base` (or a
/// `file:` path), which must be a regular file.
pub fn read_uri(uri: &str, base: &Path) -> Result<Vec<u8>> {
    use base64::Engine;
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest.split_once(";base64,").ok_or_else(|| anyhow!("a data: URI that is not base64"))?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| anyhow!("malformed base64 in a data: URI: {e}"));
    }
    let path = match uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
        Some(p) => std::path::PathBuf::from(p),
        None if uri.contains(':') => bail!("unsupported URI scheme in {uri:?}"),
        None => {
            let decoded = urlencoding::decode(uri).map_err(|_| anyhow!("the URI {uri:?} is not UTF-8 once decoded"))?;
            base.join(&*decoded)
        }
    };
    read_file::read_bytes(&path, read_file::DATA_LIMIT)
}

/// Checks the node hierarchy reachable from the scene's roots: no cycle, no node with
/// two parents. Returns the triangles and vertices its meshes place.
pub fn check_nodes(doc: &Document, scene: &gltf::Scene<'_>) -> Result<(u64, u64), String> {
    const NEW: u8 = 0;
    const OPEN: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![NEW; doc.nodes().len()];
    let (mut triangles, mut vertices) = (0u64, 0u64);
    // Depth first, iteratively: (node, entering) pairs; leaving closes the node.
    let mut stack: Vec<(gltf::Node<'_>, bool)> = scene.nodes().map(|n| (n, true)).collect();
    while let Some((node, entering)) = stack.pop() {
        let i = node.index();
        if !entering {
            state[i] = DONE;
            continue;
        }
        match state[i] {
            OPEN => return Err(format!("the node hierarchy has a cycle through node {i}")),
            DONE => return Err(format!("node {i} has more than one parent (glTF node hierarchies are trees)")),
            _ => {}
        }
        state[i] = OPEN;
        if let Some(m) = node.mesh() {
            let (t, v) = mesh_size(&m);
            triangles = triangles.saturating_add(t);
            vertices = vertices.saturating_add(v);
        }
        stack.push((node.clone(), false));
        stack.extend(node.children().map(|c| (c, true)));
    }
    Ok((triangles, vertices))
}

/// The triangles and vertices one placement of `mesh` adds.
fn mesh_size(mesh: &gltf::Mesh<'_>) -> (u64, u64) {
    let (mut t, mut v) = (0u64, 0u64);
    for p in mesh.primitives().filter(|p| p.mode() == gltf::mesh::Mode::Triangles) {
        let positions = p.get(&Semantic::Positions).map_or(0, |a| a.count() as u64);
        t += p.indices().map_or(positions, |a| a.count() as u64) / 3;
        v += positions;
    }
    (t, v)
}

/// Checks every accessor the loader reads from a triangle primitive of `mesh`.
pub fn check_primitive(p: &gltf::Primitive<'_>, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    use DataType::{F32, U16, U32, U8};
    use Dimensions::{Scalar, Vec2, Vec3, Vec4};
    if let Some(a) = p.indices() {
        check_kind(&a, "indices", &[U8, U16, U32], &[Scalar])?;
        check_range(&a, "indices", buffers)?;
    }
    for (semantic, a) in p.attributes() {
        let (what, types, dims): (&str, &[DataType], &[Dimensions]) = match semantic {
            Semantic::Positions => ("POSITION", &[F32], &[Vec3]),
            Semantic::Normals => ("NORMAL", &[F32], &[Vec3]),
            Semantic::TexCoords(0) => ("TEXCOORD_0", &[F32, U8, U16], &[Vec2]),
            Semantic::Colors(0) => ("COLOR_0", &[F32, U8, U16], &[Vec3, Vec4]),
            _ => continue,
        };
        check_kind(&a, what, types, dims)?;
        check_range(&a, what, buffers)?;
    }
    Ok(())
}

fn check_kind(a: &Accessor<'_>, what: &str, types: &[DataType], dims: &[Dimensions]) -> Result<(), String> {
    if !types.contains(&a.data_type()) || !dims.contains(&a.dimensions()) {
        return Err(format!(
            "accessor {} ({what}) holds {:?} {:?}; glTF allows {types:?} {dims:?} there",
            a.index(),
            a.dimensions(),
            a.data_type()
        ));
    }
    Ok(())
}

/// The accessor's elements, and any sparse substitution, lie inside their buffer views,
/// and the views inside their buffers.
fn check_range(a: &Accessor<'_>, what: &str, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    // glTF 2.0 §5.1.1: `count` is at least 1 (the gltf crate computes `count - 1`).
    if a.count() == 0 {
        return Err(format!("accessor {} ({what}) has count 0; glTF requires at least 1", a.index()));
    }
    let elem = a.size() as u64;
    if let Some(view) = a.view() {
        let stride = view.stride().map_or(elem, |s| s as u64);
        let span = span(a.offset() as u64, a.count() as u64, stride, elem);
        check_view(&view, span, &format!("accessor {} ({what})", a.index()), buffers)?;
    }
    if let Some(s) = a.sparse() {
        let what = format!("accessor {} ({what}), sparse part", a.index());
        let count = s.count() as u64;
        if count > a.count() as u64 {
            return Err(format!("{what}: {count} substitutions in an accessor of {}", a.count()));
        }
        let index_size = match s.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let indices = s.indices();
        check_view(&indices.view(), span(indices.offset() as u64, count, index_size, index_size), &what, buffers)?;
        let values = s.values();
        check_view(&values.view(), span(values.offset() as u64, count, elem, elem), &what, buffers)?;
    }
    Ok(())
}

/// The bytes `count` elements of `elem` bytes, `stride` apart from `offset`, reach
/// (saturating: an absurd count reaches past any view).
fn span(offset: u64, count: u64, stride: u64, elem: u64) -> u64 {
    match count {
        0 => offset,
        n => offset.saturating_add((n - 1).saturating_mul(stride)).saturating_add(elem),
    }
}

fn check_view(
    view: &gltf::buffer::View<'_>,
    reach: u64,
    what: &str,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let (len, at) = (view.length() as u64, view.index());
    if reach > len {
        return Err(format!("{what} reaches byte {reach} of buffer view {at}, which holds {len}"));
    }
    let b = view.buffer().index();
    let have = buffers.get(b).map_or(0, |d| d.0.len() as u64);
    let end = (view.offset() as u64).saturating_add(len);
    if end > have {
        return Err(format!("buffer view {at} reaches byte {end} of buffer {b}, which holds {have}"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::input::gltf::load_gltf_bytes;
    use base64::Engine;

    /// A glTF of one triangle: 36 bytes of positions then three u16 indices, the index
    /// accessor's `type`/`componentType`/`count` and the nodes given.
    fn doc(index_accessor: &str, nodes: &str, scene_nodes: &str) -> String {
        let mut bin = Vec::new();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 0, 1, 0, 2, 0, 0, 0]);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":{scene_nodes}}}],"nodes":{nodes},
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
            "buffers":[{{"byteLength":44,"uri":"data:application/octet-stream;base64,{b64}"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":8}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,{index_accessor}}}]}}"#
        )
    }

    fn load(text: &str) -> Result<usize, String> {
        let dir = std::env::temp_dir();
        load_gltf_bytes("t.gltf", text.as_bytes(), &dir).map(|(m, _, _)| m.triangles.len()).map_err(|e| e.to_string())
    }

    const U16_INDICES: &str = r#""componentType":5123,"count":3,"type":"SCALAR""#;

    #[test]
    fn a_glb_header_shorter_than_itself_is_malformed() {
        // "glTF", version 2, length 0: the gltf crate computes 0 − 12.
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        glb.extend_from_slice(&0u32.to_le_bytes());
        glb.extend_from_slice(b"\0\0\0\0JSON{}");
        let e = load_gltf_bytes("t.glb", &glb, &std::env::temp_dir()).err().unwrap().to_string();
        assert!(e.contains("declares 0 bytes, fewer than the header's own 12"), "{e}");
    }

    #[test]
    fn a_missing_position_accessor_is_malformed() {
        let text = doc(U16_INDICES, r#"[{"mesh":0}]"#, "[0]").replace(r#""POSITION":0"#, r#""POSITION":7"#);
        let e = load(&text).unwrap_err();
        assert!(e.contains("POSITION names accessor 7, of 2 accessors"), "{e}");
    }

    #[test]
    fn a_good_triangle_loads() {
        assert_eq!(load(&doc(U16_INDICES, r#"[{"mesh":0}]"#, "[0]")), Ok(1));
    }

    #[test]
    fn bad_index_accessors_name_their_cause() {
        // FLOAT indices: the gltf crate's read_indices reaches `unreachable!`.
        let e = load(&doc(r#""componentType":5126,"count":3,"type":"SCALAR""#, r#"[{"mesh":0}]"#, "[0]")).unwrap_err();
        assert!(e.contains("accessor 1 (indices) holds Scalar F32"), "{e}");
        // 4·10⁹ indices over an 8-byte view.
        let e = load(&doc(r#""componentType":5123,"count":4000000000,"type":"SCALAR""#, r#"[{"mesh":0}]"#, "[0]"))
            .unwrap_err();
        assert!(e.contains("reaches byte 8000000000 of buffer view 1, which holds 8"), "{e}");
        // An empty accessor (the gltf crate's reader subtracts one from its count).
        let text = doc(U16_INDICES, r#"[{"mesh":0}]"#, "[0]")
            .replace(r#""componentType":5126,"count":3"#, r#""componentType":5126,"count":0"#);
        let e = load(&text).unwrap_err();
        assert!(e.contains("accessor 0 (POSITION) has count 0"), "{e}");
        // A view beyond its buffer.
        let text = doc(U16_INDICES, r#"[{"mesh":0}]"#, "[0]")
            .replace(r#""byteOffset":36,"byteLength":8"#, r#""byteOffset":40,"byteLength":8"#);
        let e = load(&text).unwrap_err();
        assert!(e.contains("buffer view 1 reaches byte 48 of buffer 0, which holds 44"), "{e}");
    }

    #[test]
    fn node_graphs_are_trees_and_placements_are_counted_first() {
        // Node 2 under both 0 and 1: not a cycle, but not a tree either.
        let dag = r#"[{"children":[2]},{"children":[2]},{"mesh":0}]"#;
        let e = load(&doc(U16_INDICES, dag, "[0,1]")).unwrap_err();
        assert!(e.contains("node 2 has more than one parent"), "{e}");
        let cycle = r#"[{"children":[1]},{"children":[0]}]"#;
        let e = load(&doc(U16_INDICES, cycle, "[0]")).unwrap_err();
        assert!(e.contains("cycle through node 0"), "{e}");
        // A mesh of 2¹⁶ triangles placed by 513 nodes: 33.6 M triangles, over the limit,
        // from a 0.5 MB file; refused before a single triangle is read.
        let tris = 1usize << 16;
        let triangle = doc(U16_INDICES, "[]", "[]");
        let mut bin: Vec<u8> = Vec::new();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
        for _ in 0..tris {
            bin.extend_from_slice(&[0, 0, 1, 0, 2, 0]);
        }
        let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
        let at = triangle.find("base64,").unwrap() + 7;
        let end = at + triangle[at..].find('"').unwrap();
        let nodes: Vec<String> = (0..513).map(|_| r#"{"mesh":0}"#.to_string()).collect();
        let roots: Vec<String> = (0..513).map(|i| i.to_string()).collect();
        let big = format!("{}{b64}{}", &triangle[..at], &triangle[end..])
            .replace(r#""byteLength":44"#, &format!(r#""byteLength":{}"#, bin.len()))
            .replace(r#""byteOffset":36,"byteLength":8"#, &format!(r#""byteOffset":36,"byteLength":{}"#, 6 * tris))
            .replace(r#""count":3,"type":"SCALAR""#, &format!(r#""count":{},"type":"SCALAR""#, 3 * tris))
            .replacen(r#""nodes":[]"#, &format!(r#""nodes":[{}]"#, roots.join(",")), 1)
            .replacen(r#""nodes":[]"#, &format!(r#""nodes":[{}]"#, nodes.join(",")), 1);
        let e = load(&big).unwrap_err();
        assert!(e.contains("33619968 triangles is more than 33554432"), "{e}");
    }

    #[test]
    fn buffers_from_devices_and_bad_uris_are_refused() {
        let text = doc(U16_INDICES, r#"[{"mesh":0}]"#, "[0]");
        let at = text.find("data:").unwrap();
        let end = at + text[at..].find('"').unwrap();
        for (uri, why) in [
            ("file:///dev/zero", "is a character device"),
            ("%FF.bin", "not UTF-8"),
            ("http://x/b.bin", "unsupported URI"),
        ] {
            let e = load(&format!("{}{uri}{}", &text[..at], &text[end..])).unwrap_err();
            assert!(e.contains(why), "{uri}: {e}");
        }
    }
}
