//! OBJ/MTL loading through tobj: polygons are triangulated ([`crate::input::polygon`]), objects merged in file
//! order, and vertices that share position, normal and texture coordinate are unified so
//! that positions and shading data share one index.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::{MaterialRecord, ShadingVertex, NULL_INDEX};

use crate::input::mesh::Mesh;
use crate::input::obj_indices;
use crate::input::polygon;
use crate::input::texture;

/// What the loader noticed but did not reject.
#[derive(Clone, Debug, Default)]
pub struct LoadNotes {
    /// One-line warnings for the user.
    pub warnings: Vec<String>,
}

fn load_options() -> tobj::LoadOptions {
    // Polygons come whole (`face_arities`) and are triangulated here: tobj's fans made
    // builds quadratic in a polygon's size.
    tobj::LoadOptions { triangulate: false, single_index: true, ignore_points: true, ignore_lines: true }
}

/// Loads an OBJ file (and the MTL files it names) into a [`Mesh`].
pub fn load_obj_file(path: &Path) -> Result<(Mesh, LoadNotes)> {
    let name = path.display().to_string();
    crate::input::panic_guard::guarded(&name, "OBJ", || load_obj_unguarded(path, name.clone()))
}

fn load_obj_unguarded(path: &Path, name: String) -> Result<(Mesh, LoadNotes)> {
    let meta = std::fs::metadata(path).map_err(|e| anyhow!("{name}: cannot read: {e}"))?;
    if meta.is_dir() {
        bail!("{name}: is a directory, not an OBJ file");
    }
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz")) {
        return load_obj_gz(path, &name);
    }
    let text = crate::input::read_file::read_bytes(path, crate::input::read_file::DATA_LIMIT)?;
    obj_indices::check_face_indices(&name, &text)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut reader = std::io::BufReader::new(text.as_slice());
    let result = tobj::load_obj_buf(&mut reader, &load_options(), |mtl| read_mtl(&dir, mtl, false));
    convert(&name, Some(path.parent().unwrap_or(Path::new("."))), result)
}

/// The material library `mtl` named by an OBJ in `dir`; for a compressed OBJ
/// (`gz_too`) a `.gz` beside it serves when the plain file is missing.
pub(crate) fn read_mtl(dir: &Path, mtl: &Path, gz_too: bool) -> tobj::MTLLoadResult {
    let limit = crate::input::read_file::TEXT_LIMIT;
    let plain = dir.join(mtl);
    if let Ok(bytes) = crate::input::read_file::read_bytes(&plain, limit) {
        return load_mtl(&bytes);
    }
    let mut gz = plain.into_os_string();
    gz.push(".gz");
    if !gz_too || !Path::new(&gz).exists() {
        return Err(tobj::LoadError::OpenFileFailed);
    }
    match crate::input::read_file::read_gzip(Path::new(&gz), limit) {
        Ok(bytes) => load_mtl(&bytes),
        Err(_) => Err(tobj::LoadError::ReadError),
    }
}

/// Parses an MTL file through tobj, after rejecting what tobj would panic on: a colour
/// (`Ka`, `Kd`, `Ks`, `Ke`) with fewer than three numbers (found by the `obj_mtl` fuzz
/// target).
fn load_mtl(bytes: &[u8]) -> tobj::MTLLoadResult {
    let text = String::from_utf8_lossy(bytes);
    for line in text.lines() {
        let mut words = line.split_whitespace();
        if matches!(words.next(), Some("Ka" | "Kd" | "Ks" | "Ke")) && words.count() < 3 {
            return Err(tobj::LoadError::MaterialParseError);
        }
    }
    tobj::load_mtl_buf(&mut std::io::BufReader::new(bytes))
}

/// A gzip-compressed OBJ (`scene.obj.gz`); its MTL files are read from beside it,
/// compressed or not.
fn load_obj_gz(path: &Path, name: &str) -> Result<(Mesh, LoadNotes)> {
    let text = crate::input::read_file::read_gzip(path, crate::input::read_file::DATA_LIMIT)?;
    obj_indices::check_face_indices(name, &text)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut reader = std::io::BufReader::new(text.as_slice());
    let result = tobj::load_obj_buf(&mut reader, &load_options(), |mtl| read_mtl(&dir, mtl, true));
    convert(name, Some(path.parent().unwrap_or(Path::new("."))), result)
}

/// Loads an OBJ from memory; `mtl` resolves material library names to their text.
pub fn load_obj_str(name: &str, obj: &str, mtl: &dyn Fn(&Path) -> Option<String>) -> Result<(Mesh, LoadNotes)> {
    obj_indices::check_face_indices(name, obj.as_bytes())?;
    let mut reader = std::io::BufReader::new(obj.as_bytes());
    let result = tobj::load_obj_buf(&mut reader, &load_options(), |p| match mtl(p) {
        Some(text) => load_mtl(text.as_bytes()),
        None => Err(tobj::LoadError::OpenFileFailed),
    });
    convert(name, None, result)
}

/// `dir`: where the OBJ is, for texture files (`None` for an OBJ held in memory).
fn convert(name: &str, dir: Option<&Path>, result: tobj::LoadResult) -> Result<(Mesh, LoadNotes)> {
    let (models, materials) = result.map_err(|e| anyhow!("{name}: malformed OBJ: {}", describe(&e)))?;
    let mut notes = LoadNotes::default();
    let materials = match materials {
        Ok(m) => m,
        Err(tobj::LoadError::OpenFileFailed) => {
            notes.warnings.push(format!("{name}: material library not found; using the default material"));
            Vec::new()
        }
        Err(e) => bail!("{name}: malformed MTL: {}", describe(&e)),
    };

    let mut mesh = Mesh::default();
    add_materials(name, dir, &materials, &mut mesh, &mut notes);
    let mut default_material = None;
    let any_normals = models.iter().any(|m| !m.mesh.normals.is_empty());
    let any_colors = models.iter().any(|m| !m.mesh.vertex_color.is_empty());
    let any_uv = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let shading = any_normals || any_colors || any_uv;

    // Objects: a new `o`/`g` name starts one (tobj also splits an object where its
    // material changes, keeping the name).
    let mut object = 0u32;
    let mut last_name: Option<&str> = None;
    for model in &models {
        let m = &model.mesh;
        if last_name.is_some_and(|n| n != model.name) {
            object += 1;
        }
        last_name = Some(&model.name);
        let arities_cover = m.face_arities.iter().map(|&a| a as usize).sum::<usize>() == m.indices.len();
        if m.positions.len() % 3 != 0 || !(m.face_arities.is_empty() && m.indices.len() % 3 == 0 || arities_cover) {
            bail!("{name}: malformed OBJ: object '{}' has incomplete data", model.name);
        }
        let base = mesh.positions.len() as u32;
        let nv = m.positions.len() / 3;
        for i in 0..nv {
            mesh.positions.push([m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]]);
            if shading {
                let get3 = |v: &Vec<f32>, d: [f32; 3]| {
                    if v.len() >= 3 * nv {
                        [v[3 * i], v[3 * i + 1], v[3 * i + 2]]
                    } else {
                        d
                    }
                };
                let uv =
                    if m.texcoords.len() >= 2 * nv { [m.texcoords[2 * i], m.texcoords[2 * i + 1]] } else { [0.0; 2] };
                mesh.shading.push(ShadingVertex {
                    normal: get3(&m.normals, [0.0; 3]),
                    uv,
                    color: get3(&m.vertex_color, [1.0; 3]),
                });
            }
        }
        let material = match m.material_id {
            Some(id) if id < mesh.materials.len() => id as u32,
            _ => *default_material.get_or_insert_with(|| {
                mesh.materials.push(MaterialRecord::DEFAULT);
                mesh.material_names.push("default".into());
                (mesh.materials.len() - 1) as u32
            }),
        };
        if m.indices.iter().any(|&v| v as usize >= nv) {
            bail!("{name}: malformed OBJ: a face in object '{}' references a missing vertex", model.name);
        }
        let mut add = |t: [u32; 3]| {
            mesh.triangles.push(t.map(|v| v + base));
            mesh.tri_materials.push(material);
            mesh.objects.push(object);
        };
        if m.face_arities.is_empty() {
            m.indices.chunks_exact(3).for_each(|t| add([t[0], t[1], t[2]]));
        } else {
            let mut start = 0;
            for &arity in &m.face_arities {
                let face = &m.indices[start..start + arity as usize];
                start += arity as usize;
                polygon::triangulate(face, &mut add);
            }
        }
    }
    mesh.validate(name)?;
    notes.warnings.extend(mesh.degenerate_warning(name));
    Ok((mesh, notes))
}

/// The MTL's materials into `mesh`, with their diffuse textures: one load (and at most
/// one warning) per texture file, however many materials use it — Sponza's 2 missing
/// files were 45 warnings — and one warning per feature raypipe does not render.
pub(crate) fn add_materials(
    name: &str,
    dir: Option<&Path>,
    materials: &[tobj::Material],
    mesh: &mut Mesh,
    notes: &mut LoadNotes,
) {
    // `Ok`: the texture's index; `Err`: the failure's index in `failed`, with the
    // materials that asked for it.
    let mut loaded: std::collections::HashMap<&str, Result<u32, usize>> = std::collections::HashMap::new();
    let mut failed: Vec<(String, Vec<&str>)> = Vec::new();
    for m in materials {
        let mut record = material_record(m);
        if let Some(spec) = &m.diffuse_texture {
            let slot = *loaded.entry(spec.as_str()).or_insert_with(|| {
                let error = match dir.map(|d| texture::load(d, spec)) {
                    Some(Ok(t)) => {
                        mesh.textures.push(t);
                        return Ok(mesh.textures.len() as u32 - 1);
                    }
                    Some(Err(e)) => e,
                    None => format!("texture {spec} cannot be read from memory"),
                };
                failed.push((error, Vec::new()));
                Err(failed.len() - 1)
            });
            match slot {
                Ok(t) => record.texture = t,
                Err(f) => failed[f].1.push(&m.name),
            }
        }
        mesh.materials.push(record);
        mesh.material_names.push(m.name.clone());
    }
    unsupported_features(name, materials, notes);
    for (e, users) in failed {
        let who = match users.as_slice() {
            [one] => format!("material '{one}' keeps its"),
            many => format!("{} materials ('{}', …) keep their", many.len(), many.first().copied().unwrap_or("?")),
        };
        notes.warnings.push(format!("{name}: {e}; {who} diffuse colour"));
    }
}

/// One warning per MTL feature raypipe does not render, naming how many materials use it
/// (rather than silently rendering them otherwise).
fn unsupported_features(name: &str, materials: &[tobj::Material], notes: &mut LoadNotes) {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    let mut note = |feature: &'static str| match seen.iter_mut().find(|(f, _)| *f == feature) {
        Some((_, n)) => *n += 1,
        None => seen.push((feature, 1)),
    };
    for m in materials {
        for (given, feature) in [
            (m.ambient_texture.is_some(), "map_Ka (ambient texture): ignored"),
            (m.specular_texture.is_some(), "map_Ks (specular texture): ignored"),
            (m.normal_texture.is_some(), "bump or normal maps: ignored"),
            (m.shininess_texture.is_some(), "map_Ns (shininess texture): ignored"),
            (m.dissolve_texture.is_some(), "map_d (opacity texture): ignored"),
        ] {
            if given {
                note(feature);
            }
        }
        for (key, value) in &m.unknown_param {
            match key.as_str() {
                // Exporters write the identity filter everywhere; only another one is lost.
                "Tf" if value.split_whitespace().all(|v| v.parse::<f32>().is_ok_and(|x| x == 1.0)) => {}
                "map_bump" | "bump" | "map_Bump" | "norm" => note("bump or normal maps: ignored"),
                "disp" => note("disp (displacement maps): ignored"),
                "refl" => note("refl (reflection maps): ignored"),
                "Tf" => note("Tf (transmission filter): ignored"),
                _ => {}
            }
        }
    }
    for (feature, n) in seen {
        let who = if n == 1 { "1 material".to_string() } else { format!("{n} materials") };
        notes.warnings.push(format!("{name}: {feature} ({who})"));
    }
}

/// The MTL material as a record; `Mesh::validate` checks its values.
fn material_record(m: &tobj::Material) -> MaterialRecord {
    let mut r = MaterialRecord::DEFAULT;
    if let Some(kd) = m.diffuse {
        r.diffuse = kd;
    }
    if let Some(ks) = m.specular {
        r.specular = ks;
    }
    r.shininess = m.shininess.unwrap_or(0.0);
    r.ior = m.optical_density.unwrap_or(1.0);
    // `Tr` (transparency) is the complement of `d`; tobj keeps it as an unknown parameter.
    let tr = m.unknown_param.get("Tr").and_then(|v| v.split_whitespace().next()?.parse::<f32>().ok());
    r.dissolve = m.dissolve.or(tr.map(|t| 1.0 - t)).unwrap_or(1.0);
    r.illum = m.illumination_model.map_or(1, u32::from);
    r.texture = NULL_INDEX;
    if let Some(ke) = m.emissive {
        r.emission = ke;
    }
    r
}

pub(crate) fn describe(e: &tobj::LoadError) -> String {
    use tobj::LoadError::*;
    match e {
        OpenFileFailed => "file cannot be opened".into(),
        ReadError => "read error".into(),
        UnrecognizedCharacter => "unrecognized character".into(),
        PositionParseError => "a vertex position is not three numbers".into(),
        NormalParseError => "a normal is not three numbers".into(),
        TexcoordParseError => "a texture coordinate is not a number pair".into(),
        FaceParseError => "a face is not a list of vertex indices".into(),
        MaterialParseError => "a material statement cannot be parsed".into(),
        InvalidObjectName => "invalid object name".into(),
        InvalidPolygon => "a face has fewer than three vertices".into(),
        FaceVertexOutOfBounds => "a face references a vertex that does not exist".into(),
        FaceTexCoordOutOfBounds => "a face references a texture coordinate that does not exist".into(),
        FaceNormalOutOfBounds => "a face references a normal that does not exist".into(),
        FaceColorOutOfBounds => "a face references a colour that does not exist".into(),
        other => format!("{other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transparency_tr_is_the_complement_of_dissolve() {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n";
        let mtl = "newmtl a\nKd 1 1 1\nTr 0.25\nnewmtl b\nKd 1 1 1\nd 0.5\nTr 0.9\n".to_string();
        let (mesh, _) = load_obj_str("t.obj", obj, &|_| Some(mtl.clone())).unwrap();
        let d = |name: &str| mesh.materials[mesh.material_names.iter().position(|n| n == name).unwrap()].dissolve;
        assert_eq!(d("a"), 0.75);
        assert_eq!(d("b"), 0.5, "d wins over Tr");
    }

    /// A texture file several materials name is loaded once and, missing, warned about
    /// once (Sponza: 45 warnings for its missing files before).
    #[test]
    fn one_warning_per_missing_texture_file() {
        let dir = tempfile::tempdir().unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\nusemtl c\nf 1 2 3\n";
        let mtl = "newmtl a\nmap_Kd gone.png\nnewmtl b\nmap_Kd gone.png\nnewmtl c\nmap_Kd other.png\n";
        std::fs::write(dir.path().join("s.obj"), obj).unwrap();
        std::fs::write(dir.path().join("m.mtl"), mtl).unwrap();
        let (_, notes) = load_obj_file(&dir.path().join("s.obj")).unwrap();
        let gone: Vec<_> = notes.warnings.iter().filter(|w| w.contains("gone.png")).collect();
        assert_eq!(gone.len(), 1, "{:?}", notes.warnings);
        assert!(gone[0].contains("2 materials"), "{}", gone[0]);
        assert_eq!(notes.warnings.iter().filter(|w| w.contains("other.png")).count(), 1);
    }

    /// Features raypipe does not render are one warning each, however many materials
    /// use them.
    #[test]
    fn unsupported_mtl_features_are_one_warning_each() {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n";
        let mtl = "newmtl a\nKd 1 1 1\nKs 0.5 0.5 0.5\nNs 50\nillum 2\nmap_Ks s.png\nmap_Bump n.png\nnewmtl b\nKs 1 1 1\nillum 2\nmap_Ks s.png\nbump n.png\ndisp d.png\n";
        let (_, notes) = load_obj_str("t.obj", obj, &|_| Some(mtl.to_string())).unwrap();
        let specular: Vec<_> = notes.warnings.iter().filter(|w| w.contains("map_Ks")).collect();
        assert_eq!(specular.len(), 1, "{:?}", notes.warnings);
        assert!(specular[0].contains("2 materials"), "{}", specular[0]);
        // Glossy highlights are rendered (Whitted, shadow caster, path tracer).
        assert!(!notes.warnings.iter().any(|w| w.contains("glossy")), "{:?}", notes.warnings);
        assert_eq!(notes.warnings.iter().filter(|w| w.contains("bump")).count(), 1, "{:?}", notes.warnings);
        assert_eq!(notes.warnings.iter().filter(|w| w.contains("disp")).count(), 1, "{:?}", notes.warnings);
    }

    /// Found by the `obj_mtl` fuzz target: tobj panics on a colour of fewer than three
    /// numbers; raypipe reports a malformed MTL instead.
    #[test]
    fn a_short_colour_line_is_a_malformed_mtl_not_a_panic() {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        for line in ["Kd 1 1", "Ka", "Ks 0.5", "Ke 1 2"] {
            let mtl = format!("newmtl a\n{line}\n");
            let e = load_obj_str("t.obj", obj, &|_| Some(mtl.clone())).unwrap_err().to_string();
            assert!(e.contains("malformed MTL") && !e.contains('\n'), "{line}: {e}");
        }
    }
}
