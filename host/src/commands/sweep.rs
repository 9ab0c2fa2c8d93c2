//! `raypipe sweep`: `simulate` over a design space, points in parallel on local cores,
//! one row per point; resumable (finished points are read back from the output and not
//! run again) and shardable (`--shard i/n`); `raypipe sweep merge` joins shards into the
//! files one run would have written.

use std::collections::HashSet;
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;

use anyhow::{anyhow, bail, Result};
use rayon::prelude::*;

use crate::study::sweep::{Point, Spec};
use crate::study::sweep_journal::Journal;
use crate::study::sweep_table::{self, Row};
use crate::{hw::chip, output, output::progress};

use super::simulate::{run_simulation, SceneCache};

use clap::Args;
use clap::Subcommand;
use std::path::PathBuf;

/// `raypipe sweep`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    /// Join shards' outputs.
    #[command(subcommand)]
    pub merge: Option<SweepCommand>,
    /// The spec: [fixed] parameters, a [grid] of lists (their cartesian product) and
    /// [[points]] (each crossed with the grid); keys are simulate flags or --set keys.
    #[arg(required = true, value_name = "SPEC.toml")]
    pub spec: Option<PathBuf>,
    /// Output prefix: PREFIX.jsonl and PREFIX.csv. Points already in PREFIX.jsonl are
    /// not run again (resume).
    #[arg(short, long, value_name = "PREFIX", default_value = "sweep")]
    pub output: PathBuf,
    /// Run only shard I of N (points whose number is I modulo N, I from 0): one task of a
    /// Slurm job array or of GNU parallel.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::study::sweep::Shard>,
    /// Points run at once (default: all cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Also write each point's full report, DIR/point-<index>.json (the stand-alone
    /// `simulate --report` file).
    #[arg(long, value_name = "DIR")]
    pub reports: Option<PathBuf>,
    /// Run every point again, ignoring rows already in PREFIX.jsonl.
    #[arg(long)]
    pub restart: bool,
    /// Spread the points over the ranks of an MPI job (`mpirun -n N raypipe sweep SPEC
    /// --mpi`): rank 0 hands them out and writes the rows, the same rows as one process
    /// writes. Needs a raypipe built with the `mpi` feature.
    #[arg(long)]
    pub mpi: bool,
}

/// Runs the points of a sweep, handing each finished row to `record` as it finishes;
/// returns the rows.
pub(crate) type RunPoints<'a> =
    dyn FnMut(&Spec, &[&Point], &(dyn Fn(&Row) -> Result<()> + Sync)) -> Result<Vec<Row>> + 'a;

/// `raypipe sweep merge`.
#[derive(Subcommand, Debug)]
pub enum SweepCommand {
    /// Join the JSON-lines outputs of shards into the files one run would have written.
    Merge(SweepMergeArgs),
}

/// `raypipe sweep merge`.
#[derive(Args, Debug)]
pub struct SweepMergeArgs {
    /// The shards' .jsonl files.
    #[arg(required = true, value_name = "SHARD.jsonl")]
    pub inputs: Vec<PathBuf>,
    /// Output prefix: PREFIX.jsonl and PREFIX.csv.
    #[arg(short, long, value_name = "PREFIX", default_value = "sweep")]
    pub output: PathBuf,
}

pub(crate) fn cmd_sweep(a: SweepArgs) -> Result<()> {
    if let Some(SweepCommand::Merge(m)) = a.merge {
        return merge(m);
    }
    if a.mpi {
        return crate::distributed::cmd_sweep_mpi(&a);
    }
    sweep_with(&a, &mut |spec, todo, record| local_points(&a, spec, todo, record))
}

/// A sweep: its points checked, the journal opened, the points still to run run by
/// `run`, and the rows written.
pub(crate) fn sweep_with(a: &SweepArgs, run: &mut RunPoints<'_>) -> Result<()> {
    let Some(spec_path) = a.spec.as_deref() else { bail!("sweep: a spec file is needed") };
    if a.jobs == Some(0) {
        bail!("--jobs must be at least 1");
    }
    let spec = Spec::load(spec_path)?;
    let points = spec.shard(a.shard);
    // Every point's configuration and files are checked before any point runs.
    for p in &points {
        let args = p.simulate_args(&spec.dir)?;
        chip::load_config(args.preset.as_deref(), args.config.as_deref(), &args.set)
            .map_err(|e| anyhow!("sweep point {} ({}): {e:#}", p.index, p.id()))?;
        for path in [&args.scene, &args.camera.camera].into_iter().flatten() {
            if !path.exists() {
                bail!("sweep point {} ({}): {}: no such file", p.index, p.id(), path.display());
            }
        }
    }
    let (jsonl, _) = sweep_table::outputs(&a.output);
    output::check_writable(&jsonl)?;
    if let Some(dir) = &a.reports {
        // Made as `mkdir -p` would, so a fresh sweep needs no preparation.
        if !dir.is_dir() {
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("--reports {}: cannot create: {e}", dir.display()))?;
        }
    }
    // Resume: rows already written for this run's points are kept, not run again; rows
    // of other shards are kept as they are.
    let journal = Journal::open(&jsonl, &spec.points, &points, a.restart)?;
    let finished: HashSet<usize> = journal.done.iter().map(|r| r.index).collect();
    let todo: Vec<&Point> = points.iter().copied().filter(|p| !finished.contains(&p.index)).collect();
    println!(
        "sweep {}: {} points{}, {} already done, {} to run{}",
        spec_path.display(),
        points.len(),
        a.shard.map_or(String::new(), |s| format!(" (shard {}/{} of {})", s.index, s.count, spec.points.len())),
        journal.done.len(),
        todo.len(),
        match journal.others.len() {
            0 => String::new(),
            n => format!(" ({n} rows of other shards kept)"),
        }
    );
    // The journal: the rows written so far, one line appended as each point finishes,
    // so a stopped sweep resumes where it was.
    let appender = Mutex::new(journal.start()?);
    let bar = progress::bar(todo.len() as u64, "sweep", true);
    let record = |row: &Row| -> Result<()> {
        let mut f = appender.lock().map_err(|_| anyhow!("sweep journal poisoned"))?;
        f.write_all(format!("{}\n", row.to_line()).as_bytes()).map_err(|e| anyhow!("{}: {e}", jsonl.display()))?;
        bar.inc(1);
        Ok(())
    };
    let new_rows = run(&spec, &todo, &record)?;
    bar.finish_and_clear();
    let mut failed = 0;
    for r in new_rows.iter().filter(|r| r.error.is_some()) {
        crate::output::warnings::warning(&format!(
            "sweep point {} ({}): {}",
            r.index,
            r.point,
            r.error.as_deref().unwrap_or("")
        ));
        failed += 1;
    }
    let rows = journal.finish(&a.output, new_rows)?;
    let (jsonl, csv) = sweep_table::outputs(&a.output);
    println!("{} rows ({} failed) -> {} and {}", rows.len(), failed, jsonl.display(), csv.display());
    Ok(())
}

/// The points run on this machine's cores, `--jobs` at once.
fn local_points(
    a: &SweepArgs,
    spec: &Spec,
    todo: &[&Point],
    record: &(dyn Fn(&Row) -> Result<()> + Sync),
) -> Result<Vec<Row>> {
    let cache = SceneCache::default();
    let jobs = a.jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build().map_err(|e| anyhow!("sweep: {e}"))?;
    pool.install(|| {
        todo.par_iter()
            .map(|p| -> Result<Row> {
                let row = run_point(p, &spec.dir, &cache, a.reports.as_deref())?;
                record(&row)?;
                Ok(row)
            })
            .collect::<Result<Vec<Row>>>()
    })
}

/// Runs one point as `raypipe simulate` would; a point that fails becomes a row with
/// its error (a deadlocked corner of the space must not stop the others).
pub(crate) fn run_point(p: &Point, dir: &Path, cache: &SceneCache, reports: Option<&Path>) -> Result<Row> {
    let args = p.simulate_args(dir)?;
    match run_simulation(&args, Some(cache), false) {
        Ok(run) => {
            if let Some(d) = reports {
                output::write_bytes(&d.join(format!("point-{}.json", p.index)), run.report.to_json().as_bytes())?;
            }
            Ok(Row::of(p, &run.report))
        }
        Err(e) => Ok(Row::failed(p, format!("{e:#}").replace('\n', " "))),
    }
}

fn merge(m: SweepMergeArgs) -> Result<()> {
    let mut rows = Vec::new();
    for path in &m.inputs {
        rows.extend(sweep_table::read_rows(path)?);
    }
    let n = rows.len();
    let rows = sweep_table::normalize(rows);
    for w in rows.windows(2) {
        if w[0].index + 1 != w[1].index {
            crate::output::warnings::warning(&format!(
                "sweep merge: points {} to {} are missing",
                w[0].index + 1,
                w[1].index - 1
            ));
        }
    }
    sweep_table::write(&m.output, &rows)?;
    let (jsonl, csv) = sweep_table::outputs(&m.output);
    println!(
        "merged {} rows from {} files ({} duplicates dropped) -> {} and {}",
        rows.len(),
        m.inputs.len(),
        n - rows.len(),
        jsonl.display(),
        csv.display()
    );
    Ok(())
}
