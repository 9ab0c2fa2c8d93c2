//! `raypipe trace`: traces a batch of rays from a file and writes their hits.

use crate::bench::median;
use crate::cli::TraceArgs;
use crate::scene;
use crate::tracer::IntersectorKind;
use anyhow::{anyhow, bail, Result};
use std::time::Instant;

use super::{structure_summary, warn, warn_range};

pub(crate) fn cmd_trace(a: TraceArgs) -> Result<()> {
    a.run.check()?;
    let rays = crate::npy::read_f32_2d(&a.rays)?;
    let name = a.rays.display();
    let rays = crate::batch::rays_from_array(&rays).map_err(|e| anyhow!("{name}: {e}"))?;
    let scene = scene::load(Some(&a.scene), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    warn_range(&view, &rays, &format!("rays of {name}"));
    let mut times = Vec::new();
    // One output for all runs, as a caller tracing batch after batch keeps one: only the
    // first run pays for touching fresh pages.
    let mut hits = Vec::new();
    for _ in 0..a.runs {
        let start = Instant::now();
        crate::batch::trace_batch_into(
            &view,
            &rays,
            IntersectorKind::resolve(a.run.intersector, &view),
            a.packet,
            a.run.threads,
            &mut hits,
        )?;
        times.push(start.elapsed().as_secs_f64());
    }
    let secs = median(&times);
    crate::npy::write_hits(&a.hits, &hits)?;
    let n_hit = hits.iter().filter(|h| h.prim >= 0).count();
    println!(
        "traced {} rays through {} ({}): {} hits ({:.2}%) in {:.3} s ({:.2} Mrays/s) -> {}",
        rays.len(),
        scene.name,
        structure_summary(&view),
        n_hit,
        100.0 * n_hit as f64 / rays.len().max(1) as f64,
        secs,
        rays.len() as f64 / secs / 1e6,
        a.hits.display()
    );
    Ok(())
}
