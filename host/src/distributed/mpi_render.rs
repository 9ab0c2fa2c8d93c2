//! `raypipe render --mpi`: one frame (or a walkthrough) rendered across the ranks of an
//! MPI job. Every rank maps the scene image itself (replicated data, from shared
//! storage); rank 0 is the master, which hands out tiles from the [`TilePool`] — a few
//! to each worker at once so that a worker never waits for the network between tiles
//! (Wald & Slusallek 2001 §6.5) — gathers them into the frame and writes it; the other
//! ranks render the tiles they are given with all their threads. A tile's colours
//! depend on the tile alone, so the image is the single-process image, bit for bit.

use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;

use super::crew::{self, Crew};
use super::launcher_stop::{catch_sigterm, stopping};
use super::patient_receive::{receive_within, try_receive, POLL};
use super::protocol::{
    decode_assign, decode_tile, encode_ready, encode_tile, tile_header, Assign, TileHeader, TAG_ASSIGN, TAG_READY,
    TAG_STOP, TAG_TILE,
};
use super::tile_pool::{tile_grid, Handout, Rect, TilePool};
use crate::commands::render::{prepare, Prepared, RenderArgs};
use crate::render::{self, FrameJob, RayTotals};

/// Tiles a worker holds at once: one it renders, two queued behind it, so that the
/// next is there when one is done.
pub const IN_FLIGHT: usize = 3;

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
}

/// `raypipe render --mpi`.
pub fn cmd_render_mpi(a: &RenderArgs) -> Result<()> {
    let mut universe = mpi::initialize().ok_or_else(|| anyhow!("--mpi: MPI was already initialized"))?;
    let world = universe.world();
    let (rank, size) = (world.rank(), world.size());
    if rank != 0 {
        // Tiles go back by buffered sends: a worker copies a tile out and renders the
        // next at once, instead of waiting until the master takes it (large messages
        // wait for the receiver). At most IN_FLIGHT tiles are owed at any time.
        let tile = a.mpi.mpi_tile as usize;
        universe.set_buffer_size((IN_FLIGHT + 1) * (tile * tile * 12 + 1024));
    }
    if size < 2 {
        bail!("--mpi needs a master and at least one worker: run it as `mpirun -n 2 raypipe render … --mpi` or more");
    }
    // Every rank loads the scene; a worker that cannot tells the master, which says so
    // once for the whole job.
    let prepared = prepare(a).and_then(|p| {
        let cams = cameras(a, &p)?;
        Ok((p, cams))
    });
    // Every rank outlives the launcher's SIGTERM a little (see `launcher_stop`).
    catch_sigterm();
    if rank != 0 {
        let ready = prepared.as_ref().map(|_| crew::here()).map_err(|e| e.to_string());
        world.process_at_rank(0).send_with_tag(&encode_ready(&ready)[..], TAG_READY);
        if let Ok((p, cams)) = &prepared {
            if let Err(e) = worker(&world, p, cams, a) {
                // The master may wait on this rank: the job ends here, with one line.
                eprintln!("error: {e:#}");
                world.abort(1);
            }
        }
        return Ok(());
    }
    let (p, cams) = match prepared {
        Ok(x) => x,
        Err(e) => {
            stop_all(&world);
            return Err(e);
        }
    };
    let result = Crew::gather(&world, timeout_of(a)).and_then(|crew| master(&world, a, &p, &cams, &crew));
    if let Err(e) = &result {
        eprintln!("error: {e:#}");
        if stopping() {
            // The launcher is ending the job and kills every rank in a moment.
            std::process::exit(1);
        }
        // The workers may be blocked in a send; only an abort ends them for sure.
        world.abort(1);
    }
    stop_all(&world);
    result
}

/// The frames to render: the walk's cameras, or the one camera.
fn cameras(a: &RenderArgs, p: &Prepared) -> Result<Vec<CameraRecord>> {
    Ok(a.walk.cameras(&p.camera)?.unwrap_or_else(|| vec![p.camera]))
}

/// `--mpi-timeout`: how long a rank that owes a message may stay silent.
fn timeout_of(a: &RenderArgs) -> Duration {
    Duration::from_secs_f64(a.mpi.mpi_timeout.max(0.001))
}

fn stop_all(world: &SimpleCommunicator) {
    for r in 1..world.size() {
        world.process_at_rank(r).send_with_tag(&[0u8; 0][..], TAG_STOP);
    }
}

/// The master: every frame's tiles handed out, gathered and written.
fn master(world: &SimpleCommunicator, a: &RenderArgs, p: &Prepared, cams: &[CameraRecord], crew: &Crew) -> Result<()> {
    let workers = (world.size() - 1) as usize;
    let (w, h) = (cams[0].width, cams[0].height);
    let tiles = tile_grid(w, h, a.mpi.mpi_tile);
    let mut pool = TilePool::new(tiles.len(), workers);
    let timeout = timeout_of(a);
    let walk = cams.len() > 1;
    println!(
        "mpi      {}: master and {workers} worker{}, {} tiles of {} px, {IN_FLIGHT} in flight per worker",
        crew.identity(),
        if workers == 1 { "" } else { "s" },
        tiles.len(),
        a.mpi.mpi_tile,
    );
    if walk {
        println!("frame      seconds   frames/s  kept tiles  mpi share    MB sent  image");
    }
    let mut display = p.display;
    let mut times = Vec::new();
    let mut rows: Vec<(f64, f64)> = Vec::new();
    for (k, cam) in cams.iter().enumerate() {
        let start = Instant::now();
        let (radiance, rays, per_worker) = gather_frame(world, crew, &mut pool, &tiles, (k as u32, w), timeout)?;
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
        let mb = per_worker.iter().map(|s| s.bytes).sum::<u64>() as f64 / 1e6;
        rows.push((1.0 / secs, mb));
        if walk {
            println!(
                "{k:>5}  {secs:>10.4}  {:>9.2}  {kept:>10}  {:>8.1}%  {mb:>9.3}  {}",
                1.0 / secs,
                share * 100.0,
                path.display()
            );
        } else {
            println!(
                "rendered {} at {}x{} on {workers} worker{} -> {}",
                p.scene.name,
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
                println!(
                    "rank {:<3} {} tiles, busy {:.3} s, idle {:.3} s, {:.3} MB sent",
                    r + 1,
                    s.tiles,
                    s.busy,
                    (secs - s.busy).max(0.0),
                    s.bytes as f64 / 1e6
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
        let title = format!("{} on {workers} MPI workers: frames/s and MB sent", p.scene.name);
        let chart = crate::output::walk_chart::write_walk_chart(&a.output, &rows, &title, "MB sent")?;
        println!("chart    {}", chart.display());
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
    timeout: Duration,
) -> Result<(Vec<Vec3>, RayTotals, Vec<WorkerFrame>)> {
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
        let r = status.source_rank();
        let w = (r - 1) as usize;
        heard[w] = Instant::now();
        let h = tile_header(&bytes).map_err(|e| anyhow!("rank {r}: {e}"))?;
        let rect = *tiles
            .get(h.tile as usize)
            .ok_or_else(|| anyhow!("rank {r} sent tile {}, which does not exist", h.tile))?;
        let pixels = ((rect.2 - rect.0) * (rect.3 - rect.1)) as usize;
        let (h, colours) = decode_tile(&bytes, pixels).map_err(|e| anyhow!("rank {r}: {e}"))?;
        if h.frame != frame {
            bail!("rank {r} sent a tile of frame {}, not {frame}", h.frame);
        }
        render::place_tile(&mut radiance, width, rect, &colours);
        rays.add(&RayTotals { primary: h.primary, secondary: h.secondary });
        let s = &mut stats[w];
        s.tiles += 1;
        s.busy += h.seconds;
        s.bytes += bytes.len() as u64;
        if let Some(at) = given[w].iter().position(|&(t, _)| t == h.tile) {
            let (_, how) = given[w].swap_remove(at);
            s.kept += (how == Handout::Kept) as u32;
        }
        received += 1;
        send(w, pool, &mut given, &mut stats);
    }
    Ok((radiance, rays, stats))
}

/// What the master says when the launcher ends the job: which worker on its host died
/// holding which tile, or, if none did, what every worker held.
fn launcher_stopped(crew: &Crew, given: &[Vec<(u32, Handout)>], tiles: &[Rect]) -> String {
    let tile = |t: u32| {
        let (x0, y0, x1, y1) = tiles[t as usize];
        format!("tile {t} (pixels {x0}..{x1} x {y0}..{y1})")
    };
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

/// An error naming the first worker that owes tiles and has been silent past
/// `timeout`, and the oldest tile it owes.
fn check_silence(heard: &[Instant], given: &[Vec<(u32, Handout)>], tiles: &[Rect], timeout: Duration) -> Result<()> {
    for (w, owed) in given.iter().enumerate() {
        let Some(&(t, _)) = owed.first() else { continue };
        if heard[w].elapsed() > timeout {
            let (x0, y0, x1, y1) = tiles[t as usize];
            bail!(
                "rank {} sent nothing for {:.0} s while rendering tile {t} (pixels {x0}..{x1} x {y0}..{y1}): it died or hangs",
                w + 1,
                timeout.as_secs_f64()
            );
        }
    }
    Ok(())
}

/// A worker: tiles rendered as they are assigned, until the master says stop.
fn worker(world: &SimpleCommunicator, p: &Prepared, cams: &[CameraRecord], a: &RenderArgs) -> Result<()> {
    let (tile_size, timeout) = (a.mpi.mpi_tile, timeout_of(a));
    let view = p.scene.view()?;
    let master = world.process_at_rank(0);
    // The master's tiles, of the first frame's size, as it cuts them.
    let tiles = tile_grid(cams[0].width, cams[0].height, tile_size);
    let eyes = cams
        .iter()
        .map(|c| Ok(render::eye_rays(c, "camera")?.with_sampler(p.opts.sampler())))
        .collect::<Result<Vec<EyeRays>>>()?;
    // One frame's job at a time (the shadow caster's G-buffers are made once a frame).
    let mut job: Option<(u32, FrameJob)> = None;
    // One thread pool for the run: a pool per tile cost more than the tile.
    let pool = render::thread_pool(p.opts.threads)?;
    loop {
        if stopping() {
            // Alive a moment past the launcher's SIGTERM, so that the master can tell
            // this rank from the one that died; then gone, quietly.
            std::thread::sleep(Duration::from_millis(300));
            std::process::exit(143);
        }
        // An idle worker may wait on a live master for as long as the slowest tile
        // (bounded by the timeout) and the image's writing: it gives up after three.
        let Some((bytes, status)) = receive_within(&master, None, 3 * timeout)? else {
            bail!(
                "rank {}: the master sent nothing for {:.0} s: it died or hangs",
                world.rank(),
                3.0 * timeout.as_secs_f64()
            );
        };
        match status.tag() {
            TAG_STOP => return Ok(()),
            TAG_ASSIGN => {}
            other => bail!("rank {}: unexpected message tag {other}", world.rank()),
        }
        let a = decode_assign(&bytes)?;
        let k = a.frame as usize;
        let (Some(cam), Some(eye)) = (cams.get(k), eyes.get(k)) else { bail!("frame {k} does not exist") };
        if job.as_ref().is_none_or(|(f, _)| *f != a.frame) {
            job = Some((a.frame, FrameJob::new(&view, eye, Vec3::from(cam.background), &p.opts)));
        }
        let Some((_, frame)) = &job else { continue };
        let rect = *tiles.get(a.tile as usize).ok_or_else(|| anyhow!("tile {} does not exist", a.tile))?;
        let start = Instant::now();
        let (colours, rays) = pool.install(|| frame.rect(rect));
        let header = TileHeader {
            frame: a.frame,
            tile: a.tile,
            primary: rays.primary,
            secondary: rays.secondary,
            seconds: start.elapsed().as_secs_f64(),
        };
        master.buffered_send_with_tag(&encode_tile(&header, &colours)[..], TAG_TILE);
    }
}
