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
use crate::stream::scalar_counts;

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

impl Default for CostModel {
    fn default() -> Self {
        let (ray, trav, hit, list, color) = (words::RAY, words::TRAVERSAL, words::HIT, words::LIST, words::COLOR);
        let k = |instructions, r, w| KernelCost { instructions, r, w, m: None };
        let kernels = BTreeMap::from([
            // Writes the ray.
            (Kernel::Generate, k(scalar_counts::GENERATE, 0, ray)),
            // Reads the ray, writes the DDA registers and the (empty) hit.
            (Kernel::Setup, k(scalar_counts::SETUP, ray, trav + hit)),
            // Reads the DDA registers and the hit; writes the registers and the list
            // state (a fragment program writes all its outputs).
            (Kernel::Traverse, k(scalar_counts::TRAVERSE, trav + hit, trav + list)),
            // Reads the ray, the hit and the list state; writes hit and list state.
            (Kernel::Intersect, k(scalar_counts::INTERSECT, ray + hit + list, hit + list)),
            // Reads ray and hit; writes the colour.
            (Kernel::Shade, k(scalar_counts::SHADE, ray + hit, color)),
            (Kernel::ShadeLight, k(scalar_counts::SHADE_LIGHT, 0, 0)),
            (Kernel::Texture, k(scalar_counts::TEXTURE, 0, 0)),
            (Kernel::Glossy, k(scalar_counts::GLOSSY, 0, 0)),
            (Kernel::GlossyLight, k(scalar_counts::GLOSSY_LIGHT, 0, 0)),
            // Writes the new ray and its weight (a colour).
            (Kernel::Spawn, k(scalar_counts::SPAWN, 0, ray + color)),
            // Reads the hit, writes the colour.
            (Kernel::ShadowAdd, k(scalar_counts::SHADOW_ADD, hit, color)),
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
