//! `raypipe trace`: traces a batch of rays from a file and writes their hits (or their
//! occlusion), with the fields asked for.

use crate::render::batch::{incoherent_share, read_rays, BatchOptions, BatchScratch};
use crate::render::packets::PacketSize;
use crate::render::ray_order::RayOrder;
use crate::render::tracer::IntersectorKind;
use crate::scene;
use crate::study::bench::median;
use anyhow::{bail, Result};
use rayon::prelude::*;
use raypipe_core::shade::ray_cone::RayCone;
use raypipe_core::shade::surface::Surface;
use raypipe_core::{Hit, NoProbe, Ray, SceneView, Vec3};
use std::time::Instant;

use super::{structure_summary, warn, warn_range};

use super::args::RunArgs;
use super::args::StructureArgs;
use clap::Args;
/// An output field of a closest-hit query.
use std::path::PathBuf;

/// `raypipe trace`.
#[derive(Args, Debug)]
pub struct TraceArgs {
    /// An OBJ file or a scene image.
    pub scene: PathBuf,
    /// Rays: float32 or float64 array of shape (N, 6) — origin, direction — or (N, 8) with
    /// t_min, t_max. A row that is no ray (NaN, zero direction, empty interval) is a miss,
    /// counted.
    #[arg(long, value_name = "NPY")]
    pub rays: PathBuf,
    /// Output: structured array of N records with the --fields chosen (closest: t, u, v
    /// float32 and prim int32, -1 on a miss, by default; any: occluded uint8).
    #[arg(long, value_name = "NPY")]
    pub hits: PathBuf,
    /// What each ray asks: the closest hit, or whether anything lies in its interval
    /// (occlusion, cheaper: traversal stops at the first hit).
    #[arg(long, value_enum, default_value_t = Query::Closest)]
    pub query: Query,
    /// Output fields, comma-separated. Closest: t, u, v, prim, ng (geometric normal,
    /// winding order, unit), ns (shading normal facing the ray, unit), material (id, -1
    /// on a miss), object (OBJ o/g name, glTF node or scene-file mesh, in input order; -1
    /// on a miss); default t,u,v,prim. Any: occluded.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub fields: Vec<String>,
    #[command(flatten)]
    pub structure: StructureArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Trace the batch this many times and report the median time.
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// Trace consecutive rays in packets of this many (1 = single rays); hits are the same.
    #[arg(long, value_enum, default_value_t = PacketSize::Single)]
    pub packet: PacketSize,
    /// The order single rays are traced in: auto groups an incoherent batch's rays by
    /// direction (octant and dominant axis) first; hits are the same, in the file's order.
    #[arg(long, value_enum, default_value_t = RayOrder::Auto)]
    pub order: RayOrder,
    #[command(flatten)]
    pub cache: super::args::CacheArgs,
}

/// What `raypipe trace` asks of each ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Query {
    /// The closest hit.
    #[default]
    Closest,
    /// Any hit in the interval (occlusion).
    Any,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Field {
    T,
    U,
    V,
    Prim,
    GeometricNormal,
    ShadingNormal,
    Material,
    Object,
}

impl Field {
    fn parse(s: &str) -> Result<Field> {
        Ok(match s.trim() {
            "t" => Field::T,
            "u" => Field::U,
            "v" => Field::V,
            "prim" => Field::Prim,
            "ng" => Field::GeometricNormal,
            "ns" => Field::ShadingNormal,
            "material" => Field::Material,
            "object" => Field::Object,
            other => {
                bail!(
                    "--fields: unknown field '{other}' (t, u, v, prim, ng, ns, material, object; any-hit queries: occluded)"
                )
            }
        })
    }

    /// Bytes of the field in a record.
    pub(crate) fn size(self) -> usize {
        match self {
            Field::GeometricNormal | Field::ShadingNormal => 12,
            _ => 4,
        }
    }

    pub(crate) fn descr(self) -> (&'static str, &'static str) {
        match self {
            Field::T => ("t", "'<f4'"),
            Field::U => ("u", "'<f4'"),
            Field::V => ("v", "'<f4'"),
            Field::Prim => ("prim", "'<i4'"),
            Field::GeometricNormal => ("ng", "'<f4', (3,)"),
            Field::ShadingNormal => ("ns", "'<f4', (3,)"),
            Field::Material => ("material", "'<i4'"),
            Field::Object => ("object", "'<i4'"),
        }
    }
}

pub(crate) fn cmd_trace(a: TraceArgs) -> Result<()> {
    a.run.check()?;
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let fields: Vec<Field> = match a.query {
        Query::Closest if a.fields.is_empty() => vec![Field::T, Field::U, Field::V, Field::Prim],
        Query::Closest => a.fields.iter().map(|f| Field::parse(f)).collect::<Result<_>>()?,
        Query::Any => {
            if let Some(f) = a.fields.iter().find(|f| f.trim() != "occluded") {
                bail!("--fields {f}: an any-hit query gives only 'occluded'");
            }
            Vec::new()
        }
    };
    if crate::input::bricked::is_bricked(&a.scene) {
        return super::trace_bricked::cmd_trace_bricked(&a, &fields);
    }
    let (rays, invalid) = read_rays(&a.rays)?;
    let name = a.rays.display();
    let scene = scene::load(Some(&a.scene), &a.structure.options())?;
    warn(&scene);
    let view = scene.view()?;
    let valid: Vec<Ray> = rays.iter().zip(&invalid).filter(|(_, bad)| !**bad).map(|(r, _)| *r).collect();
    warn_range(&view, &valid, &format!("rays of {name}"));
    let n_invalid = invalid.iter().filter(|b| **b).count();
    if n_invalid > 0 {
        crate::output::warnings::warning(&format!(
            "{name}: {n_invalid} rows are not rays (NaN or infinite values, a zero direction, an empty or negative interval): returned as misses"
        ));
    }
    if a.packet != PacketSize::Single {
        let share = incoherent_share(&rays, a.packet.lanes());
        if share > 0.25 {
            crate::output::warnings::warning(&format!(
                "{name}: {:.0}% of the packets of {} consecutive rays hold rays more than 60° from their mean direction: packets of incoherent rays split at once and trace slower than single rays (--packet 1)",
                100.0 * share,
                a.packet.lanes()
            ));
        }
    }
    let kind = IntersectorKind::resolve(a.run.intersector, &view);
    let opts = BatchOptions { kind, packet: a.packet, order: a.order, threads: a.run.threads };
    let mut times = Vec::new();
    let (data, fields_out, n_hit) = match a.query {
        Query::Closest => {
            // One output for all runs, as a caller tracing batch after batch keeps one:
            // only the first run pays for touching fresh pages.
            let (mut hits, mut scratch) = (Vec::new(), BatchScratch::default());
            for _ in 0..a.runs {
                let start = Instant::now();
                crate::render::batch::trace_batch_into(&view, &rays, opts, &mut hits, &mut scratch)?;
                times.push(start.elapsed().as_secs_f64());
            }
            let data = closest_records(&view, &rays, &hits, &invalid, &fields);
            let n_hit = hits.iter().zip(&invalid).filter(|(h, bad)| h.prim >= 0 && !**bad).count();
            (data, fields.iter().map(|f| f.descr()).collect::<Vec<_>>(), n_hit)
        }
        Query::Any => {
            let (mut blocked, mut scratch) = (Vec::new(), BatchScratch::default());
            for _ in 0..a.runs {
                let start = Instant::now();
                blocked = crate::render::batch::occluded_batch(&view, &rays, &invalid, opts, &mut scratch)?;
                times.push(start.elapsed().as_secs_f64());
            }
            let n_hit = blocked.iter().filter(|b| **b).count();
            (blocked.iter().map(|&b| b as u8).collect(), vec![("occluded", "'u1'")], n_hit)
        }
    };
    let secs = median(&times);
    crate::input::npy::write_records(&a.hits, &fields_out, rays.len(), &data)?;
    println!(
        "traced {} rays ({} query{}) through {} ({}): {} {} ({:.2}%) in {:.3} s ({:.2} Mrays/s) -> {}",
        rays.len(),
        if a.query == Query::Any { "any-hit" } else { "closest-hit" },
        if n_invalid > 0 { format!(", {n_invalid} invalid rows as misses") } else { String::new() },
        scene.name,
        structure_summary(&view),
        n_hit,
        if a.query == Query::Any { "occluded" } else { "hits" },
        100.0 * n_hit as f64 / rays.len().max(1) as f64,
        secs,
        rays.len() as f64 / secs / 1e6,
        a.hits.display()
    );
    Ok(())
}

/// The closest-hit records, packed field by field.
fn closest_records(
    view: &SceneView<'_>,
    rays: &[Ray],
    hits: &[crate::input::npy::HitRecord],
    invalid: &[bool],
    fields: &[Field],
) -> Vec<u8> {
    // Every record has the same size: each ray writes its own slice of one buffer.
    let size: usize = fields.iter().map(|f| f.size()).sum();
    let mut data = vec![0u8; size * hits.len()];
    data.par_chunks_mut(size.max(1)).zip(hits).zip(rays).zip(invalid).for_each(|(((out, h), ray), bad)| {
        let hit = (h.prim >= 0 && !bad).then_some(Hit { t: h.t, u: h.u, v: h.v, prim: h.prim as u32 });
        pack_record(view, ray, hit, hit, fields, out);
    });
    data
}

/// One closest-hit record's fields into `out`: `hit` as the file reports it (`prim`
/// scene-wide), `local` the same hit as `view` knows it (a brick's own triangle index).
pub(crate) fn pack_record(
    view: &SceneView<'_>,
    ray: &Ray,
    hit: Option<Hit>,
    local: Option<Hit>,
    fields: &[Field],
    out: &mut [u8],
) {
    let normals = fields.contains(&Field::ShadingNormal) || fields.contains(&Field::GeometricNormal);
    let surface = match (&local, normals) {
        (Some(hit), true) => Some(Surface::at(view, ray, hit, RayCone::POINT, &mut NoProbe)),
        _ => None,
    };
    let mut at = 0;
    let mut put = |bytes: &[u8]| {
        out[at..at + bytes.len()].copy_from_slice(bytes);
        at += bytes.len();
    };
    for f in fields {
        match f {
            Field::T => put(&hit.map_or(f32::INFINITY, |h| h.t).to_le_bytes()),
            Field::U => put(&hit.map_or(0.0, |h| h.u).to_le_bytes()),
            Field::V => put(&hit.map_or(0.0, |h| h.v).to_le_bytes()),
            Field::Prim => put(&hit.map_or(-1, |h| h.prim as i32).to_le_bytes()),
            Field::GeometricNormal | Field::ShadingNormal => {
                let n = surface.as_ref().map_or(Vec3::ZERO, |s| {
                    if *f == Field::GeometricNormal {
                        s.geometric.normalize_or_zero()
                    } else {
                        s.normal
                    }
                });
                n.to_array().iter().for_each(|c| put(&c.to_le_bytes()));
            }
            Field::Object => put(&local.map_or(-1, |h| view.object_of(h.prim) as i32).to_le_bytes()),
            Field::Material => {
                let id = local.and_then(|h| view.material_id(h.prim, &mut NoProbe)).map_or(-1, |m| m as i32);
                put(&id.to_le_bytes());
            }
        }
    }
}
