//! A worker of `raypipe render --mpi`: it renders the tiles the master assigns, with all
//! its threads, and sends each back as soon as it is done. What renders a tile is the
//! single-process renderer — a frame's [`FrameJob`] for a flat image, the brick cache and
//! parked rays of `render::bricked` for a bricked scene — so a tile's colours are the
//! single-process image's.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use mpi::point_to_point::Status;
use mpi::topology::{Process, SimpleCommunicator};
use mpi::traits::*;
use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::SceneView;

use super::launcher_stop::stopping;
use super::patient_receive::{serialized, try_receive, POLL};
use super::protocol::{decode_assign, encode_tile, Assign, TileHeader, TAG_ASSIGN, TAG_STOP, TAG_TILE};
use super::tile_pool::{tile_grid, Rect};
use crate::commands::render::{Prepared, RenderArgs};
use crate::input::bricked::BrickedScene;
use crate::render::bricked::brick_cache::BrickCache;
use crate::render::bricked::frame::{render_bricked_rect, BrickedFrame};
use crate::render::{self, FrameJob, RayTotals, RenderOptions};

/// A rendered tile and what rendering it did.
pub struct Rendered {
    /// Its pixels' colours, row by row.
    pub colours: Vec<Vec3>,
    /// Rays traced.
    pub rays: RayTotals,
    /// Brick visits served by the cache, bricks loaded, stored bytes loaded.
    pub bricks: (u64, u64, u64),
    /// Seconds its tracer waited with every ray parked on a brick.
    pub waited: f64,
    /// The bricks its rays needed.
    pub touched: Vec<u32>,
}

/// Renders the tiles `rects` of frame `k`, side by side.
type RenderTiles<'r> = dyn FnMut(u32, &[Rect]) -> Result<Vec<Rendered>> + 'r;

/// Tiles a worker renders side by side: more tiles than threads keep every thread busy
/// to the end of a batch (one 32-pixel tile is four of the renderer's tiles).
pub const BATCH: usize = 2;

/// The worker's loop: the tiles assigned rendered a batch at a time, each sent back as
/// soon as its batch is done, until the master says stop.
pub fn worker(
    world: &SimpleCommunicator,
    cams: &[CameraRecord],
    a: &RenderArgs,
    render: &mut RenderTiles,
) -> Result<()> {
    let timeout = Duration::from_secs_f64(a.mpi.mpi_timeout.max(0.001));
    let master = world.process_at_rank(0);
    // The master's tiles, of the first frame's size, as it cuts them.
    let tiles = tile_grid(cams[0].width, cams[0].height, a.mpi.mpi_tile);
    let mut queue: VecDeque<Assign> = VecDeque::new();
    let budget = super::mpi_render::tile_budget(a);
    loop {
        if stopping() {
            // Alive a moment past the launcher's SIGTERM, so that the master can tell
            // this rank from the one that died; then gone, quietly.
            std::thread::sleep(Duration::from_millis(300));
            std::process::exit(143);
        }
        // Every assignment already here is taken; the worker waits only with none.
        if queue.is_empty() {
            // An idle worker may wait on a live master for as long as the slowest
            // tile (bounded by the timeout) and the image's writing: it gives up after
            // three.
            let Some(msg) = wait_for_order(&master, timeout, 3 * timeout)? else {
                if stopping() {
                    continue;
                }
                bail!(
                    "rank {}: the master sent nothing for {:.0} s: it died or hangs",
                    world.rank(),
                    3.0 * timeout.as_secs_f64()
                );
            };
            if !take(world, msg, &mut queue)? {
                return Ok(());
            }
        }
        // Only the master's assignments and stop: replies to the loaders' brick
        // requests come on tags of their own and are theirs to take.
        while let Some(msg) = next_order(&master, timeout)? {
            if !take(world, msg, &mut queue)? {
                return Ok(());
            }
        }
        let frame = queue[0].frame;
        let mut batch = Vec::with_capacity(BATCH);
        while batch.len() < BATCH && queue.front().is_some_and(|j| j.frame == frame) {
            batch.extend(queue.pop_front());
        }
        if frame as usize >= cams.len() {
            bail!("frame {frame} does not exist");
        }
        let rects = batch
            .iter()
            .map(|j| tiles.get(j.tile as usize).copied().ok_or_else(|| anyhow!("tile {} does not exist", j.tile)))
            .collect::<Result<Vec<Rect>>>()?;
        let start = Instant::now();
        let done = render(frame, &rects)?;
        // The batch's time, shared by its tiles.
        let seconds = start.elapsed().as_secs_f64() / batch.len() as f64;
        for (job, tile) in batch.iter().zip(done) {
            let header = TileHeader {
                frame,
                tile: job.tile,
                primary: tile.rays.primary,
                secondary: tile.rays.secondary,
                seconds,
                hits: tile.bricks.0,
                misses: tile.bricks.1,
                loaded: tile.bricks.2,
                // Tiles of a batch run side by side: a thread's wait costs the worker
                // its share of the batch, as `seconds` is.
                waited: tile.waited / batch.len() as f64,
                touched: 0,
            };
            let msg = encode_tile(&header, &tile.colours, &tile.touched);
            if msg.len() <= budget {
                serialized(|| master.buffered_send_with_tag(&msg[..], TAG_TILE));
            } else {
                serialized(|| master.send_with_tag(&msg[..], TAG_TILE));
            }
        }
    }
}

/// The master's next assignment, or its stop, if one has begun to arrive.
fn next_order(master: &Process<'_>, timeout: Duration) -> Result<Option<(Vec<u8>, Status)>> {
    for tag in [TAG_ASSIGN, TAG_STOP] {
        if let Some(m) = try_receive(master, Some(tag), timeout)? {
            return Ok(Some(m));
        }
    }
    Ok(None)
}

/// The master's next assignment or stop, waiting at most `within` for it to begin.
fn wait_for_order(master: &Process<'_>, timeout: Duration, within: Duration) -> Result<Option<(Vec<u8>, Status)>> {
    let start = Instant::now();
    loop {
        if let Some(m) = next_order(master, timeout)? {
            return Ok(Some(m));
        }
        if start.elapsed() > within || stopping() {
            return Ok(None);
        }
        std::thread::sleep(POLL);
    }
}

/// Queues an assignment; false for the master's stop.
fn take(world: &SimpleCommunicator, (bytes, status): (Vec<u8>, Status), queue: &mut VecDeque<Assign>) -> Result<bool> {
    match status.tag() {
        TAG_STOP => Ok(false),
        TAG_ASSIGN => {
            queue.push_back(decode_assign(&bytes)?);
            Ok(true)
        }
        other => bail!("rank {}: unexpected message tag {other}", world.rank()),
    }
}

/// A worker over a flat scene image, mapped by every rank.
pub(crate) fn flat_worker(
    world: &SimpleCommunicator,
    a: &RenderArgs,
    p: &Prepared,
    view: &SceneView<'_>,
    cams: &[CameraRecord],
) -> Result<()> {
    let eyes = cams
        .iter()
        .map(|c| Ok(render::eye_rays(c, "camera")?.with_sampler(p.opts.sampler())))
        .collect::<Result<Vec<EyeRays>>>()?;
    // One frame's job at a time (the shadow caster's G-buffers are made once a frame).
    let mut job: Option<(u32, FrameJob)> = None;
    // One thread pool for the run: a pool per tile cost more than the tile.
    let pool = render::thread_pool(p.opts.threads)?;
    worker(world, cams, a, &mut |k, rects| {
        if job.as_ref().is_none_or(|(f, _)| *f != k) {
            let (cam, eye) = (&cams[k as usize], &eyes[k as usize]);
            job = Some((k, FrameJob::new(view, eye, Vec3::from(cam.background), &p.opts)));
        }
        let Some((_, frame)) = &job else { bail!("no frame job") };
        let done = pool.install(|| frame.rects(rects));
        let rendered =
            |(colours, rays)| Rendered { colours, rays, bricks: (0, 0, 0), waited: 0.0, touched: Vec::new() };
        Ok(done.into_iter().map(rendered).collect())
    })
}

/// A worker over a bricked scene (read from shared storage, or served by rank 0),
/// through its own LRU brick cache.
pub fn bricked_worker(
    world: &SimpleCommunicator,
    a: &RenderArgs,
    scene: &BrickedScene,
    cache: &BrickCache<'_>,
    opts: &RenderOptions,
    cams: &[CameraRecord],
) -> Result<()> {
    let pool = render::thread_pool(opts.threads)?;
    let opts = RenderOptions { progress: false, ..*opts };
    let cams_ref = cams;
    worker(world, cams, a, &mut |k, rects| {
        let before = cache.stats();
        let cam = &cams_ref[k as usize];
        let done: Vec<(Vec<Vec3>, BrickedFrame)> = pool.install(|| {
            rects.par_iter().map(|&rect| render_bricked_rect(scene, cache, cam, &opts, rect)).collect::<Result<_>>()
        })?;
        // The cache's counts are the batch's: the first tile carries them.
        let c = cache.stats().since(&before);
        let mut counts = Some((c.hits, c.misses, c.bytes_read));
        Ok(done
            .into_iter()
            .map(|(colours, f)| Rendered {
                colours,
                rays: f.rays,
                bricks: counts.take().unwrap_or_default(),
                waited: f.trace.idle_seconds,
                touched: f.touched,
            })
            .collect())
    })
}
