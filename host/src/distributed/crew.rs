//! The ranks of a job as the master knows them: where each runs (for the report's run
//! identity, and to tell a dead worker from a living one when the launcher ends the
//! job), gathered from the workers' ready messages.

use std::time::{Duration, Instant};

use anyhow::{bail, Result};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::launcher_stop::has_ended;
use super::patient_receive::{try_receive, POLL};
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
    /// Waits for every worker's ready message, calling `serve` between polls (a model
    /// server answers the bricks workers ask for while they get ready); the first
    /// worker that says it cannot go on, or stays silent past `timeout`, is the error.
    pub fn gather(
        world: &SimpleCommunicator,
        timeout: Duration,
        serve: &mut dyn FnMut() -> Result<()>,
    ) -> Result<Crew> {
        let start = Instant::now();
        let mut workers: Vec<Option<Whereabouts>> = vec![None; (world.size() - 1) as usize];
        while let Some(w) = workers.iter().position(Option::is_none) {
            let r = w as i32 + 1;
            let Some((msg, _)) = try_receive(&world.process_at_rank(r), Some(TAG_READY), timeout)? else {
                if start.elapsed() > timeout {
                    bail!(
                        "rank {r} did not load the scene within {:.0} s (--mpi-timeout): it died or hangs",
                        timeout.as_secs_f64()
                    );
                }
                serve()?;
                std::thread::sleep(POLL);
                continue;
            };
            match decode_ready(&msg) {
                Ok(Ok(here)) => workers[w] = Some(here),
                Ok(Err(why)) => bail!("rank {r}: {why}"),
                Err(e) => bail!("rank {r}: {e}"),
            }
        }
        Ok(Crew { master: here(), workers: workers.into_iter().flatten().collect() })
    }

    /// The hosts the ranks run on, each once.
    fn host_names(&self) -> Vec<&str> {
        let mut hosts: Vec<&str> =
            std::iter::once(&self.master).chain(&self.workers).map(|w| w.host.as_str()).collect();
        hosts.sort_unstable();
        hosts.dedup();
        hosts
    }

    /// How many hosts the ranks run on.
    pub fn hosts(&self) -> usize {
        self.host_names().len()
    }

    /// The run's identity: ranks and hosts, and the MPI library.
    pub fn identity(&self) -> String {
        let hosts = self.host_names();
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
