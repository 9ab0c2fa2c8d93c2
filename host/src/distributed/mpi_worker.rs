//! A worker of `raypipe render --mpi`: it renders the tiles the master assigns, with all
//! its threads, and sends each back as soon as it is done. What renders a tile is the
//! single-process renderer — a frame's [`FrameJob`] for a flat image, the brick cache and
//! parked rays of `render::bricked` for a bricked scene — so a tile's colours are the
//! single-process image's.

use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use mpi::topology::{Process, SimpleCommunicator};
use mpi::traits::*;
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
use crate::render::bricked::frame::render_bricked_rect;
use crate::render::{self, FrameJob, RayTotals, RenderOptions};

/// A rendered tile and what rendering it did.
pub struct Rendered {
    /// Its pixels' colours, row by row.
    pub colours: Vec<Vec3>,
    /// Rays traced.
    pub rays: RayTotals,
    /// Seconds its tracer waited with every ray parked on a brick.
    pub waited: f64,
    /// The bricks its rays needed.
    pub touched: Vec<u32>,
}

/// Renders tile `rect` of frame `k`; called from the pool's threads, several at once.
type RenderTile<'r> = dyn Fn(u32, Rect) -> Result<Rendered> + Sync + 'r;

/// A bricked worker's cache counts so far: brick visits served, bricks loaded, stored
/// bytes loaded.
type CacheCounts<'r> = dyn Fn() -> (u64, u64, u64) + 'r;

/// A tile done on a pool thread: its assignment, its wall seconds, the result.
type Done = (Assign, f64, Result<Rendered>);

/// The worker's loop (Wald & Slusallek 2001 §6.5: clients keep several tiles to hide
/// the network). Its own thread does all MPI; every assigned tile starts on the thread
/// pool at once, and the pool's threads steal the tiles' 16-pixel pieces from each
/// other, so no thread waits at the end of a tile while others are queued. A finished
/// tile goes back as soon as this thread sees it.
pub fn worker(
    world: &SimpleCommunicator,
    cams: &[CameraRecord],
    a: &RenderArgs,
    pool: &rayon::ThreadPool,
    render: &RenderTile,
    counts: &CacheCounts,
) -> Result<()> {
    let timeout = Duration::from_secs_f64(a.mpi.mpi_timeout.max(0.001));
    let master = world.process_at_rank(0);
    // The master's tiles, of the first frame's size, as it cuts them.
    let tiles = tile_grid(cams[0].width, cams[0].height, a.mpi.mpi_tile);
    let budget = super::mpi_render::tile_budget(a);
    let (tx, rx) = std::sync::mpsc::channel::<Done>();
    let mut busy = Busy::default();
    let mut sent_counts = counts();
    let mut heard = Instant::now();
    let mut waited_for: Option<Done> = None;
    pool.in_place_scope(|scope| -> Result<()> {
        loop {
            if stopping() {
                // Alive a moment past the launcher's SIGTERM, so that the master can
                // tell this rank from the one that died; then gone, quietly.
                std::thread::sleep(Duration::from_millis(300));
                std::process::exit(143);
            }
            let mut progressed = false;
            let finished = waited_for.take().into_iter().chain(std::iter::from_fn(|| rx.try_recv().ok()));
            for (job, wall, done) in finished.collect::<Vec<Done>>() {
                let tile = done?;
                let seconds = busy.finished();
                let now = counts();
                let delta = (now.0 - sent_counts.0, now.1 - sent_counts.1, now.2 - sent_counts.2);
                sent_counts = now;
                let header = TileHeader {
                    frame: job.frame,
                    tile: job.tile,
                    primary: tile.rays.primary,
                    secondary: tile.rays.secondary,
                    seconds,
                    hits: delta.0,
                    misses: delta.1,
                    loaded: delta.2,
                    // Its rays' wait, in the same share of the worker as `seconds`.
                    waited: (tile.waited * seconds / wall.max(1e-12)).min(seconds),
                    touched: 0,
                };
                let msg = encode_tile(&header, &tile.colours, &tile.touched);
                if msg.len() <= budget {
                    serialized(|| master.buffered_send_with_tag(&msg[..], TAG_TILE));
                } else {
                    serialized(|| master.send_with_tag(&msg[..], TAG_TILE));
                }
                progressed = true;
            }
            // Only the master's assignments and stop: replies to the loaders' brick
            // requests come on tags of their own and are theirs to take.
            while let Some((bytes, status)) = next_order(&master, timeout)? {
                heard = Instant::now();
                progressed = true;
                match status.tag() {
                    TAG_STOP => return Ok(()),
                    TAG_ASSIGN => {}
                    other => bail!("rank {}: unexpected message tag {other}", world.rank()),
                }
                let job = decode_assign(&bytes)?;
                if job.frame as usize >= cams.len() {
                    bail!("frame {} does not exist", job.frame);
                }
                let rect = *tiles.get(job.tile as usize).ok_or_else(|| anyhow!("tile {} does not exist", job.tile))?;
                busy.started();
                let tx = tx.clone();
                scope.spawn(move |_| {
                    let start = Instant::now();
                    let done = render(job.frame, rect);
                    // The receiver lives as long as the scope.
                    let _ = tx.send((job, start.elapsed().as_secs_f64(), done));
                });
            }
            // An idle worker may wait on a live master for as long as the slowest tile
            // (bounded by the timeout) and the image's writing: it gives up after three.
            if busy.in_flight == 0 && heard.elapsed() > 3 * timeout {
                bail!(
                    "rank {}: the master sent nothing for {:.0} s: it died or hangs",
                    world.rank(),
                    3.0 * timeout.as_secs_f64()
                );
            }
            if !progressed {
                if busy.in_flight > 0 {
                    // Tiles are rendering: wake when one is done, or after a
                    // millisecond to look for assignments (polling faster took the
                    // rendering threads' cores).
                    waited_for = rx.recv_timeout(Duration::from_millis(1)).ok();
                } else {
                    std::thread::sleep(POLL);
                }
            }
        }
    })
}

/// The master's next assignment, or its stop, if one has begun to arrive.
fn next_order(master: &Process<'_>, timeout: Duration) -> Result<Option<(Vec<u8>, mpi::point_to_point::Status)>> {
    for tag in [TAG_ASSIGN, TAG_STOP] {
        if let Some(m) = try_receive(master, Some(tag), timeout)? {
            return Ok(Some(m));
        }
    }
    Ok(None)
}

/// The worker's busy time (some tile in progress), shared out to the tiles as they
/// finish: each gets the busy time since the one before it, so that the tiles'
/// seconds add up to the worker's busy time however many ran at once.
#[derive(Default)]
struct Busy {
    in_flight: usize,
    since: Option<Instant>,
}

impl Busy {
    fn started(&mut self) {
        self.in_flight += 1;
        self.since.get_or_insert_with(Instant::now);
    }

    /// A tile finished: its share of the busy time.
    fn finished(&mut self) -> f64 {
        self.in_flight = self.in_flight.saturating_sub(1);
        let now = Instant::now();
        let seconds = self.since.map_or(0.0, |t| (now - t).as_secs_f64());
        self.since = (self.in_flight > 0).then_some(now);
        seconds
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
    // One frame's job at a time (the shadow caster's G-buffers are made once a frame):
    // a frame's tiles come only after the frame before is gathered.
    let job: std::sync::RwLock<Option<(u32, std::sync::Arc<FrameJob>)>> = std::sync::RwLock::new(None);
    // One thread pool for the run: a pool per tile cost more than the tile.
    let pool = render::thread_pool(p.opts.threads)?;
    let render = |k: u32, rect: Rect| -> Result<Rendered> {
        let current = job.read().unwrap_or_else(|e| e.into_inner()).clone();
        let frame = match current {
            Some((f, j)) if f == k => j,
            _ => {
                let mut slot = job.write().unwrap_or_else(|e| e.into_inner());
                match &*slot {
                    Some((f, j)) if *f == k => j.clone(),
                    _ => {
                        let (cam, eye) = (&cams[k as usize], &eyes[k as usize]);
                        let j = std::sync::Arc::new(FrameJob::new(view, eye, Vec3::from(cam.background), &p.opts));
                        *slot = Some((k, j.clone()));
                        j
                    }
                }
            }
        };
        let (colours, rays) = frame.rect(rect);
        Ok(Rendered { colours, rays, waited: 0.0, touched: Vec::new() })
    };
    worker(world, cams, a, &pool, &render, &|| (0, 0, 0))
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
    let render = |k: u32, rect: Rect| -> Result<Rendered> {
        let (colours, f) = render_bricked_rect(scene, cache, &cams[k as usize], &opts, rect)?;
        Ok(Rendered { colours, rays: f.rays, waited: f.trace.idle_seconds, touched: f.touched })
    };
    let counts = || {
        let c = cache.stats();
        (c.hits, c.misses, c.bytes_read)
    };
    worker(world, cams, a, &pool, &render, &counts)
}
