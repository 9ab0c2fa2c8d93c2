//! Served data (Wald & Slusallek 2001 §6.3–6.4): the bricked scene is stored once, on
//! a model server — rank 0 — which sends each worker the scene's index at the start and
//! then bricks' stored (compressed) bytes on request. A worker's loader threads ask for
//! the bricks its tracers miss; its LRU cache and parked rays are the single-process
//! ones (`render::bricked`), so the image is the same whichever way the bytes came.
//!
//! Loader threads and the worker's main thread share one MPI connection: every call is
//! made under one lock ([`serialized`]), as `MPI_THREAD_SERIALIZED` allows. Each loader
//! waits for its reply on a tag of its own, so replies never cross.

use std::sync::Mutex;
use std::time::Duration;

use anyhow::{anyhow, bail, Result};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::patient_receive::{receive_within, serialized, try_receive};
use crate::input::bricked::{BrickedScene, FetchStored};

/// Master → worker, once: the index's bytes, after the file's length (u64).
pub const TAG_INDEX: i32 = 20;
/// Worker → server: send brick `b` on reply tag `t` (two u32, little-endian).
pub const TAG_BRICK: i32 = 21;
/// The first reply tag; a worker's requests in flight use the next [`REPLY_TAGS`].
const FIRST_REPLY: i32 = 100;
/// Requests a worker may have in flight at once (its loader threads are fewer).
const REPLY_TAGS: i32 = 64;

/// Sends the index to every worker.
pub fn send_index(world: &SimpleCommunicator, scene: &BrickedScene, file_len: u64) {
    let mut msg = file_len.to_le_bytes().to_vec();
    msg.extend_from_slice(scene.index_bytes());
    for r in 1..world.size() {
        world.process_at_rank(r).send_with_tag(&msg[..], TAG_INDEX);
    }
}

/// A worker's view of the served scene: the index received, bricks fetched from rank 0.
pub fn receive_scene(name: &str, timeout: Duration) -> Result<BrickedScene> {
    let world = SimpleCommunicator::world();
    let Some((msg, _)) = receive_within(&world.process_at_rank(0), Some(TAG_INDEX), timeout)? else {
        bail!("the model server sent no index in {:.0} s", timeout.as_secs_f64());
    };
    let (len, index) = msg.split_at_checked(8).ok_or_else(|| anyhow!("a malformed index message"))?;
    let file_len = u64::from_le_bytes(len.try_into().expect("eight bytes"));
    BrickedScene::from_index(name.to_string(), index, file_len, fetcher(timeout))
}

/// Fetches bricks' stored bytes from rank 0, each on a free reply tag.
fn fetcher(timeout: Duration) -> FetchStored {
    let free: Mutex<Vec<i32>> = Mutex::new((FIRST_REPLY..FIRST_REPLY + REPLY_TAGS).collect());
    Box::new(move |b, size| {
        let tag = free.lock().unwrap_or_else(|p| p.into_inner()).pop();
        let tag = tag.ok_or_else(|| anyhow!("more than {REPLY_TAGS} bricks requested at once"))?;
        let mut request = b.to_le_bytes().to_vec();
        request.extend_from_slice(&(tag as u32).to_le_bytes());
        let world = SimpleCommunicator::world();
        serialized(|| world.process_at_rank(0).send_with_tag(&request[..], TAG_BRICK));
        let reply = receive_within(&world.process_at_rank(0), Some(tag), timeout);
        free.lock().unwrap_or_else(|p| p.into_inner()).push(tag);
        match reply? {
            Some((bytes, _)) => Ok(bytes),
            None => bail!("the model server sent no brick {b} ({size} bytes) in {:.0} s", timeout.as_secs_f64()),
        }
    })
}

/// The server's side: answers every brick request waiting now, adding the bytes sent to
/// each worker to `sent` (index = rank − 1).
pub fn serve_waiting(world: &SimpleCommunicator, scene: &BrickedScene, sent: &mut dyn FnMut(usize, u64)) -> Result<()> {
    while let Some((msg, status)) = try_receive(&world.any_process(), Some(TAG_BRICK), Duration::from_secs(5))? {
        let r = status.source_rank();
        let field = |k: usize| msg.get(4 * k..4 * k + 4).map(|b| u32::from_le_bytes(b.try_into().expect("four bytes")));
        let (Some(b), Some(tag), 8) = (field(0), field(1), msg.len()) else {
            bail!("rank {r} sent a malformed brick request of {} bytes", msg.len());
        };
        let stored = scene.read_stored(b)?;
        world.process_at_rank(r).send_with_tag(&stored[..], tag as i32);
        sent((r - 1) as usize, stored.len() as u64);
    }
    Ok(())
}
