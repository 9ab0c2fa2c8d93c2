//! `raypipe report diff`: what changed between two runs.

use std::path::Path;

use anyhow::{anyhow, Result};
use serde_json::Value;

use crate::study::report_diff::{diff, is_headline, show, Change, HEADLINE};

use clap::Args;
use clap::Subcommand;
use std::path::PathBuf;

/// `raypipe report`.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// What to do with reports.
    #[command(subcommand)]
    pub command: ReportCommand,
}

/// `raypipe report …`.
#[derive(Subcommand, Debug)]
pub enum ReportCommand {
    /// What changed between two reports: the configuration keys, then every number with
    /// its ratio, largest effect first.
    Diff(ReportDiffArgs),
}

/// `raypipe report diff`.
#[derive(Args, Debug)]
pub struct ReportDiffArgs {
    /// The first report (the baseline).
    pub a: PathBuf,
    /// The second report.
    pub b: PathBuf,
    /// Show only the N largest changes (default: all).
    #[arg(long, value_name = "N")]
    pub top: Option<usize>,
}

pub(crate) fn cmd_report(a: ReportArgs) -> Result<()> {
    match a.command {
        ReportCommand::Diff(d) => cmd_diff(d),
    }
}

fn read(path: &Path) -> Result<Value> {
    let text = crate::input::read_file::read_text(path, crate::input::read_file::TEXT_LIMIT)?;
    let v: Value = serde_json::from_str(&text).map_err(|e| anyhow!("{}: not a JSON report: {e}", path.display()))?;
    if !v.is_object() {
        return Err(anyhow!("{}: not a JSON report (not an object)", path.display()));
    }
    // A chip report names its schema; a diff of anything else (another tool's JSON, a
    // stream report) would list every key as changed and mean nothing.
    match v.get("schema").and_then(Value::as_str) {
        Some(raypipe_hw::observe::report::SCHEMA) => Ok(v),
        Some(other) => Err(anyhow!(
            "{}: a report of schema {other}; report diff reads {} (the chip's, from simulate --report)",
            path.display(),
            raypipe_hw::observe::report::SCHEMA
        )),
        None => Err(anyhow!(
            "{}: not a simulate report (no \"schema\": \"{}\")",
            path.display(),
            raypipe_hw::observe::report::SCHEMA
        )),
    }
}

fn cmd_diff(a: ReportDiffArgs) -> Result<()> {
    let d = diff(&read(&a.a)?, &read(&a.b)?);
    println!("A = {}\nB = {}", a.a.display(), a.b.display());
    if d.settings.is_empty() {
        println!("settings: the same");
    } else {
        println!("settings that differ ({}):", d.settings.len());
        let w = d.settings.iter().map(|s| s.0.len()).max().unwrap_or(0);
        for (path, x, y) in &d.settings {
            let (x, y) = (x.as_deref().unwrap_or("(absent)"), y.as_deref().unwrap_or("(absent)"));
            println!("  {path:<w$}  {x} -> {y}");
        }
    }
    for (side, name) in [(0, "A"), (1, "B")] {
        if !d.only[side].is_empty() {
            println!("only in {name}: {}", d.only[side].join(", "));
        }
    }
    println!(
        "numbers that differ: {} of {}, largest effect first (B/A: \"new\" where A is 0)",
        d.changes.len(),
        d.changes.len() + d.unchanged
    );
    let (mut head, rest): (Vec<&Change>, Vec<&Change>) = d.changes.iter().partition(|c| is_headline(&c.path));
    // The headline in its fixed order, not by effect.
    head.sort_by_key(|c| HEADLINE.iter().position(|h| *h == c.path));
    let limit = a.top.unwrap_or(usize::MAX);
    for (title, list) in [("headline", head), ("every other number", rest)] {
        if list.is_empty() {
            continue;
        }
        let shown = limit.min(list.len());
        let more = if shown < list.len() { format!(" (the first {shown} of {})", list.len()) } else { String::new() };
        println!("{title}{more}:");
        let w = list[..shown].iter().map(|c| c.path.len()).max().unwrap_or(0).max(4);
        println!("  {:<w$}  {:>14}  {:>14}  {:>9}", "path", "A", "B", "B/A");
        for c in &list[..shown] {
            let r = c.ratio();
            let ratio = if r.is_finite() { format!("{r:.3}") } else { "new".to_string() };
            println!("  {:<w$}  {:>14}  {:>14}  {:>9}", c.path, show(c.a), show(c.b), ratio);
        }
    }
    Ok(())
}
