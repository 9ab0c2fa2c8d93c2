//! Receiving without trusting the sender to live. A blocking MPI receive whose sender
//! dies in the middle of the message never returns, and a rank that hangs never sends
//! at all; so every receive of a distributed run polls, and each caller decides how long
//! silence may last before it names the silent rank (Wald & Slusallek 2001 §6.5 assume
//! clients that stay up; a cluster's users cannot).

use std::time::{Duration, Instant};

use anyhow::Result;
use mpi::point_to_point::{Message, Status};
use mpi::traits::*;
use mpi::Tag;

use super::launcher_stop::stopping;

/// Between two polls: short against a tile, long enough to leave the core to the
/// rendering threads (MPI's own waits spin).
pub const POLL: Duration = Duration::from_micros(50);

/// How long a message that began to arrive is tested for without sleeping.
const SPIN: Duration = Duration::from_millis(2);

/// The one lock every MPI call of a process is made under, so that a worker's loader
/// threads and its main thread never call MPI at once (`MPI_THREAD_SERIALIZED`).
static MPI_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs `f`, which calls MPI, under the process's MPI lock.
pub fn serialized<T>(f: impl FnOnce() -> T) -> T {
    let _held = MPI_LOCK.lock().unwrap_or_else(|p| p.into_inner());
    f()
}

/// A sender that stopped in the middle of a message.
#[derive(Debug)]
pub struct Stalled {
    /// Its rank.
    pub rank: i32,
    /// The message's length.
    pub bytes: usize,
}

impl std::fmt::Display for Stalled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "rank {} stopped in the middle of a {}-byte message: it died or hangs", self.rank, self.bytes)
    }
}

impl std::error::Error for Stalled {}

/// The next message from `source` (with `tag`, or any tag), if one has begun to
/// arrive; `None` at once if none has. A message that began to arrive must end within
/// `patience` (and before the launcher ends the job), else its sender died or hangs in
/// the middle of it: an error naming the rank.
pub fn try_receive<S: Source>(
    source: &S,
    tag: Option<Tag>,
    patience: Duration,
) -> Result<Option<(Vec<u8>, Status)>, Stalled> {
    serialized(|| try_receive_now(source, tag, patience))
}

fn try_receive_now<S: Source>(
    source: &S,
    tag: Option<Tag>,
    patience: Duration,
) -> Result<Option<(Vec<u8>, Status)>, Stalled> {
    let probed = match tag {
        Some(t) => source.immediate_matched_probe_with_tag(t),
        None => source.immediate_matched_probe(),
    };
    let Some((message, status)) = probed else { return Ok(None) };
    let len = status.count(u8::equivalent_datatype()).max(0) as usize;
    let mut buf = vec![0u8; len];
    if receive_into(message, &mut buf, patience) {
        Ok(Some((buf, status)))
    } else {
        // MPI may still write into the buffer: it is never freed (the run ends now).
        std::mem::forget(buf);
        Err(Stalled { rank: status.source_rank(), bytes: len })
    }
}

/// The next message from `source`, waiting at most `timeout` for it to begin; `None`
/// if it did not.
pub fn receive_within<S: Source>(source: &S, tag: Option<Tag>, timeout: Duration) -> Result<Option<(Vec<u8>, Status)>> {
    let start = Instant::now();
    loop {
        if let Some(m) = try_receive(source, tag, timeout)? {
            return Ok(Some(m));
        }
        if start.elapsed() > timeout {
            return Ok(None);
        }
        std::thread::sleep(POLL);
    }
}

/// Receives a probed message into `buf`; false if it did not end within `patience`.
fn receive_into(message: Message, buf: &mut [u8], patience: Duration) -> bool {
    let start = Instant::now();
    mpi::request::scope(|scope| {
        let mut request = message.immediate_matched_receive_into(scope, buf);
        loop {
            match request.test() {
                Ok(_) => return true,
                Err(r) => request = r,
            }
            // The launcher ending the job leaves a second to say why: no waiting then.
            let waited = start.elapsed();
            if waited > patience || stopping() {
                // SAFETY: the request is let go unfinished, so MPI may still write into
                // `buf`; the caller leaks `buf` and ends the run.
                let _ = unsafe { request.into_raw() };
                return false;
            }
            // A message under way takes microseconds: testing again at once finishes it
            // (a sleep here cost a tenth of a millisecond per tile); only a slow one
            // is waited for with sleeps.
            if waited > SPIN {
                std::thread::sleep(POLL);
            } else {
                std::thread::yield_now();
            }
        }
    })
}
