//! Building an instanced scene (Wald & Slusallek 2001 §8.3): each shape's mesh is built
//! once into a bottom-level scene image with the structure the user asked for, placed by
//! affine instances under a top-level BVH over their world boxes, with the lights and
//! camera in a globals image ([`raypipe_core::image::instanced`]).

pub mod writer;

use anyhow::{anyhow, bail, Result};
use glam::{DMat3, DVec3, Vec3};
use raypipe_core::image::instanced::{index_layout, mapped_box, InstanceRecord, TopLevel, TopParts};
use raypipe_core::image::{LightRecord, MaterialRecord, FLAG_DEFAULT_LIGHT, NULL_INDEX};
use raypipe_core::math::affine::{self, Affine34};
use raypipe_core::traverse::instanced::trace_instanced;
use raypipe_core::SceneView;
use raypipe_core::{NoProbe, Watertight};

use crate::build::box_bvh::build_box_bvh;
use crate::build::default_lights::lights_for;
use crate::build::emitter_sums::EmitterSums;
use crate::build::image_writer::ImageWriter;
use crate::input::camera_file::CameraSpec;
use crate::input::mesh::Mesh;
use crate::platform::aligned::AlignedBytes;
use crate::scene::{add_structure, framing_camera, Accel, BuildOptions, BuildReport, TriangleLayout};

/// One placed copy of a bottom mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// The bottom mesh it draws.
    pub bottom: u32,
    /// Object space to world space, row-major 3×4.
    pub to_world: Affine34,
    /// A material of [`InstancedScene::materials`] replacing the bottom's own.
    pub material: Option<u32>,
}

/// A scene of instanced meshes before it is built.
#[derive(Clone, Debug, Default)]
pub struct InstancedScene {
    /// What the user called it.
    pub name: String,
    /// The shapes, each in its own object space with its own materials and textures.
    pub bottoms: Vec<Mesh>,
    /// Their names for messages (the files or glTF meshes they came from).
    pub bottom_names: Vec<String>,
    /// The placed copies.
    pub instances: Vec<Instance>,
    /// Override materials.
    pub materials: Vec<MaterialRecord>,
    /// Their names.
    pub material_names: Vec<String>,
    /// Lights the input names (none: raypipe's default light for the camera).
    pub lights: Vec<LightRecord>,
    /// The input's camera settings.
    pub camera: CameraSpec,
    /// Warnings from loading.
    pub warnings: Vec<String>,
}

/// The built parts of an instanced scene, before they are laid out in one file.
pub struct BuiltParts {
    /// Each bottom's scene image.
    pub images: Vec<AlignedBytes>,
    /// The instance records.
    pub records: Vec<InstanceRecord>,
    /// The top level over them.
    pub top: crate::build::box_bvh::BoxBvh,
    /// The globals image.
    pub globals: Vec<u8>,
    /// Sizes, lights and warnings.
    pub report: BuildReport,
}

/// A built instanced scene in memory.
pub struct BuiltInstanced {
    /// What the user called it.
    pub name: String,
    /// The file's bytes.
    pub bytes: AlignedBytes,
    /// Warnings and notes from building.
    pub report: BuildReport,
}

/// The row-major 3×4 map of a glam affine matrix.
pub fn affine_of(m: glam::Mat4) -> Affine34 {
    let r = m.transpose().to_cols_array();
    [r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11]]
}

/// The inverse of `m` computed in f64 and rounded to f32, or why there is none: a
/// non-finite entry, or a linear part too close to singular for the inverse to undo it
/// in f32 ([`affine::is_inverse_pair`]).
pub fn inverse(m: &Affine34) -> Result<Affine34, &'static str> {
    if !affine::is_finite(m) {
        return Err("the transform has a NaN or infinite entry");
    }
    let d = |i: usize| f64::from(m[i]);
    let lin =
        DMat3::from_cols(DVec3::new(d(0), d(4), d(8)), DVec3::new(d(1), d(5), d(9)), DVec3::new(d(2), d(6), d(10)));
    let det = lin.determinant();
    if det == 0.0 || !det.is_finite() {
        return Err("the transform is singular (it flattens the mesh)");
    }
    let inv = lin.inverse();
    let t = -(inv * DVec3::new(d(3), d(7), d(11)));
    let c = |col: usize, row: usize| inv.col(col)[row] as f32;
    let out = [
        c(0, 0),
        c(1, 0),
        c(2, 0),
        t.x as f32,
        c(0, 1),
        c(1, 1),
        c(2, 1),
        t.y as f32,
        c(0, 2),
        c(1, 2),
        c(2, 2),
        t.z as f32,
    ];
    if !affine::is_inverse_pair(m, &out) {
        return Err("the transform is too close to singular (its inverse does not undo it in f32)");
    }
    Ok(out)
}

/// The world box of an instance: its bottom's box mapped to the world, rounded outward
/// by a margin relative to its size and magnitude, so that a ray that meets the
/// geometry in object space enters the box in world space despite rounding.
pub fn world_box(to_world: &Affine34, bottom: ([f32; 3], [f32; 3])) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = mapped_box(to_world, (Vec3::from(bottom.0), Vec3::from(bottom.1)));
    let margin = 1e-5 * (hi - lo).max_element() + 16.0 * f32::EPSILON * lo.abs().max(hi.abs()).max_element();
    let lo = (lo - Vec3::splat(margin)).to_array().map(f32::next_down);
    let hi = (hi + Vec3::splat(margin)).to_array().map(f32::next_up);
    (lo, hi)
}

/// Drops the textures no material of `mesh`'s triangles uses and renumbers the rest
/// (a glTF mesh's bottom starts with the whole document's).
pub fn keep_used_textures(mesh: &mut Mesh) {
    let mut used = vec![false; mesh.textures.len()];
    let materials = &mesh.materials;
    for &m in &mesh.tri_materials {
        if let Some(t) = materials.get(m as usize).map(|r| r.texture) {
            if let Some(u) = used.get_mut(t as usize) {
                *u = true;
            }
        }
    }
    let mut renumber = vec![NULL_INDEX; used.len()];
    let mut kept = Vec::new();
    for (i, t) in std::mem::take(&mut mesh.textures).into_iter().enumerate() {
        if used[i] {
            renumber[i] = kept.len() as u32;
            kept.push(t);
        }
    }
    mesh.textures = kept;
    for r in &mut mesh.materials {
        r.texture = renumber.get(r.texture as usize).copied().unwrap_or(NULL_INDEX);
    }
}

impl InstancedScene {
    /// Checks what the builder relies on: each bottom a valid mesh, each instance
    /// naming an existing bottom and material with an invertible finite transform.
    pub fn check(&self) -> Result<()> {
        let name = &self.name;
        if self.instances.is_empty() {
            bail!("{name}: the scene places no instance");
        }
        for (b, mesh) in self.bottoms.iter().enumerate() {
            let what = self.bottom_names.get(b).map_or_else(|| format!("bottom {b}"), |n| n.clone());
            mesh.validate(&format!("{name}: {what}"))?;
        }
        for (i, inst) in self.instances.iter().enumerate() {
            let what = format!("{name}: instance {}", i + 1);
            if inst.bottom as usize >= self.bottoms.len() {
                bail!("{what}: names a mesh that does not exist");
            }
            if inst.material.is_some_and(|m| m as usize >= self.materials.len()) {
                bail!("{what}: names a material that does not exist");
            }
            inverse(&inst.to_world).map_err(|e| anyhow!("{what}: {e}"))?;
        }
        Ok(())
    }

    /// The scene as one mesh: every instance's copy placed in the world (normals by the
    /// inverse transpose), with its override material.
    pub fn flatten(&self) -> Mesh {
        let mut out = Mesh::default();
        let overrides = out.materials.len() as u32;
        out.materials.extend_from_slice(&self.materials);
        out.material_names.extend(self.material_names.iter().cloned());
        let shading = self.bottoms.iter().any(|m| !m.shading.is_empty());
        for (k, inst) in self.instances.iter().enumerate() {
            let Some(mesh) = self.bottoms.get(inst.bottom as usize) else { continue };
            let base = out.positions.len() as u32;
            out.positions
                .extend(mesh.positions.iter().map(|&p| affine::point(&inst.to_world, Vec3::from(p)).to_array()));
            let to_object = inverse(&inst.to_world).unwrap_or(affine::IDENTITY);
            if shading {
                let none = raypipe_core::image::ShadingVertex { normal: [0.0; 3], uv: [0.0; 2], color: [1.0; 3] };
                out.shading.extend((0..mesh.positions.len()).map(|v| {
                    let s = mesh.shading.get(v).copied().unwrap_or(none);
                    let n = affine::normal(&to_object, Vec3::from(s.normal)).normalize_or_zero();
                    // An override material replaces the vertex tint too.
                    let color = if inst.material.is_some() { [1.0; 3] } else { s.color };
                    raypipe_core::image::ShadingVertex { normal: n.to_array(), color, ..s }
                }));
            }
            out.triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
            out.objects.extend(std::iter::repeat_n(k as u32, mesh.triangles.len()));
            match inst.material {
                Some(m) => out.tri_materials.extend(std::iter::repeat_n(overrides + m, mesh.triangles.len())),
                None => {
                    let (mbase, tbase) = (out.materials.len() as u32, out.textures.len() as u32);
                    out.textures.extend(mesh.textures.iter().cloned());
                    let mut materials = mesh.materials.clone();
                    if materials.is_empty() {
                        materials.push(MaterialRecord::DEFAULT);
                    }
                    out.materials.extend(materials.iter().map(|r| MaterialRecord {
                        texture: if r.texture == NULL_INDEX { NULL_INDEX } else { r.texture + tbase },
                        ..*r
                    }));
                    out.material_names.extend((0..materials.len()).map(|i| format!("instance {k} material {i}")));
                    let n = mesh.triangles.len();
                    let ids = (0..n).map(|t| mbase + mesh.tri_materials.get(t).copied().unwrap_or(0));
                    out.tri_materials.extend(ids);
                }
            }
        }
        out.lights = self.lights.clone();
        out
    }

    /// Builds the bottom images (the structure `opts` asks for), the instances, the top
    /// level and the globals image (lights chosen as the flat scene's would be).
    pub fn build(&self, opts: &BuildOptions) -> Result<BuiltInstanced> {
        let parts = self.build_parts(opts, &|_| opts.accel)?;
        let BuiltParts { images, records, top, globals, mut report } = parts;
        let bounds = (top.nodes[0].min, top.nodes[0].max);
        let bottoms: Vec<&[u8]> = images.iter().map(|i| &i[..]).collect();
        let bytes = writer::write_instanced(&bottoms, &records, &top.nodes, &top.list, &globals, bounds)?;
        report.image_bytes = bytes.len();
        Ok(BuiltInstanced { name: self.name.clone(), bytes, report })
    }

    /// Builds the parts of the scene: each bottom image with the structure
    /// `accel_of(bottom)` names, the instance records, the top level and the globals
    /// image.
    pub fn build_parts(&self, opts: &BuildOptions, accel_of: &dyn Fn(usize) -> Accel) -> Result<BuiltParts> {
        self.check()?;
        let name = &self.name;
        let mut report = BuildReport { warnings: self.warnings.clone(), ..Default::default() };
        let mut images = Vec::with_capacity(self.bottoms.len());
        let start = std::time::Instant::now();
        for (b, mesh) in self.bottoms.iter().enumerate() {
            let mut mesh = mesh.clone();
            mesh.lights.clear();
            let mut writer = ImageWriter::new(&mesh);
            let accel = accel_of(b);
            let layout = if accel == opts.accel { opts.triangles } else { TriangleLayout::Indexed };
            if layout == TriangleLayout::Wald {
                writer.wald_triangles(&mesh);
            }
            let what = format!("{name}: {}", self.bottom_names.get(b).map_or("a mesh", |s| s.as_str()));
            let mut r = BuildReport::default();
            let own = BuildOptions { accel, triangles: layout, ..opts.clone() };
            add_structure(&what, &mesh, &own, &mut r, &mut writer)?;
            report.tree_nodes += r.tree_nodes;
            report.structure_bytes += r.structure_bytes;
            report.triangles += mesh.triangles.len();
            report.vertices += mesh.positions.len();
            images.push(writer.finish().map_err(|e| anyhow!("{what}: {e}"))?);
        }
        let mut records = Vec::with_capacity(self.instances.len());
        for inst in &self.instances {
            let view = SceneView::parse(&images[inst.bottom as usize])
                .map_err(|e| anyhow!("internal error: built an invalid bottom image: {e}"))?;
            let h = view.header();
            let (lo, hi) = world_box(&inst.to_world, (h.bounds_min, h.bounds_max));
            records.push(InstanceRecord {
                to_world: inst.to_world,
                to_object: inverse(&inst.to_world).map_err(|e| anyhow!("{name}: {e}"))?,
                bottom: inst.bottom,
                material: inst.material.unwrap_or(NULL_INDEX),
                bounds_min: lo,
                bounds_max: hi,
            });
        }
        let boxes: Vec<([f32; 3], [f32; 3])> = records.iter().map(|r| (r.bounds_min, r.bounds_max)).collect();
        let top = build_box_bvh(&boxes, 1);
        report.grid_seconds = start.elapsed().as_secs_f64();
        let (globals, note) = self.globals(opts, &Parts { images: &images, records: &records, top: &top })?;
        report.lights = note;
        Ok(BuiltParts { images, records, top, globals, report })
    }

    /// The globals image: the camera, the lights and the override materials. Without
    /// lights of its own the scene gets the flat build's default ones, placed by rays
    /// through the instances (emissive triangles glow but are not sampled as area
    /// lights: their ids are shared by every copy).
    fn globals(&self, opts: &BuildOptions, parts: &Parts<'_>) -> Result<(Vec<u8>, String)> {
        let bounds = (parts.top.nodes[0].min, parts.top.nodes[0].max);
        let camera = self.camera.merged(opts.camera).apply(&framing_camera(bounds.0, bounds.1));
        let (lights, note, default_light) = if !opts.lights.is_empty() {
            crate::scene::check_user_lights(&self.name, &opts.lights)?;
            let mut lights = opts.lights.clone();
            lights.push(LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 });
            (lights, format!("{} given lights", opts.lights.len()), false)
        } else if !self.lights.is_empty() {
            (self.lights.clone(), format!("{} lights from the input", self.lights.len()), false)
        } else {
            let (lights, note) = self.default_lights(parts, bounds, &camera)?;
            let for_camera = lights.iter().any(|l| l.kind == LightRecord::POINT);
            (lights, note, for_camera)
        };
        let lights: Vec<LightRecord> = lights.into_iter().filter(|l| l.kind != LightRecord::AREA).collect();
        let mesh = Mesh {
            lights,
            materials: self.materials.clone(),
            material_names: self.material_names.clone(),
            ..Default::default()
        };
        let mut w = ImageWriter::new(&mesh);
        w.set_bounds(bounds.0, bounds.1).camera(&camera);
        if default_light {
            w.flags |= FLAG_DEFAULT_LIGHT;
        }
        let image = w.finish()?;
        if let Err(e) = SceneView::parse(&image) {
            bail!("internal error: built an invalid globals image: {e}");
        }
        Ok((image.to_vec(), note))
    }

    /// The flat build's default lights for the placed scene: emitters summed over every
    /// copy, the light placed by rays through the instances.
    fn default_lights(
        &self,
        parts: &Parts<'_>,
        bounds: ([f32; 3], [f32; 3]),
        camera: &raypipe_core::image::CameraRecord,
    ) -> Result<(Vec<LightRecord>, String)> {
        let mut sums = EmitterSums::default();
        for inst in &self.instances {
            let mesh = &self.bottoms[inst.bottom as usize];
            for (i, t) in mesh.triangles.iter().enumerate() {
                let ke = match inst.material {
                    Some(m) => self.materials[m as usize].emission,
                    None => {
                        let m = mesh.tri_materials.get(i).copied().unwrap_or(u32::MAX);
                        mesh.materials.get(m as usize).map_or([0.0; 3], |m| m.emission)
                    }
                };
                let p = t.map(|v| affine::point(&inst.to_world, Vec3::from(mesh.positions[v as usize])).to_array());
                sums.add(p, ke);
            }
        }
        let views = parts
            .images
            .iter()
            .map(|i| SceneView::parse(i).map_err(|e| anyhow!("internal error: {e}")))
            .collect::<Result<Vec<_>>>()?;
        let top = TopLevel::new(
            TopParts {
                instances: parts.records,
                nodes: &parts.top.nodes,
                list: &parts.top.list,
                addrs: index_layout(parts.records.len() as u32, views.len() as u32, parts.top.nodes.len() as u32).0,
            },
            |b| views.get(b as usize).map(|v| v.bounds()),
            self.materials.len() as u32,
        )
        .map_err(|e| anyhow!("internal error: {e}"))?;
        let first_hit = |ray: &raypipe_core::Ray| {
            trace_instanced::<Watertight, _>(&top, &views, ray, &mut NoProbe).map(|h| h.hit.t)
        };
        Ok(lights_for(&sums, bounds, camera, first_hit))
    }
}

/// What the globals image is chosen from: the built bottoms, instances and top level.
struct Parts<'a> {
    images: &'a [AlignedBytes],
    records: &'a [InstanceRecord],
    top: &'a crate::build::box_bvh::BoxBvh,
}
