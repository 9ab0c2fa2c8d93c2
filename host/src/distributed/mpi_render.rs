//! `raypipe render --mpi`: one frame (or a walkthrough) rendered across the ranks of an
//! MPI job. Rank 0 is the master (`mpi_master`), the others workers (`mpi_worker`).
//! The scene is read two ways (Wald & Slusallek 2001 §6.3–6.4): replicated — every
//! rank maps the scene image, or opens the bricked scene, from shared storage — or,
//! for a bricked scene, served — rank 0 holds the file and sends each worker's cache
//! the bricks it asks for. A tile's colours depend on the tile alone, so the image is
//! the single-process image, bit for bit, whatever the ranks and the data.

use std::path::Path;
use std::time::Duration;

use anyhow::{anyhow, bail, Result};
use mpi::environment::Threading;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::brick_service::{receive_scene, send_index};
use super::crew::{self, Crew};
use super::launcher_stop::{catch_sigterm, stopping};
use super::mpi_master::{master, Job, IN_FLIGHT};
use super::mpi_worker::{bricked_worker, flat_worker};
use super::protocol::{encode_ready, TAG_READY, TAG_STOP};
use crate::commands::render::{prepare, MpiData, RenderArgs};
use crate::commands::render_bricked::bricked_setup;
use crate::input::bricked::{is_bricked, BrickedScene};
use crate::render::bricked::brick_cache::with_cache;

/// `raypipe render --mpi`.
pub fn cmd_render_mpi(a: &RenderArgs) -> Result<()> {
    // A worker's brick loaders call MPI from their threads, one at a time.
    let (mut universe, threading) = mpi::initialize_with_threading(Threading::Serialized)
        .ok_or_else(|| anyhow!("--mpi: MPI was already initialized"))?;
    let world = universe.world();
    if world.rank() != 0 {
        // Tiles go back by buffered sends: a worker copies a tile out and renders the
        // next at once, instead of waiting until the master takes it (large messages
        // wait for the receiver). At most IN_FLIGHT tiles are owed at any time.
        universe.set_buffer_size((IN_FLIGHT + 1) * (tile_budget(a) + MPI_BSEND_OVERHEAD));
    }
    if world.size() < 2 {
        bail!("--mpi needs a master and at least one worker: run it as `mpirun -n 2 raypipe render … --mpi` or more");
    }
    // Every rank outlives the launcher's SIGTERM a little (see `launcher_stop`).
    catch_sigterm();
    let bricked = a.scene.as_deref().filter(|p| is_bricked(p));
    let served = a.mpi.mpi_data == MpiData::Served;
    let result = match bricked {
        Some(_) if served && threading < Threading::Serialized => {
            refuse(&world, anyhow!("--mpi-data served: this MPI library cannot serve threads one at a time (MPI_THREAD_SERIALIZED)"))
        }
        Some(path) => run_bricked(&world, a, path, served),
        None if served => refuse(
            &world,
            anyhow!("--mpi-data served needs a bricked scene (.rpsb, from `raypipe build … --bricks`); a scene image is read by every rank"),
        ),
        None => run_flat(&world, a),
    };
    if world.rank() != 0 {
        if let Err(e) = &result {
            // The master may wait on this rank: the job ends here, with one line.
            eprintln!("error: {e:#}");
            world.abort(1);
        }
        return Ok(());
    }
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

/// What MPI keeps beside each buffered message (generous: `MPI_BSEND_OVERHEAD` is about
/// a hundred bytes in OpenMPI and MPICH).
const MPI_BSEND_OVERHEAD: usize = 1024;

/// Bytes a tile message may take in the buffer of buffered sends: its colours, header
/// and up to 64 Ki bricks; a larger one goes by a plain send.
pub fn tile_budget(a: &RenderArgs) -> usize {
    let tile = a.mpi.mpi_tile as usize;
    tile * tile * 12 + 1024 + 4 * 65536
}

/// `--mpi-timeout`.
fn timeout_of(a: &RenderArgs) -> Duration {
    Duration::from_secs_f64(a.mpi.mpi_timeout.max(0.001))
}

/// A command line the master refuses: the workers are let go and it says why, once.
fn refuse(world: &SimpleCommunicator, e: anyhow::Error) -> Result<()> {
    if world.rank() == 0 {
        stop_all(world);
        return Err(e);
    }
    // A worker only waits to be let go.
    let _ = super::patient_receive::receive_within(&world.process_at_rank(0), Some(TAG_STOP), Duration::from_secs(60));
    Ok(())
}

/// Tells the master whether this worker is ready; returns what it prepared.
fn report_ready<T>(world: &SimpleCommunicator, prepared: Result<T>) -> Option<T> {
    let ready = prepared.as_ref().map(|_| crew::here()).map_err(|e| format!("{e:#}"));
    super::patient_receive::serialized(|| world.process_at_rank(0).send_with_tag(&encode_ready(&ready)[..], TAG_READY));
    prepared.ok()
}

/// A scene image (or OBJ, or a built-in scene) that every rank reads itself.
fn run_flat(world: &SimpleCommunicator, a: &RenderArgs) -> Result<()> {
    // Every rank loads the scene; a worker that cannot tells the master, which says so
    // once for the whole job.
    let prepared = prepare(a).and_then(|p| {
        let cams = a.walk.cameras(&p.camera)?.unwrap_or_else(|| vec![p.camera]);
        Ok((p, cams))
    });
    if world.rank() != 0 {
        let (p, cams) = match prepared {
            Ok(x) => x,
            Err(e) => {
                report_ready::<()>(world, Err(e));
                return Ok(());
            }
        };
        // The image is validated before the worker says it is ready: on a large scene
        // that takes a second, which must not fall into the first frame.
        let Some(view) = report_ready(world, p.scene.view()) else { return Ok(()) };
        return flat_worker(world, a, &p, &view, &cams);
    }
    let (p, cams) = prepared.inspect_err(|_| stop_all(world))?;
    let crew = Crew::gather(world, timeout_of(a), &mut || Ok(()))?;
    let job = Job {
        name: p.scene.name.clone(),
        cams,
        display: p.display,
        bricked: false,
        server: None,
        bricks: Vec::new(),
        timeout: timeout_of(a),
    };
    master(world, a, &job, &crew)
}

/// A bricked scene: every rank opens the file (replicated), or rank 0 serves it.
fn run_bricked(world: &SimpleCommunicator, a: &RenderArgs, path: &Path, served: bool) -> Result<()> {
    let timeout = timeout_of(a);
    let name = path.display().to_string();
    if world.rank() != 0 {
        let scene = if served { receive_scene(&name, timeout) } else { BrickedScene::open(path) };
        let prepared = scene.and_then(|scene| {
            let (cam, opts, _) = bricked_setup(a, &scene)?;
            let cams = a.walk.cameras(&cam)?.unwrap_or_else(|| vec![cam]);
            Ok((scene, opts, cams))
        });
        let Some((scene, opts, cams)) = report_ready(world, prepared) else { return Ok(()) };
        return with_cache(&scene, a.cache.cache, a.cache.loaders as usize, |cache| {
            bricked_worker(world, a, &scene, cache, &opts, &cams)
        });
    }
    let scene = BrickedScene::open(path).inspect_err(|_| stop_all(world))?;
    if served {
        let len = std::fs::metadata(path).map_err(|e| anyhow!("{name}: {e}"))?.len();
        send_index(world, &scene, len);
    }
    let server = served.then_some(&scene);
    // While the workers get ready they may already ask for bricks (the first, to
    // choose their defaults).
    let mut serve = || server.map_or(Ok(()), |s| super::brick_service::serve_waiting(world, s, &mut |_, _| {}));
    let crew = Crew::gather(world, timeout, &mut serve)?;
    let (cam, _, display) = bricked_setup(a, &scene)?;
    let cams = a.walk.cameras(&cam)?.unwrap_or_else(|| vec![cam]);
    let index = scene.view();
    let bricks =
        (0..index.brick_count()).filter_map(|b| index.brick(b)).map(|r| (r.stored_size, r.image_size)).collect();
    let job = Job { name, cams, display, bricked: true, server, bricks, timeout };
    master(world, a, &job, &crew)
}

fn stop_all(world: &SimpleCommunicator) {
    for r in 1..world.size() {
        world.process_at_rank(r).send_with_tag(&[0u8; 0][..], TAG_STOP);
    }
}
