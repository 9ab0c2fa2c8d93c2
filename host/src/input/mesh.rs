//! The in-memory triangle mesh the builder works from, and its validation.

use anyhow::{bail, Result};
use raypipe_core::image::{LightRecord, MaterialRecord, ShadingVertex};

/// The largest coordinate magnitude a mesh may have: the builders' surface areas (squares
/// of extents) and grown boxes stay finite in f32 below it (scenes of
/// extent 1e20 failed with "internal error: built an invalid image").
pub const MAX_COORDINATE: f32 = 1e18;
/// A triangle mesh with shading data, in the input's face order after triangulation
/// (triangle ids in every output refer to this order).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex shading data (same length as `positions`), or empty.
    pub shading: Vec<ShadingVertex>,
    /// Material per triangle (same length as `triangles`), or empty.
    pub tri_materials: Vec<u32>,
    /// Materials.
    pub materials: Vec<MaterialRecord>,
    /// Material names, parallel to `materials`.
    pub material_names: Vec<String>,
    /// Lights.
    pub lights: Vec<LightRecord>,
    /// Diffuse textures, indexed by `MaterialRecord::texture`.
    pub textures: Vec<crate::input::texture::TextureImage>,
    /// Object id per triangle (same length as `triangles`: OBJ `o`/`g` names in order,
    /// glTF nodes with a mesh, a scene file's meshes), or empty (one object).
    pub objects: Vec<u32>,
    /// The bounds the builders size their boxes' margins from, when not the mesh's own:
    /// a brick of a bricked scene takes the whole scene's, so that its structure stays
    /// conservative for every ray the whole scene's range admits (rays from far
    /// outside a small brick round as they would in the flat image).
    pub margin_bounds: Option<([f32; 3], [f32; 3])>,
}

impl Mesh {
    /// Checks what the builder relies on; `name` is the input named in errors.
    pub fn validate(&self, name: &str) -> Result<()> {
        if self.triangles.is_empty() {
            bail!("{name}: the mesh has no triangles");
        }
        crate::input::limits::check_triangles(name, self.triangles.len() as u64)?;
        crate::input::limits::check_vertices(name, self.positions.len() as u64)?;
        if let Some(i) = self.positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            bail!("{name}: vertex {} has a NaN or infinite coordinate", i + 1);
        }
        if let Some(i) = self.positions.iter().position(|p| p.iter().any(|c| c.abs() > MAX_COORDINATE)) {
            bail!(
                "{name}: vertex {} has a coordinate beyond ±{MAX_COORDINATE:e}, the range raypipe builds (scale the scene)",
                i + 1
            );
        }
        let nv = self.positions.len() as u32;
        if let Some(i) = self.triangles.iter().position(|t| t.iter().any(|&v| v >= nv)) {
            bail!("{name}: triangle {i} references a vertex that does not exist");
        }
        if !self.shading.is_empty() && self.shading.len() != self.positions.len() {
            bail!("{name}: shading data does not match the vertices");
        }
        if !self.objects.is_empty() && self.objects.len() != self.triangles.len() {
            bail!("{name}: object ids do not match the triangles");
        }
        for (i, m) in self.materials.iter().enumerate() {
            let mut vals =
                m.diffuse.iter().chain(&m.specular).chain(&m.emission).chain([&m.shininess, &m.ior, &m.dissolve]);
            if vals.any(|c| !c.is_finite() || *c < 0.0) {
                bail!(
                    "{name}: material '{}' has a negative, NaN or infinite value",
                    self.material_names.get(i).map_or("?", |s| s.as_str())
                );
            }
        }
        Ok(())
    }

    /// True if triangle `t` has zero area (collinear or repeated vertices), computed in
    /// double precision from the single-precision vertices.
    pub fn is_degenerate(&self, t: [u32; 3]) -> bool {
        let [a, b, c] = t.map(|i| glam::DVec3::from(self.positions[i as usize].map(f64::from)));
        (b - a).cross(c - a) == glam::DVec3::ZERO
    }

    /// Number of triangles with zero area (they can never be hit; they are kept so that
    /// triangle ids follow the input's face order).
    pub fn degenerate_count(&self) -> usize {
        self.triangles.iter().filter(|&&t| self.is_degenerate(t)).count()
    }

    /// The warning a loader gives for zero-area triangles, if there are any.
    pub fn degenerate_warning(&self, name: &str) -> Option<String> {
        let n = self.degenerate_count();
        (n > 0).then(|| format!("{name}: {n} degenerate (zero-area) triangles kept; they can never be hit"))
    }

    /// The bounds the builders' margins are relative to: [`Mesh::margin_bounds`], or the
    /// mesh's own.
    pub fn margin_reference(&self) -> ([f32; 3], [f32; 3]) {
        self.margin_bounds.unwrap_or_else(|| self.bounds())
    }

    /// The box around all vertices.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if self.positions.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        (lo, hi)
    }
}
