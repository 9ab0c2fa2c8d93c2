//! The shading pass (Purcell 2002 §3.1.4) over one screen: each ray that finished
//! traversal (and each pixel whose visibility the G-buffer gave) runs core's shading
//! kernel — the ray caster's Lambert shader, or the ray-emitting Whitted and path
//! shaders, whose new records form the next wave; a shadow ray adds its weight if
//! nothing was in the way. Radiance goes to the pixel the record carries.

use raypipe_core::image::MaterialRecord;
use raypipe_core::shade::blinn_phong::is_glossy;
use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::surface::Surface;
use raypipe_core::shade::texture::surface_texture;
use raypipe_core::{Intersector, NoProbe};

use crate::stream::config::Architecture;
use crate::stream::cost_model::Kernel;
use crate::stream::counters::{PassKind, PassRecord};
use crate::stream::frame::{Fragment, StreamMachine};
use crate::stream::memory_probe::StreamProbe;
use crate::stream::ray_state::StreamRay;
use crate::stream::stencil::{covered_fragments, StencilCounts};

impl<I: Intersector> StreamMachine<'_, I> {
    /// Shades one screen; emitted records go to `next`. Returns the pass and the most
    /// words one fragment writes (its colour and the records it emits).
    pub(crate) fn shading_pass(
        &mut self,
        wave: u32,
        screen: u32,
        frags: &[Fragment],
        ends: &[Option<StreamRay<I>>],
        next: &mut Vec<RayRecord>,
    ) -> (PassRecord, u64) {
        let (width, _) = self.screen();
        let mut p = PassRecord { wave, screen, kind: Some(PassKind::Shade), iterations: 1, ..Default::default() };
        if self.cfg.arch == Architecture::Multipass {
            p.covered = covered_fragments(frags.len(), width);
            p.stencil = StencilCounts { reads: p.covered, writes: 0 };
        }
        // The lights the shader reads at a hit: those before the area lights, and for the
        // path tracer one emitter picked by power.
        let shadowing = (0..self.scene.shading_light_count())
            .filter(|&i| Surface::casts_shadows(&self.scene.light(i, &mut NoProbe)))
            .count() as u64;
        let picks_emitter = matches!(self.shader, Some(Shader::Path(_))) && self.scene.area_light_count() > 0;
        let lights = self.scene.shading_light_count() as u64 + picks_emitter as u64;
        let (mut shaded, mut lit, mut shadows, emitted_before) = (0u64, 0u64, 0u64, next.len());
        let (mut glossy, mut textured) = (0u64, 0u64);
        let (scene, background, shader) = (self.scene, self.background, self.shader);
        // A hit's material (read again without a probe: the kernel's own read is counted)
        // and whether its surface reads a texture (core's test, that of `Surface::at`).
        let material = |hit: Option<raypipe_core::Hit>| hit.map(|h| scene.material_of(h.prim, &mut NoProbe));
        let reads_texture = |m: &MaterialRecord| surface_texture(&scene, m).is_some();
        let (sums, share) = (self.sums_radiance(), 1.0 / self.samples() as f32);
        let eye = self.eye;
        let mut probe = StreamProbe::new(&mut self.cache, false);
        let mut most_emitted = 0;
        for (i, f) in frags.iter().enumerate() {
            let (rec, hit) = match f {
                Fragment::Empty => {
                    // An eye ray that missed the scene box (wave 0 holds screen `s` of
                    // sample `s`, pixel `i`): its share of what an escaped ray sees.
                    if wave == 0 {
                        let (x, y) = (i as u32 % width, i as u32 / width);
                        let color = eye_escaped(&scene, &eye, (x, y, screen), background, &mut probe);
                        if sums {
                            if let Some(r) = self.radiance.get_mut(i) {
                                r.add(color * share);
                            }
                        } else if let Some(px) = self.framebuffer.get_mut(i) {
                            *px = color;
                        }
                    }
                    continue;
                }
                Fragment::Visible(rec, hit) => (*rec, *hit),
                Fragment::Trace(rec) => (*rec, ends.get(i).and_then(|e| e.as_ref()).and_then(StreamRay::hit)),
            };
            let pixel = rec.pixel as usize;
            if wave == 0 && rec.sample == 0 {
                if let Some(h) = self.hits.get_mut(pixel) {
                    *h = hit;
                }
            }
            match shader {
                None => {
                    shaded += 1;
                    lit += hit.is_some() as u64;
                    textured += material(hit).as_ref().is_some_and(reads_texture) as u64;
                    let color = shade(&scene, &rec.ray, rec.cone, hit, background, &mut probe);
                    if sums {
                        if let Some(r) = self.radiance.get_mut(pixel) {
                            r.add(color * rec.weight);
                        }
                    } else if let Some(px) = self.framebuffer.get_mut(pixel) {
                        *px = color;
                    }
                }
                Some(_) if rec.kind == RayKind::Shadow => {
                    shadows += 1;
                    if hit.is_none() {
                        if let Some(r) = self.radiance.get_mut(pixel) {
                            r.add(rec.weight);
                        }
                    }
                }
                Some(s) => {
                    shaded += 1;
                    lit += hit.is_some() as u64;
                    let m = material(hit);
                    textured += m.as_ref().is_some_and(reads_texture) as u64;
                    // The highlight is the shader's (the ray caster's Lambert has none).
                    glossy += m.as_ref().is_some_and(is_glossy) as u64;
                    let before = next.len();
                    let c = s.shade(&scene, &rec, hit, &mut probe, &mut |r| next.push(r));
                    most_emitted = most_emitted.max(next.len() - before);
                    if let Some(r) = self.radiance.get_mut(pixel) {
                        r.add(c);
                    }
                }
            }
        }
        let words = probe.take_words();
        drop(probe);
        let emitted = (next.len() - emitted_before) as u64;
        p.processed = shaded + shadows;
        p.useful = p.processed;
        self.charge(Kernel::Shade, shaded, shaded, words, &mut p);
        self.charge(Kernel::ShadeLight, lit * lights, 0, [0; 4], &mut p);
        self.charge(Kernel::Texture, textured, 0, [0; 4], &mut p);
        self.charge(Kernel::Glossy, glossy, 0, [0; 4], &mut p);
        self.charge(Kernel::GlossyLight, glossy * shadowing, 0, [0; 4], &mut p);
        self.charge(Kernel::Spawn, emitted, emitted, [0; 4], &mut p);
        self.charge(Kernel::ShadowAdd, shadows, shadows, [0; 4], &mut p);
        let (shade_w, spawn_w) = (self.costs.get(Kernel::Shade).w, self.costs.get(Kernel::Spawn).w);
        let written = if p.processed > 0 { shade_w + most_emitted as u64 * spawn_w } else { 0 };
        (p, written)
    }
}
