//! The cost model: instructions and memory words per kernel invocation, Purcell 2002's
//! Table 1 columns for raypipe's kernels — one set for the multipass machine, one for
//! the branching machine.
//!
//! - **Instructions** (`instructions`, `b_instructions`) are counted from raypipe-core's
//!   code. The default table counts 4-wide fragment-program instructions as the paper
//!   does ([`crate::stream::vec4_counts`]); `--isa scalar` counts one instruction per
//!   scalar operation ([`crate::stream::scalar_counts`]). A multipass kernel adds one
//!   `TEX` per state texel it reads and what it recomputes instead of storing; a
//!   branching kernel keeps both in registers. A test pins the tables so that they
//!   cannot drift silently.
//! - **R** and **W** (multipass) are the state words an invocation reads from and writes
//!   to the state textures ([`crate::stream::ray_state::words`]), whole RGBA texels.
//! - **BR** and **BW** (branching) are its stream input and output: the fused program
//!   keeps a ray's state in registers, but a secondary ray's record is read from the
//!   texture the shader wrote it to, and colours and emitted records are written.
//! - **M**, the random-access words (grid cells, list entries, vertices, shading data),
//!   are not in the table: the model counts the words core's kernels actually read,
//!   through `MemoryProbe`. A table from a file may set `m` to replace the measured
//!   words with a fixed number per invocation (to plug in the paper's counts).
//!
//! Stencil reads and writes are counted as they happen ([`crate::stream::stencil`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::stream::ray_state::words;
use crate::stream::{scalar_counts, vec4_counts};

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

/// One kernel's costs per invocation: Table 1's columns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct KernelCost {
    /// Fragment-program instructions (multipass), Table 1's figure: one iteration plus
    /// the pass's own part, `per_pass`.
    pub instructions: u64,
    /// Of `instructions`, those a processed ray executes once per pass however many
    /// iterations it unrolls: the state texels' `TEX` and what is recomputed from them
    /// (registers keep them within the pass).
    pub per_pass: u64,
    /// State words read (multipass).
    pub r: u64,
    /// State words written (multipass).
    pub w: u64,
    /// Fragment-program instructions (branching).
    pub b_instructions: u64,
    /// Stream words read (branching).
    pub br: u64,
    /// Stream words written (branching).
    pub bw: u64,
    /// Random-access words per invocation, if fixed by the table instead of measured.
    pub m: Option<f64>,
}

/// How instructions are counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Isa {
    /// 4-wide fragment-program instructions, as Purcell 2002 §3.2 counts them.
    #[default]
    Vec4,
    /// One instruction per scalar operation.
    Scalar,
}

impl std::str::FromStr for Isa {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "vec4" => Ok(Isa::Vec4),
            "scalar" => Ok(Isa::Scalar),
            _ => Err(format!("instruction set {s:?}: expected vec4 or scalar")),
        }
    }
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
        CostModel::counted(Isa::Vec4)
    }
}

/// A kernel's instruction counts: its body, what the multipass machine recomputes each
/// pass, and what the branching machine does once per ray in its place.
struct Counts {
    body: u64,
    multipass_extra: u64,
    branching_extra: u64,
}

impl CostModel {
    /// raypipe's own table, instructions counted by `isa`.
    pub fn counted(isa: Isa) -> CostModel {
        use words::{COLOR, HIT, LIST, RAY, TRAVERSAL};
        let c = |body, multipass_extra, branching_extra| Counts { body, multipass_extra, branching_extra };
        let scalar = isa == Isa::Scalar;
        let n = |k: Kernel| -> Counts {
            use Kernel::*;
            if scalar {
                // The scalar table charges both machines the same code.
                let body = match k {
                    Generate => scalar_counts::GENERATE,
                    Setup => scalar_counts::SETUP,
                    Traverse => scalar_counts::TRAVERSE,
                    Intersect => scalar_counts::INTERSECT,
                    Shade => scalar_counts::SHADE,
                    ShadeLight => scalar_counts::SHADE_LIGHT,
                    Texture => scalar_counts::TEXTURE,
                    Glossy => scalar_counts::GLOSSY,
                    GlossyLight => scalar_counts::GLOSSY_LIGHT,
                    Spawn => scalar_counts::SPAWN,
                    ShadowAdd => scalar_counts::SHADOW_ADD,
                };
                return c(body, 0, 0);
            }
            match k {
                Generate => c(vec4_counts::GENERATE, 0, 0),
                // The branching machine prepares the sheared ray once, here.
                Setup => c(vec4_counts::SETUP, 0, vec4_counts::PREPARE),
                Traverse => c(vec4_counts::TRAVERSE, vec4_counts::TRAVERSE_RECOMPUTE, 0),
                // The multipass machine re-reads the list entry it stores no copy of.
                Intersect => c(vec4_counts::INTERSECT, vec4_counts::PREPARE + 1, 0),
                Shade => c(vec4_counts::SHADE, 0, 0),
                ShadeLight => c(vec4_counts::SHADE_LIGHT, 0, 0),
                Texture => c(vec4_counts::TEXTURE, 0, 0),
                Glossy => c(vec4_counts::GLOSSY, 0, 0),
                GlossyLight => c(vec4_counts::GLOSSY_LIGHT, 0, 0),
                Spawn => c(vec4_counts::SPAWN, 0, 0),
                ShadowAdd => c(vec4_counts::SHADOW_ADD, 0, 0),
            }
        };
        // (multipass R, W; branching R, W), in words of whole RGBA texels.
        let io = |k: Kernel| -> (u64, u64, u64, u64) {
            use Kernel::*;
            let trav = TRAVERSAL + LIST;
            match k {
                // Writes the ray.
                Generate => (0, RAY, 0, 0),
                // Reads the ray; writes the DDA's texels and the empty hit (12 words: two
                // passes of at most 8, as the paper's setup takes two).
                Setup => (RAY, trav + HIT, RAY + COLOR, 0),
                // Reads ray, DDA and hit; writes the DDA's texels (the list position
                // shares the second).
                Traverse => (RAY + trav + HIT, trav, 0, 0),
                // Reads ray, DDA (t_enter and the list position) and hit; writes the hit
                // and the texel holding the list position.
                Intersect => (RAY + trav + HIT, HIT + 4, 0, 0),
                // Reads ray, hit and the ray's weight; adds the colour.
                Shade => (RAY + HIT + COLOR, COLOR, 0, COLOR),
                // Writes the new ray and its weight.
                Spawn => (0, RAY + COLOR, 0, RAY + COLOR),
                // Reads the hit and the weight; adds the weight.
                ShadowAdd => (HIT + COLOR, COLOR, 0, COLOR),
                ShadeLight | Texture | Glossy | GlossyLight => (0, 0, 0, 0),
            }
        };
        let kernels = Kernel::ALL
            .iter()
            .map(|&k| {
                let (counts, (r, w, br, bw)) = (n(k), io(k));
                // A state texel read is a `TEX` of the multipass program.
                let tex = if scalar { 0 } else { r.div_ceil(4) };
                let cost = KernelCost {
                    instructions: counts.body + counts.multipass_extra + tex,
                    per_pass: counts.multipass_extra + tex,
                    r,
                    w,
                    b_instructions: counts.body + counts.branching_extra,
                    br,
                    bw,
                    m: None,
                };
                (k, cost)
            })
            .collect();
        let source = match isa {
            Isa::Vec4 => "raypipe-core (4-wide fragment-program instructions)",
            Isa::Scalar => "raypipe-core (scalar operations)",
        };
        CostModel { kernels, source: source.into() }
    }
}

/// One kernel's entry in a cost file: any field left out keeps raypipe's count.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CostOverride {
    instructions: Option<u64>,
    r: Option<u64>,
    w: Option<u64>,
    b_instructions: Option<u64>,
    br: Option<u64>,
    bw: Option<u64>,
    m: Option<f64>,
}

impl CostModel {
    /// The costs of `k`.
    pub fn get(&self, k: Kernel) -> KernelCost {
        self.kernels.get(&k).copied().unwrap_or_default()
    }

    /// raypipe's table (counted by `isa`) with a TOML file's entries on top:
    /// `[intersect]` `instructions = 41`, `r = 14`, `w = 8`, `b_instructions = 36`,
    /// `br = 0`, `bw = 0`, `m = 11` (any subset).
    pub fn from_toml(text: &str, source: &str, isa: Isa) -> Result<CostModel, String> {
        let table: BTreeMap<String, CostOverride> = toml::from_str(text).map_err(|e| one_line(&e.to_string()))?;
        let mut model = CostModel::counted(isa);
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
            let fields = [
                ("instructions", o.instructions),
                ("r", o.r),
                ("w", o.w),
                ("b_instructions", o.b_instructions),
                ("br", o.br),
                ("bw", o.bw),
            ];
            for (what, v) in fields {
                if v.is_some_and(|v| v > 1_000_000) {
                    return Err(format!("[{name}] {what} = {}: more than 1e6 per invocation", v.unwrap_or(0)));
                }
            }
            let e = model.kernels.entry(kernel).or_default();
            if let Some(i) = o.instructions {
                // A table's figure is one invocation's: nothing is left to the pass.
                (e.instructions, e.per_pass) = (i, 0);
            }
            e.r = o.r.unwrap_or(e.r);
            e.w = o.w.unwrap_or(e.w);
            e.b_instructions = o.b_instructions.unwrap_or(e.b_instructions);
            e.br = o.br.unwrap_or(e.br);
            e.bw = o.bw.unwrap_or(e.bw);
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
    fn the_counted_tables_are_pinned() {
        // Changing a kernel in core means recounting it, on purpose.
        let pin = |isa, multipass: [u64; 11], branching: [u64; 11]| {
            let m = CostModel::counted(isa);
            let i: Vec<u64> = Kernel::ALL.iter().map(|&k| m.get(k).instructions).collect();
            let b: Vec<u64> = Kernel::ALL.iter().map(|&k| m.get(k).b_instructions).collect();
            assert_eq!((i.as_slice(), b.as_slice()), (&multipass[..], &branching[..]), "{isa:?}");
        };
        pin(
            Isa::Scalar,
            [79, 121, 30, 85, 100, 29, 209, 22, 67, 52, 4],
            [79, 121, 30, 85, 100, 29, 209, 22, 67, 52, 4],
        );
        pin(Isa::Vec4, [28, 38, 42, 53, 35, 8, 68, 11, 27, 13, 4], [28, 46, 24, 37, 31, 8, 68, 11, 27, 13, 2]);
    }

    #[test]
    fn multipass_kernels_read_state_in_whole_texels_and_add_a_tex_for_each() {
        let m = CostModel::default();
        for k in Kernel::ALL {
            let c = m.get(k);
            assert!(c.r % 4 == 0 && c.w % 4 == 0, "{k:?} {c:?}");
            assert!(c.per_pass >= c.r / 4 && c.instructions >= c.per_pass, "{k:?}");
            // The pass's part is what the branching kernel does not repeat per step.
            if matches!(k, Kernel::Traverse | Kernel::Intersect) {
                assert_eq!(c.instructions - c.per_pass, c.b_instructions, "{k:?}");
            }
        }
        // The branching machine's fused loop reads and writes no state.
        for k in [Kernel::Traverse, Kernel::Intersect] {
            assert_eq!((m.get(k).br, m.get(k).bw), (0, 0));
        }
    }

    /// Table 1 of the paper is legible for one kernel: eye-ray generation on the
    /// multipass machine, 28 instructions, reading 0 words. raypipe's kernel, counted by
    /// the rule in `vec4_counts`, is held to it within a quarter — a check of the
    /// counting rule, not a target. It writes 8 words against the paper's 5: raypipe's
    /// ray record carries its origin and t range, the paper's eye ray its direction.
    #[test]
    fn eye_ray_generation_checks_against_the_papers_table_1() {
        let g = CostModel::default().get(Kernel::Generate);
        assert_eq!(g.r, 0);
        assert!((g.instructions as f64 / 28.0 - 1.0).abs() <= 0.25, "{g:?}");
        assert_eq!(g.w, 8);
    }

    #[test]
    fn a_file_overrides_some_fields_and_names_bad_entries() {
        let m = CostModel::from_toml("[intersect]\ninstructions = 41\nm = 11.5\nbr = 2\n", "paper.toml", Isa::Vec4)
            .unwrap();
        let k = m.get(Kernel::Intersect);
        assert_eq!((k.instructions, k.m, k.br), (41, Some(11.5), 2));
        assert_eq!(k.r, CostModel::default().get(Kernel::Intersect).r);
        assert_eq!(m.source, "paper.toml");
        let e = CostModel::from_toml("[intersekt]\ninstructions = 1\n", "x", Isa::Vec4).unwrap_err();
        assert!(e.contains("intersekt"), "{e}");
        assert!(CostModel::from_toml("[shade]\nfoo = 1\n", "x", Isa::Vec4).is_err());
        assert!(CostModel::from_toml("[shade]\nm = -1\n", "x", Isa::Vec4).is_err());
        assert!(CostModel::from_toml("[shade\n", "x", Isa::Vec4).is_err());
    }
}
