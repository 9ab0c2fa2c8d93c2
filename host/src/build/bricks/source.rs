//! Where a bricked build's triangles come from, streamed once in id order: a mesh
//! already in memory, a PLY file read as a stream, or a generated scene.

use anyhow::Result;
use raypipe_core::image::{LightRecord, MaterialRecord, NULL_INDEX};

use super::tri_record::TriRecord;
use crate::build::emitter_sums::EmitterSums;
use crate::input::mesh::Mesh;
use crate::input::obj_stream::ObjStream;
use crate::input::ply_stream::PlyStream;
use crate::input::texture::TextureImage;

/// What a source knows before its triangles: the tables every brick shares.
#[derive(Clone, Debug, Default)]
pub struct SourceTables {
    /// Materials.
    pub materials: Vec<MaterialRecord>,
    /// Textures.
    pub textures: Vec<TextureImage>,
    /// Per-vertex shading data exists.
    pub shading: bool,
    /// Triangles carry materials.
    pub has_materials: bool,
    /// Triangles carry object ids other than 0.
    pub has_objects: bool,
}

/// A stream of triangles in id order.
pub trait TriangleSource {
    /// Name for messages.
    fn name(&self) -> &str;
    /// The shared tables.
    fn tables(&self) -> SourceTables;
    /// Hands every triangle, in id order, to `emit`.
    fn stream(&mut self, emit: &mut dyn FnMut(TriRecord) -> Result<()>) -> Result<()>;
    /// Bytes the source keeps in memory while streaming (its vertex table).
    fn resident_bytes(&self) -> u64;
    /// The whole mesh, when the source holds one (its lights are chosen from it exactly
    /// as a flat build chooses them).
    fn mesh(&mut self) -> Option<&mut Mesh> {
        None
    }
    /// How many triangles it will emit, if known (for progress).
    fn triangle_hint(&self) -> u64;
    /// Frees what the source holds once its triangles are spilled and its lights chosen.
    fn release(&mut self) {}
}

/// A mesh in memory.
pub struct MeshSource {
    /// Name for messages.
    pub name: String,
    /// The mesh.
    pub mesh: Mesh,
}

impl TriangleSource for MeshSource {
    fn name(&self) -> &str {
        &self.name
    }

    fn tables(&self) -> SourceTables {
        SourceTables {
            materials: self.mesh.materials.clone(),
            textures: self.mesh.textures.clone(),
            shading: !self.mesh.shading.is_empty(),
            has_materials: !self.mesh.tri_materials.is_empty(),
            has_objects: self.mesh.objects.iter().any(|&o| o != 0),
        }
    }

    fn stream(&mut self, emit: &mut dyn FnMut(TriRecord) -> Result<()>) -> Result<()> {
        let m = &self.mesh;
        for (i, t) in m.triangles.iter().enumerate() {
            let mut r = TriRecord::plain(t.map(|v| m.positions[v as usize]), i as u32);
            r.material = m.tri_materials.get(i).copied().unwrap_or(NULL_INDEX);
            r.object = m.objects.get(i).copied().unwrap_or(0);
            if !m.shading.is_empty() {
                r.shading = t.map(|v| m.shading[v as usize]);
            }
            emit(r)?;
        }
        Ok(())
    }

    fn resident_bytes(&self) -> u64 {
        let m = &self.mesh;
        (m.positions.len() * 12 + m.triangles.len() * 12 + m.shading.len() * 32 + m.tri_materials.len() * 4) as u64
    }

    fn mesh(&mut self) -> Option<&mut Mesh> {
        Some(&mut self.mesh)
    }

    fn release(&mut self) {
        self.mesh = Mesh::default();
    }

    fn triangle_hint(&self) -> u64 {
        self.mesh.triangles.len() as u64
    }
}

/// A PLY file, its faces streamed (one default material, as the in-memory reader gives).
pub struct PlySource {
    /// The opened file.
    pub ply: PlyStream,
}

impl TriangleSource for PlySource {
    fn name(&self) -> &str {
        self.ply.name()
    }

    fn tables(&self) -> SourceTables {
        SourceTables {
            materials: vec![MaterialRecord::DEFAULT],
            textures: Vec::new(),
            shading: !self.ply.shading.is_empty(),
            has_materials: true,
            has_objects: false,
        }
    }

    fn stream(&mut self, emit: &mut dyn FnMut(TriRecord) -> Result<()>) -> Result<()> {
        let mut id = 0u32;
        let (positions, shading) = (std::mem::take(&mut self.ply.positions), std::mem::take(&mut self.ply.shading));
        let r = self.ply.faces(&mut |t| {
            let mut r = TriRecord::plain(t.map(|v| positions[v as usize]), id);
            r.material = 0;
            if !shading.is_empty() {
                r.shading = t.map(|v| shading[v as usize]);
            }
            id = id.checked_add(1).ok_or_else(|| anyhow::anyhow!("more than 2^32 triangles"))?;
            emit(r)
        });
        (self.ply.positions, self.ply.shading) = (positions, shading);
        r.map(|_| ())
    }

    fn resident_bytes(&self) -> u64 {
        (self.ply.positions.len() * 12 + self.ply.shading.len() * 32) as u64
    }

    fn triangle_hint(&self) -> u64 {
        0
    }

    fn release(&mut self) {
        self.ply.positions = Vec::new();
        self.ply.shading = Vec::new();
    }
}

/// An OBJ file, its faces streamed.
pub struct ObjSource {
    /// The surveyed file.
    pub obj: ObjStream,
}

impl TriangleSource for ObjSource {
    fn name(&self) -> &str {
        self.obj.name()
    }

    fn tables(&self) -> SourceTables {
        SourceTables {
            materials: self.obj.tables.materials.clone(),
            textures: self.obj.tables.textures.clone(),
            shading: self.obj.shading,
            has_materials: true,
            has_objects: self.obj.objects,
        }
    }

    fn stream(&mut self, emit: &mut dyn FnMut(TriRecord) -> Result<()>) -> Result<()> {
        let mut id = 0u32;
        self.obj.faces(&mut |t| {
            let mut r = TriRecord::plain(t.p, id);
            (r.material, r.object) = (t.material, t.object);
            if self.obj.shading {
                r.shading = t.shading;
            }
            id = id.checked_add(1).ok_or_else(|| anyhow::anyhow!("more than 2^32 triangles"))?;
            emit(r)
        })
    }

    fn resident_bytes(&self) -> u64 {
        self.obj.resident_bytes()
    }

    fn triangle_hint(&self) -> u64 {
        self.obj.triangles
    }
}

/// The lights of a streamed scene: the user's (with a dim ambient term), or the default
/// lights a flat build chooses — a point light placed for the camera, or one standing in
/// for strong emitters (`sums`, over every triangle in id order) — less the area lights,
/// which bricks do not carry. Also whether the point light is the one placed for the
/// camera.
pub fn streamed_lights(
    user: &[LightRecord],
    bounds: ([f32; 3], [f32; 3]),
    camera: &raypipe_core::image::CameraRecord,
    sums: &EmitterSums,
    first_hit: impl Fn(&raypipe_core::Ray) -> Option<f32>,
) -> (Vec<LightRecord>, String, bool) {
    let ambient = LightRecord { position: [0.0; 3], kind: LightRecord::AMBIENT, color: [0.1; 3], triangle: 0 };
    if !user.is_empty() {
        let mut lights = user.to_vec();
        lights.push(ambient);
        let n = user.len();
        return (lights, format!("{n} given light{}", if n == 1 { "" } else { "s" }), false);
    }
    let (lights, note) = crate::build::default_lights::lights_for(sums, bounds, camera, first_hit);
    let for_camera = lights.iter().any(|l| l.kind == LightRecord::POINT);
    (lights, note, for_camera)
}

/// The generated power plant, streamed.
pub struct PowerPlantSource {
    /// Name for messages.
    pub name: String,
    /// The generator.
    pub plant: crate::input::generate::power_plant::PowerPlant,
}

impl TriangleSource for PowerPlantSource {
    fn name(&self) -> &str {
        &self.name
    }

    fn tables(&self) -> SourceTables {
        SourceTables {
            materials: crate::input::generate::power_plant::PowerPlant::materials(),
            textures: Vec::new(),
            shading: false,
            has_materials: true,
            has_objects: false,
        }
    }

    fn stream(&mut self, emit: &mut dyn FnMut(TriRecord) -> Result<()>) -> Result<()> {
        let mut id = 0u32;
        self.plant.stream(&mut |t, m| {
            let mut r = TriRecord::plain(t.map(|v| v.to_array()), id);
            r.material = m;
            id = id.checked_add(1).ok_or_else(|| anyhow::anyhow!("more than 2^32 triangles"))?;
            emit(r)
        })
    }

    fn resident_bytes(&self) -> u64 {
        0
    }

    fn triangle_hint(&self) -> u64 {
        self.plant.triangles
    }
}
