//! `raypipe trace` over a bricked scene: the batch cut into chunks, each traced by one
//! worker's brick tracer (rays parked on missing bricks while the others go on), the
//! records' shading fields read from the brick each hit lies in.

use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;
use raypipe_core::traverse::two_level::BrickHit;
use raypipe_core::Ray;

use super::trace::{pack_record, Field, Query, TraceArgs};
use crate::input::bricked::BrickedScene;
use crate::render::batch::read_rays;
use crate::render::bricked::brick_cache::with_cache;
use crate::render::bricked::brick_tracer::{BrickTracer, TraceStats};
use crate::render::tracer::IntersectorKind;

/// Rays one worker's tracer holds at once.
const CHUNK: usize = 16 * 1024;

/// Traces `a.rays` through the bricked scene `a.scene`.
pub(crate) fn cmd_trace_bricked(a: &TraceArgs, fields: &[Field]) -> Result<()> {
    let (rays, invalid) = read_rays(&a.rays)?;
    let scene = BrickedScene::open(&a.scene)?;
    let (first, _) = scene.load(0)?;
    let kind = IntersectorKind::resolve(a.run.intersector, first.view());
    drop(first);
    let any = a.query == Query::Any;
    let size: usize = if any { 1 } else { fields.iter().map(|f| f.size()).sum() };
    let mut data = vec![0u8; size * rays.len()];
    let mut times = Vec::new();
    let mut stats = TraceStats::default();
    let cache_stats = with_cache(&scene, a.cache.cache, a.cache.loaders as usize, |cache| {
        for _ in 0..a.runs {
            let start = Instant::now();
            let parts: Vec<Result<TraceStats>> = crate::render::in_pool(a.run.threads, || {
                data.par_chunks_mut(size * CHUNK)
                    .zip(rays.par_chunks(CHUNK))
                    .zip(invalid.par_chunks(CHUNK))
                    .map(|((out, rays), bad)| {
                        let mut tracer = BrickTracer::new(cache, scene.view(), a.packet);
                        crate::with_intersector!(kind, I => chunk::<I>(&mut tracer, rays, bad, any, fields, out))?;
                        Ok(tracer.stats)
                    })
                    .collect()
            })?;
            times.push(start.elapsed().as_secs_f64());
            stats = TraceStats::default();
            for p in parts {
                stats.add(&p?);
            }
        }
        Ok(cache.stats())
    })?;
    let secs = crate::study::bench::median(&times);
    let fields_out: Vec<(&str, &str)> =
        if any { vec![("occluded", "'u1'")] } else { fields.iter().map(|f| f.descr()).collect() };
    crate::input::npy::write_records(&a.hits, &fields_out, rays.len(), &data)?;
    let n_hit = if any {
        data.iter().filter(|&&b| b != 0).count()
    } else {
        let prim_at = fields.iter().position(|f| *f == Field::Prim);
        (0..rays.len())
            .filter(|&i| !invalid[i])
            .filter(|&i| match prim_at {
                Some(p) => {
                    let at = i * size + fields[..p].iter().map(|f| f.size()).sum::<usize>();
                    i32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]) >= 0
                }
                None => true,
            })
            .count()
    };
    println!(
        "traced {} rays ({} query) through {} ({} bricks): {n_hit} {} in {secs:.3} s ({:.2} Mrays/s) -> {}",
        rays.len(),
        if any { "any-hit" } else { "closest-hit" },
        scene.name,
        scene.view().brick_count(),
        if any { "occluded" } else { "hits" },
        rays.len() as f64 / secs.max(1e-9) / 1e6,
        a.hits.display()
    );
    println!(
        "bricks   {} visits, hit rate {:.1}%, {} loads, {} evictions, {:.1} MB decompressed; parked {:.3} ray-s, idle {:.3} s",
        stats.brick_visits,
        100.0 * cache_stats.hit_rate(),
        cache_stats.loads,
        cache_stats.evictions,
        cache_stats.bytes_decompressed as f64 / 1e6,
        stats.parked_ray_seconds,
        stats.idle_seconds
    );
    Ok(())
}

/// One chunk of rays: traced, then each record packed from its hit's brick.
fn chunk<I: raypipe_core::Intersector>(
    tracer: &mut BrickTracer<'_, '_>,
    rays: &[Ray],
    invalid: &[bool],
    any: bool,
    fields: &[Field],
    out: &mut [u8],
) -> Result<()> {
    let hits: Vec<Option<BrickHit>> = tracer.trace_batch::<I>(rays, &vec![any; rays.len()])?;
    let hits: Vec<Option<BrickHit>> = hits.into_iter().zip(invalid).map(|(h, &bad)| h.filter(|_| !bad)).collect();
    if any {
        for (o, h) in out.iter_mut().zip(&hits) {
            *o = h.is_some() as u8;
        }
        return Ok(());
    }
    let size: usize = fields.iter().map(|f| f.size()).sum();
    let globals = *tracer.index().globals();
    let mut work = Vec::new();
    for (i, h) in hits.iter().enumerate() {
        match h {
            // Misses need no scene data.
            None => pack_record(&globals, &rays[i], None, None, fields, &mut out[i * size..(i + 1) * size]),
            Some(h) => work.push((h.brick, i)),
        }
    }
    tracer.grouped(work, |_, view, items, _| {
        for i in items {
            let h = hits[i].map(|h| (h.hit, h.local_hit()));
            pack_record(view, &rays[i], h.map(|h| h.0), h.map(|h| h.1), fields, &mut out[i * size..(i + 1) * size]);
        }
    })
}
