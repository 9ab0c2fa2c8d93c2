//! How fast a moved mesh's BVH follows it: every sampled frame of an animation flattened
//! into one mesh (each instance's copy placed in the world, the animated triangles at
//! their keys' interpolation), then refitted, rebuilt as a linear BVH and rebuilt with
//! the binned SAH, each timed per frame and quoted in milliseconds per million
//! triangles — the figures Embree's `RTC_BUILD_QUALITY_REFIT`, `LOW` and `MEDIUM` are
//! measured by on the same vertex buffers (`bench/embree-updates.sh`).

use std::time::Instant;

use anyhow::{anyhow, Result};
use glam::Vec3;
use raypipe_core::image::{BvhNode, Position};
use raypipe_core::math::affine;

use crate::build::box_bvh::build_box_bvh;
use crate::build::dynamic::lbvh::build_lbvh;
use crate::build::dynamic::refit::{bounds_of, margin_for, refit, sah_cost};
use crate::input::aff::AffScene;
use crate::study::animation_report::percentile;

/// The flattened animation: one triangle list, each sampled frame's vertices.
pub struct FlatFrames {
    /// Triangles (the same every frame).
    pub triangles: Vec<[u32; 3]>,
    /// Sampled frames: their numbers and vertices.
    pub frames: Vec<(u32, Vec<Position>)>,
}

/// Flattens the frames `frames` of `aff`.
pub fn flatten_frames(aff: &AffScene, frames: impl Iterator<Item = u32>) -> FlatFrames {
    let s = &aff.scene;
    let mut triangles = Vec::new();
    let mut base = 0u32;
    for inst in &s.instances {
        let mesh = &s.bottoms[inst.bottom as usize];
        triangles.extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
        base += mesh.positions.len() as u32;
    }
    let frames = frames
        .map(|k| {
            let t = aff.time(k);
            let deformed: std::collections::HashMap<u32, Vec<[f32; 3]>> = aff.deformed(t).into_iter().collect();
            let mut positions = Vec::with_capacity(base as usize);
            for (i, inst) in s.instances.iter().enumerate() {
                let m = aff.instance_transform(i, t);
                let verts = deformed.get(&inst.bottom).unwrap_or(&s.bottoms[inst.bottom as usize].positions);
                positions.extend(verts.iter().map(|p| Position(affine::point(&m, Vec3::from(*p)).to_array())));
            }
            (k, positions)
        })
        .collect();
    FlatFrames { triangles, frames }
}

/// One method's times per frame, ms per million triangles, and its trees' SAH cost
/// relative to the binned SAH build of the same frame.
#[derive(Clone, Debug, Default)]
pub struct MethodTimes {
    /// ms per million triangles, per frame.
    pub ms_per_million: Vec<f64>,
    /// SAH cost over the full build's, per frame.
    pub cost_ratio: Vec<f64>,
}

impl MethodTimes {
    /// `median (p10 … p90)` of the times.
    pub fn summary(&self) -> String {
        let v = &self.ms_per_million;
        format!("{:8.1} ({:.1} … {:.1})", percentile(v, 50.0), percentile(v, 10.0), percentile(v, 90.0))
    }
}

/// Refit, linear BVH and binned SAH over every sampled frame (the refit starts from the
/// first frame's SAH tree and follows the frames in order).
pub fn time_updates(flat: &FlatFrames) -> [MethodTimes; 3] {
    let tris = &flat.triangles;
    let million = tris.len() as f64 / 1e6;
    let mut out: [MethodTimes; 3] = Default::default();
    let sah_tree = |positions: &[Position]| -> (Vec<BvhNode>, Vec<u32>) {
        let boxes: Vec<([f32; 3], [f32; 3])> = tris
            .iter()
            .map(|t| {
                let p = |k: usize| Vec3::from(positions[t[k] as usize].0);
                (p(0).min(p(1)).min(p(2)).to_array(), p(0).max(p(1)).max(p(2)).to_array())
            })
            .collect();
        let b = build_box_bvh(&boxes, 4);
        (b.nodes, b.list)
    };
    let Some((_, first)) = flat.frames.first() else { return out };
    let (mut refitted, refit_prims) = sah_tree(first);
    for (_, positions) in &flat.frames {
        let (lo, hi) = bounds_of(positions);
        let margin = margin_for(lo, hi);
        let start = Instant::now();
        let (mut sah_nodes, sah_prims) = sah_tree(positions);
        refit(&mut sah_nodes, &sah_prims, tris, positions, margin);
        let sah_ms = start.elapsed().as_secs_f64() * 1e3;
        let full_cost = sah_cost(&sah_nodes).max(f64::MIN_POSITIVE);

        let start = Instant::now();
        refit(&mut refitted, &refit_prims, tris, positions, margin);
        let refit_ms = start.elapsed().as_secs_f64() * 1e3;

        let start = Instant::now();
        let (mut lbvh, lbvh_prims) = build_lbvh(tris, positions, 4);
        refit(&mut lbvh, &lbvh_prims, tris, positions, margin);
        let lbvh_ms = start.elapsed().as_secs_f64() * 1e3;

        for (m, (ms, cost)) in
            out.iter_mut().zip([(refit_ms, sah_cost(&refitted)), (lbvh_ms, sah_cost(&lbvh)), (sah_ms, full_cost)])
        {
            m.ms_per_million.push(ms / million);
            m.cost_ratio.push(cost / full_cost);
        }
    }
    out
}

/// Writes the flattened frames for the Embree harness: `u32` triangle count, vertex
/// count and frame count, the triangles (3 × `u32` each), then each frame's vertices
/// (3 × `f32` each), little-endian.
pub fn write_dump(path: &std::path::Path, flat: &FlatFrames) -> Result<()> {
    let nv = flat.frames.first().map_or(0, |f| f.1.len());
    crate::output::write_atomic(path, |w| {
        let io = |e: std::io::Error| anyhow!("cannot write: {e}");
        for v in [flat.triangles.len(), nv, flat.frames.len()] {
            w.write_all(&(v as u32).to_le_bytes()).map_err(io)?;
        }
        w.write_all(bytemuck::cast_slice(&flat.triangles)).map_err(io)?;
        for (_, p) in &flat.frames {
            w.write_all(bytemuck::cast_slice(p)).map_err(io)?;
        }
        Ok(())
    })
}
