//! The `raypipe` command line: the parser (one options struct per subcommand, each defined
//! beside what it does in [`crate::commands`]), `main`, and the dispatch.

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

use crate::commands;

use crate::commands::animate::AnimateArgs;
use crate::commands::bench::BenchArgs;
use crate::commands::bench_updates::BenchUpdatesArgs;
use crate::commands::build::BuildArgs;
use crate::commands::cluster::ClusterArgs;
use crate::commands::fixed_point::FixedPointArgs;
use crate::commands::info::InfoArgs;
use crate::commands::museum_art::MuseumArtArgs;
use crate::commands::plot::PlotArgs;
use crate::commands::rays::RaysArgs;
use crate::commands::render::RenderArgs;
use crate::commands::report::ReportArgs;
use crate::commands::simulate::SimulateArgs;
use crate::commands::stats::StatsArgs;
use crate::commands::stream::StreamArgs;
use crate::commands::sweep::SweepArgs;
use crate::commands::trace::TraceArgs;

/// raypipe: a ray tracing engine whose no_std kernels drive both this host renderer and
/// a cycle-level hardware model.
#[derive(Parser, Debug)]
#[command(name = "raypipe", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    /// Print no warnings (errors still).
    #[arg(long, short, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Print every warning, not a one-line summary of a long list.
    #[arg(long, short, global = true)]
    pub verbose: bool,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Compile an OBJ scene (with its MTL) into a scene image.
    Build(BuildArgs),
    /// Render a scene to a PNG (the built-in Cornell box when no scene is given).
    Render(RenderArgs),
    /// Render an animated BART scene (AFF) frame by frame: per-frame update and render
    /// times, the frames as PNG (and a video with ffmpeg).
    Animate(AnimateArgs),
    /// Write BART's museum art with 4^LEVEL animated triangles (animartN.aff for the
    /// museum's larger variants, which the benchmark's files lack).
    MuseumArt(MuseumArtArgs),
    /// Time refit, linear-BVH and binned-SAH updates of an animation's frames (ms per
    /// million triangles), and dump its vertex buffers for Embree's harness.
    BenchUpdates(BenchUpdatesArgs),
    /// Print Purcell's scene statistics for a view: hits, nodes and triangles per ray.
    Stats(StatsArgs),
    /// Measure build time, image size and primary-ray throughput.
    Bench(BenchArgs),
    /// Trace a batch of rays from a NumPy .npy array and write the closest hits.
    Trace(TraceArgs),
    /// Write the primary rays of a view as a NumPy .npy array (N × 8 float32).
    Rays(RaysArgs),
    /// Run the cycle-level hardware model on a scene (the built-in Cornell box when none
    /// is given): image, summary and JSON report.
    Simulate(Box<SimulateArgs>),
    /// Compare the fixed-point datapath's hits with f32's (same triangle, distance between
    /// the hit points, nodes visited) on scenes, per format.
    FixedPoint(FixedPointArgs),
    /// Run Purcell's stream machine (a programmable GPU ray tracing in rendering passes,
    /// multipass or branching) on a scene: passes, instructions, memory words, texture
    /// cache, frame time; image, JSON report and charts.
    Stream(StreamArgs),
    /// Describe a scene: bounds, triangles, materials, lights, camera, structure and the
    /// image's sections.
    Info(InfoArgs),
    /// Run `simulate` over a grid of parameters (a TOML spec) on local cores, in shards
    /// for a cluster: one row per point (CSV and JSON lines), resumable; `sweep merge`
    /// joins shards.
    Sweep(SweepArgs),
    /// Predict a cluster from a distributed run's recording (`render --mpi --mpi-record`):
    /// frames per second, efficiency and network bytes for 1…64 workers of given speed,
    /// links and latency, with a model server for bricks.
    Cluster(ClusterArgs),
    /// Plot a sweep's rows as SVG or PNG: a metric against a parameter (one line per value
    /// of --series), a heatmap over two parameters (--value), or stacked bars (--stack).
    Plot(PlotArgs),
    /// Work with JSON reports: `report diff A.json B.json` says what changed.
    Report(ReportArgs),
}

/// Parses the process arguments, runs, and turns any error into one line on stderr.
pub fn main() -> ExitCode {
    // Output piped into `head` and closed early ends the process quietly, as for any
    // Unix tool, instead of a panic in `println!`.
    #[cfg(unix)]
    // SAFETY: restoring the default action of SIGPIPE, before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Every command's kernels may take their AVX forms from here on (core cannot ask the
    // operating system; the batch and render entry points also report it, for library
    // callers).
    crate::platform::isa::report_cpu();
    let cli = match <Cli as clap::Parser>::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    use crate::output::warnings::{set_verbosity, Verbosity};
    set_verbosity(match (cli.quiet, cli.verbose) {
        (true, _) => Verbosity::Quiet,
        (_, true) => Verbosity::Verbose,
        _ => Verbosity::Normal,
    });
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if !crate::distributed::is_secondary_rank() {
                let msg = format!("{e:#}").replace('\n', " ");
                eprintln!("error: {msg}");
            }
            ExitCode::FAILURE
        }
    }
}

/// A command line clap refused: help and version as clap prints them, anything else as
/// one line on stderr (clap's own runs over three or four, with a usage block), with
/// the values an option takes when it names them. Exit code 2, as clap's.
fn usage_error(e: clap::Error) -> ExitCode {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit();
    }
    if crate::distributed::is_secondary_rank() {
        return ExitCode::from(2);
    }
    let text = e.render().to_string();
    let first = text.lines().next().unwrap_or("error: bad command line").trim_end();
    let mut line = first.to_string();
    if let Some(ContextValue::Strings(values)) = e.get(ContextKind::ValidValue) {
        line.push_str(&format!(" (possible values: {})", values.join(", ")));
    }
    if let Some(ContextValue::String(tip)) = e.get(ContextKind::SuggestedArg) {
        line.push_str(&format!(" (did you mean '{tip}'?)"));
    }
    eprintln!("{line}");
    ExitCode::from(2)
}

/// Runs a parsed command.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Build(a) => commands::build::cmd_build(a),
        Command::Render(a) => commands::render::cmd_render(a),
        Command::Animate(a) => commands::animate::cmd_animate(a),
        Command::MuseumArt(a) => commands::museum_art::cmd_museum_art(a),
        Command::BenchUpdates(a) => commands::bench_updates::cmd_bench_updates(a),
        Command::Stats(a) => commands::stats::cmd_stats(a),
        Command::Bench(a) => commands::bench::cmd_bench(a),
        Command::Trace(a) => commands::trace::cmd_trace(a),
        Command::Rays(a) => commands::rays::cmd_rays(a),
        Command::Simulate(a) => commands::simulate::cmd_simulate(*a),
        Command::FixedPoint(a) => commands::fixed_point::cmd_fixed_point(a),
        Command::Stream(a) => commands::stream::cmd_stream(a),
        Command::Info(a) => commands::info::cmd_info(a),
        Command::Sweep(a) => commands::sweep::cmd_sweep(a),
        Command::Plot(a) => commands::plot::cmd_plot(a),
        Command::Cluster(a) => commands::cluster::cmd_cluster(a),
        Command::Report(a) => commands::report::cmd_report(a),
    }
}
