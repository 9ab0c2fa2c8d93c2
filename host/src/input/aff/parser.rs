//! Reading AFF files into a scene graph of movers (BART §4): every command of NFF and
//! AFF, includes followed (relative to the including file, cycles refused), static
//! transforms folded into the geometry they enclose, and each animated transform a
//! *mover* whose geometry is kept in its own space.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};
use glam::{DMat3, DMat4, DQuat, DVec3};
use raypipe_core::image::{LightRecord, MaterialRecord, ShadingVertex, NULL_INDEX};

use super::shapes::{cone, sphere, Shape};
use super::tokens::Tokens;
use super::track::Track;
use crate::input::texture::TextureImage;

/// Deepest include nesting.
const MAX_INCLUDE_DEPTH: usize = 32;
/// Most triangles one AFF scene may hold (stored, before instancing).
const MAX_TRIANGLES: usize = crate::input::limits::MAX_TRIANGLES as usize;

/// An animated transform in the graph: its parent mover, the static map from the
/// parent's space to where it stands, and the name of its keyframes.
#[derive(Clone, Debug)]
pub struct Mover {
    /// The enclosing mover (`None` for the root, the world).
    pub parent: Option<usize>,
    /// The static transforms between the parent and this transform.
    pub local: DMat4,
    /// Its keyframes' name (empty for the root).
    pub name: String,
}

/// Geometry gathered in one mover's space.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading data (filled once any primitive has normals or uvs).
    pub shading: Vec<ShadingVertex>,
    /// Whether any primitive brought normals or texture coordinates.
    pub has_shading: bool,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Material of each triangle.
    pub materials: Vec<u32>,
}

/// A triangle of the museum's unorganised animation (`tpa`): its vertices at each key.
#[derive(Clone, Debug)]
pub struct AnimatedTriangle {
    /// Key times, increasing.
    pub times: Vec<f64>,
    /// Vertices at each key.
    pub verts: Vec<[DVec3; 3]>,
    /// The material in force where it stands.
    pub material: u32,
}

/// The view (`v`).
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Eye.
    pub from: DVec3,
    /// Point looked at.
    pub at: DVec3,
    /// Up.
    pub up: DVec3,
    /// Vertical field of view, degrees.
    pub angle: f64,
    /// Image size.
    pub resolution: (u32, u32),
}

/// Everything the files said.
#[derive(Default)]
pub struct Parsed {
    /// Movers; 0 is the world.
    pub movers: Vec<Mover>,
    /// Static geometry of each mover.
    pub geometry: Vec<Gathered>,
    /// Animated triangles of each mover.
    pub animated: Vec<Vec<AnimatedTriangle>>,
    /// Keyframes by name.
    pub tracks: HashMap<String, Track>,
    /// Materials: the ambient colour (for the global ambient light) and the record.
    pub materials: Vec<([f32; 3], MaterialRecord)>,
    /// Textures, by index.
    pub textures: Vec<TextureImage>,
    /// Point lights.
    pub lights: Vec<LightRecord>,
    /// The global ambient light (`am`; 1 1 1 when not given).
    pub ambient: [f64; 3],
    /// Background.
    pub background: [f64; 3],
    /// The view.
    pub view: Option<View>,
    /// `a start end frames`.
    pub animation: Option<(f64, f64, u32)>,
    /// Notes for the user.
    pub warnings: Vec<String>,
}

/// The reader's state between commands.
pub(super) struct State {
    pub(super) parsed: Parsed,
    /// The current material (index into `materials`, with its texture-less form).
    pub(super) material: ([f32; 3], MaterialRecord),
    pub(super) material_index: HashMap<Vec<u32>, u32>,
    pub(super) texture_index: HashMap<String, u32>,
    /// Where each keyframe block was read (file and line).
    pub(super) track_origin: HashMap<String, String>,
    /// Open blocks: the mover and local map to restore when each closes.
    pub(super) blocks: Vec<(usize, DMat4)>,
    pub(super) owner: usize,
    pub(super) local: DMat4,
    pub(super) detail: i64,
    pub(super) includes: Vec<PathBuf>,
    pub(super) root_dir: PathBuf,
    pub(super) triangles: usize,
}

/// Reads the AFF scene whose entry file is `path`.
pub fn parse(path: &Path) -> Result<Parsed> {
    parse_entry(path, None)
}

/// Reads the AFF scene whose entry file `path` holds `text` (read from memory; its
/// includes and textures are found beside `path`).
pub fn parse_text(path: &Path, text: &str) -> Result<Parsed> {
    parse_entry(path, Some(text))
}

fn parse_entry(path: &Path, text: Option<&str>) -> Result<Parsed> {
    let root_dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut s = State {
        parsed: Parsed {
            movers: vec![Mover { parent: None, local: DMat4::IDENTITY, name: String::new() }],
            geometry: vec![Gathered::default()],
            animated: vec![Vec::new()],
            ambient: [1.0; 3],
            ..Default::default()
        },
        material: ([0.0; 3], MaterialRecord::DEFAULT),
        material_index: HashMap::new(),
        texture_index: HashMap::new(),
        track_origin: HashMap::new(),
        blocks: Vec::new(),
        owner: 0,
        local: DMat4::IDENTITY,
        detail: 0,
        includes: Vec::new(),
        root_dir,
        triangles: 0,
    };
    match text {
        Some(text) => s.text(path, text)?,
        None => s.file(path)?,
    }
    if !s.blocks.is_empty() {
        bail!("{}: {} transform block(s) are never closed with '}}'", path.display(), s.blocks.len());
    }
    let name = path.display();
    // A transform without keyframes stays where its static maps put it, as in BART's
    // reader (its robots name grippers they never move).
    let mut still: Vec<String> = s
        .parsed
        .movers
        .iter()
        .skip(1)
        .filter(|m| !s.parsed.tracks.contains_key(&m.name))
        .map(|m| m.name.clone())
        .collect();
    still.sort();
    still.dedup();
    if !still.is_empty() {
        s.parsed.warnings.push(format!("{name}: transforms without keyframes stay still: {}", still.join(", ")));
    }
    if s.triangles == 0 {
        bail!("{name}: the scene has no geometry");
    }
    Ok(s.parsed)
}

impl State {
    /// Reads one file (the entry file or an include).
    fn file(&mut self, path: &Path) -> Result<()> {
        let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if let Some(k) = self.includes.iter().position(|p| *p == canon) {
            let chain: Vec<String> =
                self.includes[k..].iter().chain([&canon]).map(|p| p.display().to_string()).collect();
            bail!("include cycle: {}", chain.join(" includes "));
        }
        if self.includes.len() >= MAX_INCLUDE_DEPTH {
            bail!("{}: includes nest deeper than {MAX_INCLUDE_DEPTH}", path.display());
        }
        // BART's files are ASCII with the odd Latin-1 byte in a comment.
        let bytes = crate::input::read_file::read_bytes(path, crate::input::read_file::TEXT_LIMIT)?;
        let text = String::from_utf8_lossy(&bytes);
        self.text(path, &text)
    }

    /// Reads the commands of `text`, the file `path`.
    fn text(&mut self, path: &Path, text: &str) -> Result<()> {
        let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        self.includes.push(canon);
        let depth = self.blocks.len();
        let mut t = Tokens::new(&path.display().to_string(), text);
        while let Some(tok) = t.next_token() {
            self.command(tok.text, &mut t, path)?;
        }
        if self.blocks.len() != depth {
            bail!("{}: a transform block opened here is not closed in the same file", path.display());
        }
        self.includes.pop();
        Ok(())
    }

    /// One command.
    fn command(&mut self, cmd: &str, t: &mut Tokens<'_>, path: &Path) -> Result<()> {
        match cmd {
            "v" => self.view(t),
            "l" | "la" => self.light(t, cmd == "la"),
            "b" => {
                self.parsed.background = t.vec3("the background colour")?;
                Ok(())
            }
            "am" => {
                self.parsed.ambient = t.vec3("the ambient light")?;
                Ok(())
            }
            "f" | "fm" => self.fill(t, cmd == "fm"),
            "c" => {
                let (b, r0, a, r1) = (t.vec3("a cone")?, t.number("a cone")?, t.vec3("a cone")?, t.number("a cone")?);
                self.add(t, cone(DVec3::from(b), r0.abs(), DVec3::from(a), r1.abs()), None)
            }
            "s" => {
                let (c, r) = (t.vec3("a sphere")?, t.number("a sphere")?);
                self.add(t, sphere(DVec3::from(c), r.abs()), None)
            }
            "p" | "pp" => self.poly(t, cmd == "pp"),
            "tt" | "ttp" => self.textured_triangle(t, cmd == "ttp", path),
            "tpa" => self.animated_triangle(t),
            "m" => self.mesh(t, path),
            "i" => self.include(t, path),
            "d" => {
                self.detail = t.number("a detail level")? as i64;
                Ok(())
            }
            "xs" => self.static_transform(t),
            "x" => self.animated_transform(t),
            "}" => match self.blocks.pop() {
                Some((owner, local)) => {
                    (self.owner, self.local) = (owner, local);
                    Ok(())
                }
                None => Err(anyhow!("{}:{}: '}}' closes no transform block", t.name, t.line())),
            },
            "a" => {
                let (start, end) = (t.number("the animation's start")?, t.number("the animation's end")?);
                let frames = t.number("the animation's frame count")?;
                if end < start || !(1.0..=1e7).contains(&frames) || frames.fract() != 0.0 {
                    return Err(t.error(format!("animation {start} .. {end} in {frames} frames is impossible")));
                }
                self.parsed.animation = Some((start, end, frames as u32));
                Ok(())
            }
            "k" => self.keyframes(t),
            other => Err(anyhow!("{}:{}: unknown command '{other}'", t.name, t.previous_line())),
        }
    }

    fn view(&mut self, t: &mut Tokens<'_>) -> Result<()> {
        let (mut from, mut at, mut up) = (None, None, None);
        let (mut angle, mut resolution) = (None, None);
        while let Some(w) = t.peek().map(|w| w.text) {
            match w {
                "from" | "at" | "up" => {
                    t.next_token();
                    let v = DVec3::from(t.vec3(w)?);
                    match w {
                        "from" => from = Some(v),
                        "at" => at = Some(v),
                        _ => up = Some(v),
                    }
                }
                "angle" => {
                    t.next_token();
                    angle = Some(t.number("angle")?);
                }
                "hither" => {
                    t.next_token();
                    t.number("hither")?;
                }
                "resolution" => {
                    t.next_token();
                    let (w, h) = (t.number("resolution")?, t.number("resolution")?);
                    if !(1.0..=16384.0).contains(&w) || !(1.0..=16384.0).contains(&h) {
                        return Err(t.error(format!("resolution {w}x{h} is impossible")));
                    }
                    resolution = Some((w as u32, h as u32));
                }
                _ => break,
            }
        }
        let missing = |what: &str| t.error(format!("the view has no '{what}'"));
        let view = View {
            from: from.ok_or_else(|| missing("from"))?,
            at: at.ok_or_else(|| missing("at"))?,
            up: up.ok_or_else(|| missing("up"))?,
            angle: angle.ok_or_else(|| missing("angle"))?,
            resolution: resolution.ok_or_else(|| missing("resolution"))?,
        };
        if !(0.0..180.0).contains(&view.angle) || view.angle == 0.0 {
            return Err(t.error(format!("a view angle of {} degrees is impossible", view.angle)));
        }
        self.parsed.view = Some(view);
        Ok(())
    }

    fn light(&mut self, t: &mut Tokens<'_>, animated: bool) -> Result<()> {
        let name = if animated { Some(t.word("an animated light's name")?.to_string()) } else { None };
        let p = self.local.transform_point3(DVec3::from(t.vec3("a light")?));
        let colour = if t.peek().is_some_and(|w| w.text.parse::<f64>().is_ok()) {
            t.vec3("a light's colour")?
        } else {
            [1.0; 3]
        };
        if colour.iter().any(|&c| c < 0.0) {
            return Err(t.error("a light's colour is negative"));
        }
        if let Some(n) = name {
            self.parsed.warnings.push(format!("{}: animated light '{n}' is held at its first position", t.name));
        } else if self.owner != 0 {
            self.parsed.warnings.push(format!("{}: a light inside a moving transform is held where it starts", t.name));
        }
        let p = self.world_of_owner().transform_point3(p);
        self.parsed.lights.push(LightRecord {
            position: p.as_vec3().to_array(),
            kind: LightRecord::POINT,
            color: colour.map(|c| c as f32),
            triangle: 0,
        });
        Ok(())
    }

    /// The owner's map to the world at the animation's start (for lights).
    fn world_of_owner(&self) -> DMat4 {
        let mut m = DMat4::IDENTITY;
        let mut at = Some(self.owner);
        while let Some(i) = at {
            let mover = &self.parsed.movers[i];
            let own = self.parsed.tracks.get(&mover.name).map_or(DMat4::IDENTITY, |tr| tr.matrix(0.0));
            m = mover.local * own * m;
            at = mover.parent;
        }
        m
    }

    fn fill(&mut self, t: &mut Tokens<'_>, extended: bool) -> Result<()> {
        let (ambient, diffuse, specular, shine, transmit, ior) = if extended {
            let (a, d, s) = (t.vec3("fm")?, t.vec3("fm")?, t.vec3("fm")?);
            (a, d, s, t.number("fm")?, t.number("fm")?, t.number("fm")?)
        } else {
            let c = t.vec3("f")?;
            let (kd, ks) = (t.number("f")?, t.number("f")?);
            let (shine, transmit, ior) = (t.number("f")?, t.number("f")?, t.number("f")?);
            (c.map(|x| x * kd), c.map(|x| x * kd), [ks; 3], shine, transmit, ior)
        };
        let all = ambient.iter().chain(&diffuse).chain(&specular).chain([&shine, &transmit, &ior]);
        if all.clone().any(|v| *v < 0.0) {
            return Err(t.error("a material value is negative"));
        }
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        // NFF's Ks is the mirror reflection a ray tracer follows (Haines' SPD), and T the
        // light passed through: raypipe's mirror (illum 3) and glass (illum 4, d = 1 − T).
        let illum = if transmit > 0.0 {
            4
        } else if specular.iter().any(|&s| s > 0.0) {
            3
        } else {
            1
        };
        let record = MaterialRecord {
            diffuse: f(diffuse),
            specular: f(specular),
            shininess: shine as f32,
            ior: if ior > 0.0 { ior as f32 } else { 1.0 },
            dissolve: (1.0 - transmit).clamp(0.0, 1.0) as f32,
            illum,
            texture: NULL_INDEX,
            ..MaterialRecord::DEFAULT
        };
        self.material = (f(ambient), record);
        Ok(())
    }

    /// The index of the current material, with `texture`.
    pub(super) fn material_id(&mut self, texture: u32) -> u32 {
        let (ambient, mut record) = self.material;
        record.texture = texture;
        let mut key: Vec<u32> = ambient.iter().map(|a| a.to_bits()).collect();
        key.extend(bytemuck::cast_slice::<_, u32>(std::slice::from_ref(&record)));
        let next = self.parsed.materials.len() as u32;
        let id = *self.material_index.entry(key).or_insert(next);
        if id == next {
            self.parsed.materials.push((ambient, record));
        }
        id
    }

    /// Adds a primitive with the current material (and `texture`) to the current
    /// mover's geometry, placed by the open static transforms.
    pub(super) fn add(&mut self, t: &Tokens<'_>, shape: Shape, texture: Option<u32>) -> Result<()> {
        self.triangles += shape.triangles.len();
        if self.triangles > MAX_TRIANGLES {
            return Err(t.error(format!("the scene passes {MAX_TRIANGLES} triangles")));
        }
        let material = self.material_id(texture.unwrap_or(NULL_INDEX));
        let m = self.local;
        let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
        let g = &mut self.parsed.geometry[self.owner];
        let base = g.positions.len() as u32;
        let shaded = shape.normals.is_some() || shape.uvs.is_some();
        if shaded && !g.has_shading {
            g.has_shading = true;
            g.shading = vec![ShadingVertex { normal: [0.0; 3], uv: [0.0; 2], color: [1.0; 3] }; g.positions.len()];
        }
        for (i, p) in shape.positions.iter().enumerate() {
            let w = m.transform_point3(*p);
            if !w.is_finite() {
                return Err(t.error("a vertex is not finite once transformed"));
            }
            g.positions.push(w.as_vec3().to_array());
            if g.has_shading {
                let n = shape
                    .normals
                    .as_ref()
                    .and_then(|n| n.get(i))
                    .map_or(DVec3::ZERO, |n| (normal_matrix * *n).normalize_or_zero());
                let uv = shape.uvs.as_ref().and_then(|u| u.get(i)).copied().unwrap_or([0.0; 2]);
                g.shading.push(ShadingVertex {
                    normal: n.as_vec3().to_array(),
                    uv: uv.map(|x| x as f32),
                    color: [1.0; 3],
                });
            }
        }
        for tri in &shape.triangles {
            if tri.iter().any(|&v| v as usize >= shape.positions.len()) {
                return Err(t.error("a triangle names a vertex that does not exist"));
            }
            g.triangles.push(tri.map(|v| v + base));
            g.materials.push(material);
        }
        Ok(())
    }

    fn include(&mut self, t: &mut Tokens<'_>, path: &Path) -> Result<()> {
        let level = t.number("an include's detail level")?;
        let file = t.word("an include's file name")?.to_string();
        if level as i64 > self.detail {
            return Ok(());
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let child = [dir.join(&file), self.root_dir.join(&file)].into_iter().find(|p| p.is_file());
        let Some(child) = child else {
            return Err(t.error(format!("include '{file}' does not exist")));
        };
        self.file(&child)
    }

    fn static_transform(&mut self, t: &mut Tokens<'_>) -> Result<()> {
        let scale = DVec3::from(t.vec3("a static transform's scale")?);
        let axis = DVec3::from(t.vec3("a static transform's axis")?);
        let degrees = t.number("a static transform's angle")?;
        let shift = DVec3::from(t.vec3("a static transform's translation")?);
        t.open("a static transform")?;
        if scale.abs().min_element() == 0.0 {
            return Err(t.error("a static transform scales by zero"));
        }
        let rotation = if degrees == 0.0 {
            DQuat::IDENTITY
        } else if axis.length_squared() == 0.0 {
            return Err(t.error("a static transform rotates about a zero axis"));
        } else {
            DQuat::from_axis_angle(axis.normalize(), degrees.to_radians())
        };
        self.blocks.push((self.owner, self.local));
        self.local *= DMat4::from_scale_rotation_translation(scale, rotation, shift);
        Ok(())
    }

    fn animated_transform(&mut self, t: &mut Tokens<'_>) -> Result<()> {
        let name = t.word("an animated transform's name")?.to_string();
        t.open("an animated transform")?;
        self.blocks.push((self.owner, self.local));
        self.parsed.movers.push(Mover { parent: Some(self.owner), local: self.local, name });
        self.parsed.geometry.push(Gathered::default());
        self.parsed.animated.push(Vec::new());
        self.owner = self.parsed.movers.len() - 1;
        self.local = DMat4::IDENTITY;
        Ok(())
    }
}
