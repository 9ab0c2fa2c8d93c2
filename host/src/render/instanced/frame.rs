//! A frame of an instanced scene, tile by tile on the worker pool: eye rays walk the two
//! levels, hits are shaded from their instance's world-space surface with the globals
//! image's lights; Whitted's records are traced depth first per pixel (every bottom is
//! resident, so there is nothing to wait for), each pixel's samples summed exactly
//! ([`RadianceSum`]).

use anyhow::{bail, Result};
use rayon::prelude::*;
use raypipe_core::camera::EyeRays;
use raypipe_core::image::CameraRecord;
use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::instance_surface::instance_surface;
use raypipe_core::shade::lambert::shade_surface;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::whitted::{shade_whitted_surface, WhittedOptions};
use raypipe_core::{Intersector, NoProbe, RayCounters, Vec3};

use super::tracer::{occluded_instance, trace_instance};
use super::Instances;
use crate::output::progress;
use crate::render::{eye_rays, in_pool, place_tile, tiles, Algorithm, Frame, RayTotals, RenderOptions};
use crate::with_intersector;

/// Checks that `opts` can render an instanced scene: ray casting and Whitted (the
/// shadow caster rasterizes a flat triangle list, path tracing samples area lights
/// by triangle id).
pub fn check_algorithm(opts: &RenderOptions) -> Result<()> {
    match opts.algo {
        Algorithm::Cast | Algorithm::Whitted => Ok(()),
        Algorithm::Shadow => bail!(
            "--algo shadow rasterizes one flat triangle list: render an instanced scene with --algo cast or whitted"
        ),
        Algorithm::Path => bail!(
            "--algo path samples emitters by triangle id, which instances share: render an instanced scene with --algo cast or whitted"
        ),
    }
}

/// Renders the instanced scene as `camera` sees it; returns the frame and the rays
/// traced.
pub fn render_instanced(s: &Instances<'_>, camera: &CameraRecord, opts: &RenderOptions) -> Result<(Frame, RayTotals)> {
    check_algorithm(opts)?;
    let eye = eye_rays(camera, "camera")?.with_sampler(opts.sampler());
    let background = Vec3::from(camera.background);
    let (w, h) = (camera.width, camera.height);
    let shader = match opts.shader(background) {
        Some(Shader::Whitted(o)) => Some(o),
        _ => None,
    };
    let all = tiles(w, h);
    let bar = progress::bar(all.len() as u64, "tiles", opts.progress);
    let done = in_pool(opts.threads, || {
        all.par_iter()
            .map(|&t| {
                let r = with_intersector!(opts.intersector, I => tile::<I>(s, &eye, background, shader.as_ref(), t));
                bar.inc(1);
                (t, r)
            })
            .collect::<Vec<_>>()
    })?;
    bar.finish_and_clear();
    let mut radiance = vec![Vec3::ZERO; (w * h) as usize];
    let mut totals = RayTotals::default();
    for (t, (colours, rays)) in done {
        place_tile(&mut radiance, w, t, &colours);
        totals.add(&rays);
    }
    Ok((Frame::from_radiance(w, h, radiance), totals))
}

/// One tile's pixels, row by row.
fn tile<I: Intersector>(
    s: &Instances<'_>,
    eye: &EyeRays,
    background: Vec3,
    shader: Option<&WhittedOptions>,
    (x0, y0, x1, y1): (u32, u32, u32, u32),
) -> (Vec<Vec3>, RayTotals) {
    let (lo, hi) = s.globals.test_bounds();
    let (samples, cone) = (eye.samples(), eye.cone());
    let mut totals = RayTotals::default();
    let mut c = RayCounters::default();
    let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
    let mut stack = Vec::new();
    // One sample of ray casting is its colour as it is (a sum of one would round it).
    let direct = shader.is_none() && samples == 1;
    for y in y0..y1 {
        for x in x0..x1 {
            let mut sum = RadianceSum::default();
            for k in 0..samples {
                let Some(ray) = eye.sample_ray_in_scene(x, y, k, lo, hi) else {
                    let c = eye_escaped(&s.globals, eye, (x, y, k), background, &mut NoProbe);
                    if direct {
                        out.push(c);
                    } else {
                        sum.add(c / samples as f32);
                    }
                    continue;
                };
                totals.primary += 1;
                let hit = trace_instance::<I>(s, &ray, &mut c);
                let surface =
                    hit.and_then(|h| instance_surface(&s.top, &s.bottoms, &s.globals, &ray, &h, cone, &mut NoProbe));
                let Some(opts) = shader else {
                    let colour = shade_surface(&s.globals, &ray, surface, background, &mut NoProbe);
                    if direct {
                        out.push(colour);
                    } else {
                        sum.add(colour / samples as f32);
                    }
                    continue;
                };
                let rec = RayRecord::eye_sample(ray, y * eye.width + x, k, samples, cone);
                sum.add(shade_whitted_surface(&s.globals, &rec, surface, opts, &mut NoProbe, &mut |r| stack.push(r)));
                totals.secondary += whitted_records::<I>(s, opts, &mut stack, &mut sum, &mut c);
            }
            if !direct {
                out.push(sum.value());
            }
        }
    }
    (out, totals)
}

/// Traces the records on `stack` (and those they emit) to the end, adding their
/// radiance to `sum`; returns the rays traced.
fn whitted_records<I: Intersector>(
    s: &Instances<'_>,
    opts: &WhittedOptions,
    stack: &mut Vec<RayRecord>,
    sum: &mut RadianceSum,
    c: &mut RayCounters,
) -> u64 {
    let mut traced = 0;
    while let Some(rec) = stack.pop() {
        traced += 1;
        if rec.kind == RayKind::Shadow {
            if !occluded_instance::<I>(s, &rec.ray, c) {
                sum.add(rec.weight);
            }
            continue;
        }
        let hit = trace_instance::<I>(s, &rec.ray, c);
        let surface =
            hit.and_then(|h| instance_surface(&s.top, &s.bottoms, &s.globals, &rec.ray, &h, rec.cone, &mut NoProbe));
        sum.add(shade_whitted_surface(&s.globals, &rec, surface, opts, &mut NoProbe, &mut |r| stack.push(r)));
    }
    traced
}
