//! The ranks of a job as the master knows them: where each runs (for the report's run
//! identity, and to tell a dead worker from a living one when the launcher ends the
//! job), gathered from the workers' ready messages.

use std::time::Duration;

use anyhow::{bail, Result};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::launcher_stop::has_ended;
use super::patient_receive::receive_within;
use super::protocol::{decode_ready, Whereabouts, TAG_READY};

/// The job's ranks.
pub struct Crew {
    /// Rank 0.
    pub master: Whereabouts,
    /// Ranks 1…, in order.
    pub workers: Vec<Whereabouts>,
}

/// Where this process runs.
pub fn here() -> Whereabouts {
    let host = mpi::environment::processor_name().unwrap_or_else(|_| "?".to_string());
    Whereabouts { host, pid: std::process::id() }
}

impl Crew {
    /// Waits for every worker's ready message; the first that says it cannot go on, or
    /// stays silent past `timeout`, is the error.
    pub fn gather(world: &SimpleCommunicator, timeout: Duration) -> Result<Crew> {
        let mut workers = Vec::new();
        for r in 1..world.size() {
            match receive_within(&world.process_at_rank(r), Some(TAG_READY), timeout)? {
                Some((msg, _)) => match decode_ready(&msg) {
                    Ok(Ok(w)) => workers.push(w),
                    Ok(Err(why)) => bail!("rank {r}: {why}"),
                    Err(e) => bail!("rank {r}: {e}"),
                },
                None => bail!(
                    "rank {r} did not load the scene within {:.0} s (--mpi-timeout): it died or hangs",
                    timeout.as_secs_f64()
                ),
            }
        }
        Ok(Crew { master: here(), workers })
    }

    /// The run's identity: ranks and hosts, and the MPI library.
    pub fn identity(&self) -> String {
        let mut hosts: Vec<&str> =
            std::iter::once(&self.master).chain(&self.workers).map(|w| w.host.as_str()).collect();
        hosts.sort_unstable();
        hosts.dedup();
        let ranks = self.workers.len() + 1;
        format!(
            "{ranks} ranks on {} host{} ({}); {}",
            hosts.len(),
            if hosts.len() == 1 { "" } else { "s" },
            hosts.join(", "),
            library()
        )
    }

    /// Workers (0-based) on the master's host whose process has ended.
    pub fn ended_here(&self) -> Vec<usize> {
        (0..self.workers.len())
            .filter(|&w| self.workers[w].host == self.master.host && has_ended(self.workers[w].pid))
            .collect()
    }
}

/// The MPI library's name and version.
pub fn library() -> String {
    let v = mpi::environment::library_version().unwrap_or_default();
    v.lines().next().unwrap_or("MPI").split(',').next().unwrap_or("MPI").trim().to_string()
}
