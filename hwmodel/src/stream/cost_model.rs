//! The cost model: instructions and memory words per kernel invocation, Purcell 2002's
//! Table 1 columns for raypipe's kernels.
//!
//! - **Instructions** are fragment-program instructions counted from raypipe-core's
//!   code, one per arithmetic operation, comparison, select, conversion, `sqrt` or
//!   reciprocal on one value — a vector operation on a `Vec3` counts 3, since the core
//!   kernels are written on scalars and would be scalar code on a fragment processor
//!   with no swizzle to spare. Loads are not instructions: they are the M column. Each
//!   entry's count is broken down against the function it comes from below; change the
//!   kernel, change the count (a test pins the table so that it cannot drift silently).
//! - **R** and **W** are the state words a multipass invocation reads from and writes to
//!   the state textures ([`crate::stream::ray_state::words`], sized from core's records);
//!   the branching machine keeps state in registers and has none.
//! - **M**, the random-access words (grid cells, list entries, vertices, shading data),
//!   are not in the table: the model counts the words core's kernels actually read,
//!   through `MemoryProbe`. A table from a file may set `m` to replace the measured
//!   words with a fixed number per invocation (to plug in the paper's counts).
//!
//! Stencil reads and writes are counted as they happen ([`crate::stream::stencil`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::stream::ray_state::words;

/// The kernels the machine runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kernel {
    /// Eye-ray generation with the scene-box test (§3.1.1).
    Generate,
    /// Traversal setup: the 3D-DDA's first voxel (§3.1.2).
    Setup,
    /// One traversal step: a DDA step and a cell read (§3.1.2).
    Traverse,
    /// One ray–triangle test and the next list entry (§3.1.3).
    Intersect,
    /// Shading a ray's end: the surface at the hit (§3.1.4), without the lights.
    Shade,
    /// One light evaluated by the shading kernel.
    ShadeLight,
    /// A textured hit's mipmap level and trilinear filter (per textured hit).
    Texture,
    /// A glossy surface's lobes: Kd and Ks scaled together (per glossy hit).
    Glossy,
    /// One light's Blinn–Phong highlight at a glossy hit.
    GlossyLight,
    /// One ray record emitted by a shader (shadow, reflection, refraction, bounce).
    Spawn,
    /// A shadow ray's end: its weight added to the pixel if nothing was in the way.
    ShadowAdd,
}

impl Kernel {
    /// How many kernels there are.
    pub const COUNT: usize = 11;

    /// Every kernel, in table order.
    pub const ALL: [Kernel; Kernel::COUNT] = [
        Kernel::Generate,
        Kernel::Setup,
        Kernel::Traverse,
        Kernel::Intersect,
        Kernel::Shade,
        Kernel::ShadeLight,
        Kernel::Texture,
        Kernel::Glossy,
        Kernel::GlossyLight,
        Kernel::Spawn,
        Kernel::ShadowAdd,
    ];

    /// The name used in tables, reports and cost files.
    pub const fn name(self) -> &'static str {
        match self {
            Kernel::Generate => "generate",
            Kernel::Setup => "setup",
            Kernel::Traverse => "traverse",
            Kernel::Intersect => "intersect",
            Kernel::Shade => "shade",
            Kernel::ShadeLight => "shade_light",
            Kernel::Texture => "texture",
            Kernel::Glossy => "glossy",
            Kernel::GlossyLight => "glossy_light",
            Kernel::Spawn => "spawn",
            Kernel::ShadowAdd => "shadow_add",
        }
    }

    /// The kernel of a name.
    pub fn from_name(s: &str) -> Option<Kernel> {
        Kernel::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// One kernel's costs per invocation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct KernelCost {
    /// Fragment-program instructions.
    pub instructions: u64,
    /// State words read (multipass).
    pub r: u64,
    /// State words written (multipass).
    pub w: u64,
    /// Random-access words per invocation, if fixed by the table instead of measured.
    pub m: Option<f64>,
}

/// The table, one entry per kernel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CostModel {
    /// Costs by kernel.
    pub kernels: BTreeMap<Kernel, KernelCost>,
    /// Where the table came from ("raypipe-core" or a file name).
    pub source: String,
}

/// Instruction counts of core's kernels, with their breakdown (see the module comment
/// for the counting rule).
pub mod counted {
    /// `EyeRays::ray` + `clip_ray` against the scene box (core/src/camera.rs,
    /// core/src/traverse/aabb.rs).
    /// - pixel to screen: x and y each convert, +0.5, ×1/w, ×2, −1: 10;
    /// - direction `forward + right·(sx·hw) + up·(sy·hh)`: 2 + 3 + 3 + 6 = 14;
    /// - `normalize`: dot 5, sqrt, reciprocal, scale 3: 10;
    /// - `clip_ray`, per axis: d = 0 test, 1/d, near (2), far (2), compare and swap (3),
    ///   far × growth, near/t0 and far/t1 compare-select (4), t0 > t1 test: 15, × 3 = 45.
    pub const GENERATE: u64 = 10 + 14 + 10 + 45;
    /// `Dda::new` (core/src/traverse/dda.rs):
    /// - `Ray::is_valid` (finite origin and direction, non-zero direction): 4;
    /// - `clip_ray` against the grid box: 45 (as above); entry point `ray.at(t0)`: 6;
    /// - per axis: cell `floor((p − min)/size)` with NaN guard, clamp, convert: 8; step
    ///   sign: 3; 1/d with zero guard: 3; `boundary_t`: select k (3), convert, × size,
    ///   + min, − origin, × 1/d (5): 8 — 22, × 3 = 66.
    pub const SETUP: u64 = 4 + 45 + 6 + 66;
    /// `GridTraversal::step` + `Dda::step` (core/src/traverse/grid.rs, dda.rs):
    /// - done test 1; first-boundary axis: 2 compares, 2 selects: 4; its distance 1;
    /// - `t_exit`: compare, max, select: 3; cell index x + dx·(y + dy·z): 4;
    /// - end test 1; advance the cell 2; bounds test 2; `boundary_t` 8; `t_enter` 1;
    /// - hit-is-final test (`best.t < t_enter`): 2; empty-cell test: 1.
    pub const TRAVERSE: u64 = 1 + 4 + 1 + 3 + 4 + 1 + 2 + 2 + 8 + 1 + 2 + 1;
    /// `Watertight::prepare` + `Watertight::intersect` + `test_triangle` + the list
    /// advance (core/src/intersect/watertight.rs, triangle.rs; the model's read-ahead):
    /// - prepare (the sheared ray is not kept between passes): |d| 3, major axis 3
    ///   compares + 2 selects, kx/ky 2, sign swap 3, sx, sy, sz 3 divisions: 16;
    /// - vertices relative to the origin: 9; shear (`shear_edges`): 6 × (mul, sub): 12;
    /// - edge functions: 3 × (2 mul, sub): 9; sign test: 6 compares, 4 logic ops: 10;
    /// - det: 2 adds, zero test 1; `scaled_distance`: 3 + 3 mul, 2 add: 8;
    /// - 1/det, t, u, v: 4; `in_range`: 3; `keep_closest` on (t, prim): 3 compares, 4
    ///   selects: 7; list advance, terminator test, voxel-exit test: 4.
    pub const INTERSECT: u64 = 16 + 9 + 12 + 9 + 10 + 3 + 8 + 4 + 3 + 7 + 4;
    /// `Surface::at` (core/src/shade/surface.rs) and the shader's fixed part:
    /// - geometric normal: 2 vector subs, cross: 6 + 9 = 15; weights: 2;
    /// - normal interpolation 15 and its checks (length², finite, select) 12;
    /// - colour interpolation 15; `normalize_or_zero` 12; facing test and flip 9;
    /// - scene extent 5; hit point `ray.at(t)` 6; final colour (diffuse × tint × light +
    ///   emission) 9.
    pub const SHADE: u64 = 15 + 2 + 15 + 12 + 15 + 12 + 9 + 5 + 6 + 9;
    /// One point light in `lambert::shade` / `shade_whitted`: direction 3, normalize 12,
    /// dot 5, clamp 1, × colour 3, accumulate 3, kind tests 2 (an ambient light: 6 of
    /// these 29).
    pub const SHADE_LIGHT: u64 = 3 + 12 + 5 + 1 + 3 + 3 + 2;
    /// The texture part of `Surface::at` and `texture::sample` (core/src/shade/surface.rs,
    /// texture.rs, ray_cone.rs), charged as the trilinear case (two levels; a magnified
    /// hit reads one):
    /// - uv interpolation 10; uv edges 4, their cross product 3, abs 1, × width × height
    ///   with conversions 4; incidence: normalize both 24, dot 5; cone width: |d| 6,
    ///   multiply-add 3; level: divide 1, three log2 3, half, sub, add 3, NaN test 1: 68;
    /// - level clamp, floor, fraction 4; each level's record (size shifts, the chain's
    ///   offset) 10;
    /// - per level: two axes (wrap, scale, floor, fraction) 12, four wrapped texel
    ///   coordinates 8, four sRGB decodes (3 lookups each) 12, three Vec3 blends 27: 59,
    ///   × 2 = 118; the blend of the two levels 9.
    pub const TEXTURE: u64 = 68 + 4 + 10 + 118 + 9;
    /// `blinn_phong::lobes` at a glossy hit: `Ks` clamped 6, `Ns` tests and clamp 3,
    /// `Kd + Ks` 3, its largest channel 2 and the max with 1: 3, reciprocal 1, both
    /// lobes scaled 6.
    pub const GLOSSY: u64 = 6 + 3 + 3 + 3 + 1 + 6;
    /// `BlinnPhong::eval_pi` for one light (core/src/shade/blinn_phong.rs) and its share
    /// of `Surface::point_light_shadow`:
    /// - the eye direction: normalize 12, negate 3; hemisphere tests: 2 dots 10, 2
    ///   compares;
    /// - half vector: add 3, normalize 12; N·H 5, max 1; `powf` as exp2(n·log2 x): 3;
    /// - normalisation `(n+2)(n+4) / (8 (2^(−n/2) + n))`: 2 adds, 1 product, exp2 of a
    ///   product 2, add, ×8, divide 2: 9;
    /// - × the power and × `Ks`: 4; added to the diffuse reflectance 3.
    pub const GLOSSY_LIGHT: u64 = 12 + 3 + 10 + 2 + 3 + 12 + 5 + 1 + 3 + 9 + 4 + 3;
    /// One emitted record: `Surface::offset_point` (normalize 12, dot and flip 8,
    /// scale 8, offset 6) and the direction 3, the weight (3 products of 3) 9, its
    /// tests (max, finite) 6: 52.
    pub const SPAWN: u64 = 12 + 8 + 8 + 6 + 3 + 9 + 6;
    /// A shadow ray's end: the occlusion test and the weighted add: 1 + 3.
    pub const SHADOW_ADD: u64 = 4;
}

impl Default for CostModel {
    fn default() -> Self {
        let (ray, trav, hit, list, color) = (words::RAY, words::TRAVERSAL, words::HIT, words::LIST, words::COLOR);
        let k = |instructions, r, w| KernelCost { instructions, r, w, m: None };
        let kernels = BTreeMap::from([
            // Writes the ray.
            (Kernel::Generate, k(counted::GENERATE, 0, ray)),
            // Reads the ray, writes the DDA registers and the (empty) hit.
            (Kernel::Setup, k(counted::SETUP, ray, trav + hit)),
            // Reads the DDA registers and the hit; writes the registers and the list
            // state (a fragment program writes all its outputs).
            (Kernel::Traverse, k(counted::TRAVERSE, trav + hit, trav + list)),
            // Reads the ray, the hit and the list state; writes hit and list state.
            (Kernel::Intersect, k(counted::INTERSECT, ray + hit + list, hit + list)),
            // Reads ray and hit; writes the colour.
            (Kernel::Shade, k(counted::SHADE, ray + hit, color)),
            (Kernel::ShadeLight, k(counted::SHADE_LIGHT, 0, 0)),
            (Kernel::Texture, k(counted::TEXTURE, 0, 0)),
            (Kernel::Glossy, k(counted::GLOSSY, 0, 0)),
            (Kernel::GlossyLight, k(counted::GLOSSY_LIGHT, 0, 0)),
            // Writes the new ray and its weight (a colour).
            (Kernel::Spawn, k(counted::SPAWN, 0, ray + color)),
            // Reads the hit, writes the colour.
            (Kernel::ShadowAdd, k(counted::SHADOW_ADD, hit, color)),
        ]);
        CostModel { kernels, source: "raypipe-core (counted)".into() }
    }
}

/// One kernel's entry in a cost file: any field left out keeps raypipe's count.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CostOverride {
    instructions: Option<u64>,
    r: Option<u64>,
    w: Option<u64>,
    m: Option<f64>,
}

impl CostModel {
    /// The costs of `k`.
    pub fn get(&self, k: Kernel) -> KernelCost {
        self.kernels.get(&k).copied().unwrap_or(KernelCost { instructions: 0, r: 0, w: 0, m: None })
    }

    /// raypipe's table with a TOML file's entries on top:
    /// `[intersect]` `instructions = 41`, `r = 14`, `w = 8`, `m = 11` (any subset).
    pub fn from_toml(text: &str, source: &str) -> Result<CostModel, String> {
        let table: BTreeMap<String, CostOverride> = toml::from_str(text).map_err(|e| one_line(&e.to_string()))?;
        let mut model = CostModel::default();
        for (name, o) in table {
            let kernel = Kernel::from_name(&name).ok_or_else(|| {
                let names: Vec<_> = Kernel::ALL.iter().map(|k| k.name()).collect();
                format!("unknown kernel [{name}] (kernels: {})", names.join(", "))
            })?;
            if let Some(m) = o.m {
                if !(m.is_finite() && (0.0..=1e6).contains(&m)) {
                    return Err(format!("[{name}] m = {m}: expected words per invocation between 0 and 1e6"));
                }
            }
            for (what, v) in [("instructions", o.instructions), ("r", o.r), ("w", o.w)] {
                if v.is_some_and(|v| v > 1_000_000) {
                    return Err(format!("[{name}] {what} = {}: more than 1e6 per invocation", v.unwrap_or(0)));
                }
            }
            let e = model.kernels.entry(kernel).or_insert(KernelCost { instructions: 0, r: 0, w: 0, m: None });
            e.instructions = o.instructions.unwrap_or(e.instructions);
            e.r = o.r.unwrap_or(e.r);
            e.w = o.w.unwrap_or(e.w);
            e.m = o.m.or(e.m);
        }
        model.source = source.to_string();
        Ok(model)
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counted_table_is_pinned() {
        // Changing a kernel in core means recounting it here, on purpose.
        let m = CostModel::default();
        let i: Vec<u64> = Kernel::ALL.iter().map(|&k| m.get(k).instructions).collect();
        assert_eq!(i, [79, 121, 30, 85, 100, 29, 209, 22, 67, 52, 4]);
        assert_eq!(m.get(Kernel::Intersect).r, words::RAY + words::HIT + words::LIST);
    }

    #[test]
    fn a_file_overrides_some_fields_and_names_bad_entries() {
        let m = CostModel::from_toml("[intersect]\ninstructions = 41\nm = 11.5\n", "paper.toml").unwrap();
        let k = m.get(Kernel::Intersect);
        assert_eq!((k.instructions, k.m), (41, Some(11.5)));
        assert_eq!(k.r, CostModel::default().get(Kernel::Intersect).r);
        assert_eq!(m.source, "paper.toml");
        let e = CostModel::from_toml("[intersekt]\ninstructions = 1\n", "x").unwrap_err();
        assert!(e.contains("intersekt"), "{e}");
        assert!(CostModel::from_toml("[shade]\nfoo = 1\n", "x").is_err());
        assert!(CostModel::from_toml("[shade]\nm = -1\n", "x").is_err());
        assert!(CostModel::from_toml("[shade\n", "x").is_err());
    }
}
