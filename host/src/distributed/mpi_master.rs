//! The master of `raypipe render --mpi` (Wald & Slusallek 2001 §6.5): for each frame
//! it hands out tiles from the [`TilePool`] — a few to each worker at once, so that a
//! worker never waits for the network between tiles — gathers them into the frame,
//! writes it and reports what every worker did; when the data are served it is the
//! model server too, answering brick requests between tiles. A worker that goes silent
//! while it owes tiles, or dies, ends the run with one line naming it and its tile.

use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use raypipe_core::image::CameraRecord;

use super::brick_service::serve_waiting;
use super::crew::Crew;
use super::launcher_stop::stopping;
use super::patient_receive::{try_receive, POLL};
use super::protocol::{decode_tile, tile_header, Assign, TAG_ASSIGN, TAG_TILE};
use super::tile_pool::{tile_grid, Handout, Rect, TilePool};
use crate::commands::render::RenderArgs;
use crate::input::bricked::BrickedScene;
use crate::output::tone_map::DisplayChoice;
use crate::render::{self, RayTotals};
use crate::study::cluster::recording::{Recording, RunRecord, TileRecord};

/// Tiles a worker holds at once: a batch it renders side by side
/// ([`super::mpi_worker::BATCH`]) and as many queued behind it, so that the next batch
/// is there when one is done.
pub const IN_FLIGHT: usize = 2 * super::mpi_worker::BATCH;

/// What the master renders.
pub struct Job<'s> {
    /// The scene's name, for the report.
    pub name: String,
    /// The frames' cameras (one, or a walk's).
    pub cams: Vec<CameraRecord>,
    /// How frames are displayed.
    pub display: DisplayChoice,
    /// A bricked scene: the report gives the workers' caches.
    pub bricked: bool,
    /// The scene the master serves bricks of, when the data are served.
    pub server: Option<&'s BrickedScene>,
    /// A bricked scene's bricks: stored and decompressed bytes, for the recording.
    pub bricks: Vec<(u64, u64)>,
    /// How long a worker that owes tiles may stay silent (`--mpi-timeout`).
    pub timeout: Duration,
}

/// What the run did, tile by tile, for `--mpi-record`.
#[derive(Default)]
pub struct RunLog {
    /// Every tile received.
    pub tiles: Vec<TileRecord>,
    /// Seconds the master spent on them (decoding, placing, answering).
    pub master_seconds: f64,
}

/// What one worker did in one frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct WorkerFrame {
    /// Tiles rendered.
    pub tiles: u32,
    /// Of them, tiles it had rendered in the frame before.
    pub kept: u32,
    /// Seconds spent rendering.
    pub busy: f64,
    /// Bytes sent between it and the master (assignments and tiles).
    pub bytes: u64,
    /// Brick visits its cache served.
    pub hits: u64,
    /// Bricks it loaded.
    pub misses: u64,
    /// Stored bytes of the bricks it loaded.
    pub loaded: u64,
    /// Bytes of bricks the model server sent it.
    pub served: u64,
}

impl WorkerFrame {
    /// Brick visits its cache served, over all.
    pub fn hit_rate(&self) -> f64 {
        self.hits as f64 / (self.hits + self.misses).max(1) as f64
    }
}

/// The walk table's brick columns: MB of bricks loaded, and each worker's hit rate.
fn brick_columns(per_worker: &[WorkerFrame]) -> String {
    let mb = per_worker.iter().map(|s| s.loaded).sum::<u64>() as f64 / 1e6;
    let rates: Vec<String> = per_worker.iter().map(|s| format!("{:.0}", s.hit_rate() * 100.0)).collect();
    format!("  {mb:>9.3}  {}%", rates.join("/"))
}

/// The master: every frame's tiles handed out, gathered and written.
pub fn master(world: &SimpleCommunicator, a: &RenderArgs, job: &Job<'_>, crew: &Crew) -> Result<()> {
    let cams = &job.cams[..];
    let workers = (world.size() - 1) as usize;
    let (w, h) = (cams[0].width, cams[0].height);
    let tiles = tile_grid(w, h, a.mpi.mpi_tile);
    let mut pool = TilePool::new(tiles.len(), workers);
    let walk = cams.len() > 1;
    println!(
        "mpi      {}: master and {workers} worker{}, {} tiles of {} px, {IN_FLIGHT} in flight per worker",
        crew.identity(),
        if workers == 1 { "" } else { "s" },
        tiles.len(),
        a.mpi.mpi_tile,
    );
    if walk {
        let bricks = if job.bricked { "  MB bricks  hit rate per worker" } else { "" };
        println!("frame      seconds   frames/s  kept tiles  mpi share    MB sent{bricks}  image");
    }
    let mut display = job.display;
    let mut log = RunLog::default();
    let mut times = Vec::new();
    let mut rows: Vec<(f64, f64)> = Vec::new();
    for (k, cam) in cams.iter().enumerate() {
        let start = Instant::now();
        let (radiance, rays, per_worker) = gather_frame(world, crew, &mut pool, &tiles, (k as u32, w), job, &mut log)?;
        let secs = start.elapsed().as_secs_f64().max(1e-9);
        let frame = render::Frame::from_radiance(cam.width, cam.height, radiance);
        let path = if walk { crate::output::frame_path(&a.output, k) } else { a.output.clone() };
        if k == 0 {
            (display, _) = display.fixed_by(&frame.radiance);
        }
        crate::output::write_frame(&path, &frame, &display)?;
        let busy: f64 = per_worker.iter().map(|s| s.busy).sum();
        // The share of the workers' frame time not spent rendering: messages, waiting
        // for the master, and the master's own work.
        let share = 1.0 - busy / (secs * workers as f64);
        let kept: u32 = per_worker.iter().map(|s| s.kept).sum();
        let mb = per_worker.iter().map(|s| s.bytes + s.served).sum::<u64>() as f64 / 1e6;
        rows.push((1.0 / secs, mb));
        if walk {
            let bricks = if job.bricked { brick_columns(&per_worker) } else { String::new() };
            println!(
                "{k:>5}  {secs:>10.4}  {:>9.2}  {kept:>10}  {:>8.1}%  {mb:>9.3}{bricks}  {}",
                1.0 / secs,
                share * 100.0,
                path.display()
            );
        } else {
            println!(
                "rendered {} at {}x{} on {workers} worker{} -> {}",
                job.name,
                w,
                h,
                if workers == 1 { "" } else { "s" },
                path.display()
            );
            println!(
                "time     render {secs:.3} s ({:.2} Mrays/s); workers busy {:.1}%, mpi share {:.1}%",
                rays.total() as f64 / secs / 1e6,
                busy / (secs * workers as f64) * 100.0,
                share * 100.0
            );
            for (r, s) in per_worker.iter().enumerate() {
                let bricks = if job.bricked {
                    format!(
                        "; bricks: hit rate {:.1}%, {} loaded, {:.3} MB{}",
                        s.hit_rate() * 100.0,
                        s.misses,
                        s.loaded as f64 / 1e6,
                        if job.server.is_some() { " served" } else { " read" }
                    )
                } else {
                    String::new()
                };
                println!(
                    "rank {:<3} {} tiles, busy {:.3} s, idle {:.3} s, {:.3} MB sent{bricks}",
                    r + 1,
                    s.tiles,
                    s.busy,
                    (secs - s.busy).max(0.0),
                    (s.bytes + s.served) as f64 / 1e6
                );
            }
        }
        times.push(secs);
    }
    if walk {
        let total: f64 = times.iter().sum();
        println!(
            "path     {} frames in {total:.3} s: {:.2} frames/s on average",
            cams.len(),
            cams.len() as f64 / total
        );
        let title = format!("{} on {workers} MPI workers: frames/s and MB sent", job.name);
        let chart = crate::output::walk_chart::write_walk_chart(&a.output, &rows, &title, "MB sent")?;
        println!("chart    {}", chart.display());
    }
    if let Some(path) = &a.mpi.mpi_record {
        let run = RunRecord {
            identity: crew.identity(),
            workers: workers as u32,
            host_threads: std::thread::available_parallelism().map_or(1, |n| n.get() as u32),
            hosts: crew.hosts() as u32,
            width: w,
            height: h,
            tile: a.mpi.mpi_tile,
            in_flight: IN_FLIGHT as u32,
            batch: super::mpi_worker::BATCH as u32,
            frame_seconds: times,
            master_seconds_per_tile: log.master_seconds / log.tiles.len().max(1) as f64,
            bricks: job.bricks.clone(),
        };
        Recording { run, tiles: log.tiles }.write(path)?;
        println!("record   {}", path.display());
    }
    Ok(())
}

/// One frame: tiles handed out `IN_FLIGHT` at a time and gathered into its radiance.
fn gather_frame(
    world: &SimpleCommunicator,
    crew: &Crew,
    pool: &mut TilePool,
    tiles: &[Rect],
    (frame, width): (u32, u32),
    job: &Job<'_>,
    log: &mut RunLog,
) -> Result<(Vec<Vec3>, RayTotals, Vec<WorkerFrame>)> {
    let timeout = job.timeout;
    let workers = (world.size() - 1) as usize;
    let height = tiles.iter().map(|t| t.3).max().unwrap_or(0);
    let mut radiance = vec![Vec3::ZERO; (width * height) as usize];
    let mut rays = RayTotals::default();
    let mut stats = vec![WorkerFrame::default(); workers];
    let mut given: Vec<Vec<(u32, Handout)>> = vec![Vec::new(); workers];
    pool.start_frame();
    let send = |w: usize, pool: &mut TilePool, given: &mut Vec<Vec<(u32, Handout)>>, stats: &mut [WorkerFrame]| {
        if let Some((t, how)) = pool.next_for(w) {
            let msg = Assign { frame, tile: t as u32 };
            world.process_at_rank(w as i32 + 1).send_with_tag(bytemuck::bytes_of(&msg), TAG_ASSIGN);
            given[w].push((t as u32, how));
            stats[w].bytes += std::mem::size_of::<Assign>() as u64;
        }
    };
    for _ in 0..IN_FLIGHT {
        for w in 0..workers {
            send(w, pool, &mut given, &mut stats);
        }
    }
    // When each worker was last heard from (or last given work when idle).
    let mut heard = vec![Instant::now(); workers];
    let mut received = 0;
    while received < tiles.len() {
        if let Some(scene) = job.server {
            serve_waiting(world, scene, &mut |w, bytes| {
                if let Some(s) = stats.get_mut(w) {
                    s.served += bytes;
                }
            })?;
        }
        let received_tile = try_receive(&world.any_process(), Some(TAG_TILE), timeout);
        if stopping() {
            bail!("{}", launcher_stopped(crew, &given, tiles));
        }
        let received_tile = received_tile.map_err(|e| {
            let owed = usize::try_from(e.rank - 1).ok().and_then(|w| given.get(w)?.first());
            let owed = owed.map_or(String::new(), |&(t, _)| format!(" tile {t}:"));
            anyhow!("rank {} stopped in the middle of sending{owed} it died or hangs", e.rank)
        });
        let Some((bytes, status)) = received_tile? else {
            check_silence(&heard, &given, tiles, timeout)?;
            std::thread::sleep(POLL);
            continue;
        };
        let took = Instant::now();
        let r = status.source_rank();
        let w = (r - 1) as usize;
        heard[w] = took;
        let h = tile_header(&bytes).map_err(|e| anyhow!("rank {r}: {e}"))?;
        let rect = *tiles
            .get(h.tile as usize)
            .ok_or_else(|| anyhow!("rank {r} sent tile {}, which does not exist", h.tile))?;
        let pixels = ((rect.2 - rect.0) * (rect.3 - rect.1)) as usize;
        let (h, colours, touched) = decode_tile(&bytes, pixels).map_err(|e| anyhow!("rank {r}: {e}"))?;
        if h.frame != frame {
            bail!("rank {r} sent a tile of frame {}, not {frame}", h.frame);
        }
        render::place_tile(&mut radiance, width, rect, &colours);
        rays.add(&RayTotals { primary: h.primary, secondary: h.secondary });
        let s = &mut stats[w];
        s.tiles += 1;
        s.busy += h.seconds;
        s.bytes += bytes.len() as u64;
        (s.hits, s.misses, s.loaded) = (s.hits + h.hits, s.misses + h.misses, s.loaded + h.loaded);
        if let Some(at) = given[w].iter().position(|&(t, _)| t == h.tile) {
            let (_, how) = given[w].swap_remove(at);
            s.kept += (how == Handout::Kept) as u32;
        }
        received += 1;
        send(w, pool, &mut given, &mut stats);
        log.master_seconds += took.elapsed().as_secs_f64();
        let (seconds, waited) = (h.seconds, h.waited.min(h.seconds));
        let bytes = bytes.len() as u64;
        log.tiles.push(TileRecord { frame, tile: h.tile, rank: r as u32, seconds, waited, bytes, bricks: touched });
    }
    Ok((radiance, rays, stats))
}

/// What the master says when the launcher ends the job: which worker on its host died
/// holding which tile, or, if none did, what every worker held.
fn launcher_stopped(crew: &Crew, given: &[Vec<(u32, Handout)>], tiles: &[Rect]) -> String {
    let tile = |t: u32| describe_tile(tiles, t);
    let ended = crew.ended_here();
    if let Some(&w) = ended.first() {
        let held = given[w].first().map_or("no tile".to_string(), |&(t, _)| tile(t));
        let who = &crew.workers[w];
        return format!(
            "rank {} (pid {} on {}) died while rendering {held}; mpirun is ending the job",
            w + 1,
            who.pid,
            who.host
        );
    }
    let held: Vec<String> = given
        .iter()
        .enumerate()
        .filter_map(|(w, g)| g.first().map(|&(t, _)| format!("rank {} {}", w + 1, tile(t))))
        .collect();
    format!(
        "mpirun is ending the job (a rank on another host died, or it was interrupted); tiles out: {}",
        held.join(", ")
    )
}

/// A tile as the master's errors name it: its number and pixels.
fn describe_tile(tiles: &[Rect], t: u32) -> String {
    let (x0, y0, x1, y1) = tiles[t as usize];
    format!("tile {t} (pixels {x0}..{x1} x {y0}..{y1})")
}

/// An error naming the first worker that owes tiles and has been silent past
/// `timeout`, and the oldest tile it owes.
fn check_silence(heard: &[Instant], given: &[Vec<(u32, Handout)>], tiles: &[Rect], timeout: Duration) -> Result<()> {
    for (w, owed) in given.iter().enumerate() {
        let Some(&(t, _)) = owed.first() else { continue };
        if heard[w].elapsed() > timeout {
            bail!(
                "rank {} sent nothing for {:.0} s while rendering {}: it died or hangs",
                w + 1,
                timeout.as_secs_f64(),
                describe_tile(tiles, t)
            );
        }
    }
    Ok(())
}
