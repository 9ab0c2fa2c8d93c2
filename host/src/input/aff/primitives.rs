//! AFF's primitives read into the current mover's geometry: polygons and patches,
//! textured triangles, meshes with their own normal and texture-coordinate indices,
//! the museum's animated triangles, and the PPM textures they name.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Result};
use glam::DVec3;
use raypipe_core::image::NULL_INDEX;

use super::parser::{AnimatedTriangle, State};
use super::shapes::{polygon, Shape};
use super::tokens::Tokens;

impl State {
    pub(super) fn poly(&mut self, t: &mut Tokens<'_>, patch: bool) -> Result<()> {
        let each = if patch { 6 } else { 3 };
        let n = t.count("a polygon's vertex count", each)?;
        if n < 3 {
            return Err(t.error(format!("a polygon of {n} vertices")));
        }
        let mut verts = Vec::with_capacity(n);
        let mut normals = Vec::new();
        for _ in 0..n {
            verts.push(DVec3::from(t.vec3("a polygon vertex")?));
            if patch {
                normals.push(DVec3::from(t.vec3("a patch normal")?));
            }
        }
        self.add(t, polygon(verts, patch.then_some(normals)), None)
    }

    /// A PPM texture, read once per name: beside the file naming it, or in the scene's
    /// `TextureFiles` folder (BART's layout).
    pub(super) fn texture(&mut self, name: &str, t: &Tokens<'_>, path: &Path) -> Result<u32> {
        if let Some(&i) = self.texture_index.get(name) {
            return Ok(i);
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let candidates = [
            dir.join(name),
            self.root_dir.join("../TextureFiles").join(name),
            self.root_dir.join("TextureFiles").join(name),
        ];
        let Some(found) = candidates.iter().find(|p| p.is_file()) else {
            return Err(t.error(format!("texture '{name}' is not beside the file or in TextureFiles")));
        };
        let bytes = crate::input::read_file::read_bytes(found, crate::input::read_file::DATA_LIMIT)?;
        let image =
            crate::input::ppm::decode_ppm(&bytes).map_err(|e| t.error(format!("texture {}: {e}", found.display())))?;
        self.parsed.textures.push(image);
        let i = self.parsed.textures.len() as u32 - 1;
        self.texture_index.insert(name.to_string(), i);
        Ok(i)
    }

    pub(super) fn textured_triangle(&mut self, t: &mut Tokens<'_>, patch: bool, path: &Path) -> Result<()> {
        let name = t.word("a texture name")?.to_string();
        let texture = self.texture(&name, t, path)?;
        let mut shape = Shape { triangles: vec![[0, 1, 2]], uvs: Some(Vec::new()), ..Default::default() };
        let mut normals = Vec::new();
        for _ in 0..3 {
            shape.positions.push(DVec3::from(t.vec3("a textured triangle")?));
            if patch {
                normals.push(DVec3::from(t.vec3("a textured triangle's normal")?));
            }
            let uv = [t.number("a texture coordinate")?, t.number("a texture coordinate")?];
            if let Some(u) = shape.uvs.as_mut() {
                u.push(uv);
            }
        }
        shape.normals = patch.then_some(normals);
        self.add(t, shape, Some(texture))
    }

    pub(super) fn animated_triangle(&mut self, t: &mut Tokens<'_>) -> Result<()> {
        let n = t.count("an animated triangle's key count", 19)?;
        if n == 0 {
            return Err(t.error("an animated triangle without keys"));
        }
        let material = self.material_id(NULL_INDEX);
        let mut tri = AnimatedTriangle { times: Vec::with_capacity(n), verts: Vec::with_capacity(n), material };
        for _ in 0..n {
            let time = t.number("an animated triangle's key time")?;
            if tri.times.last().is_some_and(|&last| time < last) {
                return Err(t.error(format!("an animated triangle's key times go backwards (to {time})")));
            }
            let mut v = [DVec3::ZERO; 3];
            for vert in &mut v {
                *vert = self.local.transform_point3(DVec3::from(t.vec3("an animated vertex")?));
                t.vec3("an animated normal")?;
            }
            tri.times.push(time);
            tri.verts.push(v);
        }
        self.triangles += 1;
        self.parsed.animated[self.owner].push(tri);
        Ok(())
    }

    pub(super) fn mesh(&mut self, t: &mut Tokens<'_>, path: &Path) -> Result<()> {
        let expect = |t: &mut Tokens<'_>, w: &str| -> Result<()> {
            let line = t.line();
            let got = t.word(w)?;
            if got != w {
                bail!("{}:{line}: a mesh expects '{w}', found '{got}'", t.name);
            }
            Ok(())
        };
        expect(t, "vertices")?;
        let nv = t.count("a mesh's vertex count", 3)?;
        let verts: Vec<DVec3> = (0..nv).map(|_| t.vec3("a mesh vertex").map(DVec3::from)).collect::<Result<_>>()?;
        let mut normals = None;
        let mut uvs = None;
        let mut texture = None;
        let mut word = t.word("a mesh's triangles")?;
        if word == "normals" {
            let n = t.count("a mesh's normal count", 3)?;
            normals = Some((0..n).map(|_| t.vec3("a mesh normal").map(DVec3::from)).collect::<Result<Vec<_>>>()?);
            word = t.word("a mesh's triangles")?;
        }
        if word == "texturecoords" {
            let n = t.count("a mesh's texture coordinate count", 2)?;
            let name = t.word("a mesh's texture name")?.to_string();
            texture = Some(self.texture(&name, t, path)?);
            uvs = Some(
                (0..n)
                    .map(|_| Ok([t.number("a texture coordinate")?, t.number("a texture coordinate")?]))
                    .collect::<Result<Vec<_>>>()?,
            );
            word = t.word("a mesh's triangles")?;
        }
        if word != "triangles" {
            return Err(t.error(format!("a mesh expects 'triangles', found '{word}'")));
        }
        let per = 3 * (1 + normals.is_some() as usize + uvs.is_some() as usize);
        let nt = t.count("a mesh's triangle count", per)?;
        // Each corner is a (vertex, normal, uv) triple: corners that share all three
        // share a vertex.
        let mut shape = Shape {
            normals: normals.as_ref().map(|_| Vec::new()),
            uvs: uvs.as_ref().map(|_| Vec::new()),
            ..Default::default()
        };
        let mut corners: HashMap<[u32; 3], u32> = HashMap::new();
        let index = |t: &mut Tokens<'_>, limit: usize, what: &str| -> Result<u32> {
            let v = t.number(what)?;
            if v < 0.0 || v.fract() != 0.0 || v as usize >= limit {
                return Err(t.error(format!("{what} {v} does not exist ({limit} given)")));
            }
            Ok(v as u32)
        };
        for _ in 0..nt {
            let mut v = [0u32; 3];
            let mut n = [u32::MAX; 3];
            let mut u = [u32::MAX; 3];
            for k in &mut v {
                *k = index(t, verts.len(), "a mesh triangle's vertex")?;
            }
            if let Some(ns) = &normals {
                for k in &mut n {
                    *k = index(t, ns.len(), "a mesh triangle's normal")?;
                }
            }
            if let Some(us) = &uvs {
                for k in &mut u {
                    *k = index(t, us.len(), "a mesh triangle's texture coordinate")?;
                }
            }
            let mut tri = [0u32; 3];
            for c in 0..3 {
                let key = [v[c], n[c], u[c]];
                let next = shape.positions.len() as u32;
                let id = *corners.entry(key).or_insert(next);
                if id == next {
                    shape.positions.push(verts[v[c] as usize]);
                    if let (Some(out), Some(ns)) = (shape.normals.as_mut(), normals.as_ref()) {
                        out.push(ns[n[c] as usize]);
                    }
                    if let (Some(out), Some(us)) = (shape.uvs.as_mut(), uvs.as_ref()) {
                        out.push(us[u[c] as usize]);
                    }
                }
                tri[c] = id;
            }
            shape.triangles.push(tri);
        }
        self.add(t, shape, texture)
    }
}
