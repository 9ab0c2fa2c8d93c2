//! `raypipe sweep SPEC --mpi`: a sweep's points spread over the ranks of an MPI job.
//! Rank 0 checks the spec, opens the journal and hands out the points still to run, one
//! at a time to whichever worker is free (points take very different times: a small
//! cache thrashes, a large one does not); workers run each point as `raypipe simulate`
//! would and send back its row; rank 0 appends the rows to the journal as they arrive
//! and writes the tables. The rows are the single-process sweep's, byte for byte: a
//! point's row depends on the point alone.

use std::time::Duration;

use anyhow::{anyhow, bail, Result};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::patient_receive::{try_receive, POLL};
use crate::commands::simulate::SceneCache;
use crate::commands::sweep::{run_point, sweep_with, SweepArgs};
use crate::study::sweep::{Point, Spec};
use crate::study::sweep_table::Row;

/// Worker → master: free for a point (after starting, or with the row of the last).
const TAG_WANT: i32 = 11;
/// Worker → master: a finished point's row (JSON), and free for the next.
const TAG_ROW: i32 = 12;
/// Worker → master: this worker cannot go on (the message says why).
const TAG_FAIL: i32 = 13;
/// Master → worker: run the point of this index (u64, little-endian).
const TAG_POINT: i32 = 14;
/// Master → worker: no more points.
const TAG_STOP: i32 = 15;

/// `raypipe sweep SPEC --mpi`.
pub fn cmd_sweep_mpi(a: &SweepArgs) -> Result<()> {
    let universe = mpi::initialize().ok_or_else(|| anyhow!("--mpi: MPI was already initialized"))?;
    let world = universe.world();
    if world.size() < 2 {
        bail!("--mpi needs a master and at least one worker: run it as `mpirun -n 2 raypipe sweep … --mpi` or more");
    }
    // The master outlives the launcher's SIGTERM a moment, to say what was running.
    super::launcher_stop::catch_sigterm();
    if world.rank() != 0 {
        return worker(&world, a);
    }
    let mut stopped = vec![false; world.size() as usize];
    let result = sweep_with(a, &mut |_, todo, record| master(&world, todo, record, &mut stopped));
    if let Err(e) = &result {
        eprintln!("error: {e:#}");
        if super::launcher_stop::stopping() {
            // The launcher is ending the job and kills every rank in a moment.
            std::process::exit(1);
        }
        // Workers may be running points: only an abort ends them at once.
        world.abort(1);
    }
    // Workers still waiting (the sweep had nothing left to run) are let go.
    for r in 1..world.size() {
        if !stopped[r as usize] {
            let (_, status) = world.process_at_rank(r).receive_vec::<u8>();
            if status.tag() == TAG_WANT || status.tag() == TAG_ROW {
                world.process_at_rank(r).send_with_tag(&[0u8; 0][..], TAG_STOP);
            }
        }
    }
    result
}

/// Hands out `todo` to whichever worker is free and gathers their rows, recording each.
fn master(
    world: &SimpleCommunicator,
    todo: &[&Point],
    record: &(dyn Fn(&Row) -> Result<()> + Sync),
    stopped: &mut [bool],
) -> Result<Vec<Row>> {
    let mut rows = Vec::with_capacity(todo.len());
    let mut next = 0;
    // The point each rank runs.
    let mut running: Vec<Option<usize>> = vec![None; world.size() as usize];
    while rows.len() < todo.len() {
        let (msg, status) = loop {
            // A point may run for hours: no timeout, but no blocking receive either (a
            // sender that dies mid-message would block it for ever).
            let got = try_receive(&world.any_process(), None, Duration::from_secs(60))?;
            if super::launcher_stop::stopping() {
                let held: Vec<String> =
                    running.iter().enumerate().filter_map(|(r, p)| p.map(|p| format!("rank {r} point {p}"))).collect();
                bail!(
                    "mpirun is ending the job (a rank died, or it was interrupted) while running: {}",
                    held.join(", ")
                );
            }
            match got {
                Some(m) => break m,
                None => std::thread::sleep(POLL),
            }
        };
        let r = status.source_rank();
        running[r as usize] = None;
        match status.tag() {
            TAG_WANT => {}
            TAG_ROW => {
                let row: Row =
                    serde_json::from_slice(&msg).map_err(|e| anyhow!("rank {r} sent a malformed row: {e}"))?;
                record(&row)?;
                rows.push(row);
            }
            TAG_FAIL => bail!("rank {r}: {}", String::from_utf8_lossy(&msg)),
            t => bail!("rank {r} sent an unexpected message (tag {t})"),
        }
        if let Some(p) = todo.get(next) {
            world.process_at_rank(r).send_with_tag(&(p.index as u64).to_le_bytes()[..], TAG_POINT);
            running[r as usize] = Some(p.index);
            next += 1;
        } else {
            world.process_at_rank(r).send_with_tag(&[0u8; 0][..], TAG_STOP);
            stopped[r as usize] = true;
        }
    }
    rows.sort_by_key(|r| r.index);
    Ok(rows)
}

/// A worker: points run as they come, until the master says stop.
fn worker(world: &SimpleCommunicator, a: &SweepArgs) -> Result<()> {
    let master = world.process_at_rank(0);
    let spec = match a.spec.as_deref().ok_or_else(|| anyhow!("sweep: a spec file is needed")).and_then(Spec::load) {
        Ok(s) => s,
        Err(e) => {
            master.send_with_tag(format!("{e:#}").as_bytes(), TAG_FAIL);
            return Err(e);
        }
    };
    let cache = SceneCache::default();
    master.send_with_tag(&[0u8; 0][..], TAG_WANT);
    loop {
        let (msg, status) = master.receive_vec::<u8>();
        if status.tag() == TAG_STOP {
            return Ok(());
        }
        let index = <[u8; 8]>::try_from(&msg[..]).map(u64::from_le_bytes).map_err(|_| anyhow!("a malformed point"))?;
        let point = spec.points.iter().find(|p| p.index as u64 == index);
        let row = point
            .ok_or_else(|| anyhow!("point {index} is not in the spec"))
            .and_then(|p| run_point(p, &spec.dir, &cache, a.reports.as_deref()));
        match row {
            Ok(row) => master.send_with_tag(row.to_line().as_bytes(), TAG_ROW),
            Err(e) => {
                master.send_with_tag(format!("point {index}: {e:#}").as_bytes(), TAG_FAIL);
                return Err(e);
            }
        }
    }
}
