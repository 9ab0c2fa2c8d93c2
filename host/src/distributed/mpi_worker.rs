//! A worker of `raypipe render --mpi`: it renders the tiles the master assigns, with all
//! its threads, and sends each back as soon as it is done. What renders a tile is the
//! single-process renderer — a frame's [`FrameJob`] for a flat image, the brick cache and
//! parked rays of `render::bricked` for a bricked scene — so a tile's colours are the
//! single-process image's.

use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;

use super::launcher_stop::stopping;
use super::patient_receive::{receive_within, serialized};
use super::protocol::{decode_assign, encode_tile, TileHeader, TAG_ASSIGN, TAG_STOP, TAG_TILE};
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
    /// Brick visits served by the cache, bricks loaded, stored bytes loaded.
    pub bricks: (u64, u64, u64),
}

/// Renders tile `rect` of frame `k`.
type RenderTile<'r> = dyn FnMut(u32, Rect) -> Result<Rendered> + 'r;

/// The worker's loop: tiles rendered as they are assigned, until the master says stop.
pub fn worker(
    world: &SimpleCommunicator,
    cams: &[CameraRecord],
    a: &RenderArgs,
    render: &mut RenderTile,
) -> Result<()> {
    let timeout = Duration::from_secs_f64(a.mpi.mpi_timeout.max(0.001));
    let master = world.process_at_rank(0);
    // The master's tiles, of the first frame's size, as it cuts them.
    let tiles = tile_grid(cams[0].width, cams[0].height, a.mpi.mpi_tile);
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
        let job = decode_assign(&bytes)?;
        if job.frame as usize >= cams.len() {
            bail!("frame {} does not exist", job.frame);
        }
        let rect = *tiles.get(job.tile as usize).ok_or_else(|| anyhow!("tile {} does not exist", job.tile))?;
        let start = Instant::now();
        let done = render(job.frame, rect)?;
        let header = TileHeader {
            frame: job.frame,
            tile: job.tile,
            primary: done.rays.primary,
            secondary: done.rays.secondary,
            seconds: start.elapsed().as_secs_f64(),
            hits: done.bricks.0,
            misses: done.bricks.1,
            loaded: done.bricks.2,
        };
        let msg = encode_tile(&header, &done.colours);
        serialized(|| master.buffered_send_with_tag(&msg[..], TAG_TILE));
    }
}

/// A worker over a flat scene image, mapped by every rank.
pub(crate) fn flat_worker(
    world: &SimpleCommunicator,
    a: &RenderArgs,
    p: &Prepared,
    cams: &[CameraRecord],
) -> Result<()> {
    let view = p.scene.view()?;
    let eyes = cams
        .iter()
        .map(|c| Ok(render::eye_rays(c, "camera")?.with_sampler(p.opts.sampler())))
        .collect::<Result<Vec<EyeRays>>>()?;
    // One frame's job at a time (the shadow caster's G-buffers are made once a frame).
    let mut job: Option<(u32, FrameJob)> = None;
    // One thread pool for the run: a pool per tile cost more than the tile.
    let pool = render::thread_pool(p.opts.threads)?;
    worker(world, cams, a, &mut |k, rect| {
        if job.as_ref().is_none_or(|(f, _)| *f != k) {
            let (cam, eye) = (&cams[k as usize], &eyes[k as usize]);
            job = Some((k, FrameJob::new(&view, eye, Vec3::from(cam.background), &p.opts)));
        }
        let Some((_, frame)) = &job else { bail!("no frame job") };
        let (colours, rays) = pool.install(|| frame.rect(rect));
        Ok(Rendered { colours, rays, bricks: (0, 0, 0) })
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
    worker(world, cams, a, &mut |k, rect| {
        let before = cache.stats();
        let (colours, frame) = pool.install(|| render_bricked_rect(scene, cache, &cams[k as usize], &opts, rect))?;
        let c = cache.stats().since(&before);
        Ok(Rendered { colours, rays: frame.rays, bricks: (c.hits, c.misses, c.bytes_read) })
    })
}
