//! Ray batches: rays from an array, closest hits out, traced on all cores in fixed-size
//! chunks, each worker taking the next chunk as it finishes one (the result does not
//! depend on the thread count).

use anyhow::{bail, Result};
use std::mem::MaybeUninit;

use raypipe_core::{Intersector, NoProbe, Ray, RayCounters, SceneView, Vec3};

use crate::input::npy::{Array2, HitRecord};
use crate::platform::huge_pages;
use crate::platform::prefetch::prefetch;
use crate::platform::thread_pools::for_each_claimed;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::wide_bvh::last_occluder::LastOccluder;

use crate::render::packets::PacketSize;
use crate::render::ray_order::{RayOrder, Reordered};
use crate::render::tracer::{occluded_each, occluded_packet, trace_each, trace_packet, IntersectorKind};
use crate::with_intersector;

/// Rays traced as one unit of work.
const CHUNK: usize = 4096;
/// How many rays ahead a single-ray trace asks for its ray records (512 bytes; 4, 8, 32
/// and 64 measured alike on Sponza, 1.10–1.20x against none).
const SINGLE_PREFETCH_AHEAD: usize = 16;

/// How many packets ahead a packet trace asks for its ray records.
const PACKET_PREFETCH_AHEAD: usize = 1;

/// Asks for the records of the `n` rays from `first` on, one cache line (two rays) at a
/// time: a cheap packet (rays that miss) otherwise waits on its rays' arrival from memory.
#[inline(always)]
fn prefetch_packet(rays: &[Ray], first: usize, n: usize) {
    for r in rays.iter().skip(first).take(n).step_by(2) {
        prefetch(Some(r));
    }
}

/// The rays of the `.npy` file at `path` ([`rays_from_array`]); an error names the file.
pub fn read_rays(path: &std::path::Path) -> Result<(Vec<Ray>, Vec<bool>)> {
    let array = crate::input::npy::read_f32_2d(path)?;
    rays_from_array(&array).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// Rays from an (N, 6) or (N, 8) array, and which rows could not be rays (NaN or
/// infinite values, a zero direction, an empty, NaN or negative interval): those are
/// traced as an empty ray that hits nothing, and the caller reports them as misses.
pub fn rays_from_array(a: &Array2) -> Result<(Vec<Ray>, Vec<bool>)> {
    if a.cols != 6 && a.cols != 8 {
        bail!("array has {} columns; expected 6 (origin, direction) or 8 (and t_min, t_max)", a.cols);
    }
    let mut rays = huge_pages::empty_vec(a.rows);
    let mut invalid = vec![false; a.rows];
    for (i, row) in a.data.chunks_exact(a.cols).enumerate() {
        let origin = Vec3::new(row[0], row[1], row[2]);
        let dir = Vec3::new(row[3], row[4], row[5]);
        let (t_min, t_max) = if a.cols == 8 { (row[6], row[7]) } else { (0.0, f32::INFINITY) };
        let valid = origin.is_finite()
            && dir.is_finite()
            && dir != Vec3::ZERO
            && !t_min.is_nan()
            && !t_max.is_nan()
            && t_min <= t_max
            && t_min >= 0.0;
        if valid {
            rays.push(Ray { origin, dir, t_min, t_max });
        } else {
            invalid[i] = true;
            rays.push(NO_RAY);
        }
    }
    Ok((rays, invalid))
}

/// What an invalid row is traced as: an interval no hit can fall in.
const NO_RAY: Ray = Ray { origin: Vec3::ZERO, dir: Vec3::X, t_min: 1.0, t_max: 0.0 };

/// The share of packets of `n` consecutive rays whose directions do not agree (a ray
/// more than 60° from the packet's mean direction): what `trace --packet` warns about,
/// since incoherent packets split at once and cost more than single rays.
pub fn incoherent_share(rays: &[Ray], n: usize) -> f64 {
    if n <= 1 || rays.is_empty() {
        return 0.0;
    }
    let groups = rays.chunks(n);
    let total = groups.len();
    let bad = rays
        .chunks(n)
        .filter(|g| {
            let mean: Vec3 = g.iter().map(|r| r.dir.normalize_or_zero()).sum::<Vec3>().normalize_or_zero();
            g.iter().any(|r| r.dir.normalize_or_zero().dot(mean) < 0.5)
        })
        .count();
    bad as f64 / total as f64
}

/// How a batch is traced: the intersector, the packet size, the order of single rays,
/// and the threads (all cores when `None`).
#[derive(Clone, Copy, Debug)]
pub struct BatchOptions {
    pub kind: IntersectorKind,
    pub packet: PacketSize,
    pub order: RayOrder,
    pub threads: Option<usize>,
}

/// What a caller tracing batch after batch keeps besides the output: the reordered
/// rays and their hits in tracing order ([`RayOrder`]), whose fresh pages would be
/// faulted in again for every batch.
#[derive(Debug, Default)]
pub struct BatchScratch {
    order: Reordered,
    hits: Vec<HitRecord>,
}

/// Closest hit of every ray.
pub fn trace_batch(scene: &SceneView<'_>, rays: &[Ray], opts: BatchOptions) -> Result<Vec<HitRecord>> {
    let mut out = Vec::new();
    trace_batch_into(scene, rays, opts, &mut out, &mut BatchScratch::default())?;
    Ok(out)
}

/// Closest hit of every ray into `out`, replacing its contents and keeping its memory
/// where it is large enough: a caller tracing batch after batch keeps one output, and
/// does not pay the first touch of fresh pages for every batch (16 bytes a ray; about
/// 1.6 ms per million rays on this project's benchmark machine, a twentieth of a
/// bunny's 8×8-packet trace). Single rays go in the order `opts.order` makes, through
/// `scratch`'s buffers, which the caller keeps likewise.
pub fn trace_batch_into(
    scene: &SceneView<'_>,
    rays: &[Ray],
    opts: BatchOptions,
    out: &mut Vec<HitRecord>,
    scratch: &mut BatchScratch,
) -> Result<()> {
    let threads = opts.threads;
    with_intersector!(opts.kind, I => match opts.packet.usable_for(scene) {
        PacketSize::Single => {
            if scratch.order.sort(rays, opts.order, threads)? {
                trace_with::<I, 1>(scene, scratch.order.rays(), threads, &mut scratch.hits)?;
                return scratch.order.restore(&scratch.hits, out, threads);
            }
            trace_with::<I, 1>(scene, rays, threads, out)
        }
        PacketSize::P4 => trace_with::<I, 4>(scene, rays, threads, out),
        PacketSize::P16 => trace_with::<I, 16>(scene, rays, threads, out),
        PacketSize::P64 => trace_with::<I, 64>(scene, rays, threads, out),
    })
}

/// Whether each ray is blocked within its interval (the any-hit query of shadow rays),
/// rays marked `invalid` reported unblocked. With packets, runs of `N` consecutive rays
/// are traced as one packet (on the 4-wide BVH; ray by ray on the other structures).
/// Single rays go in the order `opts.order` makes, through `scratch`'s buffers, which a
/// caller tracing batch after batch keeps (as for [`trace_batch_into`]).
pub fn occluded_batch(
    scene: &SceneView<'_>,
    rays: &[Ray],
    invalid: &[bool],
    opts: BatchOptions,
    scratch: &mut BatchScratch,
) -> Result<Vec<bool>> {
    let threads = opts.threads;
    with_intersector!(opts.kind, I => match opts.packet {
        PacketSize::Single => {
            let order = &mut scratch.order;
            if order.sort(rays, opts.order, threads)? {
                let traced = occluded_with::<I, 1>(scene, order.rays(), &order.apply(invalid), threads)?;
                let mut out = Vec::new();
                order.restore(&traced, &mut out, threads)?;
                return Ok(out);
            }
            occluded_with::<I, 1>(scene, rays, invalid, threads)
        }
        PacketSize::P4 => occluded_with::<I, 4>(scene, rays, invalid, threads),
        PacketSize::P16 => occluded_with::<I, 16>(scene, rays, invalid, threads),
        PacketSize::P64 => occluded_with::<I, 64>(scene, rays, invalid, threads),
    })
}

/// Chunks of `CHUNK` rays per task, each run of `N` rays one packet.
fn occluded_with<I: Intersector, const N: usize>(
    scene: &SceneView<'_>,
    rays: &[Ray],
    invalid: &[bool],
    threads: Option<usize>,
) -> Result<Vec<bool>> {
    crate::platform::isa::report_cpu();
    let mut out = vec![false; rays.len()];
    let chunks = out.chunks_mut(CHUNK).zip(rays.chunks(CHUNK)).zip(invalid.chunks(CHUNK));
    for_each_claimed(threads, chunks, |((out, chunk), bad)| {
        if N == 1 {
            let ray = |i: usize| {
                prefetch(chunk.get(i + SINGLE_PREFETCH_AHEAD));
                chunk.get(i).filter(|_| !bad.get(i).copied().unwrap_or(true))
            };
            let blocked = |i: usize, b: bool| {
                if let Some(o) = out.get_mut(i) {
                    *o = b;
                }
            };
            occluded_each::<I, _>(scene, chunk.len(), ray, &mut NoProbe, &mut RayCounters::default(), blocked);
            return;
        }
        let mut pc = PacketCounters::default();
        let mut packet = RayPacket::<N>::new();
        let mut cache = LastOccluder::default();
        for ((out, group), bad) in out.chunks_mut(N).zip(chunk.chunks(N)).zip(bad.chunks(N)) {
            packet.fill(group);
            let blocked = occluded_packet::<I, _, N>(scene, &packet, &mut cache, &mut NoProbe, &mut pc);
            for (i, (o, bad)) in out.iter_mut().zip(bad).enumerate() {
                *o = !bad && blocked & (1 << i) != 0;
            }
        }
    })?;
    Ok(out)
}

fn record(hit: Option<raypipe_core::Hit>) -> HitRecord {
    match hit {
        Some(h) => HitRecord { t: h.t, u: h.u, v: h.v, prim: h.prim as i32 },
        None => HitRecord { t: f32::INFINITY, u: 0.0, v: 0.0, prim: -1 },
    }
}

/// Traces `rays` one by one into `out`, writing every record of `out` up to the length
/// of the shorter of the two.
fn trace_singles<I: Intersector>(scene: &SceneView<'_>, out: &mut [MaybeUninit<HitRecord>], rays: &[Ray]) {
    let n = out.len().min(rays.len());
    let ray = |i: usize| {
        prefetch(rays.get(i + SINGLE_PREFETCH_AHEAD));
        rays.get(i)
    };
    let hit = |i: usize, _: Option<&Ray>, h| {
        if let Some(o) = out.get_mut(i) {
            o.write(record(h));
        }
    };
    trace_each::<I, _, _>(scene, n, ray, &mut NoProbe, &mut RayCounters::default(), hit);
}

/// Chunks of `CHUNK` rays per task; with `N > 1`, runs of `N` consecutive rays are traced
/// as one packet.
fn trace_with<I: Intersector, const N: usize>(
    scene: &SceneView<'_>,
    rays: &[Ray],
    threads: Option<usize>,
    out: &mut Vec<HitRecord>,
) -> Result<()> {
    crate::platform::isa::report_cpu();
    // Each chunk writes its own slice of one preallocated output: no per-chunk vectors
    // to gather and copy afterwards. The output is not filled beforehand: that pass
    // wrote all 16 bytes per ray once more (to memory, for large batches) before the
    // trace wrote them again.
    let n = rays.len();
    out.clear();
    if out.capacity() < n {
        *out = huge_pages::empty_vec::<HitRecord>(n);
    }
    let chunks = out.spare_capacity_mut()[..n].chunks_mut(CHUNK).zip(rays.chunks(CHUNK));
    for_each_claimed(threads, chunks, |(out, chunk)| {
        if N == 1 {
            trace_singles::<I>(scene, out, chunk);
        } else {
            let mut pc = PacketCounters::default();
            let mut hits = [None; N];
            // One packet record, refilled: only the active mask needs clearing.
            let mut packet = RayPacket::<N>::new();
            for (k, (out, group)) in out.chunks_mut(N).zip(chunk.chunks(N)).enumerate() {
                prefetch_packet(chunk, (k + PACKET_PREFETCH_AHEAD) * N, N);
                packet.fill(group);
                trace_packet::<I, _, N>(scene, &packet, &mut hits, &mut NoProbe, &mut pc);
                for (o, h) in out.iter_mut().zip(&hits) {
                    o.write(record(*h));
                }
            }
        }
    })?;
    // SAFETY: the capacity is at least `n` (made so above), and each of the first `n`
    // records has been written: the output's chunks pair with the rays' chunks of the
    // same lengths; a single-ray chunk hands every index below its length to `hit`, and
    // a packet's records zip with its `N` hits, so every record of a run of at most `N`
    // is written.
    unsafe { out.set_len(n) };
    Ok(())
}
