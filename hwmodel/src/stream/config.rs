//! The stream machine's parameters, declared once with their meaning and source.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::stream::gpu::Machine;
use crate::stream::oracle::Oracle;
use crate::stream::texture_cache::TextureCacheConfig;

/// The two architectures of Purcell 2002 §4.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Architecture {
    /// No branching in fragment programs: one kernel per rendering pass, ray state in
    /// the stencil buffer and in state textures (§4.1).
    #[default]
    Multipass,
    /// Branching fragment programs: the kernels fused with loops and branches in one
    /// pass per screen of rays; state stays in registers (§4.2).
    Branching,
}

impl FromStr for Architecture {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "multipass" => Ok(Architecture::Multipass),
            "branching" => Ok(Architecture::Branching),
            _ => Err(format!("architecture {s:?}: expected multipass or branching")),
        }
    }
}

impl fmt::Display for Architecture {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Architecture::Multipass => "multipass",
            Architecture::Branching => "branching",
        })
    }
}

/// Loop unrolling (§4.1): kernel iterations per pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Unroll {
    /// Traversal steps per traversal pass (N; Purcell tried 4).
    pub traverse: u32,
    /// Triangle tests per intersection pass (M; Purcell tried 2).
    pub intersect: u32,
}

impl Default for Unroll {
    fn default() -> Self {
        Unroll { traverse: 1, intersect: 1 }
    }
}

impl FromStr for Unroll {
    type Err = String;
    /// `traverse=N,intersect=M` (either may be left out: 1).
    fn from_str(s: &str) -> Result<Self, String> {
        let mut u = Unroll::default();
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (k, v) =
                part.split_once('=').ok_or_else(|| format!("unroll {s:?}: expected traverse=N,intersect=M"))?;
            let n: u32 = v.trim().parse().map_err(|_| format!("unroll {s:?}: '{v}' is not a count"))?;
            if !(1..=64).contains(&n) {
                return Err(format!("unroll {s:?}: {k} = {n} is not between 1 and 64"));
            }
            match k.trim() {
                "traverse" => u.traverse = n,
                "intersect" => u.intersect = n,
                other => return Err(format!("unroll {s:?}: unknown kernel '{other}' (traverse, intersect)")),
            }
        }
        Ok(u)
    }
}

/// Everything the stream machine is configured by.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StreamConfig {
    /// Multipass or branching.
    pub arch: Architecture,
    /// How the multipass loop picks the next pass.
    pub oracle: Oracle,
    /// Iterations per pass (multipass).
    pub unroll: Unroll,
    /// Suppress the memory references of unrolled iterations after a ray has finished
    /// its kernel mid-pass (§4.1); without it the fragment program, which cannot
    /// branch, still issues them.
    pub suppress: bool,
    /// Branching: fragments that run in lock step (1: each fragment branches alone;
    /// a wider group runs both branches whenever its rays disagree).
    pub simd: u32,
    /// Words a fragment program may write in one pass: Purcell 2002 §2.2 allows "1 or 2
    /// floating point RGBA (4-vectors)" of output, so 8. A kernel with more to write
    /// runs as several passes over the same fragments, each reading its inputs again.
    pub output_words: u32,
    /// The texture cache.
    pub cache: TextureCacheConfig,
    /// State-texture reads go through the texture cache, as every texture read does on
    /// the paper's machine (§5.3: the streaming state "displaces cacheable data");
    /// `false` lets them bypass it.
    pub cache_state: bool,
    /// The machine that turns totals into a frame time.
    pub machine: Machine,
}

impl Default for StreamConfig {
    fn default() -> Self {
        StreamConfig {
            arch: Architecture::Multipass,
            oracle: Oracle::default(),
            unroll: Unroll::default(),
            suppress: false,
            simd: 1,
            output_words: 8,
            cache: TextureCacheConfig::default(),
            cache_state: true,
            machine: Machine::default(),
        }
    }
}

impl StreamConfig {
    /// Checks the combination.
    pub fn validate(&self) -> Result<(), String> {
        self.cache.validate()?;
        if !(1..=1024).contains(&self.simd) {
            return Err(format!("simd width {} is not between 1 and 1024", self.simd));
        }
        if !(4..=64).contains(&self.output_words) || !self.output_words.is_multiple_of(4) {
            return Err(format!(
                "{} output words per pass: expected whole RGBA outputs, 4 to 64 words",
                self.output_words
            ));
        }
        if self.arch == Architecture::Branching && (self.unroll != Unroll::default() || self.suppress) {
            return Err("loop unrolling and suppression are for the multipass architecture".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unroll_parses_and_rejects() {
        assert_eq!("traverse=4,intersect=2".parse(), Ok(Unroll { traverse: 4, intersect: 2 }));
        assert_eq!("intersect=3".parse(), Ok(Unroll { traverse: 1, intersect: 3 }));
        for bad in ["traverse=0", "traverse=65", "walk=2", "traverse", "traverse=x"] {
            assert!(bad.parse::<Unroll>().is_err(), "{bad}");
        }
        let c = StreamConfig { arch: Architecture::Branching, suppress: true, ..Default::default() };
        assert!(c.validate().is_err());
    }
}
