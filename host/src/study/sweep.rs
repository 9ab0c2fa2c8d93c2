//! A design-space sweep's points: a spec (TOML) names fixed parameters, a grid whose
//! cartesian product is run, and listed points (each crossed with the grid); every
//! parameter is a `raypipe simulate` flag (`scene`, `preset`, `size`, `camera`, `algo`,
//! `accel`, `samples`, …) or a configuration key given to `--set` (`traversal.units`,
//! `memory.model`, …). A point is the argument list of one stand-alone `simulate` run,
//! so its report is that run's. Points are numbered in spec order; `--shard i/n` takes
//! those whose number is `i` modulo `n`, a deterministic split for job arrays.
//!
//! ```toml
//! [fixed]
//! scene = "bunny.obj"          # relative paths are relative to the spec file
//! preset = "saarcor"
//! size = "256x192"
//! [grid]
//! "traversal.units" = [1, 2, 4, 8]
//! "cache.nodes.size_bytes" = [4096, 16384, 65536]
//! [[points]]                   # optional; each is crossed with the grid
//! accel = "kd"
//! [[points]]
//! accel = "bvh4"
//! ```

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;

use crate::commands::simulate::{parse_simulate_line, SimulateArgs};

/// Most points a spec may expand to.
pub const MAX_POINTS: usize = 1_000_000;

/// Keys that name files, resolved against the spec's directory.
const PATH_KEYS: [&str; 3] = ["scene", "camera", "config"];

/// Keys the sweep sets itself for every point.
const RESERVED: [&str; 3] = ["output", "report", "help"];

/// One point: its number in the spec and its parameters, in spec order.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// Position in the whole sweep (not the shard).
    pub index: usize,
    /// Parameter name and value.
    pub params: Vec<(String, toml::Value)>,
}

/// A parsed spec.
#[derive(Debug)]
pub struct Spec {
    /// Every point, in order.
    pub points: Vec<Point>,
    /// The spec file's directory (relative paths start there).
    pub dir: PathBuf,
}

/// `i/n`: shard `i` (from 0) of `n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard.
    pub index: usize,
    /// Shards in all.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Shard, String> {
        let (i, n) = s.split_once('/').ok_or_else(|| format!("{s:?} is not i/n (shard i of n, from 0)"))?;
        let parse = |t: &str| t.trim().parse::<usize>().map_err(|_| format!("{s:?} is not i/n (shard i of n, from 0)"));
        let (index, count) = (parse(i)?, parse(n)?);
        if count == 0 || index >= count {
            return Err(format!("{s:?}: the shard must be 0 to n-1 of n ≥ 1 shards"));
        }
        Ok(Shard { index, count })
    }
}

impl Point {
    /// The point's identity: every parameter, `key=value` in spec order (what a resumed
    /// sweep matches finished rows by).
    pub fn id(&self) -> String {
        // Control characters (a multi-line string's newlines) escaped: the id is one
        // line of a message or a table.
        let one_line = |t: String| {
            t.chars()
                .map(|c| if c.is_control() { c.escape_default().to_string() } else { c.into() })
                .collect::<String>()
        };
        self.params.iter().map(|(k, v)| format!("{k}={}", one_line(value_text(v)))).collect::<Vec<_>>().join(", ")
    }

    /// The `raypipe simulate` arguments of this point (without outputs), paths resolved
    /// against `dir`.
    pub fn args(&self, dir: &Path) -> Result<Vec<String>> {
        let flags = simulate_flags();
        let mut args = vec!["simulate".to_string()];
        let mut scene = None;
        for (key, value) in &self.params {
            let flag = key.replace('_', "-");
            let text = |v: &toml::Value| -> Result<String> {
                let t = value_text(v);
                Ok(if PATH_KEYS.contains(&key.as_str()) { resolve(dir, &t) } else { t })
            };
            if key == "scene" {
                scene = Some(text(value)?);
            } else if flags.contains(&flag) {
                let values = match value {
                    toml::Value::Array(a) => a.clone(),
                    v => vec![v.clone()],
                };
                for v in values {
                    match v {
                        toml::Value::Boolean(true) => args.push(format!("--{flag}")),
                        toml::Value::Boolean(false) => {}
                        v => args.extend([format!("--{flag}"), text(&v)?]),
                    }
                }
            } else {
                args.extend(["--set".to_string(), format!("{key}={value}")]);
            }
        }
        args.extend(scene);
        Ok(args)
    }

    /// This point as parsed `raypipe simulate` arguments, writing nowhere it is told to.
    pub fn simulate_args(&self, dir: &Path) -> Result<SimulateArgs> {
        let args = self.args(dir)?;
        parse_simulate_line(&args)
            .map_err(|e| anyhow!("{}", e.to_string().lines().next().unwrap_or("").trim_start_matches("error: ")))
            .with_context(|| format!("sweep point {} ({})", self.index, self.id()))
    }
}

/// A value as the command line writes it: strings bare, everything else as TOML.
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        v => v.to_string(),
    }
}

fn resolve(dir: &Path, p: &str) -> String {
    let path = Path::new(p);
    if path.is_absolute() {
        p.to_string()
    } else {
        dir.join(path).display().to_string()
    }
}

/// The long flags `raypipe simulate` takes (read from its argument definition once).
fn simulate_flags() -> &'static [String] {
    static FLAGS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    FLAGS.get_or_init(|| {
        let cmd = SimulateArgs::augment_args(clap::Command::new("simulate"));
        cmd.get_arguments().filter_map(|a| a.get_long().map(str::to_string)).collect()
    })
}

impl Spec {
    /// Reads and expands the spec at `path`.
    pub fn load(path: &Path) -> Result<Spec> {
        let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let dir = if dir.as_os_str().is_empty() { PathBuf::from(".") } else { dir };
        Spec::parse(&text, dir).map_err(|e| anyhow!("{}: {e:#}", path.display()))
    }

    /// Expands a spec's text.
    pub fn parse(text: &str, dir: PathBuf) -> Result<Spec> {
        let doc: toml::Table = toml::from_str(text).map_err(|e| anyhow!("{}", e.to_string().replace('\n', " ")))?;
        for key in doc.keys() {
            if !["fixed", "grid", "points"].contains(&key.as_str()) {
                bail!("unknown section {key:?} (a spec has [fixed], [grid] and [[points]])");
            }
        }
        let table = |name: &str| -> Result<toml::Table> {
            match doc.get(name) {
                None => Ok(toml::Table::new()),
                Some(toml::Value::Table(t)) => Ok(t.clone()),
                Some(_) => bail!("[{name}] must be a table"),
            }
        };
        if doc
            .values()
            .all(|v| v.as_table().is_some_and(toml::Table::is_empty) || v.as_array().is_some_and(Vec::is_empty))
        {
            bail!("the spec sets no parameter ([fixed], [grid] or [[points]]): it would only simulate the built-in scene once");
        }
        let fixed = table("fixed")?;
        let grid = table("grid")?;
        let listed: Vec<toml::Table> = match doc.get("points") {
            None => vec![toml::Table::new()],
            Some(toml::Value::Array(a)) if !a.is_empty() => a
                .iter()
                .map(|p| p.as_table().cloned().ok_or_else(|| anyhow!("each [[points]] entry must be a table")))
                .collect::<Result<_>>()?,
            Some(_) => bail!("points must be a non-empty array of tables ([[points]])"),
        };
        let mut axes: Vec<(String, Vec<toml::Value>)> = Vec::new();
        for (k, v) in &grid {
            match v {
                toml::Value::Array(a) if !a.is_empty() => axes.push((k.clone(), a.clone())),
                _ => bail!("grid.{k} must be a non-empty list of values"),
            }
        }
        let product = axes.iter().try_fold(listed.len(), |n, (_, a)| n.checked_mul(a.len()));
        match product {
            Some(n) if n <= MAX_POINTS => {}
            _ => bail!("the grid has more than {MAX_POINTS} points"),
        }
        for key in fixed.keys().chain(grid.keys()).chain(listed.iter().flat_map(|p| p.keys())) {
            if RESERVED.contains(&key.as_str()) {
                bail!("{key:?} cannot be a sweep parameter (the sweep writes each point's outputs itself)");
            }
        }
        let per_listed: usize = axes.iter().map(|(_, a)| a.len()).product();
        let mut points = Vec::new();
        for extra in &listed {
            for n in 0..per_listed {
                let mut params: Vec<(String, toml::Value)> = Vec::new();
                let mut put = |k: &str, v: &toml::Value| {
                    params.retain(|(key, _)| key != k);
                    params.push((k.to_string(), v.clone()));
                };
                fixed.iter().for_each(|(k, v)| put(k, v));
                // Grid point `n` in mixed radix, the last axis fastest.
                let mut rest = n;
                let mut picks = vec![0; axes.len()];
                for (i, (_, values)) in axes.iter().enumerate().rev() {
                    picks[i] = rest % values.len();
                    rest /= values.len();
                }
                axes.iter().zip(&picks).for_each(|((k, vs), &i)| put(k, &vs[i]));
                extra.iter().for_each(|(k, v)| put(k, v));
                points.push(Point { index: points.len(), params });
            }
        }
        let spec = Spec { points, dir };
        // Every point must be a valid simulate command line before anything runs. A
        // point's flags are its keys' and each key's value is checked alone, so it is
        // enough to parse every value of every axis once and every listed point once
        // (a million-point spec parses in a second, not in minutes).
        let mut probes: Vec<usize> = (0..listed.len()).map(|l| l * per_listed).collect();
        let mut stride = 1;
        for (_, values) in axes.iter().rev() {
            probes.extend((1..values.len()).map(|i| i * stride));
            stride *= values.len();
        }
        for i in probes {
            spec.points[i].simulate_args(&spec.dir)?;
        }
        Ok(spec)
    }

    /// The points of `shard` (all without one).
    pub fn shard(&self, shard: Option<Shard>) -> Vec<&Point> {
        self.points.iter().filter(|p| shard.is_none_or(|s| p.index % s.count == s.index)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_multi_line_value_makes_a_one_line_error() {
        // The fuzzer's spec: `size` a multi-line string that is no size.
        let text = "[fixed]\nsize ='''oinetits\" = [, 2, 4]\npa[f\t\t\t\t\tcket_size = [4,'''";
        let e = format!("{:#}", Spec::parse(text, PathBuf::from("/nonexistent")).unwrap_err());
        assert!(!e.contains('\n') && e.contains("sweep point 0 (size=oinetits") && e.contains("\\n"), "{e}");
    }
}
